"""Where a warm geometric-phase plan spends its time: the phases of rollplan.plan on the benchmark's targets.

    python scripts/profile_plan.py [--repeats 41] [--root-solver c] [--out-dir results]

Writes ``plan_profile.md`` and ``plan_profile.json``. The targets and k are those of the plan section of
``scripts/benchmark.py``. Each phase is timed inside the plan (wall time, mean over the repeats) by
wrapping the planner's calls. With the default root solver ``c`` a plan is one call of the C planner
(:func:`rollplan.planners.geometric.compiled_search.certified_plan`: search, polish and certificate); with
``--root-solver ipopt`` (or ``newton``) the phases of the Python path: the compiled C search of the shortest root
(:func:`rollplan.planners.geometric.compiled_search.shortest_root`, the planner's only search); the IPOPT polish of the
winning root (``GeometricPhasePlanner._polish``), the step's shift for gamma (the compiled leaf-map step)
and the RK8 certificate; "rest" is the plan's time minus these (problem checks, gamma, the result objects).
The fixed costs below them are measured alone: one C search, one IPOPT call on a trivial 2 x 2 system (IPOPT's cost
without evaluations), the compiled residual of (32)-(33) and its Jacobian (the evaluations of one IPOPT
call from a root), and one figure eight of the certificate (its coarse and fine RK8 runs).
"""

from __future__ import annotations

import argparse
import datetime
import os
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path

import casadi as ca
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rollplan
from rollplan.io import write_atomic, write_json
from rollplan.planners.geometric import certify, planner
from rollplan.planners.geometric.compiled_search import shortest_root
from rollplan.planners.geometric.leafmap import panels_for
from rollplan.planners.geometric.refine import leaf_residual

from benchmark import TARGETS, K, git_commit

#: The root solver of the profiled plans (``--root-solver``; the default path is one C call).
ROOT_SOLVER = ["c"]
PHASES = ("C planner (search, polish, certificate)", "C search", "polish (IPOPT)", "step for gamma",
          "certificate (RK8)")


def _timed(acc: dict, label: str, fn):
    def run(*args, **kwargs):
        t = time.perf_counter()
        try:
            return fn(*args, **kwargs)
        finally:
            acc[label] += time.perf_counter() - t
    return run


def _alone(fn, repeats: int) -> tuple[float, float]:
    """(median, min) wall time [us] of ``fn()`` called alone, after one warm-up call."""
    fn()
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts) * 1e6, min(ts) * 1e6


def in_plan(repeats: int) -> list:
    """Per target: median wall and CPU time of a warm plan and the mean time of each phase inside it [ms]."""
    acc = defaultdict(float)
    pl = planner.default_planner(ROOT_SOLVER[0])
    saved = (planner.leaf_step, planner.shortest_root, planner.certified_plan)
    planner.shortest_root = _timed(acc, "C search", planner.shortest_root)
    planner.certified_plan = _timed(acc, "C planner (search, polish, certificate)", planner.certified_plan)
    pl._polish = _timed(acc, "polish (IPOPT)", pl._polish)
    pl.certifier.certify = _timed(acc, "certificate (RK8)", pl.certifier.certify)
    step = planner.leaf_step

    class TimedStep:
        def __init__(self, panels):
            self.call = _timed(acc, "step for gamma", step(panels).call)

    planner.leaf_step = TimedStep
    rows = []
    try:
        for target, steps in TARGETS:
            p = rollplan.plan(target, steps, k=K, root_solver=ROOT_SOLVER[0])
            acc.clear()
            wall, cpu = [], []
            for _ in range(repeats):
                t, c = time.perf_counter(), time.process_time()
                rollplan.plan(target, steps, k=K, root_solver=ROOT_SOLVER[0])
                cpu.append(time.process_time() - c)
                wall.append(time.perf_counter() - t)
            mean = sum(wall) / repeats
            row = {"target (u_a, v_a, psi)": str(tuple(target)), "n": steps, "m": p.branch,
                   "search": p.stats.details["search"],
                   "warm median [ms]": statistics.median(wall) * 1e3, "warm min [ms]": min(wall) * 1e3,
                   "CPU median [ms]": statistics.median(cpu) * 1e3}
            for name in PHASES:
                row[f"{name} [ms]"] = acc[name] / repeats * 1e3
            row["rest [ms]"] = (mean - sum(acc[n] for n in PHASES) / repeats) * 1e3
            row["IPOPT iterations"] = p.stats.iterations
            rows.append(row)
    finally:
        planner.leaf_step, planner.shortest_root, planner.certified_plan = saved
        del pl._polish, pl.certifier.certify
    return rows


