#!/usr/bin/env python
"""Speed of the numpy reference enumeration (tests/reference_enumerate.py), before and after.

Writes ``results/enumerate_speed.md`` and ``results/enumerate_speed.json``. Run from the repository
root (git is used to load the enumeration of a base commit next to the current one):

    python scripts/bench_enumerate.py [--quick] [--base COMMIT] [--out-dir results]

For each target, in one run and interleaved (the machine is shared: only ratios within one run mean
anything):

* ``shortest``: the planner's search for the shortest plan without its certificate (branches in
  chunks of growing size ordered by their lower bound of ``a + b``, ``roots(..., first_only=True)``
  below the best length so far, as ``ReferencePlanner._solve_enumerated`` of tests/reference_enumerate.py does), with
  ``branches`` included; every root is taken as certified;
* ``all``: ``roots`` of every branch.

Times are min and median over the repeats, in ms, with the tables of k in memory (warm). The base
commit's module is the same file at that commit, loaded beside the current package (its leaf map is
the current one); ``--base none`` measures the current code only. High k (10, 20, K_MAX) is
measured for the current code only, with the answers (shortest length, number of roots) of both.
"""

from __future__ import annotations

import argparse
import datetime
import importlib.util
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import rollplan
from rollplan.io import write_atomic, write_json
from rollplan.problem import K_MAX

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import reference_enumerate as current  # noqa: E402  (tests/ is on the path: the numpy enumeration lives there)
from benchmark import git_commit, machine  # noqa: E402  (scripts/ is on the path)

ROOT = Path(__file__).resolve().parent.parent
#: (target (u, v, psi), steps, k): typical targets at k = 2.5, n = 1..5, |target| <= 1.5.
TARGETS = [((0.0, 1.0, 0.0), 1, 2.5), ((0.5, 0.3, 0.4), 2, 2.5), ((1.0, -0.5, 1.0), 3, 2.5),
           ((0.2, 0.2, -0.3), 1, 2.5), ((-0.7, 0.9, 2.0), 4, 2.5), ((0.0621, 0.0847, 2.4915), 5, 2.5),
           ((1.2, 0.6, -2.5), 5, 2.5), ((0.3, -0.2, 0.0), 2, 1.5)]
HIGH_K = [((0.0, 1.0, 0.0), 1, 10.0), ((0.3, 0.8, 0.5), 2, 20.0), ((3.0, 3.0, 0.0), 1, 20.0),
          ((0.0, 1.0, 0.0), 1, K_MAX), ((3.0, 3.0, 0.0), 1, K_MAX)]
_CHUNK = 64


def load_base(commit: str):
    """The enumeration module at ``commit``, loaded as ``rollplan.planners.geometric._enumerate_base``."""
    src = subprocess.run(["git", "-C", str(ROOT), "show", f"{commit}:rollplan/planners/geometric/enumerate.py"],
                         capture_output=True, text=True, check=True).stdout
    folder = Path(tempfile.mkdtemp(prefix="rollplan_enum_base_"))
    path = folder / "enumerate_base.py"
    path.write_text(src)
    name = "rollplan.planners.geometric._enumerate_base"
    spec = importlib.util.spec_from_file_location(name, path)
    mod = importlib.util.module_from_spec(spec)
    mod.__package__ = "rollplan.planners.geometric"
    sys.modules[name] = mod
    spec.loader.exec_module(mod)
    return mod


def shortest(mod, target, steps, k, **kw):
    """The planner's bounded search for the shortest root (module docstring): ``(m, a + b)`` or None;
    ``kw`` goes to ``roots``."""
    u, v, psi = target
    brs = mod.branches(k, psi, steps, math.hypot(u, v))
    best, found = math.inf, None
    start, size = 0, 4
    while start < len(brs):
        chunk = [br for br in brs[start:start + size] if br.y0 < best]
        start, size = start + size, min(2 * size, _CHUNK)
        if not chunk:
            break
        for r in mod.roots(chunk, k, first_only=True, lengths=(0.0, best), **kw):
            if r.a + r.b < best:
                best, found = r.a + r.b, (r.m, r.a + r.b)
    return found


def all_roots(mod, target, steps, k):
    u, v, psi = target
    return len(mod.roots(mod.branches(k, psi, steps, math.hypot(u, v)), k))


