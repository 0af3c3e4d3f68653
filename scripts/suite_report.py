#!/usr/bin/env python
"""Run the test suite by tier and write results/suite.md (and suite.json) from that measurement.

    python scripts/suite_report.py [--tier unit] [--tier full] [--warm] [--jobs auto] [--out-dir results]

Tiers: ``unit`` is ``pytest -m "not slow"``, ``full`` the whole suite; each runs as the README's test command
(``pytest -q -n JOBS``) with ``ROLLPLAN_REQUIRE_EMBEDDED=1`` and ``ROLLPLAN_REQUIRE_MUJOCO=1`` as in ``.ci/run``
(``--no-require`` leaves the environment as it is). Measured per tier: the wall time of the pytest command
(collection and the workers' start included), its CPU time (user + system of pytest and everything it started),
the load average at the start and the end (the machine may be shared), the machine's speed at the start and the
end (:func:`speed_probe`: a virtual machine's speed can change by half from one minute to the next), the counts of
passed, failed (errors included), errored and skipped tests, the names of the failed and errored tests (with the
first line of their message) and of the skipped ones (with the reason), and each test's duration (setup, call and
teardown, from pytest's JUnit XML). A tier not run this time keeps its last measurement (read back from
suite.json); suite.md is rendered from suite.json alone.

Build cache: by default a tier is measured cold, every C library and compiled function built anew in a fresh cache
directory (as on a clean clone). With ``--warm`` it is measured as a developer's next run is: an unmeasured run
first fills the tests' build cache of this package content (tests/conftest.py), then the measured run loads from
it. Cold and warm measurements are kept apart (``unit`` and ``unit, warm cache``).
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from collections import defaultdict
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
#: tier -> (pytest arguments selecting it, budget in s on 2 cores, what the budget is)
TIERS = {"unit": (["-m", "not slow"], 60.0, "under 60 s on 2 cores"),
         "full": ([], 360.0, "under 6 min on 2 cores, idle")}
SLOWEST = 20
FILES = 15
#: at most this many skipped tests are named (all are counted)
SKIPPED_NAMED = 50


#: Iterations of the pure-Python loop of :func:`speed_probe`.
PROBE_ITERATIONS = 3_000_000
#: The loop, run as a module's code (its names in a dict, as a script's top level): the lookups go through memory
#: and so feel a virtual machine's neighbours, as the tests' work does; a function's local variables hardly do.
_PROBE = compile("x = 0\nfor i in range(N):\n    x += i\n", "speed_probe", "exec")


def speed_probe() -> float:
    """Seconds of a fixed pure-Python loop (:data:`PROBE_ITERATIONS` additions at a module's top level; the median
    of three runs): the machine's speed at that moment, measured the same way before and after a tier."""
    times = []
    for _ in range(3):
        t = time.perf_counter()
        exec(_PROBE, {"N": PROBE_ITERATIONS})
        times.append(time.perf_counter() - t)
    return sorted(times)[1]


def processor() -> str:
    """The processor's model name (``/proc/cpuinfo``, else :func:`platform.processor`) and its widest vector
    instructions (they choose the kernels of the OpenBLAS that CasADi bundles, and so the round-off of its solvers;
    ``OPENBLAS_CORETYPE`` overrides them and is named when set): machines differ between runs."""
    model, flags = platform.processor() or "unknown", set()
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as f:
            info = dict(line.split(":", 1) for line in f.read().split("\n\n")[0].splitlines() if ":" in line)
        info = {key.strip(): value.strip() for key, value in info.items()}
        model, flags = info.get("model name", model), set(info.get("flags", "").split())
    except OSError:
        pass
    widest = next((f for f in ("avx512f", "avx2", "avx", "sse4_2") if f in flags), None)
    extra = [x for x in (widest, os.environ.get("OPENBLAS_CORETYPE") and
                         f"OPENBLAS_CORETYPE={os.environ['OPENBLAS_CORETYPE']}") if x]
    return f"{model} ({', '.join(extra)})" if extra else model


