"""Regenerate the paper's case study (Section III.C) into a folder.

Usage: python scripts/reproduce_paper.py [DIR]   (default: results/paper)

The same as ``rollplan reproduce --out DIR``: figures fig06.png..fig12.png,
reproduction.json and REPRODUCTION.md.
"""

import sys
from pathlib import Path

from rollplan.cli import main

if __name__ == "__main__":
    out = sys.argv[1] if len(sys.argv) > 1 else str(Path(__file__).resolve().parent.parent / "results" / "paper")
    sys.exit(main(["reproduce", "--out", out]))
