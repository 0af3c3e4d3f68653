"""Regenerate results/atlas_k2.5.png: h(a, b) and eta(a, b) of one figure eight at k = 2.5.

Run: python scripts/make_atlas.py   (the same as `rollplan atlas --out ...`: k = 2.5, DEFAULT_RESOLUTION)
"""

from pathlib import Path

from rollplan.io import save_figure
from rollplan.plots.atlas import plot_atlas
from rollplan.studies.atlas import compute_atlas

OUT = Path(__file__).resolve().parent.parent / "results" / "atlas_k2.5.png"

if __name__ == "__main__":
    save_figure(plot_atlas(compute_atlas(2.5)), OUT)  # the defaults of `rollplan atlas`
    print(f"wrote {OUT}")
