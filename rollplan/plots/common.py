"""Shared pieces of the figures: axes of the sphere and of the plane, and path segments.

Functions take results and draw; they compute nothing.
"""

from __future__ import annotations

import numpy as np

__all__ = ["LEAF_COLORS", "segments", "sphere_axes", "plane_axes", "draw_sphere_path", "draw_plane_path"]

LEAF_COLORS = ("tab:red", "tab:blue")  # first half-step red, second blue (paper's figures)


def segments(traj):
    """``(start, stop, segment)`` of each run of samples on one segment of a :class:`~rollplan.result.Trajectory`.

    Each run includes the joint sample before it, so consecutive runs connect.
    """
    seg = traj.segment
    change = np.nonzero(np.diff(seg[1:]) != 0)[0] + 1
    bounds = np.concatenate([[0], change, [seg.size - 1]])
    return [(int(s), int(e) + 1, int(seg[e])) for s, e in zip(bounds[:-1], bounds[1:])]


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


def plane_axes(ax, target=None, unit="R", title="contact path on the plane", start=(0.0, 0.0)):
    """Start and target marks, labels, equal aspect, grid and legend of a plane view."""
    ax.plot([start[0]], [start[1]], "ko", markersize=4, label="start")
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
    for s, e, leaf in segments(traj):
        c = traj.contact[s:e + 1]
        ax.plot(c[:, 0], c[:, 1], c[:, 2], color=LEAF_COLORS[leaf % 2], linewidth=1.6)
    sphere_axes(ax, radius, unit)


def draw_plane_path(ax, traj, target=None, unit="R"):
    """Contact path on the plane, first half-steps red, second blue."""
    for s, e, leaf in segments(traj):
        ax.plot(traj.u_a[s:e + 1], traj.v_a[s:e + 1], color=LEAF_COLORS[leaf % 2], linewidth=1.4)
    plane_axes(ax, target, unit, start=(traj.u_a[0], traj.v_a[0]))
