"""Figures 6-12 of the paper's case study (Section III.C).

Functions take results of :mod:`rollplan.studies.paper` and return matplotlib
figures; they compute nothing. Conventions as in the paper: the first
half-step (first leaf of the figure eight) in red, the second in blue; the
contact path on the sphere (body frame, 3-D, and a close-up seen from below) and on the plane.
"""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .colors import COMPUTED, PRINTED
from .common import draw_bottom_view, draw_plane_path, draw_sphere_path, leaf_handles

__all__ = ["contact_figure", "shift_vs_k_figure", "shift_vs_a_figure", "case_study_figures"]


def contact_figure(plan, traj, title: str) -> Figure:
    """Contact path of a one-step plan: on the sphere in 3-D (left, as in the paper), a close-up of it seen
    from below (middle, equal aspect) and on the plane (right).

    Parameters
    ----------
    plan : Plan
        The plan (a, b, k, gamma, target).
    traj : Trajectory
        Its sampled trajectory (``plan.sample()``).
    title : str
        Figure title.
    """
    fig = Figure(figsize=(16, 5.4), layout="constrained")
    fig.get_layout_engine().set(wspace=0.12)
    grid = fig.add_gridspec(1, 3, width_ratios=[0.8, 1, 1])
    ax1 = fig.add_subplot(grid[0], projection="3d")
    draw_sphere_path(ax1, traj, plan.radius)
    ax1.view_init(elev=-25, azim=-50)  # from below: the paths lie around the south pole
    ax1.set_title("on the sphere in 3-D, from below", pad=28)
    ax1.legend(handles=leaf_handles(), loc="lower left", fontsize=8)
    draw_bottom_view(fig.add_subplot(grid[1]), traj, plan.radius, "R")
    draw_plane_path(fig.add_subplot(grid[2]), traj, plan.goal[:2], "R")
    fig.suptitle(title)
    return fig


def shift_vs_k_figure(sweep, sweep_printed=None, paper_zeros=()) -> Figure:
    """Fig. 9: normalized shift h/R versus k at fixed a, with its zeros.

    Parameters
    ----------
    sweep : Sweep
        ``variable == "k"``, the radius the paper's numbers correspond to.
    sweep_printed : Sweep, optional
        The same at the radius printed in the paper (dashed, for comparison).
    paper_zeros : sequence of float
        The zeros printed in the paper (marked with crosses).
    """
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(sweep.x, sweep.h, color="k", linewidth=1.5, label=f"a = {sweep.fixed:.6f} R")
    if sweep_printed is not None:
        ax.plot(sweep_printed.x, sweep_printed.h, color="0.6", linestyle="--", linewidth=1.0,
                label=f"a = {sweep_printed.fixed:.6f} R (as printed)")
    ax.plot(sweep.roots, np.zeros(len(sweep.roots)), "o", color=COMPUTED, markersize=6,
            label="zeros (root finding)")
    for i, r in enumerate(sweep.roots, 1):
        ax.annotate(f"$k_{i}$={r:.5g}", (r, 0), textcoords="offset points", xytext=(0, -16), ha="center", fontsize=8)
    if len(paper_zeros):
        ax.plot(paper_zeros, np.zeros(len(paper_zeros)), "x", color=PRINTED, markersize=9, mew=1.5,
                label="zeros printed in the paper")
    ax.set_xlabel("inertia ratio k [-]")
    ax.set_ylabel("normalized shift h/R [-]")
    ax.set_xlim(sweep.x[0], sweep.x[-1])
    ax.set_ylim(bottom=-0.3)
    ax.axhline(0.0, color="0.3", linewidth=0.6)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title("Fig. 9: non-holonomic shift versus k (n = 1, a = b)")
    fig.tight_layout()
    return fig


def shift_vs_a_figure(sweep, level: float = 1.0, paper_roots=(), labelled: int = 4) -> Figure:
    """Fig. 10: normalized shift h/R versus a/R at fixed k, with the roots of h/R = level.

    Parameters
    ----------
    sweep : Sweep
        ``variable == "a"``.
    level : float
        The desired shift (horizontal line).
    paper_roots : sequence of float
        The roots printed in the paper (marked with crosses).
    labelled : int
        How many roots to label ``a_i``.
    """
    fig = Figure(figsize=(8, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    ax.plot(sweep.x, sweep.h, color="k", linewidth=1.2, label=f"k = {sweep.fixed:g}")
    ax.axhline(level, color="0.5", linestyle=":", linewidth=1.0, label=f"h/R = {level:g}")
    ax.plot(sweep.roots, np.full(len(sweep.roots), level), "o", color=COMPUTED, markersize=5,
            label="roots (root finding)")
    for i, r in enumerate(sweep.roots[:labelled], 1):
        ax.annotate(f"$a_{i}$={r:.6f}", (r, level), textcoords="offset points", xytext=(-4, 12 + 10 * (i % 2)),
                    ha="right", fontsize=8)
    if len(paper_roots):
        ax.plot(paper_roots, np.full(len(paper_roots), level), "x", color=PRINTED, markersize=9, mew=1.5,
                label="roots printed in the paper")
    ax.set_xlabel("circle radius a/R [-]")
    ax.set_ylabel("normalized shift h/R [-]")
    ax.set_xlim(0, sweep.x[-1])
    ax.set_ylim(0, min(float(np.max(sweep.h)) * 1.05, 4.0))
    ax.grid(True, alpha=0.3)
    ax.legend(loc="upper left", fontsize=8)
    ax.set_title(f"Fig. 10: non-holonomic shift versus a/R for k = {sweep.fixed:g} (n = 1, a = b)")
    fig.tight_layout()
    return fig


def case_study_figures(result, paper: dict) -> list:
    """Figs 6-12 of the case study, in order, from a :class:`~rollplan.studies.paper.CaseStudyResult`.

    ``paper`` maps the keys of :data:`rollplan.studies.paper.values.PAPER` to the printed values.
    """
    figs = []
    a_txt = f"a = {result.a0:.6f} R (paper prints a = {paper['a_k0']} R)"
    for num, key in ((6, "k0"), (7, "k2.5"), (8, "k5")):
        p, traj = result.plans[key]
        figs.append(contact_figure(p, traj, f"Fig. {num}: k = {p.k:g}, {a_txt}, gamma = {p.gamma:.6f} rad, "
                                            f"h = {p.h:.6f} R"))
    figs.append(shift_vs_k_figure(result.k_sweep, result.k_sweep_printed,
                                  [float(paper[f"k{i}"]) for i in range(1, 6)]))
    figs.append(shift_vs_a_figure(result.a_sweep, 1.0, [float(paper[f"a{i}"]) for i in range(1, 5)]))
    for num, key in ((11, "a1"), (12, "a2")):
        p, traj = result.plans[key]
        figs.append(contact_figure(p, traj, f"Fig. {num}: k = {p.k:g}, {key} = {p.a:.6f} R, "
                                            f"gamma = {p.gamma:.6f} rad, h = {p.h:.6f} R"))
    return figs