def _cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def parse_junit(path) -> list:
    """``[(node id, seconds, outcome, message)]`` of every test case of a JUnit XML report written by pytest;
    outcome is ``passed``, ``failed`` (an assertion or exception in the test), ``error`` (in a fixture's setup or
    teardown, or a collection error) or ``skipped``; message is the first line of the failure's, error's or skip's
    message (empty for a pass). A test that failed and then errored in its teardown is ``failed``."""
    cases = []
    for case in ET.parse(path).getroot().iter("testcase"):
        parts = case.get("classname", "").split(".")
        # pytest writes tests/test_x.py::TestY::test_z as classname tests.test_x.TestY, name test_z
        split = next((i for i, p in enumerate(parts) if p.startswith("test_") or p == "conftest"), len(parts) - 1)
        node = "/".join(parts[:split + 1]) + ".py"
        for p in parts[split + 1:]:
            node += "::" + p
        node += "::" + case.get("name", "")
        children = {child.tag: child for child in case}
        outcome = next((o for o, tag in (("failed", "failure"), ("error", "error"), ("skipped", "skipped"))
                        if tag in children), "passed")
        message = ""
        if outcome != "passed":
            child = children["failure" if outcome == "failed" else outcome]
            message = next((line.strip() for line in (child.get("message") or child.text or "").splitlines()
                            if line.strip()), "")
        cases.append((node, float(case.get("time", 0.0)), outcome, message))
    return cases


#: the short summary lines of pytest's ``-ra`` report: ``FAILED node - message`` / ``ERROR node - message``
_SHORT = re.compile(r"^(FAILED|ERROR) (\S+)(?: - (.*))?$")


def failures_in_output(stdout: str) -> list:
    """``[(node id, outcome, message)]`` named by pytest's short test summary (``-ra``) in ``stdout``: the failed and
    errored tests when no JUnit XML was written (a crash of the run)."""
    found = []
    for line in stdout.splitlines():
        m = _SHORT.match(line.strip())
        if m:
            found.append((m.group(2), "failed" if m.group(1) == "FAILED" else "error", (m.group(3) or "").strip()))
    return found


#: the suffix of the key of a measurement with a warm build cache (``--warm``)
WARM = ", warm cache"


