"""Figure of a reachability atlas (:mod:`rollplan.studies.atlas`). It computes nothing."""

from __future__ import annotations

import numpy as np

from ..core.plane import wrap

__all__ = ["plot_atlas"]


def plot_atlas(at):
    """Figure of an :class:`~rollplan.studies.atlas.Atlas` (computes nothing).

    h and eta over (a, b) with contours and the fold ``det = 0`` (black), and
    the (turn, shift) pairs n steps reach (turn wrapped to (-pi, pi]).
    """
    from matplotlib.colors import LogNorm, SymLogNorm
    from matplotlib.figure import Figure

    fig = Figure(figsize=(16, 5.2), layout="constrained")
    axes = fig.subplots(1, 3)
    big = float(np.abs(at.eta).max()) or 1.0
    eta_levels = np.unique(np.concatenate([-np.geomspace(0.05, big, 12)[::-1], [0.0], np.geomspace(0.05, big, 12)]))
    for ax, z, title, cmap, levels, norm in (
            (axes[0], at.h, "shift of one step h(a, b) [R]", "viridis", 24, None),
            (axes[1], at.eta, "holonomy of one step eta(a, b) [rad]", "coolwarm", eta_levels,
             SymLogNorm(0.05, vmin=-big, vmax=big))):
        cf = ax.contourf(at.b, at.a, z, cmap=cmap, levels=levels, norm=norm)
        cs = ax.contour(at.b, at.a, z, colors="w", linewidths=0.5, levels=levels)
        ax.clabel(cs, cs.levels[::3], fontsize=7, fmt="%.2g")
        if np.nanmin(at.det) < 0 < np.nanmax(at.det):
            ax.contour(at.b, at.a, at.det, levels=[0.0], colors="k", linewidths=1.8)
        ax.plot([at.a[0], at.a[-1]], [at.a[0], at.a[-1]], ls=":", color="0.3", lw=0.8)
        ax.set_xlabel("b [R]")
        ax.set_ylabel("a [R]")
        ax.set_title(title)
        ax.set_aspect("equal")
        fig.colorbar(cf, ax=ax, shrink=0.85)
    ax = axes[2]
    turn = wrap(at.turn_total.ravel())
    shift = at.shift_total.ravel()
    hist, xe, ye = np.histogram2d(turn, shift, bins=(72, 60), range=((-np.pi, np.pi), (0.0, float(shift.max()))))
    hist = np.where(hist > 0, hist, np.nan)
    mesh = ax.pcolormesh(xe, ye, hist.T, cmap="cividis", norm=LogNorm())
    fig.colorbar(mesh, ax=ax, shrink=0.85, label="grid points (a, b) landing in the cell")
    ax.set_xlabel(f"turn psi reached by {at.steps} step(s), n eta wrapped to (-pi, pi] [rad]")
    ax.set_ylabel(f"shift reached by {at.steps} step(s) [R]")
    ax.set_title("reachable (turn, shift) pairs (white: none on the grid)")
    fig.suptitle(f"Reachability atlas of the figure eight, k = {at.k:g}, n = {at.steps}")
    return fig
