"""Measure the generated C planner: microseconds per plan, code size, and accuracy vs steps per leaf.

Usage::

    python scripts/bench_codegen.py                 # timing and code size at the default steps per leaf
    python scripts/bench_codegen.py --accuracy      # also: error vs steps per leaf
                                                    # (writes results/codegen_accuracy.json)

:func:`measure` is the entry point for ``scripts/benchmark.py``. Needs a C compiler (``cc``) and ``make``.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import os
import shutil
import subprocess
import tempfile
import time
from pathlib import Path

import casadi as ca
import numpy as np

from rollplan import Problem
from rollplan.codegen import c_library as codegen
from rollplan.core.curves import figure_eight
from rollplan.core.integrate import spectral_step
from rollplan.core.plane import wrap
from rollplan.io import write_json
from rollplan.planners import geometric

#: Targets (u, v, psi, steps, k) of the timing run.
TARGETS = [
    (0.0, 1.0, 0.0, 1, 2.5),
    (1.0, 0.0, 0.0, 1, 2.5),
    (0.3, -0.2, 0.5, 1, 2.5),
    (2.0, 1.0, 1.0, 3, 2.5),
    (0.5, 0.5, -2.0, 2, 2.5),
    (0.0, 1.0, 0.0, 1, 0.5),
    (0.0, 1.0, 0.0, 1, 5.0),
    (-0.4, 0.8, 0.3, 1, 1.5),
]

#: Targets (u, v, psi, steps, k) whose shortest plan lies on a branch far down the search order: many branches
#: (up to 25) are searched below it (reported apart in results/embedded.md).
MANY_BRANCH_TARGETS = [
    (0.0, 2.0, 0.0, 1, 5.0),
    (0.0, 2.5, 0.0, 1, 5.0),
    (0.0, 1.0, 3.0, 1, 5.0),
    (0.0, 2.0, 0.0, 1, 2.5),
]

#: Extra targets of the accuracy sweep whose leaves come close to A_MAX (where the step map is hardest).
LARGE_TARGETS = [
    (0.0, 2.8, 0.0, 1, 2.5),
    (1.0, 2.0, 0.3, 1, 2.5),
    (0.0, 2.0, 0.0, 1, 0.5),
    (3.0, 3.0, 0.2, 2, 2.5),
]

#: Leaves (a, b, k) near A_MAX whose own step is the target (psi = eta(a, b), n = 1): plans that must
#: use such a leaf, where the step map is hardest to integrate.
STRESS_LEAVES = [(0.688, 0.3, 2.5), (0.68, 0.5, 5.0), (0.685, 0.2, 1.0)]


def stress_targets():
    """Targets (u, v, psi, 1, k) reached by one step of the figure eights in :data:`STRESS_LEAVES`."""
    out = []
    for a, b, k in STRESS_LEAVES:
        s = geometric.step(a, b, k=k)
        out.append((float(s.shift[0]), float(s.shift[1]), float(s.eta), 1, k))
    return out


_BENCH_C = r"""
#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <stdlib.h>
#include <time.h>
#include "@PREFIX@.h"
static const double T[][5] = { @TARGETS@ };
static double now_us(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec * 1e6 + t.tv_nsec / 1e3;
}
/* Per target, the best of reps: a plan for a new k (the leaf map's table rebuilt first), a plan with the
 * table kept (same k), the same without the certificate, and the plan's certificate alone. One line per
 * target: "new_k same_k no_cert cert status". */
