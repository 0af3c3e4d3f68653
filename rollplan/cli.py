"""The ``rollplan`` command. Exit codes: 0 success, 2 bad input, 3 no plan, 4 solver failure."""

from __future__ import annotations

import argparse
import logging
import math
import sys

from . import geometric
from .errors import InputError, NoPlanError, SolverError, check_finite
from .io import check_writable, plan_to_dict, save_figure, write_json
from .robot import load_robot

EXIT_OK, EXIT_INPUT, EXIT_NOPLAN, EXIT_SOLVER = 0, 2, 3, 4


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad input in one line with exit code 2."""

    def error(self, message):
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message}\n")


def _number(text: str) -> float:
    try:
        return check_finite("value", float(text))
    except (ValueError, InputError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number") from None


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None


def _k_or_robot(args):
    """(k, robot) from --k / --robot."""
    if args.robot is not None:
        return None, load_robot(args.robot)
    return args.k, None


def _fmt_plan(p, unit) -> str:
    lines = [
        f"  figure eight  a = {p.a:.9g} {unit}   b = {p.b:.9g} {unit}   gamma = {p.gamma:.9g} rad   (branch m = {p.branch})",
        f"  one step      h = {p.h:.9g} {unit}   eta = {p.eta:.9g} rad",
        f"  path length   {p.path_length:.9g} {unit}",
        f"  final         u_a = {p.final[0]:.12g}  v_a = {p.final[1]:.12g}  psi = {p.final[2]:.12g}"
        f"  u_o = {p.final[3]:.3g}  v_o = {p.final[4]:.3g}",
        f"  residual      {p.residual:.2e} (CVODES, independent of the planner)",
    ]
    return "\n".join(lines)


def cmd_plan(args) -> int:
    for path in (args.json, args.plot):
        if path is not None:
            check_writable(path)
    k, robot = _k_or_robot(args)
    p = geometric.plan((args.to[0], args.to[1], args.psi), args.steps, k, robot, args.radius, args.all, args.method)
    unit = "m" if robot is not None else ("R" if args.radius is None else "")
    print(f"rollplan: k = {p.k:.9g}, R = {p.radius:g}, steps = {p.steps}, target (u_a, v_a, psi) = "
          f"({p.target[0]:g}, {p.target[1]:g}, {p.target[2]:g})")
    print(_fmt_plan(p, unit))
    print(f"  solver        {p.stats.method}: {p.stats.status}, {p.stats.iterations} iterations, "
          f"{p.stats.candidates} brackets, {p.stats.solves} solves, {p.stats.time_s * 1e3:.1f} ms")
    for i, alt in enumerate(p.alternatives, 1):
        print(f"alternative {i}:")
        print(_fmt_plan(alt, unit))
    traj = p.trajectory() if (args.json or args.plot) else None
    if args.json:
        write_json(args.json, plan_to_dict(p, traj))
        print(f"wrote {args.json}")
    if args.plot:
        from .plots import plot_plan

        save_figure(plot_plan(p, traj, unit or "R"), args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


def cmd_step(args) -> int:
    if args.json is not None:
        check_writable(args.json)
    r = geometric.step(args.a, args.b, args.k, args.gamma)
    u, v = r.shift
    # final psi of one step equals eta
    print(f"rollplan step: a = {r.a:g} R, b = {r.b:g} R, k = {r.k:g}, gamma = {r.gamma:g} rad")
    print(f"  h = {r.h:.12g} R   eta = {r.eta:.12g} rad   direction = {r.direction:.12g} rad")
    print(f"  final u_a = {u:.12g} R   v_a = {v:.12g} R   psi = {r.eta:.12g} rad")
    if args.json:
        write_json(args.json, {"a": r.a, "b": r.b, "k": r.k, "gamma": r.gamma, "h": r.h, "eta": r.eta,
                               "direction": r.direction, "final": {"u_a": float(u), "v_a": float(v), "psi": r.eta}})
        print(f"wrote {args.json}")
    return EXIT_OK


def cmd_batch(args) -> int:
    import os

    from .batch import run_batch

    try:
        jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
        r = run_batch(args.targets, args.out, jobs, args.resume, args.overwrite, args.method,
                      progress=not args.quiet)
    except KeyboardInterrupt:
        print(f"\nrollplan: interrupted; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return 130
    print(f"rollplan batch: {r.total} targets, {r.skipped} already done, {r.planned} planned "
          f"({r.failed} failed) in {r.time_s:.1f} s; wrote {args.out}")
    return EXIT_OK


def cmd_atlas(args) -> int:
    from .atlas import atlas_to_dict, compute_atlas, plot_atlas

    for path in (args.out, args.json):
        if path is not None:
            check_writable(path)
    at = compute_atlas(args.k, args.steps, args.resolution)
    save_figure(plot_atlas(at), args.out)
    print(f"rollplan atlas: k = {at.k:g}, steps = {at.steps}, {at.a.size} x {at.b.size} grid on (0, {at.a[-1]:g}]^2")
    print(f"  shift per step h in [{at.h.min():.6g}, {at.h.max():.6g}] R, holonomy eta in "
          f"[{at.eta.min():.6g}, {at.eta.max():.6g}] rad, {at.fold_cells} grid cells on the fold det = 0")
    print(f"wrote {args.out}")
    if args.json:
        write_json(args.json, atlas_to_dict(at))
        print(f"wrote {args.json}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rollplan", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true", help="log the planner's progress")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("plan", help="plan a motion to a target by tracing a figure eight n times")
    p.add_argument("--to", nargs=2, type=_number, metavar=("U", "V"), default=(0.0, 1.0),
                   help="target contact point (u_a, v_a) on the plane (default 0 1)")
    p.add_argument("--psi", type=_number, default=0.0, help="target contact angle [rad] (default 0)")
    p.add_argument("--steps", type=_whole, default=1, help="number of figure eights n >= 1 (default 1)")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--k", type=_number, default=None, help="inertia ratio k >= 0 (default 2.5)")
    g.add_argument("--robot", metavar="FILE.toml", help="robot parameters (k from eq. 14; lengths in metres)")
    p.add_argument("--radius", type=_number, default=None, help="sphere radius R (default 1, or the robot's)")
    p.add_argument("--all", action="store_true", help="also list every other verified solution branch")
    p.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    p.add_argument("--json", metavar="FILE", help="write the plan as JSON")
    p.add_argument("--plot", metavar="FILE.png", help="draw the contact path on the sphere and the plane")
    p.set_defaults(func=cmd_plan)

    s = sub.add_parser("step", help="what one figure eight does: shift h and holonomy eta")
    s.add_argument("--a", type=_number, required=True, help="first leaf radius [R], 0 < a <= %g" % geometric.A_MAX)
    s.add_argument("--b", type=_number, default=None, help="second leaf radius [R] (default a)")
    s.add_argument("--k", type=_number, required=True, help="inertia ratio k >= 0")
    s.add_argument("--gamma", type=_number, default=0.0, help="rotation about OZ [rad] (default 0)")
    s.add_argument("--json", metavar="FILE", help="write the result as JSON")
    s.set_defaults(func=cmd_step)

    b = sub.add_parser("batch", help="plan every target of a CSV file (u_a, v_a, psi, steps, k) in parallel")
    b.add_argument("targets", metavar="TARGETS.csv", help="CSV with header u_a, v_a, psi, steps, k")
    b.add_argument("--out", required=True, metavar="PLANS.jsonl", help="output: one JSON line per target")
    b.add_argument("--jobs", type=_whole, default=None, help="worker processes (default: number of cores)")
    b.add_argument("--resume", action="store_true", help="keep the lines in --out and plan only the missing rows")
    b.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    b.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    b.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    b.set_defaults(func=cmd_batch)

    t = sub.add_parser("atlas", help="maps of h(a, b) and eta(a, b) with contours and the fold of the step map")
    t.add_argument("--k", type=_number, required=True, help="inertia ratio k >= 0")
    t.add_argument("--steps", type=_whole, default=1, help="also map what n figure eights reach (default 1)")
    t.add_argument("--resolution", type=_whole, default=81, help="grid points per axis (default 81)")
    t.add_argument("--out", required=True, metavar="FILE.png", help="figure")
    t.add_argument("--json", metavar="FILE", help="write the maps as JSON")
    t.set_defaults(func=cmd_atlas)
    return parser


DEFAULT_K = 2.5


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.ERROR, format="%(name)s: %(message)s")
    if getattr(args, "command", None) == "plan" and args.k is None and args.robot is None:
        args.k = DEFAULT_K
    try:
        return args.func(args)
    except InputError as exc:
        print(f"rollplan: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except NoPlanError as exc:
        print(f"rollplan: no plan: {exc}", file=sys.stderr)
        return EXIT_NOPLAN
    except SolverError as exc:
        print(f"rollplan: solver failed ({exc.status}): {exc}", file=sys.stderr)
        return EXIT_SOLVER


if __name__ == "__main__":
    sys.exit(main())
