#!/usr/bin/env python
"""Benchmarks of rollplan against a hand-written scipy baseline.

Writes ``results/benchmarks.md`` (tables, machine, date, commit, profile) and
``results/benchmarks.json``. Run from the repository root:

    python scripts/benchmark.py [--quick] [--no-jit] [--out-dir results] [--only plan cold high_k]
                                [--build-dir DIR]

The benchmark is a list of sections (:data:`SECTIONS`). A section is a
function ``section(ctx) -> dict`` returning ``{"title": str, "rows": [dict],
"notes": [str], ...}``; rows become a markdown table (columns in the order of
the first row's keys). To add a planner, write a section function and append
it to :data:`SECTIONS`. Sections: the geometric-phase plan against scipy (warm,
with the share of the IPOPT polish and of the RK8 certificate), the cold start of
`rollplan plan`, plans at high k, the step map, the collocation planner
(``scripts/bench_collocation.py:measure``), the generated C planner
(``scripts/bench_codegen.py:measure``; skipped without a C compiler), memory, a
profile, batches, `plan --all` per plan listed, the default plan between full states
(``scripts/bench_default.py:measure``), and the budgets of the issues with their measured values
(shown first). ``--only`` reruns some sections and keeps the others from the
existing ``benchmarks.json`` (each section carries its own date and commit). The
load average at start is recorded: the machine is shared. ``--build-dir DIR`` keeps
the C planner's build of the c_planner section (``DIR/host-<digest>``, :func:`bench_codegen.kept`) for later runs
of the same sources and compilers.

The scipy baseline is what a researcher would write by hand from the paper:
the printed equations (28)-(30) for the figure eight of circles (35) in numpy
(nothing from rollplan), integrated by ``solve_ivp`` (DOP853 at rtol 1e-12 or
1e-13), and (32)-(33) solved by ``scipy.optimize.least_squares`` (trust-region
reflective, bounds (0, A_MAX], 2-point finite-difference Jacobian). It is started
1e-3 from rollplan's plan on the plan's branch (same eta_m and h_m), i.e. it gets
the branch selection and a close start for free, untimed. Both plans' gamma come
from the same composition rule, and both plans are checked by the same
independent CVODES integration (``GeometricPhasePlanner(certifier="cvodes")``).
"""

from __future__ import annotations

import argparse
import cProfile
import datetime
import json
import math
import os
import platform
import pstats
import resource
import shutil
import statistics
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import casadi as ca
import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.optimize import least_squares

import rollplan
from rollplan import Problem
from rollplan.core.curves import A_MAX
from rollplan.core.plane import target_shift, wrap
from rollplan.io import write_atomic, write_json
from rollplan.planners import geometric

import bench_batch
import bench_codegen
import bench_collocation
from suite_report import processor

K = 2.5
#: (target (u_a, v_a, psi), steps) of the plan benchmark, all at k = K.
TARGETS = [((0.0, 1.0, 0.0), 1), ((0.5, 0.3, 0.4), 2), ((1.0, -0.5, 1.0), 3), ((0.2, 0.2, -0.3), 1)]
#: Issue 11's budgets: warm plan median, speed-up over the baseline at equal accuracy, cold start ratio.
BUDGET_PLAN_MS = 2.0
BUDGET_COLD_RATIO = 2.0
BUDGET_RATIO = 50.0
BUDGET_STEP_EVALS = 20000.0
#: Issue 2's budget: a single plan under 50 ms median.
BUDGET_PLAN_MS_FOUNDATION = 50.0
#: Issue 6's budget: a C plan under 1 ms.
BUDGET_C_PLAN_US = 1000.0
#: Issue 28's budgets: warm plan median, speed-up over the baseline at equal accuracy, plan_many on 2 cores.
BUDGET_PLAN_MS_28 = 0.5
BUDGET_RATIO_28 = 300.0
BUDGET_MANY_PER_S = 5000.0
#: Issue 28's budget: `plan --all` at most this many ms per plan listed (k = 12, n = 4).
BUDGET_ALL_MS_PER_PLAN = 5.0
#: (target, steps, k) of the --all section (issue 28's case), and of its --quick smoke run.
ALL_CASE = ((0.0, 1.0, 0.0), 4, 12.0)
ALL_CASE_QUICK = ((0.0, 1.0, 0.0), 1, 2.5)


# ----------------------------------------------------------------------------- scipy baseline (by hand)


def _circle(a, phi, side):
    """Circle (35) of radius a through the south pole (side +1: +y leaf, -1: -y leaf) and d/dphi."""
    d = math.sqrt(1.0 - a * a)
    s, c = math.sin(phi), math.cos(phi)
    return (a * s, side * (d * a - a * d * c), -a * a * c - d * d), (a * c, side * a * d * s, a * a * s)


def _rhs(phi, state, a, side, k):
    """The paper's printed (28)-(30), R = 1, gamma = 0 ((29)'s ``v^2`` read as ``y^2``)."""
    (x, y, z), (xt, yt, zt) = _circle(a, phi, side)
    psi = state[2]
    s = math.sqrt(1.0 - y * y)
    cut = z * xt - x * zt                                   # c_u . c_theta, (26)
    cvt = (-x * y * xt - y * z * zt) / s + s * yt           # c_v . c_theta, (26)
    cp, sp = math.cos(psi), math.sin(psi)
    return [-cp / s * cut + sp * cvt, sp / s * cut + cp * cvt,
            (1 - k) * y * cut / (s * s) + k * x * cvt / (z * s)]


def scipy_step(a, b, k, rtol=1e-10, atol=1e-12):
    """(u_a, v_a, psi) after one figure eight from zero, gamma = 0, by DOP853."""
    x = [0.0, 0.0, 0.0]
    for r, side in ((a, 1.0), (b, -1.0)):
        x = solve_ivp(_rhs, (0.0, 2 * math.pi), x, method="DOP853", rtol=rtol, atol=atol, args=(r, side, k)).y[:, -1]
    return np.asarray(x)


def scipy_plan(target, steps, k, x0, eta_m, h_m, rtol=1e-10):
    """Solve (32)-(33) with least_squares from x0 on the branch (eta_m, h_m); gamma by composition."""
    atol = rtol * 1e-2

    def residual(ab):
        x = scipy_step(ab[0], ab[1], k, rtol, atol)
        return [x[2] - eta_m, math.hypot(x[0], x[1]) - h_m]

    sol = least_squares(residual, x0, bounds=([1e-6, 1e-6], [A_MAX, A_MAX]), xtol=1e-15, ftol=1e-15, gtol=1e-15,
                        method="trf", diff_step=1e-7)
    a, b = sol.x
    x = scipy_step(a, b, k, rtol, atol)
    total = complex(x[0], x[1]) * complex(np.exp(-1j * x[2] * np.arange(steps)).sum())
    gamma = math.atan2(target[1], target[0]) - math.atan2(total.imag, total.real)
    return a, b, gamma, sol.nfev


# ----------------------------------------------------------------------------- helpers


def _median_time(fn, repeats):
    ts = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t)
    return statistics.median(ts), ts


def _median_times(fn, repeats):
    """(median wall time, median CPU time of this process, wall times) [s]."""
    wall, cpu = [], []
    for _ in range(repeats):
        t, c = time.perf_counter(), time.process_time()
        fn()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - t)
    return statistics.median(wall), statistics.median(cpu), wall


def verified_residual(verifier, a, b, k, gamma, steps, target):
    """Residual of the independent CVODES integration to the target, as rollplan reports it."""
    return Problem(target, k=k, steps=steps).residual(verifier.certifier.final(a, b, k, gamma, steps))


def _start_near(p, target):
    """The baseline's start: 1e-3 from rollplan's plan in a and in b, on the plan's branch (eta_m, h_m)."""
    h_des = math.hypot(target[0], target[1])
    eta_m = (float(wrap(target[2])) + 2 * math.pi * p.branch) / p.steps
    return (min(p.a + 1e-3, A_MAX), max(p.b - 1e-3, 1e-6)), eta_m, float(target_shift(h_des, eta_m, p.steps))


