"""Regressions of the reliability review (issue 16): nothing wrong is reported as success, nothing hangs,
and a user's mistake is one line with exit 2. Each test names the defect it pins down; the items checked in
other files are listed in the issue's table of the closing report (test_inputs, test_outputs, test_batch,
test_robot, test_interrupts, test_codegen, test_fuzz)."""

import dataclasses
import json
import math
import os
import subprocess
import sys
import warnings
from fractions import Fraction

import numpy as np
import pytest
from conftest import one_line, run

import rollplan
from rollplan import GeometricPhasePlanner, InputError, Problem, Robot, State
from rollplan.problem import arrival_error

import references


def angle_gap(a, b):
    two_pi = references.two_pi_fraction()
    d = (Fraction(a) - Fraction(b)) % two_pi
    return float(min(d, two_pi - d))


# ----------------------------------------------------------------------------- wrong results reported as success


@pytest.mark.parametrize("psi", ["1e8", "1e10", "1e16", "-3.7e12"])
def test_large_psi_is_reached_to_full_accuracy(tmp_path, capsys, psi):
    """`plan --psi 1e8` claimed 3e-14 with a true orientation error of 5.9e-9 (0.47 rad at 1e16): the plan's
    figure eight, integrated by DOP853 on the printed equations, reaches psi modulo the exact 2 pi."""
    out = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", "--to", "0", "1", f"--psi={psi}", "--k", "2.5", "--json", str(out))
    assert code == 0, err
    d = json.loads(out.read_text())
    fe = d["figure_eight"]
    x = references.trace(fe["a"], fe["b"], 2.5, fe["gamma"], 1)
    assert math.hypot(x[0], x[1] - 1.0) < 1e-9 and angle_gap(x[2], float(psi)) < 1e-9
    assert d["residual"] < 1e-9


def test_arrival_error_reduces_each_angle_exactly():
    """arrival_error (the residual of every certificate and of the rotor simulation) compares psi modulo the
    exact 2 pi: a final psi equal to 1e16 reduced is at distance 0 from 1e16 (float wrap: 0.47 rad)."""
    two_pi = references.two_pi_fraction()
    for goal in (1e8, 1e16, -2.5e300):
        reduced = float(Fraction(goal) - two_pi * round(Fraction(goal) / two_pi))
        err = arrival_error(State(0, 0, reduced), State(0, 0, goal))
        assert abs(err[2]) < 1e-15
        err = arrival_error(State(0, 0, reduced + 1e-12), State(0, 0, goal))
        assert abs(err[2] - 1e-12) < 1e-15


def test_rotor_simulation_from_a_large_psi_keeps_full_accuracy():
    """A rotor-driven motion started at psi = 1e8 + x is the motion started at x (psi is an angle)."""
    t = np.linspace(0, 2, 201)
    rates = np.column_stack([10 * np.sin(3 * t), 8 * np.cos(2 * t) - 8])
    robot = Robot()
    big = rollplan.simulate_rotors(robot, t, rates, x0=(0, 0, 1e8, 0, 0))
    two_pi = references.two_pi_fraction()
    reduced = float(Fraction(1e8) - two_pi * round(Fraction(1e8) / two_pi))
    small = rollplan.simulate_rotors(robot, t, rates, x0=(0, 0, reduced, 0, 0))
    np.testing.assert_allclose(big.series.state, small.series.state, atol=1e-12)