def run_tier(tier: str, jobs: str, tests: str, require: bool, extra: list, warm: bool = False) -> dict:
    """Run one tier, cold or with a warm build cache (module docstring); its measurement as a dict."""
    select, _, _ = TIERS[tier]
    env = dict(os.environ)
    if require:
        env.update(ROLLPLAN_REQUIRE_EMBEDDED="1", ROLLPLAN_REQUIRE_MUJOCO="1")
    env.pop("ROLLPLAN_TEST_FRESH_CACHE", None)
    if not warm:
        env["ROLLPLAN_TEST_FRESH_CACHE"] = "1"
    with tempfile.TemporaryDirectory() as tmp:
        xml = Path(tmp) / "junit.xml"
        cache = [] if warm else ["-p", "no:cacheprovider"]   # the build cache lives in pytest's cache folder
        cmd = [sys.executable, "-m", "pytest", "-q", "-n", jobs, *cache, *select, f"--junitxml={xml}", *extra, tests]
        if warm:
            print(f"{tier}: filling the build cache (unmeasured run)", file=sys.stderr)
            subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, check=False)
        probe0, load0, start = speed_probe(), os.getloadavg(), datetime.datetime.now(datetime.timezone.utc)
        c, t = _cpu(), time.perf_counter()
        run = subprocess.run(cmd, cwd=ROOT, env=env, capture_output=True, text=True, check=False)
        wall, cpu, load1 = time.perf_counter() - t, _cpu() - c, os.getloadavg()
        probe1 = speed_probe()
        cases = parse_junit(xml) if xml.exists() else []
    if run.returncode not in (0, 1):
        print(run.stdout[-3000:], run.stderr[-3000:], sep="\n", file=sys.stderr)
    summary = next((line for line in reversed(run.stdout.splitlines()) if line.strip()), "")
    bad = [[n, o, m] for n, _, o, m in cases if o in ("failed", "error")] if cases else \
        [list(f) for f in failures_in_output(run.stdout)]
    files = defaultdict(float)
    for node, seconds, _, _ in cases:
        files[node.split("::")[0]] += seconds
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True, check=False).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no"],
                           capture_output=True, text=True, check=False).stdout.strip()
    return {
        "cache": "warm" if warm else "fresh",
        "command": " ".join(["python -m pytest -q -n", jobs, *(f'-m "{s}"' for s in select[1:]), tests, *extra]),
        "date": f"{start:%Y-%m-%d %H:%M UTC}", "commit": commit + ("+" if dirty else ""),
        "exit_status": run.returncode, "summary": summary, "cores": os.cpu_count(), "processor": processor(),
        "jobs": jobs,
        "required": require, "wall_s": round(wall, 1), "cpu_s": round(cpu, 1),
        "load_start": [round(x, 2) for x in load0], "load_end": [round(x, 2) for x in load1],
        "probe_s": [round(probe0, 3), round(probe1, 3)], "probe_iterations": PROBE_ITERATIONS,
        "tests": len(cases), "passed": sum(o == "passed" for _, _, o, _ in cases),
        "failed": sum(o in ("failed", "error") for _, _, o, _ in cases),
        "errors": sum(o == "error" for _, _, o, _ in cases),
        "skipped": sum(o == "skipped" for _, _, o, _ in cases),
        "failures": bad,
        "skipped_tests": [[n, m] for n, _, o, m in cases if o == "skipped"][:SKIPPED_NAMED],
        "test_seconds": round(sum(s for _, s, _, _ in cases), 1),
        "slowest": [[n, round(s, 2)] for n, s, _, _ in sorted(cases, key=lambda x: -x[1])[:SLOWEST]],
        "files": [[f, round(s, 1)] for f, s in sorted(files.items(), key=lambda x: -x[1])[:FILES]],
    }


def _minutes(seconds: float) -> str:
    return f"{int(seconds // 60)} min {seconds % 60:04.1f} s" if seconds >= 60 else f"{seconds:.1f} s"


def _cell(text: str, width: int = 200) -> str:
    """``text`` as one cell of a Markdown table: one line, pipes escaped, at most ``width`` characters."""
    text = " ".join(text.split()).replace("|", "\\|")
    return text if len(text) <= width else text[:width - 3] + "..."


def _rows(data: dict) -> list:
    """``[(key, TIERS entry)]``: each tier cold, then with a warm cache where measured."""
    return [(tier + suffix, spec) for tier, spec in TIERS.items() for suffix in ("", WARM)
            if not suffix or tier + suffix in data]


def _probe(m: dict) -> str:
    """The speed cell of a measurement: the loop's seconds at the start and the end, or "not recorded"."""
    probe = m.get("probe_s")
    return f"{probe[0]:.2f} s, {probe[1]:.2f} s" if probe else "not recorded"


