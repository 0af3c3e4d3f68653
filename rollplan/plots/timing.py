"""Figures of timed motions: rotor rates and torques in time with the motors' limits, and the phase plane (s, s').

The functions take :class:`rollplan.execution.actuation.Actuation` objects (and the maximum
velocity curve, :func:`rollplan.execution.timing.velocity_limit`) and compute nothing.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .colors import LAW, LIMIT, ROTOR, ROTOR_LABELS

__all__ = ["draw_rates_torques", "draw_phase_plane", "plot_timing"]


def _limit_lines(ax, value, scale, label):
    if value is not None:
        for sign in (1, -1):
            ax.axhline(sign * value * scale, color=LIMIT, linestyle="--", linewidth=0.8,
                       label=label if sign == 1 else None)


def draw_rates_torques(ax_rates, ax_torques, motion, legend=True):
    """Rotor rates [rad/s] and motor torques [N m] of a motion against time, with the robot's limits dashed."""
    lim, m = motion.limits, motion.series
    for i, color in enumerate(ROTOR):
        ax_rates.plot(m.time, m.rotor_rates[:, i], color=color, linewidth=1.0,
                      label=f"$\\dot\\varphi_{i + 1}$, {ROTOR_LABELS[i]}")
        ax_torques.plot(m.time, m.rotor_torques[:, i], color=color, linewidth=1.0,
                        label=f"$\\tau_{i + 1}$, {ROTOR_LABELS[i]}")
    _limit_lines(ax_rates, lim.max_rotor_rate, 1.0, "max_rotor_rate")
    _limit_lines(ax_torques, lim.max_rotor_torque, 1.0, "max_rotor_torque")
    shortest = ("" if motion.minimum_duration is None else " (the shortest)"
                if abs(motion.duration - motion.minimum_duration) <= 1e-9 * motion.duration
                else f" (shortest {motion.minimum_duration:.6g} s)")
    ax_rates.set_title(f"{motion.timing}: T = {motion.duration:.6g} s{shortest}", fontsize=10)
    ax_rates.set_ylabel("rotor rate [rad/s]")
    ax_torques.set_ylabel("motor torque [N m]")
    for ax in (ax_rates, ax_torques):
        ax.set_xlabel("time t [s]")
        ax.set_xlim(m.time[0], m.time[-1])
        ax.grid(True, alpha=0.3)
        if legend:
            ax.legend(loc="upper right", fontsize=7)


def draw_phase_plane(ax, motions, velocity_limit=None, joints=(), reference=None, radius=1.0, unit="R"):
    """The phase plane (s, s'): each motion's profile, the maximum velocity curve and the joints, in ``unit``
    (the arguments are in R: every arc length is drawn times ``radius``, the radius in ``unit``).

    Parameters
    ----------
    motions : sequence of Actuation
    velocity_limit : (s, s'_max), optional
        The maximum velocity curve [R, R/s] (inf where no limit binds).
    joints : sequence of float
        s at the joints between pieces (half-steps, rolls) (dotted verticals) [R].
    reference : (label, s, s'), optional
        Another profile to draw dashed (e.g. an independent computation) [R, R/s].
    radius, unit : float, str
        The radius in the unit of the figure (default: R itself).
    """
    tops = []
    if velocity_limit is not None:
        s, top = velocity_limit
        top = np.where(np.isfinite(top), top, np.nan) * radius
        ax.plot(np.asarray(s) * radius, top, color=LIMIT, linewidth=1.2, label="maximum velocity curve (limits)")
        if np.any(np.isfinite(top)):
            tops.append(np.nanpercentile(top, 50))
    for m in motions:
        ax.plot(m.s * radius, m.s_dot * radius, linewidth=1.1, label=m.timing, color=LAW.get(m.timing))
        tops.append(float(m.s_dot.max()) * radius)
    if reference is not None:
        label, s, sd = reference
        ax.plot(np.asarray(s) * radius, np.asarray(sd) * radius, color=LIMIT, linestyle=(0, (3, 3)), linewidth=0.9,
                label=label, zorder=5)  # on top
    for sj in joints:
        ax.axvline(sj * radius, color="0.7", linestyle=":", linewidth=0.8)
    ax.set_ylim(0, 1.15 * max(tops) if max(tops) > 0 else 1.0)
    ax.set_xlabel(f"contact arc length s [{unit}]   (dotted: joints between pieces)")
    ax.set_ylabel(f"s' [{unit}/s]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower center", fontsize=7, ncol=3, framealpha=0.95)


def plot_timing(motions, velocity_limit=None, title: str = "", reference=None) -> Figure:
    """Rates and torques in time (one column per motion, limits dashed) above the phase plane (s, s').

    Parameters
    ----------
    motions : Actuation or sequence of Actuation
        Timed motions of one path (e.g. the same plan under several laws).
    velocity_limit : (s, s'_max), optional
        The maximum velocity curve, :func:`rollplan.execution.timing.velocity_limit`.
    title : str
    reference : (label, s, s'), optional
        A profile drawn dashed in the phase plane.
    """
    if not isinstance(motions, (list, tuple)):
        motions = [motions]
    n = len(motions)
    fig = Figure(figsize=(max(7.0, 4.2 * n), 9.0), layout="constrained")
    grid = fig.add_gridspec(3, n)
    for col, m in enumerate(motions):
        ax_r = fig.add_subplot(grid[0, col])
        ax_t = fig.add_subplot(grid[1, col], sharex=ax_r)
        draw_rates_torques(ax_r, ax_t, m, legend=col == 0)
    path = motions[0].path   # None for the empty motion
    m = motions[0]
    r = m.robot   # a robot's lengths are in metres
    draw_phase_plane(fig.add_subplot(grid[2, :]), motions, velocity_limit, () if path is None else path.joints,
                     reference, r.radius, "m")
    fig.suptitle(title or (f"R = {r.radius:.6g} m, k = {r.k:.6g}, {m.limits.describe()}; "
                           f"{int(m.series.segment.max()) + 1} pieces"), fontsize=10)
    return fig
