"""Figures of planner comparisons. Functions take results and return matplotlib Figures; they compute nothing."""

from __future__ import annotations

from matplotlib.figure import Figure

from .common import plane_axes, sphere_axes

__all__ = ["plot_comparison"]

COLORS = {"geometric_phase": "tab:red", "collocation": "tab:blue"}
LABELS = {"geometric_phase": "geometric phase", "collocation": "collocation"}


def plot_comparison(c, unit: str = "R") -> Figure:
    """A :class:`~rollplan.studies.comparison.Comparison`: both contact paths (sphere, body frame, and plane)
    and, in time, |omega|, the rotor rates and the motor torques of both motions."""
    fig = Figure(figsize=(13, 8))
    ax1 = fig.add_subplot(2, 3, 1, projection="3d")
    ax2 = fig.add_subplot(2, 3, 2)
    series = [fig.add_subplot(2, 3, i) for i in (3, 4, 5, 6)]
    for name, side in (("geometric_phase", c.gp), ("collocation", c.collocation)):
        m, color = side.motion, COLORS[name]
        traj = m.trajectory()
        label = f"{LABELS[name]}: length {side.costs['path_length']:.4g} {unit}, {c.cost} {side.costs[c.cost]:.4g}"
        contact = traj.contact
        ax1.plot(contact[:, 0], contact[:, 1], contact[:, 2], color=color, linewidth=1.5)
        ax2.plot(traj.u_a, traj.v_a, color=color, linewidth=1.4, label=label)
        series[0].plot(m.t, (m.omega ** 2).sum(axis=1) ** 0.5, color=color, label=LABELS[name])
        for i, style in ((0, "-"), (1, "--")):
            series[1].plot(m.t, m.rotor_rates[:, i], style, color=color, linewidth=1.0)
            series[2].plot(m.t, m.rotor_torques[:, i], style, color=color, linewidth=1.0)
        series[3].plot(m.t, (m.omega ** 2).sum(axis=1), color=color)
    p, g = c.problem, c.problem.goal
    sphere_axes(ax1, p.radius, unit, "contact paths on the sphere")
    plane_axes(ax2, g[:2], unit, "contact paths on the plane")
    for ax, ylabel in zip(series, ("|omega| [rad/s]", "rotor rates [rad/s] (1 solid, 2 dashed)",
                                   "motor torques [N m] (1 solid, 2 dashed)", "|omega|^2 [rad^2/s^2]")):
        ax.set_xlabel("t [s]")
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
    series[0].legend(fontsize=8)
    tr = c.result.transcription
    fig.suptitle(f"k = {p.k:.4g}, target (u_a, v_a, psi) = ({g.u_a:g}, {g.v_a:g}, {g.psi:g}), n = {p.steps}, "
                 f"rest to rest over T = {c.horizon:g} s, cost {c.cost}, N = {tr.intervals}, "
                 f"contact bound {c.contact_bound:.4g} rad")
    fig.tight_layout()
    return fig
