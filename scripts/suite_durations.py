#!/usr/bin/env python
"""Durations of chosen tests in two versions of tests/: a base commit's and the working tree's.

    python scripts/suite_durations.py --base 7936e69 [--repeats 1] [--out results/suite_durations.md] NODE...

Each NODE (e.g. ``tests/test_batch.py::test_cli_batch`` or ``tests/test_reconfigure.py -k brute``, quoted)
is run by pytest from the base commit's ``tests/`` and ``scripts/`` (exported into a temporary folder with
``git archive``) and from this tree's, alternating which goes first, against the same installed package,
so only the tests differ. Reported per node: the wall time and the CPU time (user + system of pytest and
everything it started, from ``getrusage``) of each run, min over the repeats. The machine is shared: the
load average at the start and the end is recorded, and the CPU time is the less load-dependent figure.
"""

from __future__ import annotations

import argparse
import datetime
import os
import resource
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def run(folder: Path, node: str) -> tuple:
    """(wall, CPU, passed) of ``pytest NODE`` run in ``folder``."""
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *shlex.split(node)]
    c, t = _cpu(), time.perf_counter()
    r = subprocess.run(cmd, cwd=folder, capture_output=True, text=True, check=False, timeout=3600)
    if r.returncode:
        print(f"{folder}: pytest {node} failed:\n{r.stdout[-3000:]}", file=sys.stderr)
    return time.perf_counter() - t, _cpu() - c, r.returncode == 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("nodes", nargs="+")
    ap.add_argument("--base", required=True, help="commit whose tests/ are the 'before'")
    ap.add_argument("--repeats", type=int, default=1)
    ap.add_argument("--out", default=None)
    args = ap.parse_args(argv)
    load0 = os.getloadavg()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        archive = subprocess.run(["git", "-C", str(ROOT), "archive", args.base, "tests", "scripts", "pyproject.toml"],
                                 capture_output=True, check=True).stdout
        subprocess.run(["tar", "-x", "-C", str(base)], input=archive, check=True)
        for node in args.nodes:
            runs = {"base": [], "this": []}
            for rep in range(args.repeats):
                for which in (("base", "this") if rep % 2 == 0 else ("this", "base")):
                    runs[which].append(run(base if which == "base" else ROOT, node))
            rows.append((node, runs))
            print(node, runs, file=sys.stderr)
    load1 = os.getloadavg()
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, check=True).stdout.strip()
    lines = ["# Durations of the tests changed to shorten the suite", "",
             f"- date: {datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M UTC}; command: "
             f"`python {' '.join(shlex.quote(a) for a in ['scripts/suite_durations.py', *sys.argv[1:]])}`",
             f"- base: tests of `{args.base}`; this: tests of `{commit}` (working tree); same installed package",
             f"- {os.cpu_count()} cores; load average (1, 5, 15 min) at the start "
             f"{', '.join(f'{x:.2f}' for x in load0)}, at the end {', '.join(f'{x:.2f}' for x in load1)} "
             "(other sessions running: wall times are inflated; CPU times less so)", "",
             "| tests | base wall [s] | this wall [s] | base CPU [s] | this CPU [s] | CPU saved [s] | passed |",
             "|---|---:|---:|---:|---:|---:|---|"]
    total = [0.0, 0.0, 0.0, 0.0]
    for node, runs in rows:
        bw, tw = min(w for w, _, _ in runs["base"]), min(w for w, _, _ in runs["this"])
        bc, tc = min(c for _, c, _ in runs["base"]), min(c for _, c, _ in runs["this"])
        ok = all(p for _, _, p in runs["base"] + runs["this"])
        total = [total[0] + bw, total[1] + tw, total[2] + bc, total[3] + tc]
        lines.append(f"| `{node}` | {bw:.1f} | {tw:.1f} | {bc:.1f} | {tc:.1f} | {bc - tc:.1f} | {ok} |")
    lines.append(f"| total | {total[0]:.1f} | {total[1]:.1f} | {total[2]:.1f} | {total[3]:.1f} | "
                 f"{total[2] - total[3]:.1f} | |")
    text = "\n".join(lines) + "\n"
    print(text)
    if args.out:
        Path(args.out).write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
