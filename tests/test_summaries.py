"""What the command prints: the unit of every length, the solver's part in words, psi wrapped and the
duration as used (issue 29, items 14 and 16). Each test runs the command in a subprocess."""

import math
import os
import subprocess
import sys

import pytest


def rollplan(*argv, cwd=None, timeout=300):
    """``rollplan argv`` in a subprocess: (exit code, stdout, stderr)."""
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", *argv], capture_output=True, text=True,
                       timeout=timeout, check=False, cwd=cwd, env={**os.environ, "COLUMNS": "200"})
    return r.returncode, r.stdout, r.stderr


def test_no_plan_for_a_target_in_metres_names_it_in_radii_and_the_likely_cause():
    """`plan --to 0 1 --duration 10` (the default robot, R = 0.1 m) said only "try more steps": the target is
    1 m = 10 R away, beyond what one figure eight can do; the message says it in both units and how the
    target reads in metres if it was meant in units of R."""
    code, out, err = rollplan("plan", "--to", "0", "1", "--duration", "10")
    assert code == 3, err
    line = err.strip().splitlines()[-1]
    assert "Traceback" not in err and line.startswith("rollplan: no plan:")
    assert "(0 m, 1 m, 0 rad)" in line and "(0 R, 10 R)" in line and "R = 0.1 m" in line
    assert "metres" in line and "(0 m, 0.1 m)" in line   # 0 1 in units of R, in metres


def test_no_plan_for_a_far_target_in_radii_says_how_far():
    code, _, err = rollplan("plan", "--to", "0", "30", "--k", "2.5")
    assert code == 3 and "Traceback" not in err
    assert "30 R away" in err and "metres" not in err


@pytest.fixture(scope="module")
def plan_file(tmp_path_factory):
    """A timed plan of the default robot, psi = 1 rad after one figure eight."""
    folder = tmp_path_factory.mktemp("summaries")
    code, out, err = rollplan("plan", "--to", "0", "0.1", "--psi", "1", "--duration", "10", "--json", "p.json",
                              cwd=folder)
    assert code == 0, err
    return folder / "p.json", out


def test_open_and_closed_loop_name_the_position_error_in_the_same_units(plan_file):
    """The rate-plant simulation printed its position error in m, the executed (open or closed loop) in R:
    both now print metres and radii, and the arrival error by the same norm."""
    path, _ = plan_file
    lines = {}
    for argv in ((), ("--plant", "torques")):
        code, out, err = rollplan("simulate", str(path), *argv)
        assert code == 0, err
        (line,) = [x for x in out.splitlines() if x.strip().startswith("arrival error")]
        lines[argv] = line
    for line in lines.values():
        assert "lengths in R, angles in rad" in line
        pos = line.split("position ", 1)[1]
        value_m, unit_m, value_r, unit_r = pos.replace("(", " ").replace(")", " ").replace(",", " ").split()[:4]
        assert unit_m == "m" and unit_r == "R"
        assert math.isclose(float(value_m), 0.1 * float(value_r), rel_tol=2e-3, abs_tol=1e-15)
