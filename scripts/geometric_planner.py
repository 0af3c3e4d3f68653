#!/usr/bin/env python
"""The complete geometric-phase planner in numbers: completeness cases, step accuracy, speed.

Writes ``results/geometric_planner.md`` and ``results/geometric_planner.json``. Run from the
repository root:

    python scripts/geometric_planner.py [--quick] [--out-dir results]

Sections:

* the issue's three failures (shortest plan, all plans, branch 0) as the planner answers them now;
* ``step`` against scipy DOP853 on the printed equations (``scripts/benchmark.py:scipy_step`` at rtol
  1e-13) at the corners of the accepted domain;
* speed, as ratios measured in this run (the machine is shared: only ratios within one run mean
  anything): warm plans against the scipy shooting baseline of ``scripts/benchmark.py`` (DOP853 +
  least_squares, started 1e-3 from rollplan's own root on its branch, so given the branch and a close
  start for free, at rtol 1e-10 and 1e-13), and a high-k table (first plan with the per-k table,
  warm plan).
"""

from __future__ import annotations

import argparse
import datetime
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import rollplan
from rollplan.core.curves import A_MAX
from rollplan.core.plane import target_shift
from rollplan.io import write_atomic, write_json
from rollplan.problem import K_MAX

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import reference_enumerate as en  # noqa: E402  (tests/ is on the path: the numpy enumeration lives there)
from benchmark import _median_time, git_commit, machine, scipy_plan, scipy_step  # noqa: E402  (scripts/ is on the path)

PLAN_TARGETS = [((0.0, 1.0, 0.0), 1), ((0.5, 0.3, 0.4), 2), ((1.0, -0.5, 1.0), 3), ((0.2, 0.2, -0.3), 1)]
STEP_CASES = [(A_MAX, A_MAX, K_MAX), (0.6899, 0.05, 50.0), (A_MAX, A_MAX, 20.0), (A_MAX, A_MAX, 30.0),
              (0.3, 0.4, 2.5), (0.05, A_MAX, 100.0)]


def _median(fn, repeats):
    return _median_time(fn, repeats)[0]


def section_failures(quick):
    rows = []
    p = rollplan.plan((0.0621, 0.0847, 2.4915), steps=5, k=2.5, legs="one")
    rows.append({"case": "(0.0621, 0.0847, 2.4915), n = 5, k = 2.5, shortest", "issue": "L = 35.723 exists on m = -5",
                 "now": f"L = {p.path_length:.6f} on m = {p.branch}", "residual": p.residual})
    q = rollplan.plan((-0.2724, 0.1488, -2.9291), steps=3, k=2.5, branch=0, legs="one")
    rows.append({"case": "(-0.2724, 0.1488, -2.9291), n = 3, k = 2.5, branch 0", "issue": "L = 19.4840 exists",
                 "now": f"L = {q.path_length:.6f} on m = {q.branch}", "residual": q.residual})
    if not quick:
        a = rollplan.plan((0.2, 0.1, 2.0), steps=3, k=2.5, all_solutions=True, legs="one")
        plans = (a,) + a.alternatives
        rows.append({"case": "(0.2, 0.1, 2), n = 3, k = 2.5, all plans", "issue": "at least 46 exist",
                     "now": f"{len(plans)} certified plans", "residual": max(x.residual for x in plans)})
    return {"title": "The issue's failures", "rows": rows}


def section_step(quick):
    rows = []
    for a, b, k in STEP_CASES[:3] if quick else STEP_CASES:
        s = rollplan.step(a, b, k=k)
        ref = scipy_step(a, b, k, rtol=1e-13, atol=1e-15)
        rows.append({"a": a, "b": b, "k": k, "shift": f"({s.shift[0]:.10f}, {s.shift[1]:.10f})",
                     "eta": s.eta, "max |error| vs DOP853": float(np.abs(np.r_[s.shift, s.eta] - ref).max())})
    return {"title": "step against DOP853 (rtol 1e-13) on the printed equations", "rows": rows}


def _baseline(p, target, rtol):
    """The scipy shooting baseline on the plan's branch, started 1e-3 from its root."""
    eta_m = (rollplan.core.plane.wrap(target[2]) + 2 * math.pi * p.branch) / p.steps
    h_m = float(target_shift(math.hypot(target[0], target[1]), eta_m, p.steps))
    x0 = (min(p.a + 1e-3, A_MAX), max(p.b - 1e-3, 1e-6))
    return lambda: scipy_plan(target, p.steps, p.k, x0, eta_m, h_m, rtol=rtol)