@pytest.mark.parametrize("options, needle", [
    (dict(tol=float("nan"), nodes=2), "tol"), (dict(tol=-1), "tol"), (dict(tol=math.inf), "tol"),
    (dict(tol="1e-9"), "tol"), (dict(nodes=0), "nodes"), (dict(nodes=-1), "nodes"), (dict(nodes=1.5), "nodes"),
    (dict(nodes=2), "nodes"), (dict(method=["ipopt"]), "method"), (dict(method="IPOPT"), "method"),
])
def test_every_option_of_the_planner_is_validated(options, needle):
    """GeometricPhasePlanner(tol=nan, nodes=2) returned a plan with residual 1.1e-3."""
    with pytest.raises(InputError, match=needle) as err:
        GeometricPhasePlanner(**options)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("options, needle", [
    (dict(intervals=0), "intervals"), (dict(degree=10), "degree"), (dict(scheme=["x"]), "scheme"),
    (dict(cost="energy"), "cost"), (dict(contact_bound=2.0), "contact_bound"), (dict(tol=float("nan")), "tol"),
    (dict(max_iter=1.5), "max_iter"), (dict(verify_samples=0), "verify_samples"), (dict(verify_tol=-1), "verify_tol"),
])
def test_every_option_of_the_collocation_planner_is_validated(options, needle):
    with pytest.raises(InputError, match=needle):
        rollplan.CollocationPlanner(**options)


def test_other_public_classes_validate_their_options():
    from rollplan.core.curves import figure_eight
    from rollplan.core.integrate import CvodesIntegrator
    from rollplan.planners.geometric.certify import CvodesCertifier

    for bad in (dict(reltol=float("nan")), dict(abstol=0.0), dict(multistep="rk4")):
        with pytest.raises(InputError):
            CvodesIntegrator(figure_eight(), **bad)
    with pytest.raises(InputError):
        CvodesIntegrator("curve")
    with pytest.raises(InputError):
        CvodesCertifier(reltol=-1.0)


@pytest.mark.slow
def test_short_duration_is_served_or_refused_never_a_failed_motion_with_exit_0(tmp_path, capsys):
    """`--duration 1e-6` printed "rotor-only arrival error 1.00e+00" and exited 0: the shortest accepted
    duration is served (the rotor simulation runs in normalized time, so the motion reaches its goal, which an
    independent DOP853 simulation of the JSON's rotor rates confirms); shorter and longer ones, and durations
    whose rates or torques overflow, are refused before any work."""
    from rollplan.execution.timing import DURATION_RANGE

    out = tmp_path / "p.json"
    shortest = repr(DURATION_RANGE[0])
    code, text, err = run(capsys, "plan", "--to", "0", "0.1", "--duration", shortest, "--json", str(out))
    assert code == 0, err
    d = json.loads(out.read_text())
    assert d["rotor_simulation"]["arrival_error"] < 1e-6
    final = references.rotor_drive(d["robot"], np.asarray(d["time"]), np.asarray(d["rotor_rates"]))[-1]
    assert math.hypot(final[0] - 0.0, final[1] - 0.1) / d["radius"] < 1e-6
    assert code == 0 and run(capsys, "simulate", str(out))[0] == 0
    _too_short_or_long_durations_are_refused(tmp_path, capsys)


def test_durations_and_samples_out_of_range_are_refused_before_any_work(tmp_path, capsys):
    """The refusals of the test above, in the unit tier (they cost no plan)."""
    _too_short_or_long_durations_are_refused(tmp_path, capsys)


def _too_short_or_long_durations_are_refused(tmp_path, capsys):
    from rollplan.execution.timing import DURATION_RANGE

    out = tmp_path / "p.json"
    for duration in ("1e-6", "1e-300", "1e308", repr(DURATION_RANGE[1] * 1.5), "0", "-1"):
        code, text, err = run(capsys, "plan", "--to", "0", "0.1", "--duration", duration)
        assert code == 2 and "duration" in err and one_line(err) and text == ""   # refused before planning
    for argv in (["--duration", "5"], ["--duration", "5", "--json", str(out)], []):
        code, text, err = run(capsys, "plan", "--to", "0", "0.1", *argv, "--samples", "10000000000")
        assert code == 2 and "samples" in err and one_line(err) and text == ""


