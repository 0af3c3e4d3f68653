"""Figures of planner comparisons. Functions take results and return matplotlib Figures; they compute nothing."""

from __future__ import annotations

from matplotlib.figure import Figure

from .plots import plane_axes, sphere_axes

__all__ = ["plot_comparison", "plot_scaling"]

COLORS = {"geometric_phase": "tab:red", "collocation": "tab:blue"}
LABELS = {"geometric_phase": "geometric phase", "collocation": "collocation"}


def plot_comparison(c, unit: str = "R") -> Figure:
    """Both contact paths overlaid: on the sphere (body frame, 3-D) and on the plane."""
    fig = Figure(figsize=(11, 5))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    ax2 = fig.add_subplot(1, 2, 2)
    for s in (c.geometric_phase, c.collocation):
        label = f"{LABELS[s.name]}: length {s.path_length:.4g} {unit}"
        ax1.plot(s.contact[:, 0], s.contact[:, 1], s.contact[:, 2], color=COLORS[s.name], linewidth=1.5)
        ax2.plot(s.u_a, s.v_a, color=COLORS[s.name], linewidth=1.4, label=label)
    sphere_axes(ax1, c.radius, unit, "contact paths on the sphere")
    plane_axes(ax2, c.target, unit, "contact paths on the plane")
    fig.suptitle(f"k = {c.k:.4g}, target (u_a, v_a, psi) = ({c.target[0]:g}, {c.target[1]:g}, {c.target[2]:g}), "
                 f"n = {c.steps}, collocation {c.result.cost} N = {c.result.intervals} d = {c.result.degree}")
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
