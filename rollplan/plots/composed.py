"""Figure of a composed plan or a route: the contact path by piece on the plane and on the sphere (a close-up
seen from below), and the contact coordinates along the path. It computes nothing."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .colors import LEAF, LEAF_LABELS, MARK, PIECE, PIECE_LABELS, REST, TURN, TURN_LABELS
from .common import bottom_view_axes, plane_axes, segments

__all__ = ["piece_runs", "draw_waypoints", "draw_composed_plane", "plot_composed"]


def piece_runs(plan, traj):
    """``(start, stop, colour, label)`` of each piece of ``traj`` (:func:`.common.segments`), in the colours of
    :mod:`.colors`: rolls by kind, the leaves of figure eights alternating 1st/2nd half-step, the circles of a
    turn in place alternating too."""
    out = []
    count = {"leaf": 0, "turn": 0}
    for s, e, j in segments(traj):
        kind = plan.pieces[j].kind
        if kind in ("leaf", "turn"):
            colors, labels = (LEAF, LEAF_LABELS) if kind == "leaf" else (TURN, TURN_LABELS)
            i = count[kind] % 2
            count[kind] += 1
            out.append((s, e, colors[i], labels[i]))
        else:
            out.append((s, e, PIECE.get(kind, MARK), PIECE_LABELS.get(kind, kind)))
    return out


def _handles(runs):
    seen, out = set(), []
    for _, _, color, label in runs:
        if label not in seen:
            seen.add(label)
            out.append(Line2D([], [], color=color, linewidth=1.6, label=label))
    return out


def draw_waypoints(ax, waypoints) -> list:
    """Each waypoint of a route marked (white circle) and labelled with its number (from 1) and label; the
    labels of waypoints at one point are joined. Returns the legend handle."""
    places: dict = {}
    for i, w in enumerate(waypoints, 1):
        key = (round(float(w.state[0]), 9), round(float(w.state[1]), 9))
        places.setdefault(key, []).append(f"{i} {w.label}".strip())
    for (u, v), names in places.items():
        ax.plot([u], [v], "o", markerfacecolor="white", markeredgecolor=MARK, markersize=7, zorder=4,
                label="_waypoint")
        ax.annotate(", ".join(names), (u, v), xytext=(6, 6), textcoords="offset points", fontsize=8, zorder=5,
                    bbox={"boxstyle": "round,pad=0.2", "facecolor": "white", "edgecolor": "none", "alpha": 0.8})
    return [Line2D([], [], color=MARK, marker="o", markerfacecolor="white", linestyle="",
                   label="waypoint (number, label)")]


def draw_composed_plane(ax, plan, traj, unit="R", title=None) -> None:
    """The contact path of a composed plan or route on the plane, by piece, with start, goal, the waypoints of
    a route (:func:`draw_waypoints`) and a legend."""
    runs = piece_runs(plan, traj)
    for s, e, color, _ in runs:
        ax.plot(traj.u_a[s:e + 1], traj.v_a[s:e + 1], color=color, linewidth=1.4)
    marks = draw_waypoints(ax, plan.waypoints) if getattr(plan, "waypoints", None) else []
    plane_axes(ax, (plan.goal.u_a, plan.goal.v_a), unit,
               title or f"contact path on the plane ({plan.path_length:.6g} {unit})", handles=_handles(runs) + marks,
               start=(traj.u_a[0], traj.v_a[0]))


def plot_composed(plan, traj, unit="R") -> Figure:
    """Three panels: the plane path, the sphere path seen from below and ``psi, u_o, v_o`` along the path.

    ``plan`` is a :class:`~rollplan.planners.geometric.ComposedPlan` or a
    :class:`~rollplan.planners.geometric.Route` (its ``pieces`` name the kind of each
    segment of ``traj``, a :class:`~rollplan.result.Trajectory` of it).
    """
    fig = Figure(figsize=(16, 5.4), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(1, 3)
    draw_composed_plane(ax1, plan, traj, unit)
    runs = piece_runs(plan, traj)
    c = traj.contact
    for s, e, color, _ in runs:
        ax2.plot(c[s:e + 1, 0], c[s:e + 1, 1], color=color, linewidth=1.4)
    reach = float(np.abs(c[:, :2]).max()) if c.size else plan.radius
    bottom_view_axes(ax2, 1.12 * reach, plan.radius, unit)
    ax2.legend(handles=_handles(runs) + [Line2D([], [], color=MARK, marker="+", markersize=9, linestyle="",
                                                label="south pole")], loc="upper right", fontsize=8)
    for s, _, _, _ in runs[1:]:
        ax3.axvline(traj.s[s], color=REST, linewidth=0.6, zorder=0)
    for values, style, label in ((traj.psi, "-", "psi"), (traj.u_o, "--", "u_o"), (traj.v_o, ":", "v_o")):
        ax3.plot(traj.s, values, color=MARK, linestyle=style, linewidth=1.2, label=label)
    ax3.set_xlabel("path parameter (pi per piece)")
    ax3.set_ylabel("angle [rad]")
    ax3.set_xlim(traj.s[0], traj.s[-1])
    ax3.grid(True, alpha=0.3)
    ax3.legend(handles=ax3.get_legend_handles_labels()[0] + [Line2D([], [], color=REST, linewidth=0.6,
                                                                    label="joints between pieces (at rest)")],
               loc="best", fontsize=8)
    ax3.set_title("contact angle and contact point along the path")
    mode = getattr(plan, "mode", "route")
    units = (unit, unit, "rad", "rad", "rad")
    start, goal = (", ".join(f"{float(v):.6g} {u}" for v, u in zip(x, units)) for x in (plan.problem.start, plan.goal))
    fig.suptitle(f"k = {plan.k:.6g}, mode {mode}, {len(plan.pieces)} pieces: from (u_a, v_a, psi, u_o, v_o) = "
                 f"({start})\nto ({goal}); residual {plan.residual:.1e} (Euclidean norm; lengths in R, angles in rad)")
    return fig
