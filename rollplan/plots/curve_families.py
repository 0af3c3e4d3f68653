"""The curve-family study's figure (scripts/curve_families.py): per case, each family's shortest plan.

Takes the study's report (a dict: ``rows``, each with ``target``, ``steps``, ``k`` and ``families`` holding the
measured ``path_length``, ``omega2``, ``t_min``, ``nonstop_continuous``) and computes nothing.
"""

from __future__ import annotations

from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from .colors import FAMILY

__all__ = ["plot_curve_families"]

_PANELS = (("path_length", "contact path length [R]"),
           ("omega2", "int|omega|^2 dt, optimal timing, T = 1 s [rad^2/s]"),
           ("t_min", "time-optimal duration within the limits [s]"))


def plot_curve_families(report: dict) -> Figure:
    """Three panels (path length, int|omega|^2, time-optimal duration) against the case; one colour per family
    (:data:`.colors.FAMILY`), a filled marker where a non-stop timing with continuous torques exists."""
    rows = report["rows"]
    fig = Figure(figsize=(max(7.0, 0.45 * len(rows) + 3.0), 9.0), layout="constrained")
    axes = fig.subplots(len(_PANELS), 1, sharex=True)
    offsets = {name: 0.12 * (i - 1.5) for i, name in enumerate(FAMILY)}
    for ax, (key, label) in zip(axes, _PANELS):
        for name, color in FAMILY.items():
            for x, r in enumerate(rows):
                f = r["families"].get(name, {})
                if key not in f:
                    continue
                ax.plot(x + offsets[name], f[key], "o", color=color, markersize=6,
                        markerfacecolor=color if f["nonstop_continuous"] else "white")
        ax.set_ylabel(label, fontsize=8)
        ax.set_yscale("log")
        ax.grid(True, which="both", alpha=0.3)
    labels = [f"({', '.join(format(v, 'g') for v in r['target'])})\nn={r['steps']}, k={r['k']:.3g}" for r in rows]
    axes[-1].set_xticks(range(len(rows)))
    axes[-1].set_xticklabels(labels, rotation=90, fontsize=7)
    axes[-1].set_xlabel("target (u_a, v_a, psi) [R, rad], figure eights n, inertia ratio k")
    handles = [Line2D([], [], marker="o", linestyle="", color=c, label=n) for n, c in FAMILY.items()]
    handles.append(Line2D([], [], marker="o", linestyle="", color="0.3", markerfacecolor="0.3",
                          label="filled: non-stop timing with continuous torques exists"))
    handles.append(Line2D([], [], marker="o", linestyle="", color="0.3", markerfacecolor="white",
                          label="hollow: it must stop (pole or corners)"))
    axes[0].legend(handles=handles, fontsize=7, ncol=3, loc="best")
    fig.suptitle("Each leaf family's shortest certified plan (scripts/curve_families.py)")
    return fig
