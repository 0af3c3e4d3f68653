"""Figures of a timed motion: omega, rotor rates and rotor torques in time. They compute nothing."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .common import draw_plane_path

__all__ = ["plot_motion", "draw_time_series"]


def _rests(ax, motion):
    for t in motion.time[motion.rest_indices]:
        ax.axvline(t, color="0.8", linewidth=0.7, zorder=0)


def draw_time_series(ax, motion, values, labels, ylabel, title, scale=1.0):
    """Columns of ``values`` against time; thin grey lines mark the rest points (stops between pieces)."""
    _rests(ax, motion)
    for col, label in zip(np.asarray(values).T, labels):
        ax.plot(motion.time, col * scale, linewidth=1.2, label=label)
    ax.set_xlabel("time t [s]")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.set_xlim(motion.time[0], motion.time[-1])
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper right", fontsize=8)


def plot_motion(motion, plan=None, traj=None, unit="m") -> Figure:
    """Omega, rotor rates and torques of a :class:`rollplan.execution.actuation.Motion` in time.

    With ``plan`` and ``traj`` (a :class:`rollplan.result.Trajectory`) a fourth panel
    shows the contact path on the plane.
    """
    fig = Figure(figsize=(12, 8))
    axes = fig.subplots(2, 2)
    draw_time_series(axes[0, 0], motion, motion.omega, ["$\\omega_x$", "$\\omega_y$", "$\\omega_z$"],
                     "angular velocity [rad/s]", "sphere angular velocity (plane frame)")
    draw_time_series(axes[0, 1], motion, motion.rotor_rates, ["$\\dot\\varphi_1$", "$\\dot\\varphi_2$"],
                     "rotor rate [rad/s]", "rotor rates, eq. (11)")
    draw_time_series(axes[1, 0], motion, motion.rotor_torques, ["$\\tau_1$", "$\\tau_2$"],
                     "motor torque [mN m]", "rotor torques", scale=1e3)
    if plan is not None and traj is not None:
        draw_plane_path(axes[1, 1], traj, plan.goal[:2], unit)
    else:
        draw_time_series(axes[1, 1], motion, motion.rotor_angles / (2 * np.pi), ["$\\varphi_1$", "$\\varphi_2$"],
                         "rotor angle [turns]", "rotor angles")
    r = motion.robot
    fig.suptitle(f"T = {motion.duration:g} s, {int(motion.segment.max()) + 1} pieces (timing {motion.timing}); "
                 f"R = {r.radius:g} m, k = {r.k:.4g}, $J_r$ = {r.rotor_inertia_axial:.3g} kg m$^2$")
    fig.tight_layout()
    return fig
