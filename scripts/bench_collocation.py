"""Budget measurement: collocation N = 100, Legendre d = 3, warm start, median IPOPT time < 1 s.

Usage: python scripts/bench_collocation.py [--repeats 11] [--cost path_length]
Prints the IPOPT wall time of each solve (the NLP is built once, outside the
timing, as a planner for repeated solves does) and the median; exit 1 if the
median exceeds 1 s.
"""

from __future__ import annotations

import argparse
import statistics
import sys

from rollplan import plan
from rollplan.collocation import COSTS, CollocationPlanner

TARGETS = [(0.3, 0.0, 0.0), (0.0, 0.5, 0.0), (0.5, 0.3, 0.4), (-0.4, 0.4, 1.0), (0.8, -0.2, -0.5)]
K = 2.5


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeats", type=int, default=11)
    ap.add_argument("--cost", choices=sorted(COSTS), default="path_length")
    args = ap.parse_args()
    P = CollocationPlanner(100, 3, "legendre", args.cost)
    print(f"NLP built in {P.build_time_s:.2f} s (N = 100, d = 3, legendre, cost {args.cost})")
    times = []
    for tgt in TARGETS:
        p = plan(tgt, 1, k=K)
        for _ in range(args.repeats):
            r = P.solve(tgt, k=K, guess=p)
            times.append(r.stats.solve_time_s)
        print(f"target {tgt}: {r.stats.status}, {r.stats.iterations} iterations, "
              f"median {statistics.median(times[-args.repeats:]):.3f} s, residual {r.residual:.1e}")
    med = statistics.median(times)
    print(f"median IPOPT time over {len(times)} solves: {med:.3f} s (budget 1 s: {'met' if med < 1 else 'NOT met'})")
    return 0 if med < 1.0 else 1


if __name__ == "__main__":
    sys.exit(main())