def test_motion_api_refuses_wrong_types():
    p = rollplan.plan((0, 0.1, 0), robot=Robot())
    for call in (lambda: rollplan.actuate(None, Robot(), 1.0), lambda: rollplan.actuate(p, None, 1.0),
                 lambda: rollplan.actuate(p, {"radius": 0.1}, 1.0), lambda: rollplan.actuate(p, Robot(), "1"),
                 lambda: rollplan.simulate_rotors(None, [0, 1, 2, 3], [[0, 0]] * 4),
                 lambda: rollplan.simulate_rotors(Robot(), [0, 1, 2, 3], [[1e300, 1e300]] * 4),
                 lambda: rollplan.simulate_rotors(Robot(), [0, 1, 2, 3], [[0, 0]] * 4, x0="abc")):
        with pytest.raises(InputError) as err:
            call()
        assert "\n" not in str(err.value)


@pytest.mark.parametrize("call, needle", [
    (lambda: rollplan.plan(None, k=2.5), "goal"),
    (lambda: rollplan.plan({"x": 1}, k=2.5), "unknown key"),
    (lambda: rollplan.plan("abc", k=2.5), "goal"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, method=["ipopt"]), "method"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, branch=float("nan")), "branch"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, all_solutions="no"), "all_solutions"),
    (lambda: rollplan.plan((0, 1, 0), robot={"radius": 1}), "robot"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, steps="2"), "steps"),
    (lambda: rollplan.solve(Problem((0, 1, 0), k=2.5), method=["x"]), "method"),
    (lambda: rollplan.step(None, k=2.5), "a"),
    (lambda: rollplan.load_robot(None), "robot file"),
    (lambda: rollplan.load_robot({}), "robot file"),
    (lambda: Robot(radius="0.1"), "radius"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5).sample("10"), "samples"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5).sample(samples_per_leaf="10"), "samples_per_leaf"),
])
def test_wrong_types_in_the_python_api_are_input_errors(call, needle):
    """TypeError/AttributeError/ValueError from deep inside became InputError with one line."""
    with pytest.raises(InputError, match=needle) as err:
        call()
    assert "\n" not in str(err.value)


def test_fractions_are_numbers():
    p = rollplan.plan((Fraction(0), Fraction(1), Fraction(0)), k=Fraction(5, 2))
    assert p.residual < 1e-9 and p.k == 2.5


# ----------------------------------------------------------------------------- hangs


@pytest.mark.slow
@pytest.mark.parametrize("argv", [["plan", "--robot", "{fifo}"], ["simulate", "{fifo}"],
                                  ["animate", "{fifo}", "--out", "{dir}/a.gif"],
                                  ["batch", "{fifo}", "--out", "{dir}/o.jsonl"], ["route", "{fifo}"]])
def test_a_fifo_as_input_is_refused_without_blocking(tmp_path, argv):
    """A FIFO given as --robot, or to simulate/animate/batch, blocked for ever (in a separate process with a
    time limit: a hang fails the test instead of stopping the suite)."""
    fifo = tmp_path / "input"
    os.mkfifo(fifo)
    argv = [a.format(fifo=fifo, dir=tmp_path) for a in argv]
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", *argv], capture_output=True, text=True, timeout=120,
                       check=False)
    assert r.returncode == 2 and "FIFO" in r.stderr and one_line(r.stderr)


# ----------------------------------------------------------------------------- tracebacks turned into one line


