"""Figures of plans. Functions take results and return matplotlib figures; they compute nothing."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

__all__ = ["plot_plan", "draw_sphere_path", "draw_plane_path", "sphere_axes", "plane_axes"]

LEAF_COLORS = ("tab:red", "tab:blue")  # first half-step red, second blue (paper's figures)


def _segments(traj):
    """Index ranges of consecutive samples on the same leaf (each including its start point)."""
    change = np.nonzero(np.diff(traj.leaf[1:]) != 0)[0] + 1
    bounds = np.concatenate([[0], change, [traj.leaf.size - 1]])
    return [(int(s), int(e) + 1, int(traj.leaf[e])) for s, e in zip(bounds[:-1], bounds[1:])]


def sphere_axes(ax, radius=1.0, unit="R", title="contact path on the sphere"):
    """A wire-frame sphere of the given radius on 3-D axes, labelled (body frame)."""
    u, v = np.mgrid[0:2 * np.pi:40j, 0:np.pi:20j]
    ax.plot_wireframe(radius * np.cos(u) * np.sin(v), radius * np.sin(u) * np.sin(v), radius * np.cos(v),
                      color="0.85", linewidth=0.4)
    ax.set_xlabel(f"x [{unit}]")
    ax.set_ylabel(f"y [{unit}]")
    ax.set_zlabel(f"z [{unit}]")
    ax.set_box_aspect((1, 1, 1))
    ax.set_title(title)


def plane_axes(ax, target=None, unit="R", title="contact path on the plane"):
    """Start and target marks, labels, equal aspect, grid and legend of a plane view."""
    ax.plot([0], [0], "ko", markersize=4, label="start")
    if target is not None:
        ax.plot([target[0]], [target[1]], "k*", markersize=10, label="target")
    ax.set_xlabel(f"u_a [{unit}]")
    ax.set_ylabel(f"v_a [{unit}]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title)


def draw_sphere_path(ax, traj, radius=1.0, unit="R"):
    """Contact path on the sphere (body frame), 3-D axes, first half-steps red, second blue."""
    for s, e, leaf in _segments(traj):
        c = traj.contact[s:e + 1]
        ax.plot(c[:, 0], c[:, 1], c[:, 2], color=LEAF_COLORS[leaf % 2], linewidth=1.6)
    sphere_axes(ax, radius, unit)


def draw_plane_path(ax, traj, target=None, unit="R"):
    """Contact path on the plane, first half-steps red, second blue."""
    for s, e, leaf in _segments(traj):
        ax.plot(traj.u_a[s:e + 1], traj.v_a[s:e + 1], color=LEAF_COLORS[leaf % 2], linewidth=1.4)
    plane_axes(ax, target, unit)


def plot_plan(plan, traj, unit="R") -> Figure:
    """Two panels: the contact path on the sphere (3-D) and on the plane."""
    fig = Figure(figsize=(11, 5))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    draw_sphere_path(ax1, traj, plan.radius, unit)
    ax2 = fig.add_subplot(1, 2, 2)
    draw_plane_path(ax2, traj, plan.target, unit)
    fig.suptitle(f"k = {plan.k:g}, n = {plan.steps}: a = {plan.a:.6g}, b = {plan.b:.6g}, "
                 f"gamma = {plan.gamma:.6g} rad, residual {plan.residual:.1e}")
    fig.tight_layout()
    return fig