def render(data: dict) -> str:
    """results/suite.md from the measurements of suite.json."""
    lines = ["# Duration of the test suite", "",
             "Written by `python scripts/suite_report.py` from its own run of each tier (do not edit by hand): the "
             "wall time of the pytest command, collection and the workers' start included; cold (every C library and "
             "compiled function built anew, as on a clean clone) unless the tier says warm cache (a developer's next "
             "run: loaded from the build cache an earlier run of the same package content filled). The machine may be "
             "shared: the load average at the start and the end is given, and the CPU time (user + system of pytest "
             "and every process it started) depends less on the load than the wall time. The speed of a virtual "
             "machine also changes from minute to minute: the seconds of a fixed pure-Python loop (median of three) "
             "at the start and the end say how fast it was (smaller is faster).", "",
             "| tier | command | date, commit | tests (passed, failed, skipped) | wall time | budget | CPU time | "
             "sum of test durations | cores (processor), workers | load average at start, end (1 min) | "
             "speed: loop at start, end |",
             "|---|---|---|---:|---:|---|---:|---:|---|---|---|"]
    for key, (_, budget, what) in _rows(data):
        m = data.get(key)
        if not m:
            lines.append(f"| {key} | not run by this script yet | | | | {what} | | | | | |")
            continue
        verdict = "within" if m["wall_s"] <= budget else "over"
        lines.append(f"| {key} | `{m['command']}` | {m['date']}, `{m['commit']}` | {m['tests']} ({m['passed']}, "
                     f"{m['failed']}, {m['skipped']}) | **{_minutes(m['wall_s'])}** | {verdict} ({what}) | "
                     f"{_minutes(m['cpu_s'])} | {_minutes(m['test_seconds'])} | "
                     f"{m['cores']} ({m.get('processor', 'not recorded')}), {m['jobs']} | "
                     f"{m['load_start'][0]:.2f}, {m['load_end'][0]:.2f} | {_probe(m)} |")
    for tier, _ in _rows(data):
        m = data.get(tier)
        if not m:
            continue
        failures = m.get("failures")
        if failures is None and (m["failed"] or m.get("errors")):
            lines += ["", f"## Failed and errored tests of the {tier} tier", "", "not recorded by this run"]
        elif failures:
            lines += ["", f"## Failed and errored tests of the {tier} tier", "", "| test | outcome | message |",
                      "|---|---|---|"]
            lines += [f"| `{n}` | {o} | {_cell(msg)} |" for n, o, msg in failures]
        if m.get("skipped_tests"):
            more = m["skipped"] - len(m["skipped_tests"])
            lines += ["", f"## Skipped tests of the {tier} tier", "", "| test | reason |", "|---|---|"]
            lines += [f"| `{n}` | {_cell(reason)} |" for n, reason in m["skipped_tests"]]
            if more > 0:
                lines.append(f"| and {more} more | |")
        lines += ["", f"## The {len(m['slowest'])} slowest tests of the {tier} tier", "",
                  "Duration: setup, call and teardown of the test (session and module fixtures are paid by the first "
                  "test of a worker that uses them).", "", "| test | s |", "|---|---:|"]
        lines += [f"| `{n}` | {s:.1f} |" for n, s in m["slowest"]]
        lines += ["", f"## The {len(m['files'])} slowest files of the {tier} tier", "", "| file | s |", "|---|---:|"]
        lines += [f"| `{f}` | {s:.1f} |" for f, s in m["files"]]
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tier", action="append", choices=list(TIERS), help="tier to run (repeatable; default: both)")
    ap.add_argument("--warm", action="store_true",
                    help="measure with the build cache an unmeasured first run fills (default: cold)")
    ap.add_argument("--jobs", default="auto", help="pytest-xdist workers (-n), default auto")
    ap.add_argument("--out-dir", default=str(ROOT / "results"))
    ap.add_argument("--tests", default="tests", help="the folder (or file) of tests, default tests")
    ap.add_argument("--no-require", action="store_true",
                    help="do not set ROLLPLAN_REQUIRE_EMBEDDED and ROLLPLAN_REQUIRE_MUJOCO (tests may skip)")
    ap.add_argument("pytest_args", nargs="*", help="more arguments for pytest (after --)")
    args = ap.parse_args(argv)
    out = Path(args.out_dir)
    store = out / "suite.json"
    data = json.loads(store.read_text()) if store.exists() else {}
    status = 0
    for tier in args.tier or list(TIERS):
        m = run_tier(tier, args.jobs, args.tests, not args.no_require, args.pytest_args, warm=args.warm)
        key = tier + (WARM if args.warm else "")
        print(f"{key}: {m['summary']} in {m['wall_s']} s", file=sys.stderr)
        data[key] = m
        status = status or m["exit_status"]
    from rollplan.outputs import write_atomic, write_json

    out.mkdir(parents=True, exist_ok=True)
    write_json(store, data)
    write_atomic(out / "suite.md", render(data).encode())
    return status


if __name__ == "__main__":
    sys.exit(main())