def section_speed(quick):
    rows = []
    repeats = 5 if quick else 21
    for target, steps in PLAN_TARGETS[:2] if quick else PLAN_TARGETS:
        p = rollplan.plan(target, steps=steps, k=2.5, legs="one")
        warm = _median(lambda t=target, s=steps: rollplan.plan(t, steps=s, k=2.5, legs="one"), repeats)
        base = _median(_baseline(p, target, 1e-10), 3)
        base13 = _median(_baseline(p, target, 1e-13), 3)
        rows.append({"target": str(target), "n": steps, "rollplan warm [ms]": warm * 1e3,
                     "scipy rtol 1e-10 [ms]": base * 1e3, "scipy rtol 1e-13 [ms]": base13 * 1e3,
                     "speed-up vs 1e-10": base / warm, "speed-up vs 1e-13": base13 / warm, "residual": p.residual})
    return {"title": "Warm plans (k = 2.5) against the scipy shooting baseline, same run", "rows": rows}


def section_high_k(quick):
    rows = []
    saved = os.environ.get("ROLLPLAN_CACHE_DIR")
    for k in ((10.0, 30.0) if quick else (10.0, 20.0, 30.0, 50.0, K_MAX)):
        with tempfile.TemporaryDirectory() as cache:     # an empty disk cache: the table is built, then loaded
            os.environ["ROLLPLAN_CACHE_DIR"] = cache
            en.rho_table.cache_clear()
            t = time.perf_counter()
            table = en.rho_table(k)
            t_table = time.perf_counter() - t
            en.rho_table.cache_clear()
            t = time.perf_counter()
            en.rho_table(k)
            t_load = time.perf_counter() - t
            en.rho_table.cache_clear()
            t = time.perf_counter()
            rollplan.plan((0.0, 1.0, 0.0), k=k, legs="one")
            t_cold_cached = time.perf_counter() - t
        if saved is None:
            os.environ.pop("ROLLPLAN_CACHE_DIR", None)
        else:
            os.environ["ROLLPLAN_CACHE_DIR"] = saved
        t = time.perf_counter()
        p = rollplan.plan((0.0, 1.0, 0.0), k=k, legs="one")
        first = time.perf_counter() - t   # the table is in memory now
        warm = _median(lambda k=k: rollplan.plan((0.3, 0.8, 0.5), k=k, legs="one"), 3)
        t = time.perf_counter()
        try:
            rollplan.plan((3.0, 3.0, 0.0), k=k, legs="one")
            none = "plan"
        except rollplan.NoPlanError:
            none = "no plan"
        t_none = time.perf_counter() - t
        rows.append({"k": k, "table radii": table.r.size, "table eps": table.eps, "table built [s]": t_table,
                     "table loaded [s]": t_load, "first plan, table on disk [s]": t_cold_cached,
                     "plan (0, 1, 0), table in memory [s]": first, "warm plan (0.3, 0.8, 0.5) [s]": warm,
                     "(3, 3, 0) answer": none, "(3, 3, 0) [s]": t_none,
                     "branches (0, 1, 0)": p.stats.details["branches"], "residual (0, 1, 0)": p.residual})
    return {"title": "High k: per-k table (built in an empty cache, then loaded from disk), plans, a target "
                     "without a plan", "rows": rows}


def _fmt(v):
    if isinstance(v, float):
        return f"{v:.3g}" if (abs(v) >= 1e-3 or v == 0) else f"{v:.2e}"
    return str(v)


def to_markdown(report):
    out = ["# The complete geometric-phase planner in numbers", ""]
    out += [f"- date: {report['date']}", f"- commit: `{report['commit']}`", f"- machine: {report['machine']}",
            f"- command: `{report['command']}`", ""]
    for sec in report["sections"]:
        out += [f"## {sec['title']}", ""]
        keys = list(sec["rows"][0])
        out += ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
        out += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in sec["rows"]]
        out.append("")
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer cases and repeats")
    ap.add_argument("--out-dir", default="results")
    args = ap.parse_args(argv)
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    sections = [section_failures(args.quick), section_step(args.quick), section_speed(args.quick),
                section_high_k(args.quick)]
    m = machine()
    report = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
              "commit": git_commit(), "machine": m if isinstance(m, str) else json.dumps(m),
              "command": "python scripts/geometric_planner.py" + (" --quick" if args.quick else ""),
              "load": os.getloadavg(), "sections": sections}
    write_json(out / "geometric_planner.json", report)
    write_atomic(out / "geometric_planner.md", to_markdown(report).encode())
    print(f"wrote {out / 'geometric_planner.md'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
