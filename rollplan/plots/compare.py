"""Figures of planner comparisons. Functions take results and return matplotlib Figures; they compute nothing."""

from __future__ import annotations

from matplotlib.figure import Figure

from .common import plane_axes, sphere_axes

__all__ = ["plot_comparison", "plot_scaling"]

COLORS = {"geometric_phase": "tab:red", "collocation": "tab:blue"}
LABELS = {"geometric_phase": "geometric phase", "collocation": "collocation"}


def plot_comparison(c, unit: str = "R") -> Figure:
    """Both contact paths of a :class:`~rollplan.studies.comparison.Comparison` overlaid: on the sphere
    (body frame, 3-D) and on the plane."""
    fig = Figure(figsize=(11, 5))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    for name, traj, length in (("geometric_phase", c.plan_trajectory, c.plan_measures.path_length),
                               ("collocation", c.result.trajectory, c.result.measures.path_length)):
        label = f"{LABELS[name]}: length {length:.4g} {unit}"
        contact = traj.contact
        ax1.plot(contact[:, 0], contact[:, 1], contact[:, 2], color=COLORS[name], linewidth=1.5)
        ax2.plot(traj.u_a, traj.v_a, color=COLORS[name], linewidth=1.4, label=label)
    p, g, tr = c.problem, c.problem.goal, c.result.transcription
    sphere_axes(ax1, p.radius, unit, "contact paths on the sphere")
    plane_axes(ax2, g[:2], unit, "contact paths on the plane")
    fig.suptitle(f"k = {p.k:.4g}, target (u_a, v_a, psi) = ({g.u_a:g}, {g.v_a:g}, {g.psi:g}), "
                 f"n = {p.steps}, collocation {c.result.cost} N = {tr.intervals} d = {tr.degree}")
    fig.tight_layout()
    return fig


def plot_scaling(intervals, times, labels) -> Figure:
    """Solve time against N (log-log), one line per series; ``times`` is a list of arrays [s]."""
    fig = Figure(figsize=(6, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    for t, lab in zip(times, labels):
        ax.loglog(intervals, t, "o-", label=lab)
    ax.set_xticks(list(intervals))
    ax.set_xticklabels([str(n) for n in intervals])
    ax.minorticks_off()
    ax.set_xlabel("intervals N")
    ax.set_ylabel("IPOPT solve time [s]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