@pytest.mark.slow
def test_plan_files_that_are_not_plans(tmp_path, capsys):
    """simulate/animate on a plan with rates x1e300, a radius given as a string, a NaN target, a 5000-digit
    integer, 100k-deep arrays, a BOM: one line, exit 2 (or the simulation, for the BOM)."""
    code, _, err = run(capsys, "plan", "--to", "0.03", "0.05", "--psi", "0.3", "--duration", "4", "--samples", "800",
                       "--json", str(tmp_path / "plan.json"))
    assert code == 0, err
    text = (tmp_path / "plan.json").read_text()
    assert all(key in text for key in ('"psi": 0.3', '"steps": 1', '"branch": 0'))
    data = json.loads(text)
    fast = json.loads(text)
    fast["rotor_rates"] = [[r * 1e300 for r in row] for row in fast["rotor_rates"]]
    string_radius = json.loads(text)
    string_radius["robot"]["radius"] = "0.1"
    cases = {
        "rates": json.dumps(fast), "radius": json.dumps(string_radius),
        "NaN": text.replace('"psi": 0.3', '"psi": NaN', 1),
        "digits": text.replace('"steps": 1', '"steps": ' + "9" * 5000, 1),
        "nested": text.replace('"branch": 0', '"branch": ' + "[" * 100000 + "]" * 100000, 1),
    }
    for needle, content in cases.items():
        path = tmp_path / f"{needle}.json"
        path.write_text(content)
        for argv in (["simulate", str(path)], ["animate", str(path), "--out", str(tmp_path / "a.gif")]):
            code, _, err = run(capsys, *argv)
            assert code == 2 and one_line(err), (needle, argv, err)
    bom = tmp_path / "bom.json"
    bom.write_bytes(b"\xef\xbb\xbf" + text.encode())
    code, out, err = run(capsys, "simulate", str(bom))
    assert code == 0, err
    assert data["rotor_simulation"]["arrival_error"] < 1e-6


def test_bom_in_a_robot_file_is_read(tmp_path, capsys):
    robot = tmp_path / "robot.toml"
    robot.write_bytes(b"\xef\xbb\xbfradius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2e-4\n"
                      b"rotor_inertia_transverse = 1.2e-4\n")
    code, _, err = run(capsys, "plan", "--robot", str(robot), "--to", "0", "0.05")
    assert code == 0, err


# ----------------------------------------------------------------------------- numbers on the command line


@pytest.mark.parametrize("argv, target", [
    (["--to", "-1e-3", "1"], (-1e-3, 1.0, 0.0)), (["--to", "0", "1", "--psi", "-2e-1"], (0.0, 1.0, -0.2)),
    (["--to", "-.5", "-1E0", "--psi", "-1.5e+0"], (-0.5, -1.0, -1.5)),
])
def test_negative_numbers_in_exponent_form(tmp_path, capsys, argv, target):
    """`--to -1e-3 1` and `--psi -2e-1` were rejected ("expected 2 arguments")."""
    out = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", *argv, "--k", "2.5", "--json", str(out))
    assert code == 0, err
    tg = json.loads(out.read_text())["target"]
    assert (tg["u_a"], tg["v_a"], tg["psi"]) == target


@pytest.mark.parametrize("value", ["\u0661", "\uff11", "1_0", "0x10", "-inf", "nan", "1e400", "\u0661\u0660"])
def test_numbers_other_than_ascii_decimals_are_refused(capsys, value):
    """Unicode and full-width digits and 1_0 were accepted as numbers."""
    code, out, err = run(capsys, "plan", "--to", "0", value, "--k", "2.5")
    assert code == 2 and repr(value) in err and one_line(err) and out == ""


@pytest.mark.parametrize("argv, needle", [
    (["plan", "--k", "100.00000000000001"], "k = 100.00000000000001 is not allowed: it must lie in [0, 100]"),
    (["step", "--a", "0.6900000000000001", "--k", "2.5"], "it must lie in (0, 0.69]"),
])
def test_limits_are_printed_exactly(capsys, argv, needle):
    code, _, err = run(capsys, *argv)
    assert code == 2 and needle in err and one_line(err)


# ----------------------------------------------------------------------------- the commands of issues 12 and 17


ROUTE = "u_a,v_a,psi,u_o,v_o,steps,label\n0,0,0,,,,home\n0.5,0,0,,,1,a\n"
LIMITED = ("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2e-4\n"
           "rotor_inertia_transverse = 1.2e-4\nmax_rotor_rate = 300.0\nmax_rotor_torque = 0.05\n")