int main(int argc, char **argv) {
    int reps = argc > 1 ? atoi(argv[1]) : 20, n = (int)(sizeof T / sizeof T[0]), r, i, q, status;
    @PREFIX@_plan_t p;
    @PREFIX@_options_t no_cert = {0, 0, 0};
    double best[4], t, res, bound;
    for (i = 0; i < n; ++i) {
        status = @PREFIX@_plan(T[i][0], T[i][1], T[i][2], (int)T[i][3], T[i][4], &p);
        for (q = 0; q < 4; ++q) best[q] = 1e300;
        for (r = 0; r < reps; ++r) {
            @PREFIX@_forget_table();
            t = now_us();
            @PREFIX@_plan(T[i][0], T[i][1], T[i][2], (int)T[i][3], T[i][4], &p);
            t = now_us() - t;
            if (t < best[0]) best[0] = t;
            t = now_us();
            @PREFIX@_plan(T[i][0], T[i][1], T[i][2], (int)T[i][3], T[i][4], &p);
            t = now_us() - t;
            if (t < best[1]) best[1] = t;
            t = now_us();
            @PREFIX@_plan_with(T[i][0], T[i][1], T[i][2], (int)T[i][3], T[i][4], &no_cert, &p);
            t = now_us() - t;
            if (t < best[2]) best[2] = t;
            t = now_us();
            @PREFIX@_certify(p.a, p.b, p.gamma, (int)T[i][3], T[i][4], T[i][0], T[i][1], T[i][2], NULL, &res, &bound);
            t = now_us() - t;
            if (t < best[3]) best[3] = t;
        }
        printf("%.3f %.3f %.3f %.3f %d\n", best[0], best[1], best[2], best[3], status);
    }
    return 0;
}
"""


def build(out: Path, steps_per_leaf: int = codegen.DEFAULT_STEPS_PER_LEAF, prefix: str = "rollplan"):
    """Generate the library into ``out`` and build ``plan_demo``; returns the GeneratedCode."""
    g = codegen.generate(out, steps_per_leaf, prefix)
    subprocess.run(["make", "-s", "-C", str(out)], check=True, capture_output=True)
    return g


#: The make variables of the environment that the generated Makefiles read (``CC ?= cc`` and the like): part of
#: a kept build's key (:func:`kept`).
MAKE_VARIABLES = ("CC", "CFLAGS", "CPPFLAGS", "LDFLAGS", "ARM", "MAKEFLAGS")


def kept_folder(out: Path, build_dir: str, name: str, tools: dict) -> Path:
    """Where :func:`kept` keeps the build of the generated folder ``out``: ``build_dir/<name>-<digest>``, the digest
    of its files, of ``tools`` and of the environment's :data:`MAKE_VARIABLES`."""
    h = hashlib.sha256(repr(sorted(tools.items())).encode())
    h.update(repr([(v, os.environ.get(v)) for v in MAKE_VARIABLES]).encode())
    for path in sorted(out.rglob("*")):
        if path.is_file():
            h.update(str(path.relative_to(out)).encode() + b"\0" + path.read_bytes() + b"\0")
    return Path(build_dir) / f"{name}-{h.hexdigest()[:16]}"


def kept(out: Path, build_dir: str | None, name: str, tools: dict, build) -> Path:
    """Build ``out`` (a generated folder) by ``build(folder)``, there, or with ``build_dir`` in its copy
    ``build_dir/<name>-<digest>`` (the digest of its files, of ``tools``, e.g. the compilers' versions, and of the
    environment's :data:`MAKE_VARIABLES`): made once, then reused by every later run of the same sources, tools and
    variables, where ``build`` (``make``) rebuilds nothing. A new copy is built under a temporary name and renamed
    only once ``build`` succeeded: a stopped or failed build leaves no kept folder, and of two runs building the
    same one at once the second to finish uses the first's. Returns the built folder."""
    if build_dir is None:
        build(out)
        return out
    folder = kept_folder(out, build_dir, name, tools)
    if folder.exists():
        build(folder)
        return folder
    part = folder.with_name(f"{folder.name}.part{os.getpid()}")
    shutil.rmtree(part, ignore_errors=True)
    shutil.copytree(out, part, symlinks=True)
    try:
        build(part)
        part.rename(folder)
    except OSError:
        if not folder.exists():
            raise
        build(folder)   # built meanwhile by another run
    finally:
        shutil.rmtree(part, ignore_errors=True)
    return folder


def host_tools() -> dict:
    """The first line of ``cc --version`` and ``make --version``: what a host build depends on besides its sources."""
    return {tool: subprocess.run([tool, "--version"], capture_output=True, text=True, check=True).stdout.split("\n")[0]
            for tool in ("cc", "make")}


