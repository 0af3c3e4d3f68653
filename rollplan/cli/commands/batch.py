"""``rollplan batch``: every target of a CSV file, in parallel."""

from __future__ import annotations

import argparse
import sys

from ... import interrupts
from ...errors import InputError
from ...planners import geometric
from ..arguments import whole
from ..common import EXIT_INTERRUPTED, EXIT_NOPLAN, EXIT_OK, EXIT_SOLVER, EXIT_SOME_FAILED, EXIT_TERMINATED, quiet_dask

_BATCH_EPILOG = """\
TARGETS.csv: a header, then one target per line; columns u_a, v_a (required), psi (default 0),
steps (default 1), k (default 2.5), curve (the leaf family: circles, viviani, triangle, square or best;
default circles; echoed as "curve" in the output); an empty cell takes the default; more columns are carried into
the output; blank lines and lines starting with # are skipped. Example:

  # u_a, v_a in units of R, psi in rad
  u_a,v_a,psi,steps,k
  0,1,0,1,2.5
  0.5,0.3,0.4,2,
  -0.2,0.6

exit status: 0 every row planned, 1 some rows failed, 3 every row failed (each failed row has
"status": "failed" and a "reason" in the output), 2 bad input, 4 the cluster failed, 130 interrupted
(Ctrl-C) or 143 terminated (SIGTERM) (finished lines are kept: rerun with --resume).
"""


def cmd_batch(args) -> int:
    from ...studies.batch import run_batch
    from ...studies.executor import ExecutorError, cpu_count

    if args.out == "-":
        raise InputError("batch --out - is not allowed: batch writes its lines to a file that --resume reads back; "
                         "give --out FILE.jsonl")
    quiet_dask(args)
    try:
        jobs = args.jobs if args.jobs is not None else cpu_count()
        r = run_batch(args.targets, args.out, jobs, args.resume, args.overwrite, root_solver=args.method,
                      progress=not args.quiet, scheduler=args.scheduler)
    except interrupts.Terminated:
        print(f"rollplan: terminated; finished lines are kept in {args.out}: rerun with --resume", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print(f"\nrollplan: interrupted; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    except ExecutorError as exc:
        print(f"rollplan: the cluster failed: {exc}; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return EXIT_SOLVER
    print(f"rollplan batch: {r.total} targets, {r.skipped} already done, {r.planned} planned "
          f"({r.failed} failed) in {r.time_s:.1f} s; wrote {args.out}")
    if r.total and r.failed_total == r.total:
        print(f"rollplan: every row failed ({r.failed_total} of {r.total}); see 'reason' in {args.out}",
              file=sys.stderr)
        return EXIT_NOPLAN
    if r.failed_total:
        print(f"rollplan: {r.failed_total} of {r.total} rows failed; see 'reason' in {args.out}", file=sys.stderr)
        return EXIT_SOME_FAILED
    return EXIT_OK


def _batch_arguments(b) -> None:
    from ...studies.executor import MAX_JOBS

    b.add_argument("targets", metavar="TARGETS.csv", help="CSV with header u_a, v_a[, psi, steps, k] (see below)")
    b.add_argument("--out", required=True, metavar="PLANS.jsonl", help="output: one JSON line per target, in order")
    b.add_argument("--jobs", type=whole, default=None,
                   help=f"worker processes in [1, {MAX_JOBS}] (default: number of cores)")
    b.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="plan on a Dask distributed cluster instead, e.g. tcp://host:8786 (needs: pip install "
                        "'rollplan[distributed]'; workers: dask worker ADDRESS --nthreads 1)")
    b.add_argument("--resume", action="store_true", help="keep the lines in --out and plan only the missing rows")
    b.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    b.add_argument("--method", choices=sorted(geometric.SOLVERS), default=geometric.DEFAULT_ROOT_SOLVER,
                   help="root solver")
    b.add_argument("--quiet", action="store_true", help="no progress on stderr")
    b.set_defaults(func=cmd_batch)


def register(sub) -> None:
    """The ``batch`` command (its options are added when it is used)."""
    sub.add_parser("batch", help="plan every target of a CSV file (u_a, v_a, psi, steps, k) in parallel",
                   epilog=_BATCH_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
                   builder=_batch_arguments)