def alone(repeats: int) -> list:
    """Fixed costs measured alone (module docstring) [us]."""
    p = rollplan.plan(TARGETS[1][0], TARGETS[1][1], k=K)
    x = ca.MX.sym("x", 2)
    trivial = ca.nlpsol("trivial", "ipopt", {"x": x, "f": 0, "g": x},
                        {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "record_time": False,
                         "ipopt.hessian_approximation": "limited-memory", "calc_lam_p": False, "calc_lam_x": False})
    f = leaf_residual(panels_for(K))
    jac = f.jacobian()
    par = [K, p.eta, p.h]
    n = certify.initial_steps(p.a, p.b, K, p.steps)
    eight = certify._eight_pair_function(n, True)
    z = np.zeros(3)
    pa, pb = np.array([p.a, 1.0, K, p.gamma]), np.array([p.b, -1.0, K, p.gamma])
    psi = TARGETS[1][0][2]
    cases = [("C search of the shortest root (compiled_search.shortest_root)",
              lambda: shortest_root(*TARGETS[1][0][:2], psi, TARGETS[1][1], K)),
             ("IPOPT on the trivial system x = 0 (2 x 2), from x = 0", lambda: trivial(x0=[0, 0], lbg=0, ubg=0)),
             ("compiled residual of (32)-(33), one evaluation", lambda: f.call([[p.a, p.b], par])),
             ("its Jacobian, one evaluation", lambda: jac.call([[p.a, p.b], par, [0, 0]])),
             (f"one figure eight of the certificate (RK8, {n} and {2 * n} steps per leaf)",
              lambda: eight.call([z, z, pa, pb]))]
    rows = []
    for name, fn in cases:
        med, low = _alone(fn, repeats)
        rows.append({"call (alone)": name, "median [us]": med, "min [us]": low})
    return rows


def _fmt(v):
    return f"{v:.3g}" if isinstance(v, float) else str(v)


def _table(rows) -> list:
    cols = list(rows[0])
    return (["| " + " | ".join(cols) + " |", "|" + "|".join("---" for _ in cols) + "|"]
            + ["| " + " | ".join(_fmt(r[c]) for c in cols) + " |" for r in rows])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=41)
    ap.add_argument("--root-solver", choices=("c", "ipopt", "newton"), default="c")
    ap.add_argument("--out-dir", default="results")
    args = ap.parse_args(argv)
    load = list(os.getloadavg())
    ROOT_SOLVER[0] = args.root_solver
    plans = in_plan(args.repeats)
    fixed = alone(4 * args.repeats)
    load_end = list(os.getloadavg())
    date = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    md = ["# Where a warm plan spends its time", "",
          f"- date: {date}; commit `{git_commit()}`; {os.cpu_count()} cores; load average at start "
          f"{', '.join(f'{x:.2f}' for x in load)}, at the end {', '.join(f'{x:.2f}' for x in load_end)}",
          f"- command: `python scripts/profile_plan.py --repeats {args.repeats} --root-solver {args.root_solver}`; "
          f"k = {K}, the targets of scripts/benchmark.py's plan section", "",
          "## Phases inside a warm plan", ""] + _table(plans) + [
          "", f"- {args.repeats} warm plans per target after one warm-up; phases: mean wall time inside the plan "
          "(module docstring of scripts/profile_plan.py); 'rest' = mean plan time minus the phases.", "",
          "## Fixed costs, measured alone", ""] + _table(fixed) + [
          "", f"- median and minimum of {4 * args.repeats} calls after one warm-up. Alone, the caches hold the "
          "callee's code and data; inside a plan the same calls take longer.", ""]
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "plan_profile.md", "\n".join(md).encode())
    write_json(out / "plan_profile.json", {"date": date, "load_average_start": load, "load_average_end": load_end,
                                           "repeats": args.repeats, "k": K, "plans": plans, "alone": fixed})
    print("\n".join(md))
    return 0


if __name__ == "__main__":
    sys.exit(main())
