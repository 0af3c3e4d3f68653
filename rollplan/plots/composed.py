"""Figure of a composed plan or a route: the contact path by piece on the plane and on the sphere, and the
contact coordinates along the path. It computes nothing."""

from __future__ import annotations

from matplotlib.figure import Figure

from .common import LEAF_COLORS, segments, sphere_axes

__all__ = ["PIECE_COLORS", "plot_composed"]

#: Colours by kind of piece; leaves alternate the two colours of :data:`.common.LEAF_COLORS`.
PIECE_COLORS = {"approach": "black", "departure": "0.45", "turn": ("tab:green", "tab:purple")}


def _color(kind: str, j: int):
    c = PIECE_COLORS.get(kind, LEAF_COLORS)
    return c if isinstance(c, str) else c[j % 2]


def plot_composed(plan, traj, unit="R") -> Figure:
    """Three panels: the plane path, the sphere path (body frame) and ``psi, u_o, v_o`` along the path.

    ``plan`` is a :class:`~rollplan.planners.geometric.ComposedPlan` or a
    :class:`~rollplan.planners.geometric.Route` (its ``pieces`` name the kind of each
    segment of ``traj``, a :class:`~rollplan.result.Trajectory` of it).
    """
    fig = Figure(figsize=(16, 5.2))
    ax1 = fig.add_subplot(1, 3, 1)
    ax2 = fig.add_subplot(1, 3, 2, projection="3d")
    ax3 = fig.add_subplot(1, 3, 3)
    shown = set()
    for s, e, j in segments(traj):
        kind = plan.pieces[j].kind
        label = kind if kind not in shown else None
        shown.add(kind)
        color = _color(kind, j)
        width = 2.2 if kind in ("approach", "departure") else 1.3
        ax1.plot(traj.u_a[s:e + 1], traj.v_a[s:e + 1], color=color, linewidth=width, label=label)
        c = traj.contact[s:e + 1]
        ax2.plot(c[:, 0], c[:, 1], c[:, 2], color=color, linewidth=width)
        ax3.axvline(traj.s[s], color="0.85", linewidth=0.6, zorder=0)
    ax1.plot([traj.u_a[0]], [traj.v_a[0]], "ko", markersize=5, label="start")
    ax1.plot([plan.goal.u_a], [plan.goal.v_a], "k*", markersize=11, label="goal")
    ax1.set_xlabel(f"u_a [{unit}]")
    ax1.set_ylabel(f"v_a [{unit}]")
    ax1.set_aspect("equal", adjustable="datalim")
    ax1.grid(True, alpha=0.3)
    ax1.legend(loc="best", fontsize=8)
    ax1.set_title(f"contact path on the plane ({plan.path_length:.4g} {unit})")
    sphere_axes(ax2, plan.radius, unit, "contact path on the sphere (body frame)")
    ax3.plot(traj.s, traj.psi, label="psi")
    ax3.plot(traj.s, traj.u_o, label="u_o")
    ax3.plot(traj.s, traj.v_o, label="v_o")
    ax3.set_xlabel("path parameter (pi per piece; grey: joints, at rest)")
    ax3.set_ylabel("[rad]")
    ax3.grid(True, alpha=0.3)
    ax3.legend(loc="best", fontsize=8)
    ax3.set_title("contact angle and contact point along the path")
    mode = getattr(plan, "mode", "route")
    start, goal = (", ".join(f"{float(v):.4g}" for v in x) for x in (plan.problem.start, plan.goal))
    fig.suptitle(f"k = {plan.k:g}, {mode}, {len(plan.pieces)} pieces: from ({start}) to ({goal}), "
                 f"residual {plan.residual:.1e}")
    fig.tight_layout()
    return fig
