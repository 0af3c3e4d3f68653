"""Shared pieces of the figures: the contact path on the sphere (a close-up seen from below, or 3-D), on
the plane, psi along the path, and the legends of the colours (:mod:`.colors`).

Functions take results and draw; they compute nothing.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from .colors import LEAF, LEAF_LABELS, MARK

__all__ = ["LEAF_COLORS", "segments", "by_leaf", "leaf_handles", "sphere_axes", "plane_axes", "draw_sphere_path",
           "draw_bottom_view", "bottom_view_axes", "draw_plane_path", "draw_psi", "SPIKE_LABEL", "clip_spikes"]

#: Label (hidden from legends) of the marks of values drawn outside a robust range (:func:`clip_spikes`).
SPIKE_LABEL = "_clipped"

#: Colours of the first and second half-step (see :mod:`.colors`).
LEAF_COLORS = LEAF


def segments(traj):
    """``(start, stop, segment)`` of each run of samples on one segment of a :class:`~rollplan.result.Trajectory`.

    Each run includes the joint sample before it, so consecutive runs connect.
    """
    seg = traj.segment
    change = np.nonzero(np.diff(seg[1:]) != 0)[0] + 1
    bounds = np.concatenate([[0], change, [seg.size - 1]])
    return [(int(s), int(e) + 1, int(seg[e])) for s, e in zip(bounds[:-1], bounds[1:])]


def by_leaf(traj, *columns):
    """``(colour, columns)`` per half-step parity: the columns' runs of that leaf joined by NaN breaks, so a
    path of many steps is drawn by one line per colour."""
    runs = segments(traj)
    for parity, color in enumerate(LEAF):
        picked = [(s, e) for s, e, leaf in runs if leaf % 2 == parity]
        if not picked:
            continue
        out = []
        for col in columns:
            col = np.asarray(col, float)
            out.append(np.concatenate([np.append(col[s:e + 1], np.nan) for s, e in picked]))
        yield color, out


def leaf_handles():
    """Legend handles of the two half-steps (leaves) of a figure eight."""
    return [Line2D([], [], color=c, linewidth=1.6, label=lab) for c, lab in zip(LEAF, LEAF_LABELS)]


def _mark_handles(target=True):
    out = [Line2D([], [], color=MARK, marker="o", markersize=4, linestyle="", label="start")]
    if target:
        out.append(Line2D([], [], color=MARK, marker="*", markersize=10, linestyle="", label="target"))
    return out


def sphere_axes(ax, radius=1.0, unit="R", title="contact path on the sphere (body frame)"):
    """A wire-frame sphere of the given radius on 3-D axes: orthographic, equal aspect, labelled."""
    u, v = np.mgrid[0:2 * np.pi:37j, 0:np.pi:19j]
    ax.plot_wireframe(radius * np.cos(u) * np.sin(v), radius * np.sin(u) * np.sin(v), radius * np.cos(v),
                      color="0.88", linewidth=0.4)
    ax.set_proj_type("ortho")
    for setter, ticks in ((ax.set_xlim, ax.set_xticks), (ax.set_ylim, ax.set_yticks), (ax.set_zlim, ax.set_zticks)):
        setter(-radius, radius)
        ticks([-radius, 0.0, radius])
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.pane.set_alpha(0.0)
    ax.set_box_aspect((1, 1, 1))
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    ax.set_zlabel(f"z [{unit}]")
    ax.set_title(title)


def plane_axes(ax, target=None, unit="R", title="contact path on the plane", handles=(), start=(0.0, 0.0)):
    """Start and target marks, labels, equal aspect, grid and a legend (``handles`` first) of a plane view."""
    ax.plot([start[0]], [start[1]], "o", color=MARK, markersize=4)
    if target is not None:
        ax.plot([target[0]], [target[1]], "*", color=MARK, markersize=10)
    ax.set_xlabel(f"u_a [{unit}]")
    ax.set_ylabel(f"v_a [{unit}]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(handles=list(handles) + _mark_handles(target is not None), loc="best", fontsize=8)
    ax.set_title(title)


def draw_sphere_path(ax, traj, radius=1.0, unit="R"):
    """Contact path on the sphere (body frame), 3-D axes, in the leaf colours."""
    c = traj.contact
    for color, (x, y, z) in by_leaf(traj, c[:, 0], c[:, 1], c[:, 2]):
        ax.plot(x, y, z, color=color, linewidth=1.6)
    sphere_axes(ax, radius, unit)


def _nice_step(span_deg: float) -> float:
    for step in (0.5, 1, 2, 5, 10, 15, 30):
        if span_deg / step <= 5:
            return step
    return 30.0


def bottom_view_axes(ax, extent, radius=1.0, unit="R", title="contact path on the sphere, seen from below"):
    """A close-up of the sphere around its south pole seen from below (orthographic, equal aspect).

    The axes show the body-frame x and y of points on the lower hemisphere as a
    camera under the floor sees them (x grows to the left). Grey circles are
    the points at a constant angle from the south pole (labelled in degrees),
    grey rays the meridians every 30 degrees; ``extent`` is the half-width of
    the view [length unit].
    """
    extent = float(min(max(extent, 1e-3 * radius), radius))
    top = float(np.degrees(np.arcsin(extent / radius)))
    step = _nice_step(top)
    s = np.linspace(0.0, 2.0 * np.pi, 241)
    for deg in np.arange(step, min(top + step, 90.0 + 1e-9), step):
        r = radius * np.sin(np.radians(deg))
        ax.plot(r * np.cos(s), r * np.sin(s), color="0.8", linewidth=0.6, zorder=0)
        ax.annotate(f"{deg:g}°", (r * np.cos(np.radians(-60)), r * np.sin(np.radians(-60))), color="0.45",
                    fontsize=7, ha="center", va="center", annotation_clip=True,
                    bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none", "alpha": 0.8})
    for lon in np.radians(np.arange(0, 360, 30)):
        ax.plot([0, radius * np.cos(lon)], [0, radius * np.sin(lon)], color="0.88", linewidth=0.5, zorder=0)
    ax.plot([0], [0], "+", color=MARK, markersize=9, zorder=3)
    ax.set_xlim(extent, -extent)  # seen from below: x to the left
    ax.set_ylim(-extent, extent)
    ax.set_aspect("equal")
    ax.set_xlabel(f"x [{unit}] (body frame; seen from below, x grows to the left)")
    ax.set_ylabel(f"y [{unit}]")
    ax.set_title(title)


def draw_bottom_view(ax, traj, radius=1.0, unit="R", color=None, label=None, extent=None, axes=True):
    """The contact path on the sphere in a close-up seen from below (:func:`bottom_view_axes`).

    Drawn in the leaf colours, or in ``color`` (then labelled ``label``). ``extent``
    defaults to the path's reach plus a margin; ``axes=False`` draws the path only
    (to overlay several paths on one view).
    """
    c = traj.contact
    if color is None:
        for col, (x, y) in by_leaf(traj, c[:, 0], c[:, 1]):
            ax.plot(x, y, color=col, linewidth=1.4)
    else:
        ax.plot(c[:, 0], c[:, 1], color=color, linewidth=1.4, label=label)
    if axes:
        reach = float(np.abs(c[:, :2]).max()) if c.size else radius
        bottom_view_axes(ax, extent if extent is not None else 1.12 * reach, radius, unit)
        handles = leaf_handles() if color is None else []
        handles.append(Line2D([], [], color=MARK, marker="+", markersize=9, linestyle="", label="south pole"))
        ax.legend(handles=handles + ax.get_legend_handles_labels()[0], loc="upper right", fontsize=8)


def draw_plane_path(ax, traj, target=None, unit="R"):
    """Contact path on the plane, in the leaf colours, with a legend."""
    for color, (u, v) in by_leaf(traj, traj.u_a, traj.v_a):
        ax.plot(u, v, color=color, linewidth=1.4)
    plane_axes(ax, target, unit, handles=leaf_handles(), start=(traj.u_a[0], traj.v_a[0]))


def draw_psi(ax, traj, target_psi=None, target_label="target psi"):
    """psi along the path, in the leaf colours; the abscissa is the number of steps traced (theta / 2 pi)
    for a geometric-phase plan, else time [s]."""
    x = traj.s / (2.0 * np.pi) if traj.parameter == "theta" else traj.s
    for color, (xs, psi) in by_leaf(traj, x, traj.psi):
        ax.plot(xs, psi, color=color, linewidth=1.4)
    handles = leaf_handles()
    if target_psi is not None:
        ax.axhline(target_psi, color=MARK, linestyle=":", linewidth=1.0)
        handles.append(Line2D([], [], color=MARK, linestyle=":", label=target_label))
    ax.set_xlabel("steps traced, theta / 2 pi" if traj.parameter == "theta" else "time t [s]")
    ax.set_ylabel("contact angle psi [rad]")
    ax.set_xlim(x[0], x[-1])
    ax.grid(True, alpha=0.3)
    ax.legend(handles=handles, loc="best", fontsize=8)
    ax.set_title("psi along the path")


def clip_spikes(ax, t, values, colors, quantile: float = 0.05, margin: float = 0.5, ratio: float = 1.5) -> bool:
    """Limit the y-range of ``ax`` to a robust range of ``values`` (columns against ``t``, drawn in ``colors``)
    when a few samples reach far beyond it (e.g. the impulsive start and stop of a rest-to-rest optimum): the
    range between the ``quantile`` and ``1 - quantile`` quantiles widened by ``margin`` times its width on
    each side, used when the data reach ``ratio`` times farther; every sample outside is marked by a triangle
    on the edge and the extremes are written in the panel. Returns whether the range was limited."""
    v = np.asarray(values, float)
    lo, hi = np.quantile(v, [quantile, 1.0 - quantile])
    width = max(hi - lo, 1e-300)
    low, high = lo - margin * width, hi + margin * width
    centre = 0.5 * (low + high)
    if max(v.max() - centre, centre - v.min()) <= ratio * 0.5 * (high - low):
        return False
    ax.set_ylim(low, high)
    t = np.asarray(t, float)
    for col, color in zip(v.T, colors):
        for outside, edge, marker in ((col > high, high, "^"), (col < low, low, "v")):
            if outside.any():
                ax.plot(t[outside], np.full(outside.sum(), edge), marker, color=color, markersize=5, linestyle="",
                        clip_on=False, zorder=5, label=SPIKE_LABEL)
    ax.text(0.01, 0.02, f"range clipped (triangles): values from {v.min():.4g} to {v.max():.4g}",
            transform=ax.transAxes, fontsize=7, va="bottom",
            bbox={"boxstyle": "round,pad=0.2", "facecolor": "white", "edgecolor": "0.7", "alpha": 0.9})
    return True
