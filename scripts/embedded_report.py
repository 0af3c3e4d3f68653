"""Measure the generated C planner on its microcontrollers: flash, RAM, stack and instructions per plan.

Usage::

    python scripts/embedded_report.py               # writes results/embedded.md and results/embedded.json
    python scripts/embedded_report.py --no-host     # without the host timing (scripts/bench_codegen.py)
    python scripts/embedded_report.py --quick --no-host --out-dir /tmp/e   # the paper's case only: a check
    python scripts/embedded_report.py --build-dir build/embedded   # keep the builds; a rerun reuses them

Generates the planner in double and in float (``rollplan codegen --real float``), cross-compiles both
with the generated Makefile (Cortex-M7 with a double FPU on QEMU's mps2-an500, Cortex-M4F with a
single-precision FPU on the mps2-an386) and reads ``make size`` (flash and RAM of the planner firmware
and of plan_demo, the static stack bound of ``<prefix>_plan``, the stack plan_demo used). Instructions per
plan are counted on the emulated boards: QEMU with ``-icount shift=0`` advances its clock 1 ns per
instruction, and the boards' CMSDK timer (25 MHz) counts one tick per 40 instructions. QEMU counts
instructions, not cycles (it models no pipeline, FPU latency or flash wait states). Needs arm-none-eabi-gcc
(with newlib), qemu-system-arm, make and cc.

The builds go to a temporary folder, or with ``--build-dir DIR`` to ``DIR/<real>-<digest>`` (the digest of the
generated sources and of the toolchain's versions), kept: a later run whose generated sources and toolchain are
the same reuses that folder (``make`` rebuilds what is out of date: nothing); the measurements are made anew.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from quick_runs import refuse_quick_into_results  # noqa: E402


def parse_args(argv=None):
    """The command line; ``--quick`` without ``--out-dir`` exits 2 with one line (before the slow imports below)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", help="folder of embedded.md and embedded.json (default results; with --quick, "
                                      "required: results/ keeps the full report)")
    ap.add_argument("--no-host", action="store_true", help="skip the host timing")
    ap.add_argument("--build-dir", help="keep the builds in DIR/<real>-<digest> and reuse them in later runs of "
                                        "the same generated sources and toolchain (default: a temporary folder)")
    ap.add_argument("--quick", action="store_true",
                    help="count the instructions of the paper's case only (of the first of TARGETS), to check "
                         "that the script runs")
    args = ap.parse_args(argv)
    refuse_quick_into_results(args, "embedded_report.py")
    return args


if __name__ == "__main__":
    parse_args()

import numpy as np  # noqa: E402

from rollplan.codegen import c_library as codegen  # noqa: E402
from rollplan.io import write_atomic, write_json  # noqa: E402
from rollplan.problem import K_MIN  # noqa: E402

import bench_codegen  # noqa: E402

#: Targets (u, v, psi, steps, k) counted on the boards: the paper's case first.
TARGETS = [(0.0, 1.0, 0.0, 1, 2.5), (0.3, -0.2, 0.5, 1, 2.5), (2.0, 1.0, 1.0, 3, 2.5), (0.0, 2.0, 0.0, 1, 5.0)]
BOARDS = {"m7": "mps2-an500", "m4f": "mps2-an386"}

_BENCH_FW = r"""
/* bench_fw U V PSI STEPS K -- instructions (under QEMU -icount shift=0) of the first plan (builds the
 * rho table of the leaf map), a plan with the table kept, and the plan's certificate alone. */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include "@PREFIX@.h"
#define TIMER1_LOAD (*(volatile uint32_t *)0x40002000u)
#define TIMER1_VALUE (*(volatile uint32_t *)0x40002004u)
#define TIMER1_CONTROL (*(volatile uint32_t *)0x40002008u)
int main(int argc, char **argv) {
    @PREFIX@_plan_t plan;
    casadi_real x[5], res, bound;
    uint32_t t0, t1, t2, t3;
    int status, i;
    if (argc != 6) return 2;
    for (i = 0; i < 5; ++i) x[i] = (casadi_real)atof(argv[i + 1]);
    TIMER1_LOAD = 0xFFFFFFFFu;
    TIMER1_CONTROL = 0x80u | 0x02u;   /* enable, 32 bit, free running, prescale 1: counts down */
    t0 = TIMER1_VALUE;
    status = @PREFIX@_plan(x[0], x[1], x[2], (int)x[3], x[4], &plan);
    t1 = TIMER1_VALUE;
    status = @PREFIX@_plan(x[0], x[1], x[2], (int)x[3], x[4], &plan);
    t2 = TIMER1_VALUE;
    @PREFIX@_certify(plan.a, plan.b, plan.gamma, (int)x[3], x[4], x[0], x[1], x[2], NULL, &res, &bound);
    t3 = TIMER1_VALUE;
    printf("%d %lu %lu %lu\n", status, 40ul * (unsigned long)(t0 - t1), 40ul * (unsigned long)(t1 - t2),
           40ul * (unsigned long)(t2 - t3));
    return 0;
}
"""