@pytest.mark.parametrize("argv, needle", [
    (["plan", "--from", "0", "0", "0", "1_0", "0", "--to", "0", "1"], "'1_0'"),
    (["plan", "--contact", "\uff10", "0", "--to", "0", "1"], "'\uff10'"),
    (["plan", "--contact", "0", "nan", "--to", "0", "1"], "'nan'"),
    (["plan", "--from", "0", "0", "1e400", "0", "0", "--to", "0", "1"], "'1e400'"),
    (["plan", "--contact", "1.5707963267948966", "0", "--to", "0", "1"], "pi/2"),
    (["plan", "--to", "0", "1", "--timing", "min-jerk", "--duration", "1e-6"], "duration"),
    (["plan", "--to", "0", "1", "--timing", "time-optimal"], "max_rotor_torque"),
    (["plan", "--to", "0", "1", "--timing-plot", "t.png"], "--timing-plot needs a timed motion"),
    (["plan", "--to", "0", "1", "--duration", "5", "--timing-plot", "t.unknownext"], "extension"),
    (["route", "{dir}/none.csv"], "does not exist"),
    (["route", "{dir}"], "is a directory"),
    (["route", "{route}", "--samples", "10000000000"], "samples"),
    (["route", "{route}", "--k", "100.00000000000001"], "k = 100.00000000000001 is not allowed"),
])
def test_new_options_go_through_the_input_layer(tmp_path, capsys, argv, needle):
    """--from, --contact, --timing, --timing-plot and route read numbers and files as every other command:
    one line naming the value, exit 2, before any work."""
    (tmp_path / "w.csv").write_text(ROUTE)
    argv = [a.format(dir=tmp_path, route=tmp_path / "w.csv") for a in argv]
    code, out, err = run(capsys, *argv)
    assert code == 2 and needle in err and one_line(err), err
    assert "wrote" not in out


def test_negative_exponents_in_from_and_contact(capsys):
    code, out, err = run(capsys, "plan", "--from", "-1e-3", "0", "-2e-1", "-1e-2", "0", "--to", "0", "1",
                         "--contact", "-1e-1", "0", "--k", "2.5")
    assert code == 0, err
    assert "from (u_a, v_a, psi, u_o, v_o) = (-0.001 R, 0 R, -0.2 rad, -0.01 rad, 0 rad)" in out


def test_route_outputs_never_replace_the_waypoints_or_a_read_only_file(tmp_path, capsys):
    route = tmp_path / "w.csv"
    route.write_text(ROUTE)
    for flag in ("--json", "--plot"):
        name = route if flag == "--json" else tmp_path / "w.png"
        if flag == "--plot":
            name.symlink_to(route)
        code, _, err = run(capsys, "route", str(route), flag, str(name))
        assert code == 2 and "is the input file" in err and one_line(err), err
    assert route.read_text() == ROUTE
    ro = tmp_path / "ro.json"
    ro.write_text("keep")
    ro.chmod(0o444)
    code, _, err = run(capsys, "route", str(route), "--json", str(ro))
    assert code == 2 and "read-only" in err and one_line(err)
    (tmp_path / "w2.png").symlink_to(route)
    code, _, err = run(capsys, "route", str(route), "--duration", "3", "--timing-plot", str(tmp_path / "w2.png"))
    assert code == 2 and "is the input file" in err and one_line(err), err
    assert ro.read_text() == "keep" and route.read_text() == ROUTE


def test_route_reads_a_bom_and_comments(tmp_path, capsys):
    route = tmp_path / "w.csv"
    route.write_bytes(b"\xef\xbb\xbf# a route\n" + ROUTE.encode())
    code, out, err = run(capsys, "route", str(route), "--json", str(tmp_path / "r.json"))
    assert code == 0, err
    d = json.loads((tmp_path / "r.json").read_text())
    assert d["residual"] < 1e-9 and len(d["waypoints"]) == 2


@pytest.mark.parametrize("key, value", [("max_rotor_rate", "1e300"), ("max_rotor_rate", "1e-300"),
                                        ("max_rotor_torque", "inf"), ("max_rotor_torque", "1e-320"),
                                        ("max_rotor_rate", "-300.0")])
