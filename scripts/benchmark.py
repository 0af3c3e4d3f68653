"""Time rollplan.plan on a few targets; write results/benchmarks.md.

Run: python scripts/benchmark.py
"""

import platform
import statistics
import subprocess
import time
from datetime import datetime, timezone
from pathlib import Path

import rollplan

TARGETS = [  # (target, steps, k)
    ((0.0, 1.0, 0.0), 1, 2.5),
    ((0.5, 0.7, 0.8), 1, 2.5),
    ((1.5, -0.5, 1.0), 3, 2.5),
    ((1.0, 1.0, 0.0), 1, 0.0),
    ((0.3, 0.2, -2.0), 2, 5.0),
]
REPEATS = 21


def main() -> None:
    t0 = time.perf_counter()
    rollplan.plan(*TARGETS[0][:1], steps=1, k=2.5)
    build = time.perf_counter() - t0
    rows = []
    for target, steps, k in TARGETS:
        t0 = time.perf_counter()
        p = rollplan.plan(target, steps=steps, k=k)  # first call for this k builds its tables
        first = time.perf_counter() - t0
        times = []
        for _ in range(REPEATS):
            t0 = time.perf_counter()
            p = rollplan.plan(target, steps=steps, k=k)
            times.append(time.perf_counter() - t0)
        rows.append((target, steps, k, first, statistics.median(times), p.residual, p.a, p.b))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    lines = [
        "# Benchmarks", "",
        f"{datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC, commit {commit or 'unknown'}, "
        f"{platform.processor() or platform.machine()}, Python {platform.python_version()}, "
        f"{__import__('os').cpu_count()} cores.", "",
        f"Planner construction and first plan (symbolic build, IPOPT set-up): {build * 1e3:.0f} ms.", "",
        "| target (u_a, v_a, psi) | n | k | first call for this k [ms] | median of "
        f"{REPEATS} [ms] | residual | a | b |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for target, steps, k, first, med, res, a, b in rows:
        lines.append(f"| {target} | {steps} | {k:g} | {first * 1e3:.1f} | {med * 1e3:.1f} | {res:.1e} | {a:.6f} | {b:.6f} |")
    lines += ["", f"Budget: single plan under 50 ms median; worst median here {max(r[4] for r in rows) * 1e3:.1f} ms.", ""]
    out = Path(__file__).resolve().parent.parent / "results" / "benchmarks.md"
    out.write_text("\n".join(lines))
    print("\n".join(lines))


if __name__ == "__main__":
    main()