def time_plans(out: Path, prefix: str = "rollplan", targets=TARGETS, reps: int = 20):
    """Microseconds of each C plan of ``targets`` (best of ``reps``; built with -O2): rows of
    (new k: leaf table rebuilt, same k, same k without the certificate, the certificate alone, status).

    The planner's object files of :func:`build` (the generated Makefile compiles them with the same -O2) are
    linked when present; otherwise its sources are compiled here."""
    text = _BENCH_C.replace("@PREFIX@", prefix).replace(
        "@TARGETS@", ", ".join("{" + ", ".join(repr(float(x)) for x in t) + "}" for t in targets))
    (out / "bench.c").write_text(text)
    exe = out / "bench"
    objects = [out / "rollplan_planner.o", out / f"{prefix}_model.o"]
    if not all(o.exists() for o in objects):
        objects = [o.with_suffix(".c") for o in objects]
    subprocess.run(["cc", "-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-o", str(exe), str(out / "bench.c"),
                    *map(str, objects), "-lm"], check=True, capture_output=True)
    lines = subprocess.run([str(exe), str(reps)], check=True, capture_output=True, text=True).stdout.splitlines()
    return [tuple(float(x) for x in line.split()[:4]) + (int(line.split()[4]),) for line in lines]


def python_plan_times(targets=TARGETS) -> list:
    """Milliseconds of each Python plan of ``targets`` (the geometric-phase planner: complete enumeration and
    its certificate), after a warm-up plan of each k."""
    planner = geometric.GeometricPhasePlanner()
    for k in sorted({t[4] for t in targets}):
        planner.solve(Problem(targets[0][:3], k=k, steps=targets[0][3]))   # warm up (builds the k's tables)
    out = []
    for u, v, psi, n, k in targets:
        t0 = time.perf_counter()
        planner.solve(Problem((u, v, psi), k=k, steps=n))
        out.append((time.perf_counter() - t0) * 1e3)
    return out


def python_plan_ms(targets=TARGETS) -> float:
    """Milliseconds per Python plan, mean over ``targets``."""
    return float(np.mean(python_plan_times(targets)))


def measure(steps_per_leaf: int = codegen.DEFAULT_STEPS_PER_LEAF, reps: int = 20, python: bool = True,
            targets=TARGETS, build_dir: str | None = None) -> dict:
    """Timing and size of the C planner, side by side with the Python planner on the same targets.

    ``targets`` are (u, v, psi, steps, k) tuples. Keys of the result: ``c_us_per_plan`` (mean over the targets
    of a plan for a new k: the leaf map's table rebuilt first), ``c_us_per_plan_same_k`` (table kept),
    ``c_us_per_plan_same_k_without_certificate``, ``c_us_certificate`` (the certificate alone), their medians
    and maxima (``..._median``, ``..._max``), ``c_per_target`` (rows of the four and the status),
    ``c_failed_plans``, ``c_code_bytes`` (generated .c and .h), ``c_static_lib_bytes``, ``plan_demo_bytes``,
    ``c_work_doubles`` (static work memory), ``python_ms_per_target`` and ``python_ms_per_plan`` (mean). With
    ``build_dir`` the build is kept there and reused (:func:`kept`); the times are measured anew.
    """
    with tempfile.TemporaryDirectory() as tmp:
        g = codegen.generate(Path(tmp) / "c", steps_per_leaf)
        out = kept(Path(tmp) / "c", build_dir, "host", host_tools(),
                   lambda folder: subprocess.run(["make", "-s", "-C", str(folder)], check=True, capture_output=True))
        rows = time_plans(out, targets=targets, reps=reps)
        binary = (out / "plan_demo").stat().st_size
        lib = (out / "librollplan.a").stat().st_size
    cols = np.array([r[:4] for r in rows])
    res = {"steps_per_leaf": steps_per_leaf, "targets": len(targets), "c_per_target": [list(r) for r in rows],
           "c_failed_plans": sum(r[4] != 0 for r in rows)}
    for j, key in enumerate(("c_us_per_plan", "c_us_per_plan_same_k", "c_us_per_plan_same_k_without_certificate",
                             "c_us_certificate")):
        res[key] = float(cols[:, j].mean())
        res[key + "_median"] = float(np.median(cols[:, j]))
        res[key + "_max"] = float(cols[:, j].max())
    res.update({"c_code_bytes": g.code_bytes, "c_model_bytes": g.model_bytes, "c_static_lib_bytes": lib,
                "plan_demo_bytes": binary, "c_work_doubles": g.work_doubles})
    if python:
        res["python_ms_per_target"] = python_plan_times(targets)
        res["python_ms_per_plan"] = float(np.mean(res["python_ms_per_target"]))
    return res


