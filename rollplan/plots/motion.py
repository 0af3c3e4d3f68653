"""Figures of a timed motion: omega, rotor rates and rotor torques in time, and a rotor-driven simulation
against its plan. They compute nothing."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .colors import OMEGA, OMEGA_LABELS, PLANNED, REST, ROTOR, ROTOR_LABELS, SIMULATED
from .common import draw_plane_path, plane_axes
from .composed import draw_composed_plane

__all__ = ["plot_motion", "draw_time_series", "plot_simulation"]


def _rests(ax, times):
    for t in times:
        ax.axvline(t, color=REST, linewidth=0.7, zorder=0)


def draw_time_series(ax, motion, values, labels, ylabel, title, scale=1.0, colors=None):
    """Columns of ``values`` against time, in ``colors``; thin grey lines mark the stops (at rest) on the way."""
    stops = motion.time[motion.rest_indices]
    stops = stops[(stops > motion.time[0]) & (stops < motion.time[-1])]
    _rests(ax, stops)
    colors = colors or [None] * len(labels)
    for col, label, color in zip(np.asarray(values).T, labels, colors):
        ax.plot(motion.time, col * scale, linewidth=1.2, label=label, color=color)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.set_xlim(motion.time[0], motion.time[-1])
    ax.grid(True, alpha=0.3)
    handles, _ = ax.get_legend_handles_labels()
    if stops.size:
        handles.append(Line2D([], [], color=REST, linewidth=0.7, label="at rest (between pieces)"))
    ax.legend(handles=handles, loc="upper right", fontsize=8)


def plot_motion(motion, plan=None, traj=None, unit="m") -> Figure:
    """Omega, rotor rates and torques of a :class:`rollplan.execution.actuation.Motion` in time.

    With ``plan`` and ``traj`` (a :class:`rollplan.result.Trajectory`) a fourth panel
    shows the contact path on the plane; otherwise the rotor angles. Torques in N m.
    """
    from ..planners.geometric.planner import Plan

    one_leg = isinstance(plan, Plan)   # the paper's plan: its half-steps; else pieces (rolls, leaves, circles)
    fig = Figure(figsize=(12, 8), layout="constrained")
    axes = fig.subplots(2, 2)
    draw_time_series(axes[0, 0], motion, motion.omega, OMEGA_LABELS, "angular velocity [rad/s]",
                     "sphere angular velocity (plane frame), (18), (19), (13)", colors=OMEGA)
    rate_labels = [f"$\\dot\\varphi_{i + 1}$, {lab}" for i, lab in enumerate(ROTOR_LABELS)]
    draw_time_series(axes[0, 1], motion, motion.rotor_rates, rate_labels, "rotor rate [rad/s]",
                     "rotor rates, eq. (11)", colors=ROTOR)
    draw_time_series(axes[1, 0], motion, motion.rotor_torques, [f"$\\tau_{i + 1}$, {lab}" for i, lab in
                                                                 enumerate(ROTOR_LABELS)],
                     "motor torque [N m]", "rotor torques", colors=ROTOR)
    if plan is not None and traj is not None:
        if not one_leg:   # a composed plan or a route: rolls, leaves and turns in their colours
            draw_composed_plane(axes[1, 1], plan, traj, unit, "contact path on the plane")
        else:
            draw_plane_path(axes[1, 1], traj, plan.goal[:2], unit)
    else:
        draw_time_series(axes[1, 1], motion, motion.rotor_angles / (2 * np.pi),
                         [f"$\\varphi_{i + 1}$, {lab}" for i, lab in enumerate(ROTOR_LABELS)],
                         "rotor angle [turns]", "rotor angles", colors=ROTOR)
    r = motion.robot
    pieces = "pieces (leaves, rolls, circles)" if plan is None or not one_leg else "half-steps"
    fig.suptitle(f"T = {motion.duration:.6g} s, {int(motion.segment.max()) + 1} {pieces} (timing {motion.timing}); "
                 f"R = {r.radius:.6g} m, k = {r.k:.6g}, $J_r$ = {r.rotor_inertia_axial:.6g} kg m$^2$")
    return fig


def plot_simulation(time, simulated, rates, goal, planned=None, robot=None, title="") -> Figure:
    """A rotor-driven simulation against its plan: paths, psi, deviation and the rotor rates that drove it.

    Parameters
    ----------
    time : (N,)
        Sample times [s].
    simulated : (N, 5)
        Simulated states in :class:`~rollplan.problem.State` order [m, rad].
    rates : (N, 2)
        Rotor rates that drove the simulation [rad/s].
    goal : State or sequence
        Planned arrival (u_a, v_a, psi, ...) [m, rad].
    planned : (N, 5), optional
        The planned states at the same times (drawn dashed, and the deviation panel).
    robot : Robot, optional
        The simulated robot (named in the title).
    title : str
        Figure title (a line on the robot is added).
    """
    time = np.asarray(time, float)
    sim = np.asarray(simulated, float)
    fig = Figure(figsize=(12, 8), layout="constrained")
    axes = fig.subplots(2, 2)
    ax = axes[0, 0]
    # the simulated curve first, the planned one dashed on top of it (where they agree both stay visible)
    ax.plot(sim[:, 0], sim[:, 1], color=SIMULATED, linewidth=1.6, zorder=2, label="simulated")
    handles = [Line2D([], [], color=SIMULATED, linewidth=1.6, label="simulated")]
    if planned is not None:
        ax.plot(planned[:, 0], planned[:, 1], color=PLANNED, linestyle="--", linewidth=1.2, zorder=3, label="planned")
        handles.append(Line2D([], [], color=PLANNED, linestyle="--", label="planned (on top)"))
    plane_axes(ax, goal[:2], "m", "contact path on the plane", handles=handles)
    ax = axes[0, 1]
    ax.plot(time, sim[:, 2], color=SIMULATED, linewidth=1.6, zorder=2, label="simulated")
    if planned is not None:
        ax.plot(time, planned[:, 2], color=PLANNED, linestyle="--", linewidth=1.2, zorder=3, label="planned (on top)")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("contact angle psi [rad]")
    ax.set_title("psi in time")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax = axes[1, 0]
    if planned is not None:
        dev = np.hypot(sim[:, 0] - planned[:, 0], sim[:, 1] - planned[:, 1])
        dpsi = np.abs(sim[:, 2] - planned[:, 2])
        both = np.concatenate([dev, dpsi])
        floor = max(1e-15, float(np.percentile(both[both > 0], 5)) / 10) if np.any(both > 0) else 1e-15
        ax.semilogy(time, np.maximum(dev, floor), color=SIMULATED, linewidth=1.0,
                    label="distance of the contact points [m]")
        ax.semilogy(time, np.maximum(dpsi, floor), color=SIMULATED, linestyle=":",
                    linewidth=1.0, label="|psi difference| [rad]")
        ax.set_ylim(bottom=floor)
        ax.set_title("simulated minus planned")
        ax.set_ylabel("deviation [m] or [rad]")
        ax.legend(loc="best", fontsize=8)
    else:
        ax.text(0.5, 0.5, "the plan file has no planned states", ha="center", va="center", transform=ax.transAxes)
        ax.set_title("simulated minus planned")
    ax.set_xlabel("time t [s]")
    ax.grid(True, alpha=0.3)
    ax = axes[1, 1]
    for i, (col, lab) in enumerate(zip(np.asarray(rates, float).T, ROTOR_LABELS)):
        ax.plot(time, col, color=ROTOR[i], linewidth=1.2, label=f"$\\dot\\varphi_{i + 1}$, {lab}")
    ax.set_xlabel("time t [s]")
    ax.set_ylabel("rotor rate [rad/s]")
    ax.set_title("rotor rates driving the simulation")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)
    if robot is not None:
        title = f"{title}\nsimulated robot: R = {robot.radius:.6g} m, k = {robot.k:.6g}".strip()
    fig.suptitle(title)
    return fig
