"""Figure of a plan: the contact path on the sphere and on the plane. It computes nothing."""

from __future__ import annotations

from matplotlib.figure import Figure

from .common import draw_plane_path, draw_sphere_path

__all__ = ["plot_plan"]


def plot_plan(plan, traj, unit="R") -> Figure:
    """Two panels: the contact path on the sphere (3-D) and on the plane."""
    fig = Figure(figsize=(11, 5))
    ax1 = fig.add_subplot(1, 2, 1, projection="3d")
    draw_sphere_path(ax1, traj, plan.radius, unit)
    ax2 = fig.add_subplot(1, 2, 2)
    draw_plane_path(ax2, traj, plan.goal[:2], unit)
    fig.suptitle(f"k = {plan.k:g}, n = {plan.steps}: a = {plan.a:.6g}, b = {plan.b:.6g}, "
                 f"gamma = {plan.gamma:.6g} rad, residual {plan.residual:.1e}")
    fig.tight_layout()
    return fig
