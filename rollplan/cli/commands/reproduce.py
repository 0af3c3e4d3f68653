"""``rollplan reproduce``: the paper's case study (Figs 6-12, table, report)."""

from __future__ import annotations

import sys

from ...outputs import make_folder
from ...progress import Progress
from ..common import EXIT_OK


def cmd_reproduce(args) -> int:
    import time

    from ...studies.paper import reproduce

    t0 = time.perf_counter()
    make_folder(args.out, parents=True)   # a folder that cannot be made is refused before the first line
    print(f"rollplan reproduce: Section III.C of the paper into {args.out}", file=sys.stderr)
    with Progress() as progress:
        result = reproduce(args.out, progress=progress)
    width = max(len(r.quantity) for r in result.rows)
    for r in result.rows:
        print(f"  {r.quantity:<{width}}  paper {r.paper:<11.9g} computed {r.computed:<12.6g} {r.status}")
    n_ok = sum(r.status == "reproduced" for r in result.rows)
    print(f"{n_ok} of {len(result.rows)} reproduced, {len(result.rows) - n_ok} discrepancies "
          f"(evidence in {args.out}/REPRODUCTION.md); {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def register(sub) -> None:
    """The ``reproduce`` command's options."""
    r = sub.add_parser("reproduce", help="regenerate the paper's case study (Figs 6-12, table, report)")
    r.add_argument("--out", required=True, metavar="DIR",
                   help="folder for fig06.png..fig12.png, reproduction.json, REPRODUCTION.md (created if missing)")
    r.set_defaults(func=cmd_reproduce)