def make(out: Path, *goals: str) -> str:
    return subprocess.run(["make", "-s", "-C", str(out), *goals], check=True, capture_output=True, text=True,
                          timeout=1800).stdout


def sizes(out: Path) -> dict:
    """``make size`` of a generated folder, parsed: bytes per board."""
    text = make(out, "size")
    res = {}
    for t in BOARDS:
        fw = re.search(rf"{t} planner firmware .*flash (\d+) B, RAM (\d+) B", text)
        demo = re.search(rf"{t} plan_demo .*flash (\d+) B, RAM (\d+) B", text)
        bound = re.search(rf"{t} static stack bound: \S+: (\d+) bytes", text)
        used = re.search(rf"{t} measured stack of plan_demo .*?(\d+) bytes", text)
        res[t] = {"planner_flash": int(fw[1]), "planner_ram": int(fw[2]), "plan_demo_flash": int(demo[1]),
                  "plan_demo_ram": int(demo[2]), "stack_bound": int(bound[1]), "stack_measured": int(used[1])}
    return res


def instructions(out: Path, prefix: str, targets=TARGETS) -> dict:
    """Instructions per plan on each board for every target (first plan, plan, certificate)."""
    source = _BENCH_FW.replace("@PREFIX@", prefix)
    if not (out / "bench_fw.c").exists() or (out / "bench_fw.c").read_text() != source:   # kept: no rebuild
        (out / "bench_fw.c").write_text(source)
    res = {}
    for t, machine in BOARDS.items():
        make(out, f"build/{t}/bench_fw.elf")
        rows = []
        for target in targets:
            semi = ",".join(["enable=on", "target=native", "arg=bench_fw", *(f"arg={x!r}" for x in target)])
            run = subprocess.run(["timeout", "-k", "5", "300", "qemu-system-arm", "-M", machine, "-icount", "shift=0",
                                  "-nographic", "-monitor", "none", "-serial", "none", "-semihosting-config", semi,
                                  "-kernel", str(out / "build" / t / "bench_fw.elf")], capture_output=True, text=True,
                                 stdin=subprocess.DEVNULL, check=True, timeout=320)
            status, first, plan, cert = (int(x) for x in run.stdout.split())
            rows.append({"target": list(target), "status": status, "first_plan": first, "plan": plan,
                         "certificate": cert})
        res[t] = rows
    return res


def build(real: str, tmp: Path, build_dir: str | None, tools: dict) -> tuple[Path, str]:
    """Generate the planner in ``real`` and cross-compile it for the boards; returns (folder, prefix). The folder is
    ``tmp/real``, or with ``build_dir`` ``build_dir/<real>-<digest>`` (the generated files and ``tools``), reused
    when it exists."""
    g = codegen.generate(tmp / real, real=real)
    out = bench_codegen.kept(tmp / real, build_dir, real, tools,   # the boards only: the host build is not reported
                             lambda folder: make(folder, "-j2", "arm-m7", "arm-m4f"))
    return out, g.prefix


def versions() -> dict:
    def first_line(cmd):
        return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout.splitlines()[0]
    return {"arm-none-eabi-gcc": first_line(["arm-none-eabi-gcc", "--version"]),
            "qemu-system-arm": first_line(["qemu-system-arm", "--version"])}


