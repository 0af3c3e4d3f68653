"""Figure eights at any base point in numbers: writes results/basepoint.md and basepoint.json.

Every number but the optimal-control references (quoted from issue 25) is a measurement of this run, side by side
in one process: for the two examples of the issue and random full-state pairs (contact points up to 60 deg from
the pole, k in [1.5, 8]), the contact-path length of today's pole plan (``ComposedPlanner()``) and of
``ComposedPlanner(base="any")``, the warm time of each (median of ``--repeats`` solves after one warm-up), their
ratio, the certificate's residual and the residual of an independent DOP853 integration of the whole motion on
the printed (15), (16), (20) (``tests/references.py``).

Run: ``python scripts/basepoint_bench.py [--out-dir results] [--pairs 6] [--repeats 3] [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path


def parse_args(argv=None):
    """The command line, read before the slow imports below (a bad option is refused at once)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default="results")
    ap.add_argument("--pairs", type=int, default=6)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--quick", action="store_true", help="the README example and one random pair, each timed by its "
                                                         "first solve (a check that the script runs)")
    return ap.parse_args(argv)


if __name__ == "__main__":
    parse_args()

import numpy as np  # noqa: E402

from rollplan import Problem  # noqa: E402
from rollplan.outputs import write_atomic, write_json  # noqa: E402
from rollplan.planners.geometric import ComposedPlanner  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import references as ref  # noqa: E402  (the independent references of the tests)

#: The issue's examples and the lengths of the realizable motions its multi-start optimal-control solve found [R].
EXAMPLES = (
    ("README example", (0.0, 0.0, 0.0, 0.5, -0.3), (0.8, 0.2, 1.0, -0.4, 0.4), 2.5, 1.437),
    ("second example", (0.3, -0.2, 0.5, -0.3, 0.2), (-0.5, 0.6, -0.7, 0.35, 0.25), 4.0, 1.905),
)


def random_pairs(count: int, seed: int = 2025):
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        states = []
        for _ in range(2):
            u, v = ref.polar_contact(rng.uniform(0.0, math.radians(60)), rng.uniform(-math.pi, math.pi))
            states.append((*(float(x) for x in rng.uniform(-1, 1, 2)), float(rng.uniform(-math.pi, math.pi)), u, v))
        out.append((f"random {i + 1}", states[0], states[1], float(rng.uniform(1.5, 8.0)), None))
    return out


def reference_residual(plan, problem) -> float:
    final = ref.composed_final(plan.pieces, np.asarray(problem.start, float), problem.k)
    goal = np.asarray(problem.goal, float)
    d = final - goal
    d[2] = ref.wrap(d[2])
    return float(np.linalg.norm(d))


def timed(planner, problem, repeats: int):
    """The plan and the median wall time of ``repeats`` warm solves after a first one; with ``repeats`` 0, the time
    of that first solve (it builds what the planner needs: not a warm time)."""
    t0 = time.perf_counter()
    plan = planner.solve(problem)   # warm-up (and the plan)
    times = [] if repeats else [time.perf_counter() - t0]
    for _ in range(repeats):
        t0 = time.perf_counter()
        planner.solve(problem)
        times.append(time.perf_counter() - t0)
    return plan, float(np.median(times))


def measure(cases, repeats: int) -> list:
    pole, any_base = ComposedPlanner(), ComposedPlanner(base="any")
    rows = []
    for name, start, goal, k, ocp in cases:
        problem = Problem(goal, start=start, k=k)
        p, tp = timed(pole, problem, repeats)
        b, tb = timed(any_base, problem, repeats)
        rows.append({"case": name, "start": list(start), "goal": list(goal), "k": k,
                     "pole_length": p.path_length, "pole_ms": tp * 1e3, "any_length": b.path_length,
                     "any_ms": tb * 1e3, "time_ratio": tb / tp, "mode": b.mode,
                     "certificate": b.certificate.residual, "dop853_residual": reference_residual(b, problem),
                     "ocp_length": ocp, "ratio_to_ocp": None if ocp is None else b.path_length / ocp})
        print(f"{name}: pole {p.path_length:.3f} R ({tp * 1e3:.0f} ms), any {b.path_length:.3f} R ({tb * 1e3:.0f} ms)",
              flush=True)
    return rows


def to_markdown(report) -> str:
    timing = (f"median of {report['repeats']} warm solves" if report["repeats"] else
              "times of the first solve, which builds the solvers: not warm")
    lines = ["# Figure eights at any base point", "",
             f"`python scripts/basepoint_bench.py` ({report['pairs']} random pairs, {timing}; load average at start "
             f"{report['load']}). Lengths of the contact path in R; times measured side by side in one run. OCP: the "
             "length of a realizable motion found by a "
             "multi-start optimal-control solve (quoted from issue 25). DOP853: residual of an independent "
             "integration of the whole motion on the printed (15), (16), (20).", "",
             "| case | k | pole plan | base=\"any\" | mode | OCP | any / OCP | pole ms | any ms | time ratio | "
             "certificate | DOP853 |", "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in report["rows"]:
        ocp = "" if r["ocp_length"] is None else f"{r['ocp_length']:.3f}"
        ratio = "" if r["ratio_to_ocp"] is None else f"{r['ratio_to_ocp']:.2f}"
        lines.append(f"| {r['case']} | {r['k']:.2f} | {r['pole_length']:.3f} | {r['any_length']:.3f} | {r['mode']} | "
                     f"{ocp} | {ratio} | {r['pole_ms']:.0f} | {r['any_ms']:.0f} | {r['time_ratio']:.0f} | "
                     f"{r['certificate']:.1e} | {r['dop853_residual']:.1e} |")
    shorter = [r["any_length"] / r["pole_length"] for r in report["rows"]]
    lines += ["", f"Length of base=\"any\" over the pole plan: median {np.median(shorter):.2f}, "
              f"largest {max(shorter):.2f} (never above 1 by construction).",
              f"Warm time of base=\"any\": median {np.median([r['any_ms'] for r in report['rows']]):.0f} ms "
              "(the default must stay within 100 ms for one leg: it does not, so base=\"pole\" stays the default).",
              ""]
    return "\n".join(lines)


def main(argv=None) -> None:
    args = parse_args(argv)
    pairs, repeats = (1, 0) if args.quick else (args.pairs, args.repeats)
    load = f"{os.getloadavg()[0]:.1f}"
    rows = measure(list(EXAMPLES[:1] if args.quick else EXAMPLES) + random_pairs(pairs), repeats)
    report = {"pairs": pairs, "repeats": repeats, "load": load, "rows": rows}
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "basepoint.json", report)
    write_atomic(out / "basepoint.md", to_markdown(report).encode())


if __name__ == "__main__":
    main()
