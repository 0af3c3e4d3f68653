"""The scripts in scripts/ run on the package as it is (they are not part of the package's API)."""

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


@pytest.mark.slow
def test_timing_table_script_runs(tmp_path):
    script = Path(__file__).resolve().parent.parent / "scripts" / "timing_table.py"
    subprocess.run([sys.executable, str(script), "--quick", "--out-dir", str(tmp_path)], check=True,
                   capture_output=True, timeout=900)
    text = (tmp_path / "timing.md").read_text()
    assert "of the shortest min-jerk duration under the same limits" in text and "| default (4.86) |" in text
    assert "## Convergence in the grid size" in text and (tmp_path / "timing.json").stat().st_size > 0


@pytest.mark.slow
def test_reconfiguration_script_runs(tmp_path):
    script = Path(__file__).resolve().parent.parent / "scripts" / "reconfiguration.py"
    subprocess.run([sys.executable, str(script), "--quick", "--out-dir", str(tmp_path)], check=True,
                   capture_output=True, timeout=900)
    text = (tmp_path / "reconfiguration.md").read_text()
    assert "## Turning in place" in text and "DOP853" in text and "## A route of five waypoints" in text
    assert (tmp_path / "composed.png").stat().st_size > 0 and (tmp_path / "reconfiguration.json").stat().st_size > 0
