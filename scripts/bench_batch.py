#!/usr/bin/env python
"""Batch planning: `--jobs 2` against `--jobs 1` on the same targets.

    python scripts/bench_batch.py [--targets 200] [--repeats 3]

Two measurements, each repeated with the order of the two runs alternating (the machine is
shared, so runs of one repeat see the same load), reported as min and median:

* the whole command, cold: ``rollplan batch T.csv --out P.jsonl --jobs J --quiet`` in a new
  process (Python start, imports, the planner's construction, planning, output);
* the planning phase, warm: :func:`rollplan.studies.batch.run_batch` in this process after the
  planner and the leaf tables of k have been built (the forked workers of ``--jobs 2`` start with
  them), i.e. the throughput of a long batch.

The targets are drawn once from a fixed seed: (u_a, v_a) uniform in the disk of radius 1.2 R,
psi uniform in [-1, 1] rad, steps uniform in {1, 2, 3}, k = 2.5; rows that have no plan count
as they would in a user's batch. Both runs must write the same lines (solver times aside).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

#: The budget of issue 18: --jobs 2 at least this many times faster than --jobs 1 on 200 targets.
BUDGET_SPEEDUP = 1.7


def write_targets(path: Path, n: int, seed: int = 18) -> None:
    rng = np.random.default_rng(seed)
    r = 1.2 * np.sqrt(rng.uniform(0, 1, n))
    phi = rng.uniform(-np.pi, np.pi, n)
    psi = rng.uniform(-1, 1, n)
    steps = rng.integers(1, 4, n)
    lines = ["u_a,v_a,psi,steps,k"] + [f"{r[i] * np.cos(phi[i]):.6f},{r[i] * np.sin(phi[i]):.6f},{psi[i]:.6f},"
                                       f"{steps[i]},2.5" for i in range(n)]
    path.write_text("\n".join(lines) + "\n")


def _lines(path: Path) -> list:
    out = []
    for line in path.read_text().splitlines():
        d = json.loads(line)
        d.get("solver", {}).pop("time_s", None)
        out.append(d)
    return out


def _cold(csv: Path, out: Path, jobs: int) -> float:
    cmd = [sys.executable, "-m", "rollplan.cli", "batch", str(csv), "--out", str(out), "--jobs", str(jobs),
           "--quiet", "--overwrite"]
    t = time.perf_counter()
    r = subprocess.run(cmd, capture_output=True, text=True, check=False, timeout=3600)
    elapsed = time.perf_counter() - t
    if r.returncode not in (0, 1):
        raise RuntimeError(f"{' '.join(cmd)} exited {r.returncode}: {r.stderr}")
    return elapsed


def _warm(csv: Path, out: Path, jobs: int) -> float:
    from rollplan.studies.batch import run_batch

    return run_batch(csv, out, jobs=jobs, overwrite=True).time_s


def measure(n_targets: int = 200, repeats: int = 3, cold: bool = True) -> dict:
    """Times of --jobs 1 and --jobs 2 (cold command, unless ``cold`` is False, and warm planning phase) and
    their ratios."""
    from rollplan.planners.geometric import default_planner

    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        csv = tmp / "targets.csv"
        write_targets(csv, n_targets)
        kinds = ("cold", "warm") if cold else ("warm",)
        times = {(kind, j): [] for kind in kinds for j in (1, 2)}
        planner = default_planner("ipopt")
        planner.tables.cells(2.5, False)   # the warm runs start with the planner and the tables of k = 2.5
        for rep in range(repeats):
            for j in ((1, 2) if rep % 2 == 0 else (2, 1)) if cold else ():
                times["cold", j].append(_cold(csv, tmp / f"cold{j}.jsonl", j))
            for j in ((1, 2) if rep % 2 == 0 else (2, 1)):
                times["warm", j].append(_warm(csv, tmp / f"warm{j}.jsonl", j))
        runs = [_lines(tmp / f"{kind}{j}.jsonl") for kind in kinds for j in (1, 2)]
        same = all(r == runs[0] for r in runs)
        failed = sum(d["status"] != "ok" for d in runs[0])
    out = {"targets": n_targets, "failed_rows": failed, "repeats": repeats, "same_lines": same,
           "cores": os.cpu_count(), "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None}
    for kind in kinds:
        t1, t2 = times[kind, 1], times[kind, 2]
        ratios = [a / b for a, b in zip(t1, t2)]
        out[kind] = {"jobs1_s": t1, "jobs2_s": t2, "jobs1_median_s": statistics.median(t1),
                     "jobs2_median_s": statistics.median(t2), "speedup_median": statistics.median(ratios),
                     "speedup_min": min(ratios), "speedup_max": max(ratios)}
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--targets", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    print(json.dumps(measure(args.targets, args.repeats), indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