def times(fns, repeats):
    """Interleaved timings of the functions: per function (min wall, median wall, median CPU time of this
    process) [ms] (on a loaded machine the CPU time leaves out the time the process waited)."""
    ts = [[] for _ in fns]
    cs = [[] for _ in fns]
    for _ in range(repeats):
        for j, fn in enumerate(fns):
            t, c = time.perf_counter(), time.process_time()
            fn()
            cs[j].append(time.process_time() - c)
            ts[j].append(time.perf_counter() - t)
    return [(1e3 * min(t), 1e3 * statistics.median(t), 1e3 * statistics.median(c)) for t, c in zip(ts, cs)]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats and targets")
    ap.add_argument("--base", default="7936e69", help="commit of the enumeration to compare with ('none': skip)")
    ap.add_argument("--out-dir", default=str(ROOT / "results"))
    args = ap.parse_args(argv)
    out = Path(args.out_dir)
    base = None if args.base == "none" else load_base(args.base)
    mods = [current] + ([base] if base else [])
    reps_short, reps_all = (20, 3) if args.quick else (200, 10)
    targets = TARGETS[:3] if args.quick else TARGETS
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    rows = []
    for target, steps, k in targets:
        answers = [shortest(m, target, steps, k) for m in mods]      # also builds the tables (not timed)
        counts = [all_roots(m, target, steps, k) for m in mods]
        fns = [lambda m=m: shortest(m, target, steps, k) for m in mods]
        t_short = times(fns + [lambda: shortest(current, target, steps, k, polish=False)], reps_short)
        t_all = times([lambda m=m: all_roots(m, target, steps, k) for m in mods], reps_all)
        row = {"target": list(target), "n": steps, "k": k, "shortest (m, a + b)": answers[0], "roots": counts[0],
               "shortest min [ms]": t_short[0][0], "shortest median [ms]": t_short[0][1],
               "shortest CPU median [ms]": t_short[0][2], "unpolished min [ms]": t_short[-1][0],
               "unpolished CPU median [ms]": t_short[-1][2],
               "all min [ms]": t_all[0][0], "all median [ms]": t_all[0][1]}
        if base:
            row.update({"base shortest (m, a + b)": answers[1], "base roots": counts[1],
                        "base shortest min [ms]": t_short[1][0], "base shortest median [ms]": t_short[1][1],
                        "base shortest CPU median [ms]": t_short[1][2],
                        "base all min [ms]": t_all[1][0], "base all median [ms]": t_all[1][1],
                        "speed-up shortest (min)": t_short[1][0] / t_short[0][0],
                        "speed-up shortest (CPU median)": t_short[1][2] / t_short[0][2],
                        "speed-up all (min)": t_all[1][0] / t_all[0][0]})
        rows.append(row)
        print(row, file=sys.stderr)
    high = []
    for target, steps, k in ([] if args.quick else HIGH_K):
        current.rho_table(k)
        shortest(current, target, steps, k)
        (t_s,) = times([lambda: shortest(current, target, steps, k)], 3)
        t0 = time.perf_counter()
        n_all = all_roots(current, target, steps, k) if k <= 20 else None
        t_a = time.perf_counter() - t0
        best = shortest(current, target, steps, k)
        high.append({"target": list(target), "n": steps, "k": k, "shortest (m, a + b)": best,
                     "shortest min [ms]": t_s[0], "shortest median [ms]": t_s[1], "roots": n_all,
                     "all [ms]": 1e3 * t_a if n_all is not None else None})
        print(high[-1], file=sys.stderr)
    data = {"date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "commit": git_commit(), "base": args.base, "machine": machine(), "load average at start": load,
            "version": rollplan.__version__, "rows": rows, "high_k": high}
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "enumerate_speed.json", data)
    write_atomic(out / "enumerate_speed.md", render(data).encode())
    return 0


def _f(v):
    if v is None:
        return "-"
    if isinstance(v, float):
        return f"{v:.3g}" if abs(v) < 1000 else f"{v:.0f}"
    if isinstance(v, (tuple, list)) and len(v) == 2 and isinstance(v[1], float):
        return f"m = {v[0]}, {v[1]:.6f}"
    return str(v)


def render(data) -> str:
    lines = ["# Speed of the complete enumeration", "",
             f"Commit {data['commit']} against the enumeration of {data['base']}, {data['date']}, "
             f"{data['machine']['cpu']} ({data['machine']['cores']} cores), load average at start "
             f"{data['load average at start']:.2f}. Generated by `python scripts/bench_enumerate.py`; see its "
             "docstring for what is timed (warm tables, `branches` included, no certificate).", ""]
    rows = data["rows"]
    if rows:
        keys = [k for k in rows[0] if k not in ("target",)]
        lines += ["| target | " + " | ".join(keys) + " |", "|" + "---|" * (len(keys) + 1)]
        for r in rows:
            lines.append(f"| {tuple(r['target'])} | " + " | ".join(_f(r[k]) for k in keys) + " |")
    if data["high_k"]:
        lines += ["", "## High k (current code)", ""]
        keys = [k for k in data["high_k"][0] if k != "target"]
        lines += ["| target | " + " | ".join(keys) + " |", "|" + "---|" * (len(keys) + 1)]
        for r in data["high_k"]:
            lines.append(f"| {tuple(r['target'])} | " + " | ".join(_f(r[k]) for k in keys) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    raise SystemExit(main())
