"""The scripts in scripts/ run on the package as it is (they are not part of the package's API)."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest


@pytest.mark.slow
def test_benchmark_script_runs(tmp_path):
    script = Path(__file__).resolve().parent.parent / "scripts" / "benchmark.py"
    subprocess.run([sys.executable, str(script), "--quick", "--no-jit", "--no-cold",
                    "--out-dir", str(tmp_path)], check=True, capture_output=True, timeout=600)
    text = (tmp_path / "benchmarks.md").read_text()
    assert "evaluations/s" in text and "commit" in text and "speed-up" in text and "Profile" in text
    assert "## Budgets" in text and "Collocation planner" in text and "C planner" in text
    assert "load average at start" in text
    assert (tmp_path / "benchmarks.json").stat().st_size > 0


def run_script(name: str, out_dir, *args: str, timeout: float = 900) -> None:
    """Run scripts/NAME with ``args`` and ``--out-dir out_dir``; fails on a nonzero exit."""
    script = Path(__file__).resolve().parent.parent / "scripts" / name
    subprocess.run([sys.executable, str(script), *args, "--out-dir", str(out_dir)], check=True, capture_output=True,
                   timeout=timeout)


@pytest.mark.slow
def test_timing_table_script_runs(tmp_path):
    run_script("timing_table.py", tmp_path, "--quick")
    text = (tmp_path / "timing.md").read_text()
    assert "of the shortest min-jerk duration under the same limits" in text and "| default (4.86) |" in text
    assert "## Convergence in the grid size" in text and (tmp_path / "timing.json").stat().st_size > 0


@pytest.mark.slow
def test_reconfiguration_script_runs(tmp_path):
    run_script("reconfiguration.py", tmp_path, "--quick")
    text = (tmp_path / "reconfiguration.md").read_text()
    assert "## Turning in place" in text and "DOP853" in text and "## A route of five waypoints" in text
    assert (tmp_path / "composed.png").stat().st_size > 0 and (tmp_path / "reconfiguration.json").stat().st_size > 0


@pytest.mark.slow
def test_closed_loop_script_runs(tmp_path):
    """The script end to end with one seed per case, two model errors, one noise level of the issue's case and
    one plan of the torque-against-rate comparison (every section, fewer samples of each than even --quick)."""
    scripts = Path(__file__).resolve().parent.parent / "scripts"
    run = ("import sys; sys.path.insert(0, sys.argv[1]); import closed_loop as c; c.ERRORS = (0.01, 0.10); "
           "c.NOISE_LEVELS = (1e-3,); c.TORQUE_CASES = c.TORQUE_CASES[:1]; c.MUJOCO_STEPS = (1,); "
           "c.BEYOND = c.BEYOND[:1]; sys.argv = [c.__file__] + sys.argv[2:]; c.main()")
    subprocess.run([sys.executable, "-c", run, str(scripts), "--seeds", "1", "--torque-seeds", "1", "--mujoco-seeds",
                    "1", "--out-dir", str(tmp_path)], check=True, capture_output=True, timeout=1800)
    text = (tmp_path / "closed_loop.md").read_text()
    assert "## 1. The issue's robot" in text and "## 2. Monte Carlo" in text and "## 3. Torque-driven" in text
    assert "## 4. The issue's robot closed loop" in text and "| torque plant | 1 |" in text
    assert (tmp_path / "closed_loop.png").stat().st_size > 0 and (tmp_path / "closed_loop.json").stat().st_size > 0


@pytest.mark.slow
@pytest.mark.skipif(any(shutil.which(t) is None for t in ("arm-none-eabi-gcc", "qemu-system-arm", "make", "cc"))
                    and os.environ.get("ROLLPLAN_REQUIRE_EMBEDDED") != "1", reason="needs the ARM toolchain and QEMU")
def test_embedded_report_script_runs(tmp_path):
    run_script("embedded_report.py", tmp_path, "--no-host", timeout=1800)
    text = (tmp_path / "embedded.md").read_text()
    assert "| double | m7 (mps2-an500) |" in text and "| float | m4f (mps2-an386) |" in text
    assert "Instructions per plan" in text and (tmp_path / "embedded.json").stat().st_size > 0


FAKE_TESTS = """import time
import pytest

def test_quick():
    pass

@pytest.mark.slow
def test_slow():
    time.sleep(0.3)

@pytest.mark.parametrize("x", [1, 2])
def test_param(x):
    assert x

@pytest.mark.skip(reason="shown as skipped")
def test_skipped():
    pass

def test_fails():
    assert False