def report(data: dict) -> str:
    lines = ["# The C planner on microcontrollers", "",
             "Regenerate: `python scripts/embedded_report.py` (writes this file and `embedded.json`).",
             f"Toolchain: {data['versions']['arm-none-eabi-gcc']}; {data['versions']['qemu-system-arm']}.",
             f"Planner: {K_MIN:g} <= k <= {data['k_max']:g} (step map of rollplan_step_eval: "
             f"{data['steps_per_leaf']} steps per leaf), certificate "
             f"tolerance {codegen.CERT_TOL:g} (double) / {codegen.FLOAT_CERT_TOL:g} (float).", "",
             "## Memory (bytes; static only, no heap)", "",
             "| build | board | planner firmware flash | RAM | plan_demo flash | RAM | stack bound of plan | "
             "stack used by plan_demo |", "|---|---|---|---|---|---|---|---|"]
    for real in ("double", "float"):
        for t, machine in BOARDS.items():
            s = data[real]["sizes"][t]
            lines.append(f"| {real} | {t} ({machine}) | {s['planner_flash']} | {s['planner_ram']} | "
                         f"{s['plan_demo_flash']} | {s['plan_demo_ram']} | {s['stack_bound']} | "
                         f"{s['stack_measured']} |")
    lines += ["", "Planner firmware = the library, the libm it calls and the startup file, no stdio (planner_only.c); "
              "plan_demo adds newlib's printf/strtod (which use a heap). The stack bound is static (the "
              "deepest call chain of the linked ELF, libm included; scripts: stack_bound.py of the generated "
              "folder), without interrupts. A double build on the M4F runs in software double.", "",
              "## Instructions per plan on the emulated boards (QEMU -icount; not cycles)", "",
              "| build | board | target (u, v, psi, n, k) | status | first plan (builds the rho table) | plan | "
              "of which the certificate |", "|---|---|---|---|---|---|---|"]
    for real in ("double", "float"):
        for t in BOARDS:
            for row in data[real]["instructions"][t]:
                lines.append(f"| {real} | {t} | {tuple(row['target'])} | {row['status']} | {row['first_plan']} | "
                             f"{row['plan']} | {row['certificate']} |")
    if data.get("host"):
        h = data["host"]
        lines += ["", "## Host (x86-64, cc -O2), side by side with the Python planner", "",
                  "Per target of scripts/bench_codegen.py: the best of repeated C plans (a new k: the leaf map's "
                  "rho table is built first; the same k: the table kept), the certificate alone, and one warm "
                  "Python plan (GeometricPhasePlanner.solve, the same algorithm, its certificate included).", "",
                  "| target (u, v, psi, n, k) | C new k [us] | C same k [us] | C without certificate [us] | "
                  "certificate [us] | Python [ms] |", "|---|---|---|---|---|---|"]
        py = h.get("python_ms_per_target") or [float("nan")] * len(h["c_per_target"])
        for target, row, ms in zip(bench_codegen.TARGETS, h["c_per_target"], py):
            lines.append(f"| {tuple(target)} | {row[0]:.0f} | {row[1]:.1f} | {row[2]:.1f} | {row[3]:.1f} | {ms:.2f} |")
        lines += ["", "| quantity | mean | median | max |", "|---|---|---|---|"]
        for name, key in (("C plan, new k [us]", "c_us_per_plan"), ("C plan, same k [us]", "c_us_per_plan_same_k"),
                          ("C plan without the certificate [us]", "c_us_per_plan_same_k_without_certificate"),
                          ("certificate alone [us]", "c_us_certificate")):
            lines.append(f"| {name} | {h[key]:.1f} | {h[key + '_median']:.1f} | {h[key + '_max']:.1f} |")
        if h.get("python_ms_per_target"):
            lines.append(f"| Python plan [us] | {1e3 * h['python_ms_per_plan']:.0f} | "
                         f"{1e3 * float(np.median(py)):.0f} | {1e3 * max(py):.0f} |")
        if data.get("host_many"):
            m = data["host_many"]
            lines += ["", "Targets whose shortest plan lies below many branches of the search "
                      "(bench_codegen.MANY_BRANCH_TARGETS), measured the same way:", "",
                      "| target (u, v, psi, n, k) | C new k [us] | C same k [us] | C without certificate [us] | "
                      "certificate [us] | Python [ms] |", "|---|---|---|---|---|---|"]
            py = m.get("python_ms_per_target") or [float("nan")] * len(m["c_per_target"])
            for target, row, ms in zip(bench_codegen.MANY_BRANCH_TARGETS, m["c_per_target"], py):
                lines.append(f"| {tuple(target)} | {row[0]:.0f} | {row[1]:.1f} | {row[2]:.1f} | {row[3]:.1f} | "
                             f"{ms:.2f} |")
        lines += ["", f"Load average at the start: {data['load']}. The machine is shared: the instruction counts "
                  "above are the stable figures."]
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    args = parse_args(argv)
    args.out_dir = args.out_dir or "results"
    load = Path("/proc/loadavg").read_text().split()[0] if Path("/proc/loadavg").exists() else "?"
    data = {"quick": args.quick, "versions": versions(), "steps_per_leaf": codegen.DEFAULT_STEPS_PER_LEAF,
            "k_max": codegen.DEFAULT_K_MAX,
            "load": load}
    with tempfile.TemporaryDirectory() as tmp:
        for real in ("double", "float"):
            out, prefix = build(real, Path(tmp), args.build_dir, data["versions"])
            data[real] = {"sizes": sizes(out),
                          "instructions": instructions(out, prefix, TARGETS[:1] if args.quick else TARGETS)}
            print(f"{real}: {data[real]['sizes']}", file=sys.stderr)
    if not args.no_host:
        data["host"] = bench_codegen.measure(reps=20, python=True)
        data["host_many"] = bench_codegen.measure(reps=20, python=True, targets=bench_codegen.MANY_BRANCH_TARGETS)
    out_dir = Path(args.out_dir)
    out_dir.mkdir(exist_ok=True)
    write_json(out_dir / "embedded.json", data)
    write_atomic(out_dir / "embedded.md", report(data).encode())
    print(f"wrote {out_dir / 'embedded.md'} and {out_dir / 'embedded.json'}")


if __name__ == "__main__":
    main()