def step_map_error(steps_per_leaf: int, points) -> float:
    """Largest error of the generated step map (its symbolic twin) against a converged spectral reference."""
    step, _ = codegen.step_functions(steps_per_leaf)
    ref = spectral_step(figure_eight(), 48)
    err = 0.0
    for a, b, k in points:
        got = np.concatenate([np.array(x).ravel() for x in step([a, b], k)[:2]])
        want = np.array(ref(ca.DM.zeros(3), ca.vertcat(a, b), k, 0)).ravel()
        err = max(err, float(np.abs(got - want).max()))
    return err


def plan_error(steps_per_leaf: int, targets=None) -> dict:
    """C plans at ``steps_per_leaf``: largest CVODES-verified residual, largest gap to the Python plan."""
    targets = TARGETS + LARGE_TARGETS + stress_targets() if targets is None else targets
    planner = geometric.GeometricPhasePlanner()
    worst, gap = 0.0, 0.0
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "c"
        build(out, steps_per_leaf)
        for u, v, psi, n, k in targets:
            run = subprocess.run([str(out / "plan_demo"), *(repr(float(x)) for x in (u, v, psi)), str(n), repr(k)],
                                 capture_output=True, text=True, check=False)
            if run.returncode:
                return {"steps_per_leaf": steps_per_leaf, "failed": f"{(u, v, psi, n, k)}: {run.stderr.strip()}"}
            a, b, gamma = (float(x) for x in run.stdout.split()[:3])
            final = planner.certifier.final(a, b, k, gamma, n)
            worst = max(worst, Problem((u, v, psi), k=k, steps=n).residual(final))
            q = codegen.reference_plan((u, v, psi), n, k, near=(a, b))
            if q is not None:
                gap = max(gap, abs(q.a - a), abs(q.b - b), abs(float(wrap(q.gamma - gamma))))
    return {"steps_per_leaf": steps_per_leaf, "verified_residual": worst, "gap_to_python": gap}


def accuracy(levels=(240, 280, 320)) -> list:
    """Step-map error and plan exactness against steps per leaf (fewer than 240 are refused for k <= 5:
    the step map is not accurate to 1e-10 near A_MAX, see ``codegen.generate(k_max=...)``)."""
    points_k5 = [(0.69, 0.69, 2.5), (0.69, 0.3, 2.5), (0.1, 0.5, 0.0), (0.5, 0.69, 5.0), (0.3, 0.53, 2.5)]
    points_k10 = [(0.5, 0.69, 10.0)]
    rows = []
    for n in levels:
        row = {"steps_per_leaf": n, "step_map_error_k_le_5": step_map_error(n, points_k5),
               "step_map_error_k10": step_map_error(n, points_k10)}
        row.update(plan_error(n))
        rows.append(row)
        print(json.dumps(row))
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps-per-leaf", type=int, default=codegen.DEFAULT_STEPS_PER_LEAF)
    ap.add_argument("--reps", type=int, default=20)
    ap.add_argument("--accuracy", action="store_true", help="measure error against steps per leaf")
    args = ap.parse_args()
    res = measure(args.steps_per_leaf, args.reps)
    print(json.dumps(res, indent=1))
    if args.accuracy:
        rows = accuracy()
        Path("results").mkdir(exist_ok=True)
        write_json("results/codegen_accuracy.json", {"timing": res, "accuracy": rows})
        print("wrote results/codegen_accuracy.json")


if __name__ == "__main__":
    main()