def test_motor_limits_have_ranges(tmp_path, capsys, key, value):
    """max_rotor_rate and max_rotor_torque are keys of ROBOT_KEYS with a range (a limit of 1e300 rad/s or
    1e-320 N m is no motor), checked in robot files and in plan files."""
    robot = tmp_path / "r.toml"
    robot.write_text(LIMITED.replace(f"{key} = ", f"{key} = {value}\n# ", 1))
    code, _, err = run(capsys, "plan", "--robot", str(robot), "--to", "0", "0.05", "--duration", "5")
    assert code == 2 and key in err and one_line(err), err
    with pytest.raises(InputError, match=key):
        Robot(**{key: float(value)})


@pytest.mark.slow
def test_timed_route_is_certified_by_its_rotors_and_read_back(tmp_path, capsys):
    """A route timed within the motors' limits: its rotor rates alone carry the robot from the first waypoint
    to the last (DOP853 on the printed equations, independent of rollplan), and `simulate` reads it back."""
    robot = tmp_path / "r.toml"
    robot.write_text(LIMITED)
    route = tmp_path / "w.csv"
    route.write_text("u_a,v_a,psi\n0,0,0\n0.05,0,0\n0.05,0.05,0.5\n")
    out = tmp_path / "r.json"
    code, text, err = run(capsys, "route", str(route), "--robot", str(robot), "--timing", "smooth-cruise",
                          "--json", str(out))
    assert code == 0, err
    d = json.loads(out.read_text())
    t = np.asarray(d["time"])
    keep = np.r_[True, np.diff(t) > 0]   # a time given twice is a step of the torques: the rates once
    final = references.rotor_drive(d["robot"], t[keep], np.asarray(d["rotor_rates"])[keep])[-1]
    assert math.hypot(final[0] - 0.05, final[1] - 0.05) / d["radius"] < 1e-6 and angle_gap(final[2], 0.5) < 1e-6
    rates, torques = np.abs(d["rotor_rates"]), np.abs(d["rotor_torques"])
    assert rates.max() <= 300.0 * (1 + 1e-9) and torques.max() <= 0.05 * (1 + 1e-6)
    assert run(capsys, "simulate", str(out))[0] == 0


@pytest.mark.parametrize("law", ["duration", pytest.param("min-jerk", marks=pytest.mark.slow),
                                 pytest.param("smooth-cruise", marks=pytest.mark.slow)])
def test_a_motion_that_misses_is_not_a_success(monkeypatch, capsys, tmp_path, law):
    """Whatever makes a motion miss its goal (here: its rotor rates halved), the command does not exit 0:
    certify_motion (the rotor-only simulation from the motion's start) guards every plan and timing law."""
    from rollplan.execution import actuation

    real = actuation.sample_motion

    def halved(*args, **kwargs):
        m = real(*args, **kwargs)
        object.__setattr__(m, "series", dataclasses.replace(m.series, rotor_rates=m.series.rotor_rates / 2))
        return m

    monkeypatch.setattr(actuation, "sample_motion", halved)
    robot = tmp_path / "r.toml"
    robot.write_text(LIMITED)
    if law == "duration":
        argv = ["--to", "0", "0.1", "--duration", "5"]
    else:
        argv = ["--robot", str(robot), "--from", "0", "0", "0", "0.2", "0", "--to", "0.05", "0", "--timing", law]
    code, _, err = run(capsys, "plan", *argv)
    assert code == 3 and "misses the goal" in err and one_line(err), err


def test_actuate_refuses_wrong_types_and_durations():
    p = rollplan.plan((0, 0.05, 0), robot=Robot())
    for call in (lambda: rollplan.actuate(None, Robot(), 1.0), lambda: rollplan.actuate(p, {"radius": 0.1}, 1.0),
                 lambda: rollplan.actuate(p, Robot(), "1"), lambda: rollplan.actuate(p, Robot(), 1e-6),
                 lambda: rollplan.actuate(p, Robot(), float("nan")), lambda: rollplan.actuate(p, Robot(), 1.0, "9"),
                 lambda: rollplan.actuate(p, Robot(), 1.0, 10**12),
                 lambda: rollplan.actuate(p, Robot(), 1.0, 100, ["x"]),
                 lambda: rollplan.actuate(p, Robot(), None)):
        with pytest.raises(InputError) as err:
            call()
        assert "\n" not in str(err.value)



