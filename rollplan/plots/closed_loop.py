"""Figure of the closed-loop study: arrival error against model error, open and closed loop.

Takes the summary rows of ``scripts/closed_loop.py`` (:mod:`rollplan.studies.closed_loop`) and
computes nothing.
"""

from __future__ import annotations

from matplotlib.figure import Figure

__all__ = ["plot_closed_loop"]

_STYLE = {"open": ("tab:red", "o", "open loop"), "closed": ("tab:blue", "s", "closed loop"),
          "closed_noise": ("tab:green", "^", "closed loop, measurement noise")}


def plot_closed_loop(rows, title: str = "") -> Figure:
    """Arrival error [R and rad] against the model error [%], one panel per kind ('k', 'J_r').

    ``rows``: dicts with ``kind``, ``error`` and, per series in ``open``, ``closed``, ``closed_noise``,
    a dict ``{"median", "p95"}`` (or None). Medians are drawn as lines, 95th percentiles as dotted lines.
    """
    kinds = [k for k in ("k", "J_r") if any(r["kind"] == k for r in rows)]
    fig = Figure(figsize=(5.2 * len(kinds), 4.2), layout="constrained")
    axes = fig.subplots(1, len(kinds), squeeze=False)[0]
    for ax, kind in zip(axes, kinds):
        sel = sorted((r for r in rows if r["kind"] == kind), key=lambda r: r["error"])
        x = [100 * r["error"] for r in sel]
        for series, (color, marker, label) in _STYLE.items():
            pts = [(xi, r[series]) for xi, r in zip(x, sel) if r.get(series) and r[series]["median"] is not None]
            if not pts:
                continue
            ax.plot([p[0] for p in pts], [p[1]["median"] for p in pts], color=color, marker=marker, label=label)
            ax.plot([p[0] for p in pts], [p[1]["p95"] for p in pts], color=color, linestyle=":", linewidth=1.0)
        ax.set_yscale("log")
        ax.set_xscale("log")
        ax.set_xlabel(f"error of {'k' if kind == 'k' else 'the rotor inertia J_r'} [%]")
        ax.set_ylabel("arrival error [R, rad]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle((title + "\n" if title else "") + "lines: median; dotted: 95th percentile", fontsize=9)
    return fig