def _cold_plan_ms(target, steps, k):
    """First plan in a fresh interpreter: import, planner construction and per-k tables included."""
    code = ("import time; t0 = time.perf_counter(); import rollplan; t1 = time.perf_counter(); "
            f"p = rollplan.plan({tuple(target)!r}, {steps}, k={k}); t2 = time.perf_counter(); "
            "import resource; print((t1 - t0) * 1e3, (t2 - t1) * 1e3, p.stats.time_s * 1e3, "
            "resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    return [float(v) for v in out]


def _phases(p, target):
    """Median wall and CPU times [ms] of the polish and certificate of ``root_solver="ipopt"`` (IPOPT from the
    enumerated root, the Python RK8 certificate), measured alone on the plan's own root: ``(wall polish, wall
    certificate, CPU polish, CPU certificate)``; the default plan runs neither (one C call)."""
    from rollplan.planners.geometric.leafmap import panels_for
    from rollplan.planners.geometric.refine import polisher

    planner = geometric.default_planner()
    _, eta_m, h_m = _start_near(p, target)
    solve = polisher("ipopt", panels_for(p.k))
    t_polish, c_polish, _ = _median_times(lambda: solve([p.a, p.b], [p.k, eta_m, h_m], 1e-6, A_MAX), 41)
    t_cert, c_cert, _ = _median_times(lambda: planner.certifier.certify(p.a, p.b, p.k, p.gamma, p.steps), 41)
    return t_polish * 1e3, t_cert * 1e3, c_polish * 1e3, c_cert * 1e3


# ----------------------------------------------------------------------------- sections


def section_plan(ctx):
    """rollplan.plan (warm) against the scipy baseline on the same targets, at equal accuracy."""
    verifier = geometric.GeometricPhasePlanner(certifier="cvodes")
    rows, raw = [], []
    for target, steps in TARGETS[:1] if ctx["quick"] else TARGETS:
        p = rollplan.plan(target, steps, k=K)                 # warms the planner, per-k tables, compiled functions
        t_warm, c_warm, ts = _median_times(lambda: rollplan.plan(target, steps, k=K), ctx["repeats"])
        t_newton, _ = _median_time(lambda: rollplan.plan(target, steps, k=K, root_solver="newton"), ctx["repeats"])
        t_ipopt, _ = _median_time(lambda: rollplan.plan(target, steps, k=K, root_solver="ipopt"), ctx["repeats"])
        t_polish, t_cert, c_polish, c_cert = _phases(p, target)
        x0, eta_m, h_m = _start_near(p, target)
        res = {}
        base = {}
        for rtol in (1e-12, 1e-13):
            t_s, c_s, ts_s = _median_times(
                lambda rtol=rtol: res.update({rtol: scipy_plan(target, steps, K, x0, eta_m, h_m, rtol=rtol)}),
                ctx["scipy_repeats"])
            a_s, b_s, g_s, nfev = res[rtol]
            base[rtol] = (t_s, c_s, ts_s, verified_residual(verifier, a_s, b_s, K, g_s, steps, target), nfev)
        r_roll = verified_residual(verifier, p.a, p.b, K, p.gamma, steps, target)
        row = {"target (u_a, v_a, psi)": str(tuple(target)), "n": steps, "m": p.branch,
               "search": p.stats.details["search"],
               "rollplan warm [ms]": t_warm * 1e3, "rollplan warm CPU [ms]": c_warm * 1e3,
               "IPOPT polish alone [ms] (CPU)": f"{t_polish:.2f} ({c_polish:.2f})",
               "Python RK8 certificate alone [ms] (CPU)": f"{t_cert:.2f} ({c_cert:.2f})",
               "root_solver newton warm [ms]": t_newton * 1e3, "root_solver ipopt warm [ms]": t_ipopt * 1e3,
               "default root solver": p.stats.method,
               "scipy rtol 1e-12 [ms]": base[1e-12][0] * 1e3, "scipy rtol 1e-13 [ms]": base[1e-13][0] * 1e3,
               "speed-up vs 1e-12": base[1e-12][0] / t_warm, "speed-up vs 1e-13": base[1e-13][0] / t_warm,
               "speed-up vs 1e-13 (CPU)": base[1e-13][1] / c_warm,
               "residual rollplan (CVODES)": r_roll, "certified residual + bound": p.residual
               + p.certificate.error_bound,
               "residual scipy 1e-12": base[1e-12][3], "residual scipy 1e-13": base[1e-13][3],
               "scipy nfev 1e-13": base[1e-13][4]}
        rows.append(row)
        raw.append({"warm_s": ts, "scipy_1e-12_s": base[1e-12][2], "scipy_1e-13_s": base[1e-13][2]})
    warm = statistics.median(r["rollplan warm [ms]"] for r in rows)
    warm_cpu = statistics.median(r["rollplan warm CPU [ms]"] for r in rows)
    ratio = min(r["speed-up vs 1e-13"] for r in rows)
    ratio12 = min(r["speed-up vs 1e-12"] for r in rows)
    ratio_cpu = min(r["speed-up vs 1e-13 (CPU)"] for r in rows)
    acc = all(r["residual rollplan (CVODES)"] <= max(r["residual scipy 1e-13"], 1e-12) for r in rows)
    notes = [f"k = {K}; warm = median of {ctx['repeats']} calls of rollplan.plan after one warm-up (planner, per-k "
             "tables and compiled functions loaded); scipy = median of "
             f"{ctx['scipy_repeats']} runs. The default plan is one call of the C planner (search, Newton polish, "
             "RK8 certificate: planners/geometric/compiled_search.py, certified_plan); the root_solver ipopt and "
             "newton columns are the Python path (the C search's root polished again, then the Python RK8 "
             "certificate), measured side by side; 'alone' columns: the IPOPT polish and the Python RK8 certificate "
             "of that path timed alone on the plan's root (median of 41). Which plans IPOPT changes: "
             "results/polish_ipopt.md (scripts/polish_ipopt.py).",
             "Residual (CVODES) = |(u_a, v_a, psi, u_o, v_o) - (target, 0, 0)| after n steps by the same CVODES "
             f"verifier ({ctx['verifier']}) for both plans; 'certified residual + bound' is rollplan's own RK8 "
             "certificate (accepted when <= 1e-9).",
             "scipy baseline, written by hand from the paper: the printed (28)-(30) in numpy, solve_ivp DOP853 "
             "(rtol 1e-12, atol 1e-14, or rtol 1e-13, atol 1e-15), least_squares (trf, bounds (1e-6, A_MAX], "
             "2-point FD Jacobian, diff_step 1e-7, x/f/gtol 1e-15), started 1e-3 from rollplan's plan in a and b on "
             "the plan's branch (it is given the branch and a close start, untimed); gamma by the same "
             "composition rule. rtol 1e-13 is the equal-accuracy comparison (its residual is of the order of "
             "rollplan's), rtol 1e-12 is shown for reference.",
             f"Budget warm plan <= {BUDGET_PLAN_MS:g} ms median: {_status(warm <= BUDGET_PLAN_MS)} (median over "
             f"targets {warm:.2f} ms wall, {warm_cpu:.2f} ms CPU time). Budget >= {BUDGET_RATIO:g}x faster than the "
             "baseline at equal accuracy: "
             f"{_status(ratio >= BUDGET_RATIO and acc)} (smallest speed-up {ratio:.1f}x wall vs rtol 1e-13, "
             f"{ratio_cpu:.1f}x CPU time; {ratio12:.1f}x vs rtol 1e-12; rollplan residual <= max(scipy's, 1e-12) "
             f"on every target: {acc}).",
             f"Issue 28: warm plan <= {BUDGET_PLAN_MS_28:g} ms median: {_status(warm <= BUDGET_PLAN_MS_28)}; "
             f">= {BUDGET_RATIO_28:g}x the baseline at equal accuracy: "
             f"{_status(ratio >= BUDGET_RATIO_28 and acc)} ({ratio:.1f}x)."]
    return {"title": "Plan: rollplan.plan against a hand-written scipy baseline", "rows": rows, "notes": notes,
            "raw": raw, "summary": {"median_warm_ms": warm, "median_warm_cpu_ms": warm_cpu, "min_speedup": ratio,
                                    "min_speedup_cpu": ratio_cpu, "min_speedup_vs_rtol_1e-12": ratio12,
                                    "accuracy_ok": acc}}


COLD_ARGS = ["plan", "--to", "1", "-0.5", "--psi", "1", "--steps", "3", "--k", "2.5"]


def _wall(cmd, env=None):
    t = time.perf_counter()
    subprocess.run(cmd, capture_output=True, check=True, env=env)
    return time.perf_counter() - t


def section_cold(ctx):
    """A cold `rollplan plan` (compiled functions and tables cached on disk) against the start of Python with
    casadi, numpy and matplotlib, alternated, in one run."""
    if not ctx["cold"]:
        return {"title": "Cold start", "rows": [], "notes": ["skipped (--no-cold)."], "summary": None}
    exe = shutil.which("rollplan") or ""
    plan_cmd = [exe, *COLD_ARGS] if exe else [sys.executable, "-m", "rollplan.cli", *COLD_ARGS]
    base_cmd = [sys.executable, "-c", "import casadi, numpy, matplotlib"]
    _wall(plan_cmd)                                              # fills the disk caches (compiled, tables)
    plan_t, base_t = [], []
    for _ in range(ctx["cold_repeats"]):
        plan_t.append(_wall(plan_cmd))
        base_t.append(_wall(base_cmd))
    ratio = statistics.median(plan_t) / statistics.median(base_t)
    rows = [{"command": " ".join(["rollplan", *COLD_ARGS]), "median [s]": statistics.median(plan_t),
             "min [s]": min(plan_t)},
            {"command": 'python -c "import casadi, numpy, matplotlib"', "median [s]": statistics.median(base_t),
             "min [s]": min(base_t)}]
    notes = [f"{ctx['cold_repeats']} alternated runs of each after one run that fills the disk caches (compiled "
             "CasADi functions, leaf tables); wall time of the whole process.",
             f"Budget cold `rollplan plan` <= {BUDGET_COLD_RATIO:g}x the start of Python with casadi, numpy and "
             f"matplotlib: {_status(ratio <= BUDGET_COLD_RATIO)} (ratio of medians {ratio:.2f}, of minima "
             f"{min(plan_t) / min(base_t):.2f})."]
    return {"title": "Cold start: `rollplan plan` against importing casadi, numpy and matplotlib", "rows": rows,
            "notes": notes, "summary": {"ratio": ratio, "ratio_min": min(plan_t) / min(base_t),
                                        "plan_s": plan_t, "base_s": base_t}}


#: (target, steps) of the high-k table.
HIGH_K_TARGETS = [((0.0, 1.0, 0.0), 1), ((0.5, 0.3, 0.4), 2)]


def section_high_k(ctx):
    """Plans at high k: first call in this process (tables loaded or built) and warm, certified residual."""
    from rollplan.problem import K_MAX

    rows = []
    for k in (10.0, 20.0, 30.0, K_MAX):
        for target, steps in HIGH_K_TARGETS[:1] if ctx["quick"] else HIGH_K_TARGETS:
            t0 = time.perf_counter()
            try:
                p = rollplan.plan(target, steps, k=k)
                outcome = f"m = {p.branch}, L = {p.path_length:.4f}"
            except rollplan.NoPlanError as exc:
                p, outcome = None, f"no plan ({str(exc)[:60]}...)"
            first = time.perf_counter() - t0
            warm = float("nan")
            if p is not None:
                warm, _ = _median_time(lambda k=k, target=target, steps=steps: rollplan.plan(target, steps, k=k),
                                       ctx["high_k_repeats"])
            rows.append({"k": k, "target (u_a, v_a, psi)": str(target), "n": steps, "outcome": outcome,
                         "first call [s]": first, "warm [ms]": warm * 1e3,
                         "certified residual": p.residual if p else float("nan"),
                         "error bound": p.certificate.error_bound if p else float("nan")})
    notes = [f"First call: the first plan at this k in this process (per-k tables from the disk cache when present); "
             f"warm: median of {ctx['high_k_repeats']}. Certified residual and RK8 error bound of the returned plan."]
    return {"title": "High k", "rows": rows, "notes": notes,
            "summary": {"max_warm_ms": max((r["warm [ms]"] for r in rows if r["warm [ms]"] == r["warm [ms]"]),
                                           default=float("nan"))}}


def _compile_step(F, folder, flags):
    """Generated C of the step map, compiled to a shared library by gcc; its path."""
    c_file = os.path.join(folder, "rollplan_step.c")
    so = os.path.join(folder, "rollplan_step.so")
    cg = ca.CodeGenerator("rollplan_step.c", {"with_header": False})
    cg.add(ca.Function("rollplan_step", F.sx_in(), F.call(F.sx_in())))
    cg.generate(folder + os.sep)
    subprocess.run(["gcc", *flags.split(), "-shared", c_file, "-o", so, "-lm"], check=True)
    return so


_WORKER_STEP = {}


def _load_step(so):
    _WORKER_STEP["f"] = ca.external("rollplan_step", so)


def _eval_chunk(chunk):
    f = _WORKER_STEP["f"].map(chunk.shape[1])
    return np.array(f(np.zeros(3), chunk, K, 0))


def section_step_map(ctx):
    """Evaluations per second of the spectral step map, one at a time, batched, threaded, compiled."""
    planner = geometric.default_planner()
    F = planner.step_map
    n = ctx["batch"]
    rng = np.random.default_rng(0)
    pts = rng.uniform(0.02, A_MAX, (2, n))
    check = pts[:, : ctx["check_points"]]
    ref = np.column_stack([scipy_step(a, b, K, rtol=1e-13, atol=1e-14) for a, b in check.T])
    threads = os.cpu_count() or 1
    zeros = ca.DM.zeros(3)
    rows = []

    def add(name, fun, run, evals, build_s=0.0):
        t, _ = _median_time(run, ctx["map_repeats"])
        err = float(np.abs(np.array(fun.map(check.shape[1])(zeros, check, K, 0)) - ref).max())
        rows.append({"variant": name, "evaluations/s": evals / t, "time per eval [us]": t / evals * 1e6,
                     "build [s]": build_s, "max |error| vs scipy": err})

    one_n = min(n, ctx["single_evals"])
    add("SX, one call per point (Python loop)", F, lambda: [F(zeros, pts[:, j], K, 0) for j in range(one_n)], one_n)
    serial = F.map(n)
    add("SX, map serial", F, lambda: serial(zeros, pts, K, 0), n)
    thread = F.map(n, "thread", threads)
    add(f"SX, map thread x{threads}", F, lambda: thread(zeros, pts, K, 0), n)
    if ctx["jit"]:
        t0 = time.perf_counter()
        jit = ca.Function("step_jit", F.sx_in(), F.call(F.sx_in()), F.name_in(), F.name_out(),
                          {"jit": True, "compiler": "shell", "jit_cleanup": True,
                           "jit_options": {"flags": ctx["jit_flags"].split(), "verbose": False}})
        build = time.perf_counter() - t0
        jserial = jit.map(n)
        add(f"JIT C ({ctx['jit_flags']}), map serial", jit, lambda: jserial(zeros, pts, K, 0), n, build)
        jthread = jit.map(n, "thread", threads)
        add(f"JIT C ({ctx['jit_flags']}), map thread x{threads}", jit, lambda: jthread(zeros, pts, K, 0), n, build)
        if threads > 1:
            # the same compiled code in one process per core (generated C loaded with ca.external)
            import multiprocessing
            import tempfile

            with tempfile.TemporaryDirectory() as tmp:
                t0 = time.perf_counter()
                so = _compile_step(F, tmp, ctx["jit_flags"])
                build = time.perf_counter() - t0
                chunks = np.array_split(pts, threads, axis=1)
                with multiprocessing.get_context("spawn").Pool(threads, _load_step, (so,)) as pool:
                    pool.map(_eval_chunk, chunks)                  # warm-up: load the library in every worker
                    ext = ca.external("rollplan_step", so)
                    add(f"generated C ({ctx['jit_flags']}), {threads} processes", ext,
                        lambda: pool.map(_eval_chunk, chunks, chunksize=1), n, build)
    scipy_n = max(4, ctx["single_evals"] // 25)
    t, _ = _median_time(lambda: [scipy_step(a, b, K) for a, b in pts[:, :scipy_n].T], 1)
    rows.append({"variant": "scipy DOP853 rtol 1e-10 (baseline's map)", "evaluations/s": scipy_n / t,
                 "time per eval [us]": t / scipy_n * 1e6, "build [s]": 0.0,
                 "max |error| vs scipy": float(np.abs(np.column_stack([scipy_step(a, b, K) for a, b in check.T])
                                                   - ref).max())})
    batched = [r for r in rows if "map" in r["variant"] or "processes" in r["variant"]]
    best_row = max(batched, key=lambda r: r["evaluations/s"])
    best = best_row["evaluations/s"]
    notes = [f"k = {K}, {n} random (a, b) in (0.02, A_MAX); median of {ctx['map_repeats']} runs; {threads} cores. "
             f"Accuracy: max abs error of (u_a, v_a, psi) against scipy DOP853 at rtol 1e-13 on the printed "
             f"(28)-(30) at {check.shape[1]} points.",
             f"Budget batched >= {BUDGET_STEP_EVALS:g} evaluations/s on 2 cores: "
             f"{'MET' if best >= BUDGET_STEP_EVALS else 'MISSED'} (best batched {best:.0f}/s)."]
    return {"title": "Step map (one figure eight, spectral, 90k SX instructions)", "rows": rows, "notes": notes,
            "summary": {"best_batched_per_s": best, "best_batched_variant": best_row["variant"]}}


def section_memory(ctx):
    """Peak memory of a plan: tracemalloc (Python heap) and the process's max RSS."""
    target, steps = TARGETS[1]
    rollplan.plan(target, steps, k=K)
    tracemalloc.start()
    rollplan.plan(target, steps, k=K)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    tracemalloc.start()
    geometric.GeometricPhasePlanner().solve(Problem(target, k=K, steps=steps))
    _, peak_cold = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    rss_self = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    cold = _cold_plan_ms(target, steps, K)
    code = "import time, resource; import rollplan; print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)"
    rss_import = float(subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                                      check=True).stdout)
    rows = [{"what": "warm plan, Python heap peak (tracemalloc)", "MiB": peak / 2**20},
            {"what": "new planner + first plan at this k, Python heap peak (tracemalloc)", "MiB": peak_cold / 2**20},
            {"what": "fresh process: import rollplan, max RSS", "MiB": rss_import / 1024},
            {"what": "fresh process: import + first plan, max RSS", "MiB": cold[3] / 1024},
            {"what": "this benchmark process so far, max RSS", "MiB": rss_self / 1024}]
    notes = [f"Target {target}, n = {steps}, k = {K}. tracemalloc sees Python allocations only (numpy arrays "
             "included, CasADi's C++ heap not); max RSS is the whole process (ru_maxrss)."]
    return {"title": "Memory of a plan", "rows": rows, "notes": notes}


def section_profile(ctx):
    """Where the time of one warm plan goes (cProfile over repeated plans)."""
    planner = geometric.default_planner()
    target, steps = TARGETS[1]
    problem = Problem(target, k=K, steps=steps)
    planner.solve(problem)
    reps = ctx["repeats"]
    prof = cProfile.Profile()
    prof.enable()
    for _ in range(reps):
        planner.solve(problem)
    prof.disable()
    st = pstats.Stats(prof)
    total = 0.0
    parts = {}
    wanted = {("planner.py", "solve"): "whole plan (GeometricPhasePlanner.solve)",
              ("enumerate.py", "branches"): "branches (enumeration)",
              ("enumerate.py", "roots"): "roots of the branches (enumeration)",
              ("planner.py", "_polish"): f"polish ({planner.root_solver})",
              ("certify.py", "certify"): "certificate (RK8, n steps)",
              ("planner.py", "_certified"): "gamma + certificate",
              ("compiled_search.py", "certified_plan"): "C planner: search, polish, certificate (one call)"}
    plan_line = geometric.GeometricPhasePlanner.solve.__code__.co_firstlineno
    for (file, line, name), (_cc, _nc, _tt, ct, _callers) in st.stats.items():
        base = os.path.basename(file)
        key = wanted.get((base, name))
        if (base, name) == ("planner.py", "solve") and line != plan_line:
            key = None
        if key is not None:
            parts[key] = parts.get(key, 0.0) + ct / reps * 1e3
    total = parts.get("whole plan (GeometricPhasePlanner.solve)", float("nan"))
    rows = [{"part": k, "ms per plan": v, "share": v / total} for k, v in sorted(parts.items(), key=lambda kv: -kv[1])]
    lines = []
    import io

    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("cumulative").print_stats(12)
    lines = [ln for ln in buf.getvalue().splitlines() if ln.strip()][:30]
    return {"title": f"Profile of one warm plan (target {target}, n = {steps}, k = {K}, {reps} plans)",
            "rows": rows, "notes": ["cProfile cumulative times divided by the number of plans (profiling "
                                    "overhead included)."], "text": "\n".join(lines)}


def section_collocation(ctx):
    """Collocation planner, N = 100, d = 3 (Legendre), warm start: median IPOPT time; naive-guess convergence."""
    targets = bench_collocation.TARGETS[: ctx["coll_targets"]]
    res = bench_collocation.measure(ctx["coll_repeats"], targets, K)
    rows = [{"target (u_a, v_a, psi)": str(r["target"]), "warm: status": r["status"],
             "warm: iterations": r["iterations"],
             "warm: median IPOPT [s]": r["median_s"], "warm: verified residual": r["residual"],
             "naive: status": r["naive_status"], "naive: iterations": r["naive_iterations"] if r["naive_iterations"]
             is not None else "-", "naive: IPOPT [s]": r["naive_s"] if r["naive_s"] is not None else float("nan")}
            for r in res["rows"]]
    notes = [f"rollplan.collocation.CollocationPlanner(N = {res['intervals']}, d = {res['degree']}, {res['scheme']}, "
             f"cost {res['cost']}), k = {K}; NLP built once in {res['build_s']:.2f} s (not timed). Warm start = the "
             f"geometric-phase plan (n = 1); time = IPOPT wall time (solve_time_s), {res['repeats']} solves per target "
             "(a failed solve counts as infinite). Residual = CVODES integration of the optimized controls. Naive = "
             "one solve from the straight-line guess at rest on the south pole, same psi branch. Measured by "
             "scripts/bench_collocation.py:measure.",
             f"Naive guess converged on {res['naive_converged']} of {res['naive_total']} targets "
             f"(warm start: {sum(r['status'] == 'Solve_Succeeded' for r in res['rows'])} of {len(res['rows'])}).",
             f"Budget (issue 4) N = 100, d = 3 warm start < {res['budget_s']:g} s median: "
             f"{'MET' if res['met'] else 'MISSED'} (median over {len(res['times_s'])} solves {res['median_s']:.3f} s)."]
    return {"title": "Collocation planner (N = 100, degree 3)", "rows": rows, "notes": notes,
            "summary": {k: v for k, v in res.items() if k != "rows"}}


def section_fast_default(ctx):
    """The default plan between full states (issue 25): the pole plan and its fast polish, warm
    (``scripts/bench_default.py``)."""
    import bench_default

    res = bench_default.measure(1 if ctx["quick"] else 5, 3 if ctx["quick"] else 12)
    rows = [{"k": r["k"], "pole plan": f"{r['pole_mode']}, {r['pole']:.4f} R", "pole [ms]": r["pole_ms"],
             "default [R]": r["default"], "polished": r["polished"], "default [ms]": r["ms"],
             "default CPU [ms]": r["cpu_ms"], "of which pole plan [ms]": r["stage_pole_ms"],
             "IPOPT [ms]": r["stage_ipopt_ms"], "correction + certificate [ms]": r["stage_correction_certificate_ms"]}
            for r in res["rows"]]
    notes = [f"rollplan.plan between full states (the issue's two pairs and random pairs: contact points up to 60 deg "
             f"from the pole, k in [1.5, 8]): the pole plan, then the fast polish (rest-to-rest collocation, N = 8, "
             f"from the straight line; Newton correction; CVODES certificate), the shorter certified kept. Median of "
             f"{res['repeats']} warm solves per pair; the stages are those of the last solve (wall).",
             f"Budget (issue 25) warm default <= {res['budget_ms']:g} ms for one leg: "
             f"{'MET' if res['met'] else 'MISSED'} (median over the one-leg pairs {res['median_one_leg_ms']:.1f} ms "
             f"wall, {res['median_one_leg_cpu_ms']:.1f} ms CPU; the pole plan alone "
             f"{res['median_pole_one_leg_ms']:.1f} ms)."]
    return {"title": "Default plan between full states (issue 25)", "rows": rows, "notes": notes,
            "summary": {k: v for k, v in res.items() if k != "rows"}}


def section_c_planner(ctx):
    """The generated C planner: microseconds per plan (new k, same k) and code size (scripts/bench_codegen.py)."""
    title = "C planner (generated C, rollplan.codegen)"
    missing = [tool for tool in ("gcc", "cc", "make") if shutil.which(tool) is None]
    if missing:
        why = "no C compiler" if {"gcc", "cc"} & set(missing) else "no make"
        return {"title": title, "rows": [], "notes": [f"skipped: {why} ({', '.join(missing)} not found on PATH)."],
                "summary": {"skipped": why}}
    res = bench_codegen.measure(reps=ctx["c_reps"], python=True, build_dir=ctx.get("build_dir"))
    py_us = res["python_ms_per_plan"] * 1e3
    new_k = len({t[4] for t in bench_codegen.TARGETS} - {bench_codegen.TARGETS[0][4]})   # k after the warm-up
    second = bench_codegen.python_plan_times()                  # now every k's tables are cached
    res["python_ms_per_target_tables_cached"] = second
    res["python_ms_per_plan_tables_cached"] = float(np.mean(second))
    py_cached_us = res["python_ms_per_plan_tables_cached"] * 1e3
    py_median_us = statistics.median(second) * 1e3
    slow = int(np.argmax(second))
    rows = [{"quantity": "C plan, new k (leaf table recomputed) [us]", "value": res["c_us_per_plan"]},
            {"quantity": "C plan, same k (leaf table kept) [us]", "value": res["c_us_per_plan_same_k"]},
            {"quantity": f"Python rollplan.plan, first pass (per-k tables built for {new_k} new k) [us]",
             "value": py_us},
            {"quantity": "Python rollplan.plan, second pass (per-k tables cached), mean [us]", "value": py_cached_us},
            {"quantity": "Python rollplan.plan, second pass, median over targets [us]", "value": py_median_us},
            {"quantity": "speed-up C new k vs Python first pass", "value": py_us / res["c_us_per_plan"]},
            {"quantity": "speed-up C same k vs Python second pass",
             "value": py_cached_us / res["c_us_per_plan_same_k"]},
            {"quantity": "speed-up C same k vs Python second pass median",
             "value": py_median_us / res["c_us_per_plan_same_k"]},
            {"quantity": "C plans failed", "value": res["c_failed_plans"]},
            {"quantity": "generated code .c + .h [bytes]", "value": res["c_code_bytes"]},
            {"quantity": "  of which the model (step map) [bytes]", "value": res["c_model_bytes"]},
            {"quantity": "static library librollplan.a [bytes]", "value": res["c_static_lib_bytes"]},
            {"quantity": "plan_demo executable [bytes]", "value": res["plan_demo_bytes"]},
            {"quantity": "static work memory [doubles]", "value": res["c_work_doubles"]}]
    worst = max(res["c_us_per_plan"], res["c_us_per_plan_same_k"])
    notes = [f"{res['targets']} targets (bench_codegen.TARGETS, k in 0.5..5, n in 1..3; {res['steps_per_leaf']} "
             "steps per leaf for the C step map rollplan_step_eval, the planner uses the leaf map); C time = mean "
             f"over the targets of the best of {ctx['c_reps']} plans (cc -O2); Python time = mean of one pass over "
             "the same targets after a warm-up on the first (enumeration, IPOPT polish, RK8 certificate), then of "
             "a second pass. Measured by scripts/bench_codegen.py:measure.",
             f"Slowest Python plan of the second pass: target (u, v, psi, n, k) = {bench_codegen.TARGETS[slow]}, "
             f"{second[slow]:.0f} ms (the mean is dominated by it; the median is {py_median_us / 1e3:.1f} ms).",
             f"Budget (issue 6) C plan < {BUDGET_C_PLAN_US:g} us: {'MET' if worst < BUDGET_C_PLAN_US else 'MISSED'} "
             f"({res['c_us_per_plan']:.0f} us for the first plan of a new k, which builds the leaf table once per k; "
             f"{res['c_us_per_plan_same_k']:.0f} us for a plan with the table of its k kept)."]
    return {"title": title, "rows": rows, "notes": notes, "summary": res}


def _status(ok):
    return "MET" if ok else "MISSED"


def section_budgets(ctx):
    """All budgets of the issues with the measured values (from the sections run before)."""
    done = ctx["results"]
    rows = []

    def add(issue, budget, measured, ok):
        rows.append({"issue": issue, "budget": budget, "measured": measured, "status": ok})

    plan = done.get("section_plan", {}).get("summary")
    if plan:
        warm = plan["median_warm_ms"]
        add("2", f"single plan < {BUDGET_PLAN_MS_FOUNDATION:g} ms median", f"{warm:.2f} ms",
            _status(warm < BUDGET_PLAN_MS_FOUNDATION))
        add("11", f"warm plan <= {BUDGET_PLAN_MS:g} ms median", f"{warm:.2f} ms wall ({plan['median_warm_cpu_ms']:.2f} "
            "ms CPU time)", _status(warm <= BUDGET_PLAN_MS))
        add("11", f">= {BUDGET_RATIO:g}x faster than scipy at equal accuracy",
            f"smallest over targets {plan['min_speedup']:.1f}x wall ({plan['min_speedup_cpu']:.1f}x CPU time) vs "
            f"scipy rtol 1e-13, {plan['min_speedup_vs_rtol_1e-12']:.1f}x vs scipy rtol 1e-12; rollplan residual "
            f"<= max(scipy's, 1e-12) on every target: {plan['accuracy_ok']}",
            _status(plan["min_speedup"] >= BUDGET_RATIO and plan["accuracy_ok"]))
    else:
        add("2, 11", "single plan; speed-up vs scipy", "not run", "n/a")
    if plan:
        add("28", f"warm plan <= {BUDGET_PLAN_MS_28:g} ms median", f"{plan['median_warm_ms']:.3f} ms wall",
            _status(plan["median_warm_ms"] <= BUDGET_PLAN_MS_28))
        add("28", f">= {BUDGET_RATIO_28:g}x faster than scipy at equal accuracy",
            f"{plan['min_speedup']:.1f}x wall vs scipy rtol 1e-13",
            _status(plan["min_speedup"] >= BUDGET_RATIO_28 and plan["accuracy_ok"]))
    many = done.get("section_plan_many", {}).get("summary")
    if many:
        add("28", f"plan_many >= {BUDGET_MANY_PER_S:g} certified plans/s on 2 cores, n = 1..3",
            f"{many['min_2_workers_per_s']:.0f}/s wall, {many['min_idle_2_cores_per_s']:.0f}/s from CPU time",
            _status(many["min_2_workers_per_s"] >= BUDGET_MANY_PER_S))
    cold = done.get("section_cold", {}).get("summary")
    if cold:
        add("11", f"cold `rollplan plan` <= {BUDGET_COLD_RATIO:g}x the start of Python with casadi, numpy, matplotlib",
            f"{cold['ratio']:.2f}x (ratio of medians)", _status(cold["ratio"] <= BUDGET_COLD_RATIO))
    else:
        add("11", "cold start", "not run", "n/a")
    step = done.get("section_step_map", {}).get("summary")
    if step:
        best = step["best_batched_per_s"]
        add("7", f"batched step map >= {BUDGET_STEP_EVALS:g} evaluations/s on 2 cores",
            f"{best:.0f}/s (best: {step['best_batched_variant']})", _status(best >= BUDGET_STEP_EVALS))
    else:
        add("7", "batched step map", "not run", "n/a")
    coll = done.get("section_collocation", {}).get("summary")
    if coll:
        add("4", f"collocation N = 100, d = 3, warm start < {coll['budget_s']:g} s median",
            f"{coll['median_s']:.3f} s", _status(coll["met"]))
    else:
        add("4", "collocation", "not run", "n/a")
    peer = done.get("section_peer", {}).get("summary")
    if peer:
        add("28", f"rest-to-rest N = {peer['N']} >= {peer['budget']:g}x faster than rockit, optima within 1e-6",
            f"{peer['speedup']:.2f}x wall, {peer['speedup_cpu']:.2f}x CPU (medians, same run); optima differ by "
            f"{peer['relative_difference']:.1e}",
            _status(peer["speedup"] >= peer["budget"] and peer["relative_difference"] <= 1e-6))
    else:
        add("28", "collocation vs rockit", "not run", "n/a")
    comp = done.get("section_compare", {}).get("summary")
    if comp:
        add("28", f"`rollplan compare`{'' if comp.get('default', True) else ' --intervals 20'} <= "
            f"{comp['budget_s']:g} s (idle)",
            f"{comp['median_s']:.2f} s wall, {comp['cpu_median_s']:.2f} s CPU", _status(comp["median_s"]
                                                                                       <= comp["budget_s"]))
    else:
        add("28", "compare wall time", "not run", "n/a")
    fast = done.get("section_fast_default", {}).get("summary")
    if fast:
        add("25", f"default plan between full states, warm, one leg <= {fast['budget_ms']:g} ms median",
            f"{fast['median_one_leg_ms']:.1f} ms wall ({fast['median_one_leg_cpu_ms']:.1f} ms CPU time)",
            _status(fast["met"]))
    else:
        add("25", "default plan between full states", "not run", "n/a")
    c = done.get("section_c_planner", {}).get("summary")
    if c and "skipped" not in c:
        worst = max(c["c_us_per_plan"], c["c_us_per_plan_same_k"])
        add("6", f"C plan < {BUDGET_C_PLAN_US:g} us", f"{c['c_us_per_plan']:.0f} us first plan of a new k (builds "
            f"the leaf table, once per k), {c['c_us_per_plan_same_k']:.0f} us per plan with the table kept",
            _status(worst < BUDGET_C_PLAN_US))
    else:
        add("6", "C plan", f"skipped: {c['skipped']}" if c else "not run", "n/a")
    listed = done.get("section_list_all", {}).get("summary")
    if listed:
        per, case = listed["ms_per_plan"], listed["case"]
        add("28", f"`plan --all` at k = {ALL_CASE[2]:g}, n = {ALL_CASE[1]} <= {BUDGET_ALL_MS_PER_PLAN:g} ms per plan "
            "listed", f"{per:.2f} ms wall ({listed['cpu_ms_per_plan']:.2f} ms CPU time) per plan, "
            f"{listed['plans']} plans at k = {case[4]:g}, n = {case[3]}",
            _status(per <= BUDGET_ALL_MS_PER_PLAN) if case[3:] == [ALL_CASE[1], ALL_CASE[2]] else "n/a (--quick)")
    else:
        add("28", "`plan --all` per plan listed", "not run", "n/a")
    load = ctx["load_average"]
    notes = [f"Measured on a shared machine: load average at start {', '.join(f'{x:.2f}' for x in load or [])} on "
             f"{os.cpu_count()} cores, so timings are pessimistic. Details and the measurements behind each value in "
             "the sections below."]
    return {"title": "Budgets", "rows": rows, "notes": notes, "top": True}


def section_batch(ctx):
    """Batch planning (issue 18): --jobs 2 against --jobs 1 on 200 targets (``scripts/bench_batch.py``)."""
    m = bench_batch.measure(20 if ctx["quick"] else 200, 1 if ctx["quick"] else 3, cold=ctx["cold"])
    rows = []
    for kind, what in (("cold", "whole command `rollplan batch`, cold"),
                       ("warm", "planning phase, planner built (run_batch)")):
        if kind not in m:
            continue
        r = m[kind]
        rows.append({"measurement": what, "--jobs 1 median [s]": r["jobs1_median_s"],
                     "--jobs 2 median [s]": r["jobs2_median_s"], "speed-up median": r["speedup_median"],
                     "speed-up min..max": f"{r['speedup_min']:.2f}..{r['speedup_max']:.2f}",
                     "speed-up of the min times": r["speedup_of_min"],
                     "CPU --jobs 1 / --jobs 2 [s]": f"{r['jobs1_cpu_s']:.2f} / {r['jobs2_cpu_s']:.2f}",
                     "idle speed-up (estimate from CPU)": r["idle_speedup_estimate"],
                     f"budget >= {bench_batch.BUDGET_SPEEDUP:g}x (wall)": _status(r["speedup_median"]
                                                                                   >= bench_batch.BUDGET_SPEEDUP)})
    notes = [f"{m['targets']} targets ({m['failed_rows']} without a plan), {m['repeats']} repeat(s) alternating the "
             f"order of the two runs; the same lines from both: {m['same_lines']}. Load average at the start "
             f"{', '.join(f'{x:.2f}' for x in m['load_average_start'] or [])}, at the end "
             f"{', '.join(f'{x:.2f}' for x in m['load_average'] or [])} on {m['cores']} cores; autogroup "
             f"scheduling {'on' if m['autogroup'] else 'off'}.",
             "Cold: Python start, imports and the planner's construction are paid once in both runs (the --jobs 2 "
             "workers are forked after the parent planned the first row), so they bound the cold speed-up; warm: "
             "the throughput of a long batch.",
             "With autogroup scheduling, all processes of a session share one fair share of the CPU: while other "
             "sessions keep the cores busy, two workers get no more CPU than one, and the wall-clock speed-up "
             "measures the load, not rollplan. The idle speed-up is estimated from the measured CPU times "
             "(scripts/bench_batch.py): the serial start-up once, the rest shared by the two workers."]
    return {"title": "Batch planning: --jobs 2 against --jobs 1", "rows": rows, "notes": notes, "summary": m}


def many_targets(count, seed=28):
    """Targets of the plan_many section: (u_a, v_a) uniform in the disk of radius 1.2 R, psi in [-1, 1] rad."""
    rng = np.random.default_rng(seed)
    r, phi = 1.2 * np.sqrt(rng.uniform(0, 1, count)), rng.uniform(-np.pi, np.pi, count)
    return np.column_stack([r * np.cos(phi), r * np.sin(phi), rng.uniform(-1, 1, count)])


def _plan_many_part(job):
    """One worker's share of the plan_many section: ``(plans certified, CPU time [s])``."""
    targets, steps = job
    c = time.process_time()
    r = rollplan.plan_many(targets, k=K, steps=steps)
    return int(r.ok.sum()), time.process_time() - c


def section_plan_many(ctx):
    """rollplan.plan_many: certified plans per second with 1 worker (this process) and 2 (forked processes)."""
    import multiprocessing

    count = 500 if ctx["quick"] else 4000
    rows = []
    ctx_fork = multiprocessing.get_context("fork")
    rollplan.plan_many(many_targets(8), k=K, steps=1)   # the C library and the tables of K, before the fork
    with ctx_fork.Pool(2) as pool:
        pool.map(_plan_many_part, [(many_targets(4, seed), 1) for seed in (1, 2)])   # the workers have started
        for steps in (1, 2, 3):
            targets = many_targets(count, seed=steps)
            t = time.perf_counter()
            ok1, cpu1 = _plan_many_part((targets, steps))
            t1 = time.perf_counter() - t
            parts = [(targets[i::8], steps) for i in range(8)]
            t = time.perf_counter()
            res = pool.map(_plan_many_part, parts, chunksize=1)
            t2 = time.perf_counter() - t
            ok2, cpu2 = sum(r[0] for r in res), sum(r[1] for r in res)
            assert ok1 == ok2
            rows.append({"n": steps, "targets": count, "certified": ok1,
                         "1 worker [plans/s]": count / t1, "2 workers [plans/s]": count / t2,
                         "speed-up (wall)": t1 / t2, "CPU per plan, 1 worker [us]": cpu1 / count * 1e6,
                         "idle 2 cores, from CPU time [plans/s]": 2 * count / cpu2})
    worst = min(r["2 workers [plans/s]"] for r in rows)
    worst_idle = min(r["idle 2 cores, from CPU time [plans/s]"] for r in rows)
    notes = [f"k = {K}; targets: (u_a, v_a) uniform in the disk of radius 1.2 R, psi uniform in [-1, 1] rad; every "
             "plan certified to 1e-9 by the C RK8 certificate (the failures are targets without a one-leg plan). "
             "1 worker: plan_many in this process; 2 workers: two forked processes, each plan_many on its share "
             "(the pool started before the timing). The idle estimate divides the targets by the CPU time the "
             "workers spent, on 2 cores (the machine is shared: wall times measure the load).",
             f"Budget (issue 28) >= {BUDGET_MANY_PER_S:g} certified plans/s on 2 cores for n = 1..3: "
             f"{_status(worst >= BUDGET_MANY_PER_S)} wall ({worst:.0f}/s), "
             f"{_status(worst_idle >= BUDGET_MANY_PER_S)} from CPU time ({worst_idle:.0f}/s)."]
    return {"title": "Many plans per call: rollplan.plan_many with 1 and 2 workers", "rows": rows, "notes": notes,
            "summary": {"min_2_workers_per_s": worst, "min_idle_2_cores_per_s": worst_idle}}


#: (target, N, guess) of the peer section: a small case from the naive guess, and the comparison's setting
#: (results/comparison.md: N = 100, d = 3) from the warm start of its shortest GP branch.
PEER_CASES = [((-0.4, 0.4, 1.0), 20, "naive"), ((0.5, 0.3, 0.4), 100, "gp")]


def section_peer(ctx):
    """The rest-to-rest collocation against the same OCP transcribed by rockit (rollplan.studies.comparison_peer):
    the optima side by side and the solve times."""
    from rollplan.errors import InputError
    from rollplan.studies.comparison_peer import peer_rest_to_rest

    title = "Peer: the rest-to-rest OCP in rollplan and in rockit (same OCP, same transcription class)"
    repeats = 1 if ctx["quick"] else 5
    rows = []
    for target, n, guess in PEER_CASES[:1] if ctx["quick"] else PEER_CASES:
        try:
            r = peer_rest_to_rest(Problem(target, k=K), guess, intervals=n, repeats=repeats).row()
        except InputError as exc:    # rockit not installed
            return {"title": title, "rows": [], "notes": [str(exc)]}
        rows.append({"target (u_a, v_a, psi)": str(target), "N": n, "guess": r["guess"],
                     "optimum rollplan": f"{r['objective']:.12g}", "optimum rockit": f"{r['peer_objective']:.12g}",
                     "relative difference": r["relative_difference"], "largest control difference":
                     r["control_difference"], "iterations rollplan / rockit": f"{r['iterations']} / "
                     f"{r['peer_iterations']}", "build rollplan [s]": r["build_s"],
                     "first solve rockit (build + solve) [s]": r["peer_first_s"],
                     "solve rollplan, median [s]": r["solve_median_s"],
                     "solve rockit, median [s]": r["peer_solve_median_s"],
                     "speed-up (rockit / rollplan)": r["peer_solve_median_s"] / r["solve_median_s"],
                     "solve CPU rollplan / rockit, median [s]": f"{r['solve_cpu_median_s']:.3f} / "
                     f"{r['peer_solve_cpu_median_s']:.3f}",
                     "speed-up in CPU time": r["peer_solve_cpu_median_s"] / r["solve_cpu_median_s"]})
    notes = [f"k = {K}, T = 1 s, cost angular_velocity, contact bound 80 deg, Legendre d = 3; both IPOPT with the same "
             "options (the planner's ipopt_options: tol 1e-9, MUMPS ordered by minimum degree), from the same guess "
             "(naive: the straight line at rest; gp: the shortest geometric-"
             "phase branch timed by its optimal rest-to-rest timing). rockit's NLP: its DirectCollocation (M = 1) "
             "of the same dynamics (the model's CasADi function), cost, bounds and boundary conditions, expanded to "
             "SX like rollplan's. Solve times: wall time of the solver call from the same guess, "
             f"median of {repeats + 1} (rollplan) and {repeats} (rockit, after the first) solves; rockit's include "
             "its Opti bookkeeping per solve. Build: rollplan's NLP and solver construction; rockit's first solve "
             "includes its transcription and the solver's construction."]
    summary = None
    if rows:
        worst = max(r["relative difference"] for r in rows)
        notes.append(f"Largest relative difference of the optima: {worst:.1e} "
                     f"({'within' if worst <= 1e-6 else 'NOT within'} 1e-6).")
        main_row = rows[-1]     # N = 100, d = 3 (the first row alone with --quick)
        summary = {"N": main_row["N"], "speedup": main_row["speed-up (rockit / rollplan)"],
                   "speedup_cpu": main_row["speed-up in CPU time"],
                   "relative_difference": worst, "budget": BUDGET_PEER_SPEEDUP}
        met = "met" if summary["speedup"] >= BUDGET_PEER_SPEEDUP else "NOT met"
        notes.append(f"Speed-up of rollplan over rockit on N = {main_row['N']}: "
                     f"{summary['speedup']:.2f}x in wall time, "
                     f"{summary['speedup_cpu']:.2f}x in CPU time (budget >= {BUDGET_PEER_SPEEDUP:g}x: {met}; "
                     "both medians measured in this run, side by side; CPU time is the steadier measure on a loaded "
                     "machine).")
    return {"title": title, "rows": rows, "notes": notes, "summary": summary}


#: Issue 28: rollplan's rest-to-rest solve at least this many times faster than rockit's, same OCP, same run.
BUDGET_PEER_SPEEDUP = 1.5
#: Issue 28: wall time of the default ``rollplan compare`` on an idle machine [s].
BUDGET_COMPARE_S = 3.0
#: The command timed by :func:`section_compare` (the default comparison: N = 100, d = 3, 2 branches, 5 starts
#: screened on 10 intervals).
COMPARE_ARGS = ["compare", "--to", "0.5", "0.3"]


def section_compare(ctx):
    """Wall and CPU time of the whole default ``rollplan compare`` (a fresh process: imports, the NLP's
    construction, the GP branches, the multistart, the correction and the certificate of the best start)."""
    args = COMPARE_ARGS + (["--intervals", "20"] if ctx["quick"] else [])    # --quick: a smoke test, small N
    exe = shutil.which("rollplan", path=os.path.dirname(sys.executable))
    cmd = [exe, *args] if exe else [sys.executable, "-m", "rollplan.cli", *args]
    walls, cpus = [], []
    for _ in range(1 if ctx["quick"] else 3):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run(cmd, capture_output=True, check=True)
        walls.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime)
    m = {"median_s": statistics.median(walls), "cpu_median_s": statistics.median(cpus), "budget_s": BUDGET_COMPARE_S,
         "load_average": list(os.getloadavg()), "cores": os.cpu_count()}
    m["default"] = not ctx["quick"]
    rows = [{"command": "rollplan " + " ".join(args), "runs": len(walls),
             "wall median [s]": m["median_s"], "wall min [s]": min(walls), "CPU median [s]": m["cpu_median_s"],
             f"budget <= {BUDGET_COMPARE_S:g} s (idle)": _status(m["median_s"] <= BUDGET_COMPARE_S)}]
    notes = ["CPU: user + system time of the process and its threads (the starts are solved by two workers "
             "when two cores are free, so on an idle machine the wall time is below the CPU time). "
             f"Load average at the end {', '.join(f'{x:.2f}' for x in m['load_average'])} on {m['cores']} cores."]
    return {"title": "`rollplan compare`: the default comparison, whole command", "rows": rows, "notes": notes,
            "summary": m}