"""


@pytest.mark.slow
def test_suite_report_writes_suite_md_from_its_own_run(tmp_path):
    """scripts/suite_report.py runs each tier of a small suite whose counts are known (six tests: four pass,
    one of them slow, one is skipped, one fails) and writes suite.md from that run: the counts, the slowest
    test, the status; a second run of one tier keeps the other tier's row."""
    tests = tmp_path / "fake"
    tests.mkdir()
    (tests / "pytest.ini").write_text("[pytest]\nmarkers =\n    slow: slow\n")
    (tests / "test_fake.py").write_text(FAKE_TESTS)
    script = Path(__file__).resolve().parent.parent / "scripts" / "suite_report.py"
    out = tmp_path / "out"
    run = subprocess.run([sys.executable, str(script), "--jobs", "0", "--tests", str(tests), "--out-dir", str(out)],
                         capture_output=True, text=True, timeout=600, check=False)
    assert run.returncode == 1, run.stderr      # pytest's status: a test failed
    data = json.loads((out / "suite.json").read_text())
    assert (data["unit"]["tests"], data["unit"]["passed"], data["unit"]["failed"], data["unit"]["skipped"]) == \
        (5, 3, 1, 1)
    assert (data["full"]["tests"], data["full"]["passed"], data["full"]["failed"], data["full"]["skipped"]) == \
        (6, 4, 1, 1)
    assert data["full"]["slowest"][0][0] == "test_fake.py::test_slow" and data["full"]["slowest"][0][1] >= 0.3
    assert {n for n, _ in data["full"]["slowest"]} == {"test_fake.py::" + n for n in (
        "test_quick", "test_slow", "test_param[1]", "test_param[2]", "test_skipped", "test_fails")}
    assert data["full"]["wall_s"] >= 0.3 and data["unit"]["exit_status"] == 1
    text = (out / "suite.md").read_text()
    assert "| unit |" in text and "| full |" in text and "6 (4, 1, 1)" in text and "5 (3, 1, 1)" in text
    assert "`test_fake.py::test_slow`" in text and "scripts/suite_report.py" in text
    (tests / "test_fake.py").write_text(FAKE_TESTS.replace("assert False", "pass"))
    run = subprocess.run([sys.executable, str(script), "--jobs", "0", "--tier", "unit", "--tests", str(tests),
                          "--out-dir", str(out)], capture_output=True, text=True, timeout=600, check=False)
    assert run.returncode == 0, run.stderr
    again = json.loads((out / "suite.json").read_text())
    assert again["full"] == data["full"] and (again["unit"]["passed"], again["unit"]["failed"]) == (4, 0)
    assert "6 (4, 1, 1)" in (out / "suite.md").read_text()


@pytest.mark.slow
def test_curve_families_script_runs_and_its_plans_land(tmp_path):
    """The study's quick run (the paper's case): every family's plan, from the planner or the script's own search,
    lands on the target when its figure eight is integrated by DOP853 along the leaves typed in tests/references.py
    (the printed (28)-(30)); the report names how each plan was found and what was concluded."""
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import references

    run_script("curve_families.py", tmp_path, "--quick", timeout=1800)
    text = (tmp_path / "curve_families.md").read_text()
    assert "## Summary over the grid" in text and "## Conclusions" in text and "Non-stop with continuous" in text
    assert (tmp_path / "curve_families.png").stat().st_size > 1000
    rep = json.loads((tmp_path / "curve_families.json").read_text())
    (row,) = rep["rows"]
    assert set(row["families"]) == {"circles", "viviani", "triangle", "square"}
    for name, f in row["families"].items():
        end = references.family_trace(name, f["a"], f["b"], row["k"], f["gamma"])
        assert abs(end[0] - 0.0) < 1e-8 and abs(end[1] - 1.0) < 1e-8, name
        assert abs(references.wrap(end[2])) < 1e-8, name
        assert f["source"] in ("planner", "search") and f["path_length"] > 0
    assert row["families"]["viviani"]["nonstop_continuous"] and not row["families"]["circles"]["nonstop_continuous"]
    if "search" in {f["source"] for f in row["families"].values()}:
        assert "## How the plans were found" in text


@pytest.mark.slow
def test_basepoint_bench_script_runs(tmp_path):
    run_script("basepoint_bench.py", tmp_path, "--quick")
    text = (tmp_path / "basepoint.md").read_text()
    assert "| README example |" in text and "| random 1 |" in text and "DOP853" in text
    rows = json.loads((tmp_path / "basepoint.json").read_text())["rows"]
    assert all(r["any_length"] <= r["pole_length"] and r["dop853_residual"] <= 1e-9 for r in rows)
