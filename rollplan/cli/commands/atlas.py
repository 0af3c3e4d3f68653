"""``rollplan atlas``: maps of h(a, b) and eta(a, b) with the fold of the step map."""

from __future__ import annotations

import argparse

from ...core import families
from ...errors import InputError
from ...io import save_figure
from ...problem import DEFAULT_K
from ...progress import Progress
from ..arguments import JSON_HELP, K_HELP, STEPS_HELP, number, whole
from ..common import EXIT_OK, check_outputs, emit_json, quiet_dask
from ..format import num


def _per_k(path, k):
    """The output path for ``k``: ``{k}`` in it replaced by the value (also for a single --k)."""
    return path if path is None or path == "-" else path.replace("{k}", f"{k:g}")


def cmd_atlas(args) -> int:
    from ...plots.atlas import plot_atlas
    from ...studies.atlas import atlas_to_dict, compute_atlases

    several = len(args.k) > 1
    repeated = sorted({f"{k:g}" for k in args.k if args.k.count(k) > 1})
    if repeated:
        raise InputError(f"--k {' '.join(repeated)} is given more than once: give each value of k once")
    for path in (args.out, args.json):
        if several and path not in (None, "-") and "{k}" not in path:
            raise InputError(f"output path {path!r} is not allowed with several --k values: put {{k}} in it "
                             "(e.g. atlas_k{k}.png)")
    if several and args.json == "-":
        raise InputError("--json - is not allowed with several --k values: give a file name with {k}")
    for k in args.k:
        check_outputs(json=None if args.json is None else _per_k(args.json, k),
                       figure=_per_k(args.out, k))
    with Progress(unit="blocks", delay=1.0) as progress:
        quiet_dask(args)
        atlases = compute_atlases(args.k, args.steps, args.resolution, scheduler=args.scheduler, progress=progress,
                                  curve=args.curve)
    for at in atlases:
        out = _per_k(args.out, at.k)
        save_figure(plot_atlas(at), out)
        family = "" if at.curve == "circles" else f"curve = {at.curve}, "
        print(f"rollplan atlas: {family}k = {num(at.k)}, steps = {at.steps}, {at.a.size} x {at.b.size} grid on "
              f"(0, {num(at.a[-1])} R]^2")
        print(f"  shift per step h in [{num(at.h.min())}, {num(at.h.max())}] R, holonomy eta in "
              f"[{num(at.eta.min())}, {num(at.eta.max())}] rad, {at.fold_cells} grid cells on the fold det = 0")
        print(f"wrote {out}")
        if args.json:
            emit_json(argparse.Namespace(json=_per_k(args.json, at.k), stdout=args.stdout),
                       atlas_to_dict(at), "R")
    return EXIT_OK


def _atlas_arguments(t) -> None:
    from ...studies.atlas import DEFAULT_RESOLUTION, MAX_RESOLUTION

    t.add_argument("--k", type=number, nargs="+", default=[DEFAULT_K], metavar="K",
                   help=K_HELP + "; several values sweep over k (then put {k} in --out and --json)")
    t.add_argument("--curve", choices=families.FAMILIES, default="circles",
                   help="leaf family of the figure eight (default circles; a, b are then leaf sizes, "
                        "docs/design/curve-families.md)")
    t.add_argument("--steps", type=whole, default=1, help=f"also map what n figure eights reach, n {STEPS_HELP} "
                   "(default 1)")
    t.add_argument("--resolution", type=whole, default=DEFAULT_RESOLUTION,
                   help=f"grid points per axis in [2, {MAX_RESOLUTION}] (default {DEFAULT_RESOLUTION})")
    t.add_argument("--out", required=True, metavar="FILE.png", help="figure")
    t.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the maps"))
    t.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="evaluate the grid on a Dask distributed cluster (pip install 'rollplan[distributed]')")
    t.set_defaults(func=cmd_atlas)


def register(sub) -> None:
    """The ``atlas`` command (its options are added when it is used)."""
    sub.add_parser("atlas", help="maps of h(a, b) and eta(a, b) with contours and the fold of the step map",
                   builder=_atlas_arguments)
