"""What the command prints: the unit of every length, the solver's part in words, psi wrapped and the
duration as used (issue 29, items 14 and 16). Each test runs the command (in this process, COLUMNS=200)."""

import json
import math

import pytest
from conftest import run


@pytest.fixture(autouse=True)
def _wide(monkeypatch):
    """The terminal width that the summaries are read at."""
    monkeypatch.setenv("COLUMNS", "200")


def test_no_plan_for_a_target_in_metres_names_it_in_radii_and_the_likely_cause(capfd):
    """`plan --to 0 1 --duration 10` (the default robot, R = 0.1 m) said only "try more steps": the target is
    1 m = 10 R away, beyond what one figure eight can do; the message says it in both units and how the
    target reads in metres if it was meant in units of R."""
    code, out, err = run(capfd, "plan", "--to", "0", "1", "--duration", "10")
    assert code == 3, err
    line = err.strip().splitlines()[-1]
    assert "Traceback" not in err and line.startswith("rollplan: no plan:")
    assert "(0 m, 1 m, 0 rad)" in line and "(0 R, 10 R)" in line and "R = 0.1 m" in line
    assert "metres" in line and "(0 m, 0.1 m)" in line   # 0 1 in units of R, in metres


def test_no_plan_for_a_far_target_in_radii_says_how_far(capfd):
    code, _, err = run(capfd, "plan", "--to", "0", "30", "--k", "2.5")
    assert code == 3 and "Traceback" not in err
    assert "30 R away" in err and "metres" not in err


@pytest.fixture
def plan_file(tmp_path, capfd):
    """A timed plan of the default robot, psi = 1 rad after one figure eight."""
    code, out, err = run(capfd, "plan", "--to", "0", "0.1", "--psi", "1", "--duration", "10", "--json", "p.json",
                         cwd=tmp_path)
    assert code == 0, err
    return tmp_path / "p.json", out


@pytest.mark.slow
def test_open_and_closed_loop_name_the_position_error_in_the_same_units(plan_file, capfd):
    """The rate-plant simulation printed its position error in m, the executed (open or closed loop) in R:
    both now print metres and radii, and the arrival error by the same norm."""
    path, _ = plan_file
    lines = {}
    for argv in ((), ("--plant", "torques")):
        code, out, err = run(capfd, "simulate", str(path), *argv)
        assert code == 0, err
        (line,) = [x for x in out.splitlines() if x.strip().startswith("arrival error")]
        lines[argv] = line
    for line in lines.values():
        assert "lengths in R, angles in rad" in line
        pos = line.split("position ", 1)[1]
        value_m, unit_m, value_r, unit_r = pos.replace("(", " ").replace(")", " ").replace(",", " ").split()[:4]
        assert unit_m == "m" and unit_r == "R"
        assert math.isclose(float(value_m), 0.1 * float(value_r), rel_tol=2e-3, abs_tol=1e-15)


def _line(out, label):
    (line,) = [x for x in out.splitlines() if x.strip().startswith(label)]
    return line


def test_final_psi_is_printed_wrapped_with_its_turns(tmp_path, capfd):
    """A plan on branch m = -1 for psi = 1 rad printed the final psi unwrapped (-5.28319 rad): the summary
    prints it wrapped to [-pi, pi] with the turn taken off; the JSON keeps the unwrapped value."""
    code, out, err = run(capfd, "plan", "--to", "0.5", "0.3", "--psi", "1", "--branch", "-1", "--json", "p.json",
                         cwd=tmp_path)
    assert code == 0, err
    final = _line(out, "final")
    psi = float(final.split("psi = ", 1)[1].split()[0])
    assert psi == pytest.approx(1.0, abs=1e-5) and "-1 turn" in final
    unwrapped = json.loads((tmp_path / "p.json").read_text())["final"]["psi"]
    assert unwrapped == pytest.approx(1.0 - 2.0 * math.pi, abs=1e-9)


def test_the_solver_line_says_what_happened_in_words(capfd):
    """'ipopt: Solve_Succeeded, 0 iterations ... 1 roots certified or rejected' puzzled a reader of an exact
    planner: the line says the roots were searched exactly and what polishing them took."""
    code, out, err = run(capfd, "plan", "--to", "0", "1", "--k", "2.5")
    assert code == 0, err
    line = _line(out, "solver")   # the default: search, polish and certificate in C
    assert "root polished by Newton on the accurate leaf map and certified, in C" in line
    code, out, err = run(capfd, "plan", "--to", "0", "1", "--k", "2.5", "--method", "ipopt")
    assert code == 0, err
    line = _line(out, "solver")
    assert "Solve_Succeeded" not in line and "root polished by ipopt" in line
    iterations = int(line.split("root polished by ipopt: ", 1)[1].split()[0])
    assert ("already at the root" in line) == (iterations == 0)


@pytest.mark.slow
def test_the_shortest_duration_used_and_reported_agree(tmp_path, capfd):
    """`T = 3.68811 s` was printed beside 'shortest feasible duration 3.68812 s' for the same duration: both
    are now the same number, and the rounded-up value to give back as --duration is named as such and
    accepted."""
    robot = tmp_path / "robot.toml"
    robot.write_text("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2.0e-4\n"
                     "rotor_inertia_transverse = 1.2e-4\nmax_rotor_rate = 300.0\nmax_rotor_torque = 0.05\n")
    code, out, err = run(capfd, "plan", "--robot", str(robot), "--to", "0", "0.1", "--timing", "time-optimal")
    assert code == 0, err
    used = _line(out, "motion").split("T = ", 1)[1].split()[0]
    limits = _line(out, "limits")
    shortest = limits.split("duration with timing time-optimal is ", 1)[1].split()[0]
    assert used == shortest and "(the shortest feasible)" in _line(out, "motion")
    again = limits.split("as --duration: ", 1)[1].split()[0]
    assert float(again) >= float(shortest)
    code, out, err = run(capfd, "plan", "--robot", str(robot), "--to", "0", "0.1", "--timing", "time-optimal",
                              "--duration", again)
    assert code == 0, err