def test_two_outputs_of_one_command_are_two_files(tmp_path, capsys):
    """--json, --plot and --timing-plot naming one file (directly or by a link) would overwrite each other."""
    out = tmp_path / "p.png"
    (tmp_path / "link.png").symlink_to(out)
    for argv in (["--json", str(out), "--plot", str(out)], ["--plot", str(out), "--duration", "5",
                                                            "--timing-plot", str(tmp_path / "link.png")]):
        code, text, err = run(capsys, "plan", "--to", "0", "0.05", *argv)
        assert code == 2 and "same file" in err and one_line(err) and text == "", err
    assert not out.exists()


@pytest.mark.parametrize("call, needle", [
    (lambda: rollplan.plan_route(None, k=2.5), "waypoints"), (lambda: rollplan.plan_route(5, k=2.5), "waypoints"),
    (lambda: rollplan.plan_route([None, None], k=2.5), "waypoint 0"),
    (lambda: rollplan.plan_route([(0, 0, 0), (0.5, 0, 0)], k=2.5, progress=5), "progress"),
    (lambda: rollplan.plan_route([(0, 0, 0), (0.5, 0, 0)], k=2.5, legs=[]), "legs"),
    (lambda: rollplan.plan_route([(0, 0, 0), (0.5, 0, 0)], k=2.5, method={}), "method"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, start="x"), "start"),
    (lambda: rollplan.plan((0, 1, 0), k=2.5, legs=["one"]), "legs"),
    (lambda: rollplan.read_waypoints(None), "waypoints file"),
    (lambda: rollplan.as_composed(None), "plan"),
    (lambda: rollplan.ComposedPlanner(tol=float("nan")), "tol"),
    (lambda: rollplan.Robot(max_rotor_rate="1"), "max_rotor_rate"),
])
def test_wrong_types_in_the_new_api_are_input_errors(call, needle):
    """plan_route(None) raised TypeError, legs=[] 'unhashable type'; every public function of issues 12 and
    17 refuses in one line."""
    with pytest.raises(InputError, match=needle) as err:
        call()
    assert "\n" not in str(err.value)


@pytest.mark.slow
def test_plan_files_with_a_start_or_goal_outside_the_region(tmp_path, capsys):
    """A plan file's start and goal are states of the region plans start and end in (a start at u_o = pi/2 was
    simulated from a singular pose, exit 0); a start 1e308 m away gives an infinite arrival error without an
    overflow warning on stderr."""
    out = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", "--from", "0", "0", "0", "0.2", "0", "--to", "0.03", "0.05", "--duration", "4",
                       "--samples", "800", "--json", str(out))
    assert code == 0, err
    d = json.loads(out.read_text())
    assert d["start"]["u_o"] == 0.2
    for key, change, needle in (("start", {"u_o": math.pi / 2}, "below pi/2"), ("start", {"u_o": 3.0}, "below pi/2"),
                                ("goal", {"u_o": 1.5, "v_o": 1.5}, "below 0.05")):
        bad = tmp_path / f"{key}.json"
        bad.write_text(json.dumps({**d, key: {**d[key], **change}}))
        code, _, err = run(capsys, "simulate", str(bad))
        assert code == 2 and needle in err and str(bad.name) in err and one_line(err), err
    far = tmp_path / "far.json"
    far.write_text(json.dumps({**d, "start": {**d["start"], "u_a": 1e308}}))
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)   # an overflow warning fails the test
        code, text, err = run(capsys, "simulate", str(far))
    assert code == 0 and err == "" and "arrival error inf" in text
