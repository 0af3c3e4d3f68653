"""Figure of a reachability atlas (:mod:`rollplan.studies.atlas`). It computes nothing."""

from __future__ import annotations

import numpy as np

from ..core.plane import TWO_PI, wrap
from .colors import MARK

__all__ = ["plot_atlas"]


#: Colour of the region reached between the grid points in the (turn, shift) panel.
_REACHED = "0.82"
#: Largest turn [rad] across one grid cell that the grid resolves; the images of wider cells are drawn in
#: :data:`_COARSE`.
_CELL_TURN = 0.5
_COARSE = "0.93"

#: Contour lines and their labels are drawn only where a and b are below this fraction of the largest radius: near
#: a, b = A_MAX the contours crowd and their labels would cover one another.
_LABEL_REGION = 0.82


def _sparse_labels(ax, cs, a_max):
    """Label each contour line of ``cs`` once, in the middle of its longest run outside the crowded corner."""
    limit = _LABEL_REGION * a_max
    positions = []
    for segs in cs.allsegs:
        best = None
        for seg in segs:
            inside = np.max(seg, axis=1) < limit
            # longest run of consecutive points inside the region
            edges = np.flatnonzero(np.diff(np.concatenate([[0], inside.astype(int), [0]])))
            for start, stop in zip(edges[::2], edges[1::2]):
                if best is None or stop - start > best[1] - best[0]:
                    best = (start, stop, seg)
        if best is not None and best[1] - best[0] >= 5:
            positions.append(tuple(best[2][(best[0] + best[1]) // 2]))
    if positions:
        ax.clabel(cs, fontsize=7, fmt="%.3g", inline=True, inline_spacing=2, manual=positions)


def _cell_images(turn, shift, resolved: bool) -> np.ndarray:
    """The quadrilaterals (turn, shift) of the corners of the grid cells whose turn spans at most
    :data:`_CELL_TURN` (``resolved``) or more (turn continuous within the cell, placed with its first corner
    wrapped to (-pi, pi], and copied 2 pi apart wherever it crosses a side): the region the grid reaches,
    without the gaps between scattered grid points."""
    corners = np.stack([turn[:-1, :-1], turn[:-1, 1:], turn[1:, 1:], turn[1:, :-1]], axis=-1).reshape(-1, 4)
    heights = np.stack([shift[:-1, :-1], shift[:-1, 1:], shift[1:, 1:], shift[1:, :-1]], axis=-1).reshape(-1, 4)
    keep = (np.ptp(corners, axis=1) <= _CELL_TURN) == resolved
    corners, heights = corners[keep], heights[keep]
    corners = corners + (wrap(corners[:, 0]) - corners[:, 0])[:, None]
    if not corners.size:
        return np.zeros((0, 4, 2))
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    out = []
    for m in range(int(np.floor((-np.pi - hi.max()) / TWO_PI)), int(np.ceil((np.pi - lo.min()) / TWO_PI)) + 1):
        seen = (hi + m * TWO_PI > -np.pi) & (lo + m * TWO_PI < np.pi)
        out.append(np.stack([corners[seen] + m * TWO_PI, heights[seen]], axis=-1))
    return np.concatenate(out)


def plot_atlas(at):
    """Figure of an :class:`~rollplan.studies.atlas.Atlas` (computes nothing).

    h and eta over (a, b) with labelled contours, the fold ``det = 0`` (black) and
    the diagonal ``a = b`` (where eta = 0), and the (turn, shift) pairs n steps
    reach (turn wrapped to (-pi, pi]): the image of every grid cell, so that the spacing of the grid points
    leaves no holes.
    """
    from matplotlib.collections import PolyCollection
    from matplotlib.colors import LogNorm, SymLogNorm
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fig = Figure(figsize=(17, 5.6), layout="constrained")
    axes = fig.subplots(1, 3)
    a_max = float(at.a[-1])
    big = float(np.abs(at.eta).max()) or 1.0
    eta_levels = np.unique(np.concatenate([-np.geomspace(0.05, big, 12)[::-1], [0.0], np.geomspace(0.05, big, 12)]))
    h_top = float(at.h.max())
    h_lines = np.arange(0.25, h_top, 0.25 if h_top < 4 else 0.5)
    eta_lines = np.array([v for v in (-20, -10, -5, -2, -1, -0.5, -0.2, 0.2, 0.5, 1, 2, 5, 10, 20) if abs(v) < big])
    fold = np.nanmin(at.det) < 0 < np.nanmax(at.det)
    for ax, z, title, cmap, levels, norm, lines, label in (
            (axes[0], at.h, "shift of one step h(a, b) [R]", "viridis", 24, None, h_lines, "h [R]"),
            (axes[1], at.eta, "holonomy of one step eta(a, b) [rad]", "coolwarm", eta_levels,
             SymLogNorm(0.05, vmin=-big, vmax=big), eta_lines, "eta [rad] (symmetric log scale)")):
        cf = ax.contourf(at.b, at.a, z, cmap=cmap, levels=levels, norm=norm)
        if lines.size:   # not in the crowded band near a or b = A_MAX, where the colours alone show z
            crowded = np.maximum.outer(at.a, at.b) > _LABEL_REGION * a_max
            cs = ax.contour(at.b, at.a, np.where(crowded, np.nan, z), colors="w", linewidths=0.6, levels=lines)
            _sparse_labels(ax, cs, a_max)
        if fold:
            ax.contour(at.b, at.a, at.det, levels=[0.0], colors=MARK, linewidths=1.8)
        ax.plot([at.a[0], a_max], [at.a[0], a_max], ls=":", color="0.3", lw=1.0)
        handles = [Line2D([], [], color="w", lw=0.6, label="contours (where a, b < "
                          f"{_LABEL_REGION * a_max:.2g} R)"),
                   Line2D([], [], color="0.3", ls=":", lw=1.0, label="a = b (eta = 0)")]
        if fold:
            handles.insert(0, Line2D([], [], color=MARK, lw=1.8, label="fold: det d(h, eta)/d(a, b) = 0"))
        leg = ax.legend(handles=handles, loc="lower left", fontsize=7.5, framealpha=0.85)
        leg.get_frame().set_facecolor("0.75")
        ax.set_xlabel("b [R]")
        ax.set_ylabel("a [R]")
        ax.set_title(title)
        ax.set_aspect("equal")
        bar = fig.colorbar(cf, ax=ax, shrink=0.85, label=label)
        if norm is not None:
            bar.set_ticks([v for v in (-20, -5, -1, -0.2, 0, 0.2, 1, 5, 20) if abs(v) <= big])
    ax = axes[2]
    for resolved, color in ((False, _COARSE), (True, _REACHED)):
        ax.add_collection(PolyCollection(_cell_images(at.turn_total, at.shift_total, resolved), facecolors=color,
                                         edgecolors=color, linewidths=0.3, zorder=1 + resolved,
                                         label="_cells" if resolved else "_coarse cells"))
    turn = wrap(at.turn_total.ravel())
    shift = at.shift_total.ravel()
    hist, xe, ye = np.histogram2d(turn, shift, bins=(72, 60), range=((-np.pi, np.pi), (0.0, float(shift.max()))))
    hist = np.where(hist > 0, hist, np.nan)
    mesh = ax.pcolormesh(xe, ye, hist.T, cmap="cividis", norm=LogNorm(), zorder=3)
    fig.colorbar(mesh, ax=ax, shrink=0.85, label="grid points (a, b) landing in the cell")
    ax.set_xlim(-np.pi, np.pi)
    ax.set_ylim(0.0, float(shift.max()))
    ax.legend(handles=[Patch(facecolor=_REACHED, edgecolor="0.5", label="reached between the grid points\n"
                             "(the images of the grid cells)"),
                       Patch(facecolor=_COARSE, edgecolor="0.5", label="between grid points of cells the grid\n"
                             f"does not resolve (turn > {_CELL_TURN:g} rad across)")],
              loc="upper right", fontsize=7, framealpha=0.9)
    ax.set_xlabel(f"turn psi reached by {at.steps} step(s), n eta wrapped to (-pi, pi] [rad]")
    ax.set_ylabel(f"shift reached by {at.steps} step(s) [R]")
    ax.set_title("reachable (turn, shift) pairs (white: not reached)")
    family = "" if at.curve == "circles" else f" of {at.curve} leaves"
    fig.suptitle(f"Reachability atlas of the figure eight{family}, k = {at.k:.6g}, n = {at.steps}, "
                 f"{at.a.size} x {at.b.size} grid")
    return fig
