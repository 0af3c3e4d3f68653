"""Figures of planner comparisons. Functions take results and return matplotlib Figures; they compute nothing."""

from __future__ import annotations

import numpy as np
from matplotlib.figure import Figure

from .colors import OMEGA_LABELS, PLANNER, PLANNER_LABELS, ROTOR_LABELS
from .common import draw_bottom_view, plane_axes

__all__ = ["plot_comparison", "plot_comparison_series", "draw_comparison_series", "plot_scaling"]


def _color(name):
    return PLANNER.get(name)


def _label(name):
    return PLANNER_LABELS.get(name, name)


def _draw_paths(fig, c, unit):
    ax1, ax2 = fig.subplots(1, 2)
    sides = (("geometric_phase", c.plan_trajectory, c.plan_measures.path_length),
             ("collocation", c.result.trajectory, c.result.measures.path_length))
    reach = max(float(np.abs(traj.contact[:, :2]).max()) for _, traj, _ in sides)
    for i, (name, traj, length) in enumerate(sides):
        label = f"{_label(name)}: length {length:.6g} {unit}"
        draw_bottom_view(ax1, traj, c.problem.radius, unit, color=_color(name), label=label, extent=1.12 * reach,
                         axes=i == len(sides) - 1)
        ax2.plot(traj.u_a, traj.v_a, color=_color(name), linewidth=1.4, label=label)
    handles, _ = ax2.get_legend_handles_labels()
    plane_axes(ax2, c.problem.goal[:2], unit, "contact paths on the plane", handles=handles)


def draw_comparison_series(fig, series: dict, horizon_label: str = "time t [s]", labels: dict | None = None) -> None:
    """Time series of several motions on one set of panels of ``fig`` (a Figure or SubFigure).

    ``series`` maps a motion's name (``"geometric_phase"``, ``"collocation"``, or
    any other) to a mapping with ``"t"`` (N,) [s], ``"omega"`` (N, 3) [rad/s]
    and optionally ``"rotor_rates"`` (N, 2) [rad/s]. Panels: each component of
    omega and ``|omega|``, then each rotor rate when every motion has them; one
    colour per motion (:data:`.colors.PLANNER` for the two planners); ``labels``
    optionally maps a motion's name to its legend entry.
    """
    labels = labels or {}
    rates = all(s.get("rotor_rates") is not None for s in series.values())
    rows = 2 if rates else 1
    axes = np.atleast_2d(fig.subplots(rows, 4))
    panels = [(axes[0, j], lambda s, j=j: np.asarray(s["omega"])[:, j], f"{OMEGA_LABELS[j]} [rad/s]")
              for j in range(3)]
    panels.append((axes[0, 3], lambda s: np.linalg.norm(np.asarray(s["omega"]), axis=1), "$|\\omega|$ [rad/s]"))
    if rates:
        for j in range(2):
            panels.append((axes[1, j], lambda s, j=j: np.asarray(s["rotor_rates"])[:, j],
                           f"$\\dot\\varphi_{j + 1}$ [rad/s], {ROTOR_LABELS[j]}"))
        for ax in axes[1, 2:]:
            ax.set_visible(False)
    for ax, value, ylabel in panels:
        for name, s in series.items():
            ax.plot(np.asarray(s["t"]), value(s), color=_color(name), linewidth=1.1,
                    label=labels.get(name, _label(name)))
        ax.set_ylabel(ylabel)
        ax.set_xlabel(horizon_label)
        ax.grid(True, alpha=0.3)
    handles, _ = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=9)   # one legend, off the data


def plot_comparison(c, unit: str = "R", series: dict | None = None) -> Figure:
    """Both contact paths of a :class:`~rollplan.studies.comparison.Comparison` overlaid, on the sphere (a
    close-up seen from below) and on the plane; with ``series`` (see :func:`draw_comparison_series`)
    also the angular velocity and the rotor rates of both motions in time."""
    p, g, tr = c.problem, c.problem.goal, c.result.transcription
    title = (f"k = {p.k:.6g}, target (u_a, v_a, psi) = ({g.u_a:.6g} {unit}, {g.v_a:.6g} {unit}, {g.psi:.6g} rad), "
             f"n = {p.steps}, T = {c.horizon:.6g} s; collocation cost {c.result.cost}, N = {tr.intervals}, "
             f"d = {tr.degree}")
    if series is None:
        fig = Figure(figsize=(12, 5.4), layout="constrained")
        _draw_paths(fig, c, unit)
    else:
        fig = Figure(figsize=(16, 12), layout="constrained")
        top, bottom = fig.subfigures(2, 1, height_ratios=[1.1, 1.0])
        _draw_paths(top, c, unit)
        efforts = {"geometric_phase": c.plan_measures.effort, "collocation": c.result.measures.effort}
        labels = {name: f"{_label(name)}: effort int |omega|^2 dt = {e:.6g} rad^2/s" for name, e in efforts.items()}
        draw_comparison_series(bottom, series, labels=labels)
        bottom.suptitle("in time (geometric phase timed with t proportional to theta; the collocation's control, "
                        "the contact rates, is constant on each of its N intervals)")
    fig.suptitle(title)
    return fig


def plot_comparison_series(series: dict, title: str = "") -> Figure:
    """Figure of :func:`draw_comparison_series` alone."""
    fig = Figure(figsize=(16, 6.5), layout="constrained")
    draw_comparison_series(fig, series)
    fig.suptitle(title)
    return fig


def plot_scaling(intervals, times, labels) -> Figure:
    """Solve time against N (log-log), one line per series; ``times`` is a list of arrays [s]."""
    fig = Figure(figsize=(6, 4.5))
    ax = fig.add_subplot(1, 1, 1)
    for i, (t, lab) in enumerate(zip(times, labels)):  # all collocation: one colour, a style per series
        ax.loglog(intervals, t, "os^"[i % 3] + ("-", "--", ":")[i % 3], color=PLANNER["collocation"], label=lab)
    ax.set_xticks(list(intervals))
    ax.set_xticklabels([str(n) for n in intervals])
    ax.minorticks_off()
    ax.set_xlabel("intervals N")
    ax.set_ylabel("IPOPT solve time [s]")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig
