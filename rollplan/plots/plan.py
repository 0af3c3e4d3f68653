"""Figure of a plan: the contact path on the sphere (close-up from below), on the plane, and psi along
the path. It computes nothing."""

from __future__ import annotations

import math

from matplotlib.figure import Figure

from .common import draw_bottom_view, draw_plane_path, draw_psi

__all__ = ["plot_plan"]


def plot_plan(plan, traj, unit="R") -> Figure:
    """Three panels of a geometric-phase plan and its sampled :class:`~rollplan.result.Trajectory`.

    The contact path on the sphere seen from below (close-up, equal aspect), the
    contact path on the plane, and psi against the steps traced, which ends at
    the target psi plus ``2 pi m`` on branch m. Colours: :mod:`.colors`.
    """
    fig = Figure(figsize=(16, 5.4), layout="constrained")
    ax1, ax2, ax3 = fig.subplots(1, 3)
    draw_bottom_view(ax1, traj, plan.radius, unit)
    draw_plane_path(ax2, traj, plan.goal[:2], unit)
    m = plan.branch
    label = "target psi" if m == 0 else f"target psi {'+' if m > 0 else '-'} {2 * abs(m)} pi (branch m = {m})"
    draw_psi(ax3, traj, plan.goal.psi + 2 * math.pi * m, label)
    fig.suptitle(f"k = {plan.k:.6g}, n = {plan.steps} step(s): a = {plan.a:.6g} {unit}, b = {plan.b:.6g} {unit}, "
                 f"gamma = {plan.gamma:.6g} rad, residual {plan.residual:.1e} (Euclidean norm, lengths in R, "
                 "angles in rad)")
    return fig