def _children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def section_list_all(ctx):
    """`rollplan plan --all` (issue 28): wall and CPU time of the whole command per plan listed, and, side by side
    on a sample of the same roots, the C certificate per root against the Python polish and RK8 certificate the
    list used before."""
    import tempfile

    from rollplan.core.plane import wrap_exact
    from rollplan.planners.geometric import compiled_search
    from rollplan.planners.geometric.certify import RK8Certifier
    from rollplan.planners.geometric.leafmap import panels_for
    from rollplan.planners.geometric.refine import polisher

    (u, v, psi), steps, k = ALL_CASE_QUICK if ctx["quick"] else ALL_CASE
    args = ["plan", "--to", str(u), str(v), "--psi", str(psi), "--steps", str(steps), "--k", str(k), "--all"]
    exe = shutil.which("rollplan")
    repeats = 1 if ctx["quick"] else 3
    wall, cpu, plans = [], [], 0
    with tempfile.TemporaryDirectory() as tmp:
        js = str(Path(tmp) / "all.json")
        cmd = [exe, *args, "--json", js] if exe else [sys.executable, "-m", "rollplan.cli", *args, "--json", js]
        for _ in range(repeats):
            c0, t0 = _children_cpu(), time.perf_counter()
            subprocess.run(cmd, capture_output=True, check=True)
            wall.append(time.perf_counter() - t0)
            cpu.append(_children_cpu() - c0)
            with open(js) as f:
                plans = 1 + len(json.load(f).get("alternatives", []))
    roots = compiled_search.listed_roots(u, v, wrap_exact(psi)[0], steps, k)
    sample = roots[:: max(1, len(roots) // (10 if ctx["quick"] else 60))]
    rk8, polish = RK8Certifier(), polisher("ipopt", panels_for(k))

    def before():
        for r in sample:
            eta = (psi + 2.0 * math.pi * r.m) / steps
            polish([r.a, r.b], [k, eta, float(target_shift(math.hypot(u, v), eta, steps))], 1e-6, A_MAX)
            rk8.certify(r.a, r.b, k, r.gamma, steps)

    before()                                  # compiled functions of every step count loaded
    timed = {}
    for name, run in (("c", lambda: compiled_search.certify_roots(sample, u, v, psi, steps, k)), ("python", before)):
        c0, t0 = time.process_time(), time.perf_counter()
        run()
        timed[name] = ((time.perf_counter() - t0) / len(sample) * 1e3, (time.process_time() - c0) / len(sample) * 1e3)
    (c_ms, c_cpu), (py_ms, py_cpu) = timed["c"], timed["python"]
    per_plan = statistics.median(wall) / plans * 1e3
    per_plan_cpu = statistics.median(cpu) / plans * 1e3
    rows = [{"measurement": f"`rollplan {' '.join(args)} --json FILE`, whole command", "plans listed": plans,
             "median wall [s]": statistics.median(wall), "median CPU [s]": statistics.median(cpu),
             "wall per plan [ms]": per_plan, "CPU per plan [ms]": per_plan_cpu},
            {"measurement": f"C certificate per root (rollplan_certify), {len(sample)} of the {len(roots)} roots",
             "plans listed": "-", "median wall [s]": "-", "median CPU [s]": "-", "wall per plan [ms]": c_ms,
             "CPU per plan [ms]": c_cpu},
            {"measurement": "before: IPOPT polish + Python RK8 certificate per root, the same roots",
             "plans listed": "-", "median wall [s]": "-", "median CPU [s]": "-", "wall per plan [ms]": py_ms,
             "CPU per plan [ms]": py_cpu}]
    notes = [f"{repeats} run(s) of the whole command (start-up, C search, certificates, sampling and the streamed JSON "
             "included); per plan = total time / plans listed. The C certificate and the former per-root work "
             f"(ratio {py_ms / c_ms:.1f}x wall, {py_cpu / c_cpu:.1f}x CPU time) are timed side by side in this process "
             f"on every {max(1, len(roots) // (10 if ctx['quick'] else 60))}th root of the list.",
             f"Budget (issue 28) `plan --all` <= {BUDGET_ALL_MS_PER_PLAN:g} ms per plan listed at k = {ALL_CASE[2]:g}, "
             f"n = {ALL_CASE[1]} (here k = {k:g}, n = {steps}): "
             f"{_status(per_plan <= BUDGET_ALL_MS_PER_PLAN) if not ctx['quick'] else 'not judged (--quick)'} "
             f"({per_plan:.2f} ms wall, {per_plan_cpu:.2f} ms CPU time per plan)."]
    return {"title": "`plan --all`: time per plan listed", "rows": rows, "notes": notes,
            "summary": {"case": [u, v, psi, steps, k], "plans": plans, "wall_s": wall, "cpu_s": cpu,
                        "ms_per_plan": per_plan,
                        "cpu_ms_per_plan": per_plan_cpu, "c_certificate_ms": c_ms, "c_certificate_cpu_ms": c_cpu,
                        "python_polish_rk8_ms": py_ms, "python_polish_rk8_cpu_ms": py_cpu}}


#: The benchmark, in order. Append new sections here; :func:`section_budgets` reads the others' summaries and
#: is shown first in the report.
SECTIONS = [section_plan, section_cold, section_high_k, section_step_map, section_collocation, section_c_planner,
            section_memory, section_profile,
            section_batch, section_plan_many, section_list_all, section_budgets]
SECTIONS.insert(SECTIONS.index(section_collocation) + 1, section_peer)
SECTIONS.insert(SECTIONS.index(section_peer) + 1, section_compare)
SECTIONS.insert(SECTIONS.index(section_list_all) + 1, section_fast_default)


# ----------------------------------------------------------------------------- report


def machine():
    return {"platform": platform.platform(), "cpu": processor(), "cores": os.cpu_count(),
            "python": platform.python_version(), "casadi": ca.__version__, "numpy": np.__version__,
            "scipy": scipy.__version__, "rollplan": rollplan.__version__,
            "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None}


def git_commit():
    try:
        root = Path(__file__).resolve().parent.parent
        head = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True, text=True,
                              check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", str(root), "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def command_line(argv, script: str) -> str:
    """The command that ran ``script`` (a path) with ``argv``, as a report states it: ``sys.argv`` when ``main`` was
    called without arguments (a run from the shell), else ``python scripts/<name> argv...`` (``main(argv)`` called
    from Python, whose own ``sys.argv`` is another program's)."""
    return " ".join(["python", *(sys.argv if argv is None else [f"scripts/{Path(script).name}", *argv])])


def _fmt(v):
    if isinstance(v, float):
        if math.isnan(v):
            return "n/a"
        if v == 0:
            return "0"
        if abs(v) < 1e-3 or abs(v) >= 1e6:
            return f"{v:.2e}"
        return f"{v:.3g}" if abs(v) < 100 else f"{v:.0f}"
    return str(v)


def to_markdown(report) -> str:
    m = report["machine"]
    out = ["# rollplan benchmarks", "",
           f"- date: {report['date']}", f"- commit: `{report['commit']}`",
           f"- machine: {m['cpu']}, {m['cores']} cores, {m['platform']}; load average at start "
           f"{', '.join(f'{x:.2f}' for x in m['load_average'] or [])}",
           f"- software: Python {m['python']}, CasADi {m['casadi']}, numpy {m['numpy']}, scipy {m['scipy']}, "
           f"rollplan {m['rollplan']}",
           f"- command: `{report['command']}`", ""]
    if report.get("preamble"):
        out += [report["preamble"], ""]
    for sec in report["sections"]:
        out += [f"## {sec['title']}", ""]
        if sec.get("date") and sec["date"] != report["date"]:
            out += [f"(kept from an earlier run: {sec['date']}, commit `{sec.get('commit')}`)", ""]
        if sec["rows"]:
            cols = list(sec["rows"][0])
            out.append("| " + " | ".join(cols) + " |")
            out.append("|" + "|".join("---" for _ in cols) + "|")
            for r in sec["rows"]:
                out.append("| " + " | ".join(_fmt(r.get(c, "")) for c in cols) + " |")
            out.append("")
        for n in sec.get("notes", []):
            out.append(f"- {n}")
        if sec.get("text"):
            out += ["", "```", sec["text"], "```"]
        out.append("")
    if report.get("postscript"):
        out += [report["postscript"], ""]
    return "\n".join(out)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="few repeats, the first target only of the plan section (smoke test)")
    ap.add_argument("--no-jit", action="store_true", help="skip the JIT-compiled step map (gcc takes ~20 s)")
    ap.add_argument("--no-cold", action="store_true", help="skip the cold first-call subprocesses")
    ap.add_argument("--jit-flags", default="-O1 -fPIC", help="C compiler flags of the JIT step map")
    ap.add_argument("--out-dir", default="results")
    ap.add_argument("--build-dir", help="keep the C planner's build of the c_planner section in DIR/host-<digest> and "
                                        "reuse it in later runs of the same sources and compilers (default: a "
                                        "temporary folder; the times are measured anew)")
    ap.add_argument("--only", nargs="*", help="run only these sections (their function names without 'section_', e.g. "
                    "--only plan cold high_k); the other sections are kept from the existing benchmarks.json")
    args = ap.parse_args(argv)
    ctx = {"repeats": 5 if args.quick else 21, "scipy_repeats": 1 if args.quick else 3,
           "batch": 500 if args.quick else 4000, "map_repeats": 1 if args.quick else 5,
           "single_evals": 100 if args.quick else 1000, "check_points": 4 if args.quick else 8,
           "jit": not args.no_jit, "jit_flags": args.jit_flags, "cold": not args.no_cold,
           "coll_repeats": 1 if args.quick else 11, "coll_targets": 1 if args.quick else len(bench_collocation.TARGETS),
           "c_reps": 3 if args.quick else 20, "quick": args.quick, "cold_repeats": 3 if args.quick else 7,
           "high_k_repeats": 1 if args.quick else 3}
    v = geometric.GeometricPhasePlanner(certifier="cvodes").certifier.integrator
    ctx["verifier"] = f"{v.multistep.capitalize()}, rtol {v.reltol:g}, atol {v.abstol:g}"
    mach = machine()
    print(f"load average at start: {mach['load_average']}", file=sys.stderr, flush=True)
    report = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
              "commit": git_commit(), "machine": mach, "command": command_line(argv, __file__),
              "settings": dict(ctx), "sections": []}
    ctx["load_average"] = mach["load_average"]
    ctx["build_dir"] = args.build_dir
    ctx["results"] = {}
    out = Path(args.out_dir)
    kept = {}
    if args.only and (out / "benchmarks.json").exists():   # sections not rerun are kept, with their own date
        old = json.loads((out / "benchmarks.json").read_text())
        for sec in old.get("sections", []):
            sec.setdefault("date", old.get("date"))
            sec.setdefault("commit", old.get("commit"))
            kept[sec.get("function")] = sec
    for sec in SECTIONS:
        if args.only and sec is not section_budgets and sec.__name__.removeprefix("section_") not in args.only:
            if sec.__name__ in kept:
                ctx["results"][sec.__name__] = kept[sec.__name__]
                report["sections"].append(kept[sec.__name__])
            continue
        t = time.perf_counter()
        print(f"running {sec.__name__} ...", file=sys.stderr, flush=True)
        res = sec(ctx)
        res["function"] = sec.__name__
        res["time_s"] = time.perf_counter() - t
        res["date"], res["commit"] = report["date"], report["commit"]
        ctx["results"][sec.__name__] = res
        report["sections"].append(res)
    report["sections"].sort(key=lambda r: not r.get("top", False))     # the budgets first, the rest in order
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "benchmarks.md", to_markdown(report).encode())
    write_json(out / "benchmarks.json", json.loads(json.dumps(report, default=float).replace("NaN", "null")))
    print(f"wrote {out / 'benchmarks.md'} and {out / 'benchmarks.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
