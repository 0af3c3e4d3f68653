"""Figures of planner comparisons. Functions take results and return matplotlib Figures; they compute nothing.

Colours follow :mod:`.colors`: the two planners (``PLANNER``: geometric phase brown, collocation orange) where
both are drawn together, the rotors (``ROTOR``) and the components of omega (``OMEGA``) in each planner's own
row; every colour is named in a legend.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .colors import MARK, OMEGA, OMEGA_LABELS, PLANNER, PLANNER_LABELS, ROTOR, ROTOR_LABELS
from .common import bottom_view_axes, clip_spikes, draw_bottom_view, plane_axes

__all__ = ["plot_comparison"]

#: The sides of a :class:`~rollplan.studies.comparison.Comparison`, in drawing order, by method name.
SIDES = ("geometric", "collocation")


def _series(ax, t, values, colors, labels, ylabel, title):
    for col, color, label in zip(np.asarray(values).T, colors, labels):
        ax.plot(t, col, color=color, linewidth=1.1, label=label)
    _time_axes(ax, t, ylabel, title)


def _time_axes(ax, t, ylabel, title):
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, fontsize=10)
    ax.set_xlim(t[0], t[-1])
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=7)


def plot_comparison(c, unit: str = "R") -> Figure:
    """A :class:`~rollplan.studies.comparison.Comparison`: both contact paths (on the sphere in a close-up seen
    from below, with the contact bound, and on the plane) and |omega| of both in the planners' colours; then for
    each planner a row of omega's components (18), (19), (13), its rotor rates (11) and its motor torques, in the
    colours of the components and rotors."""
    fig = Figure(figsize=(14, 11), layout="constrained")
    ax_sphere = fig.add_subplot(3, 3, 1)
    ax_plane = fig.add_subplot(3, 3, 2)
    ax_speed = fig.add_subplot(3, 3, 3)
    rows = {name: [fig.add_subplot(3, 3, 4 + 3 * i + j) for j in range(3)] for i, name in enumerate(SIDES)}
    sides = {"geometric": c.gp, "collocation": c.collocation}
    handles, reach = [], 0.0
    torque_unit = "N m" if c.problem.robot is not None else "units of $J_{zz}$ rad/s$^2$"
    for name in SIDES:
        side, color, who = sides[name], PLANNER[name], PLANNER_LABELS[name]
        m = side.motion
        traj = m.trajectory()
        draw_bottom_view(ax_sphere, traj, c.problem.radius, unit, color=color, label=who, axes=False)
        reach = max(reach, float(np.abs(traj.contact[:, :2]).max()))
        ax_plane.plot(traj.u_a, traj.v_a, color=color, linewidth=1.4)
        handles.append(Line2D([], [], color=color, linewidth=1.5, label=f"{who}: length "
                              f"{side.costs['path_length']:.4g} {unit}, {c.cost} {side.costs[c.cost]:.4g}"))
        ax_speed.plot(m.t, np.sqrt((m.omega ** 2).sum(axis=1)), color=color, linewidth=1.2, label=who)
        omega_ax, rate_ax, torque_ax = rows[name]
        _series(omega_ax, m.t, m.omega, OMEGA, OMEGA_LABELS, "angular velocity [rad/s]",
                f"{who}: omega (plane frame)")
        _series(rate_ax, m.t, m.rotor_rates, ROTOR, [f"$\\dot\\varphi_{i + 1}$, {lab}" for i, lab in
                                                     enumerate(ROTOR_LABELS)], "rotor rate [rad/s]",
                f"{who}: rotor rates, eq. (11)")
        _series(torque_ax, m.t, m.rotor_torques, ROTOR, [f"$\\tau_{i + 1}$, {lab}" for i, lab in
                                                         enumerate(ROTOR_LABELS)], f"motor torque [{torque_unit}]",
                f"{who}: motor torques")
        clip_spikes(torque_ax, m.t, m.rotor_torques, ROTOR)   # the impulsive start and stop of T, ramped over dt
    p, g = c.problem, c.problem.goal
    bound = p.radius * np.sin(min(c.contact_bound, np.pi / 2))   # the bound's circle as seen from below
    s = np.linspace(0.0, 2.0 * np.pi, 241)
    ax_sphere.plot(bound * np.cos(s), bound * np.sin(s), color=MARK, linestyle="--", linewidth=0.9)
    bottom_view_axes(ax_sphere, 1.12 * max(reach, bound), p.radius, unit,
                     "contact paths on the sphere, seen from below")
    ax_sphere.legend(handles=[Line2D([], [], color=PLANNER[n], label=PLANNER_LABELS[n]) for n in SIDES]
                     + [Line2D([], [], color=MARK, linestyle="--", label=f"contact bound {c.contact_bound:.4g} rad"),
                        Line2D([], [], color=MARK, marker="+", linestyle="", label="south pole")],
                     loc="upper right", fontsize=7)
    plane_axes(ax_plane, g[:2], unit, "contact paths on the plane", handles=handles)
    _time_axes(ax_speed, c.gp.motion.t, "|omega| [rad/s]", "|omega| of both motions")
    tr = c.result.transcription
    fig.suptitle(f"k = {p.k:.4g}, target (u_a, v_a, psi) = ({g.u_a:g} {unit}, {g.v_a:g} {unit}, {g.psi:g} rad), "
                 f"n = {p.steps}; "
                 f"rest to rest over T = {c.horizon:g} s, cost {c.cost}, N = {tr.intervals}, contact bound "
                 f"{c.contact_bound:.4g} rad")
    return fig
