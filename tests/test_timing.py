"""Timing laws (rollplan.execution.timing) and the motions they give (rollplan.execution.actuation.actuate).

References, independent of the code under test: closed forms of the laws on paths with constant
coefficients (with and without corners), brute-force sampling of the limits, scaling identities, the
phase-plane integration of references.phase_plane_topp, the paper's printed axes (3)-(5) for the
torque identity, and a simulation driven by the rotor rates alone (CVODES on the model; scipy's DOP853 on
the printed (2), (6)-(10), (11)).
"""

import json
import math
import re
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

import rollplan
from rollplan import InputError
from rollplan.execution.actuation import actuate, sample_motion
from rollplan.execution.limits import Limits
from rollplan.execution.path import ContactPath, PathGrid
from rollplan.execution.plants import simulate_rotors
from rollplan.execution.timing import (
    LAWS,
    MinJerk,
    SmoothCruise,
    TimeOptimal,
    get_law,
    joint_times,
    peak_utilisation,
    register,
    round_up,
    unit_peaks,
)

import references

LIMITS = Limits(max_rotor_rate=300.0, max_rotor_torque=0.05)
ROBOT = replace(rollplan.Robot(), max_rotor_rate=LIMITS.max_rotor_rate, max_rotor_torque=LIMITS.max_rotor_torque)
SCALED = ["min-jerk", "nonstop-min-jerk", "smooth-cruise"]
PEAK_QUINTIC = 10 / math.sqrt(3)  # max |d2/dtau2 (10 tau^3 - 15 tau^4 + 6 tau^5)|, at tau = (3 - sqrt 3) / 6


@pytest.fixture(scope="module")
def plan(asym_plan):
    """The conftest's plan (made for the default robot; the limits do not change the plan)."""
    return asym_plan


@pytest.fixture(scope="module")
def path(plan):
    return ContactPath.of_plan(plan, ROBOT)


@pytest.fixture(scope="module")
def profiles(path):
    return {name: law.profile(path, LIMITS) for name, law in LAWS.items()}


class _Motions(dict):
    """Each law's motion sampled by its own rule (``samples_per_piece``: 400 to 20000 a piece), on the plan's goal,
    made when first asked for."""

    def __init__(self, path, profiles, goal):
        super().__init__()
        self.path, self.profiles, self.goal = path, profiles, goal

    def __missing__(self, name):
        self[name] = sample_motion(self.path, self.profiles[name], 2000, self.goal, LAWS[name].samples_per_piece)
        return self[name]


@pytest.fixture(scope="module")
def motions(path, profiles, plan):
    return _Motions(path, profiles, plan.goal)


@pytest.fixture(scope="module")
def time_optimal_3000(path, profiles, plan):
    """The time-optimal motion at 3000 samples a piece (a quarter of the law's own rule), on the plan's goal."""
    return sample_motion(path, profiles["time-optimal"], 2000, plan.goal, 3000)


def _utilisation(path, prof, samples=50001):
    """Brute force: the largest |value| / limit over uniform samples and both sides of every pole passage."""
    t = np.linspace(0, prof.duration, samples)
    s, sd, sdd = prof.evaluate(t)
    G, A, B = path.coefficients(np.clip(s, 0, path.length))
    util = LIMITS.utilisation(G * sd[:, None], A * sdd[:, None] + B * sd[:, None] ** 2).max()
    tj = joint_times(path, prof)
    s, sd, sdd = prof.evaluate(tj)
    for side in ("left", "right"):
        G, A, B = path.coefficients(path.joints, side)
        util = max(util, LIMITS.utilisation(G * sd[:, None], A * sdd[:, None] + B * sd[:, None] ** 2).max())
    return util


def test_registry():
    assert list(LAWS) == ["min-jerk", "nonstop-min-jerk", "smooth-cruise", "time-optimal"]
    with pytest.raises(InputError, match="choose one of min-jerk, nonstop-min-jerk"):
        get_law("fastest")
    with pytest.raises(ValueError, match="already registered"):
        register(MinJerk())
    assert get_law(LAWS["min-jerk"]) is LAWS["min-jerk"]


@pytest.mark.parametrize("name", list(LAWS))
def test_contract(name, profiles, path):
    """s(0) = 0, s(T) = L, rest at both ends, s' >= 0, s and s' continuous, s'' the derivative of s';
    laws that stop at the joints do."""
    prof = profiles[name]
    T, L = prof.duration, path.length
    s, sd, _ = prof.evaluate([0.0, T])
    assert s[0] == 0.0 and s[1] == pytest.approx(L, rel=1e-12)
    assert abs(sd[0]) < 1e-12 and abs(sd[1]) < 1e-9 * L / T
    b = prof.breaks[1:-1]
    k = np.arange(b.size)
    s_end, sd_end, _ = prof.evaluate(b, piece=k)        # the piece before each break, at its end
    s_beg, sd_beg, _ = prof.evaluate(b, piece=k + 1)    # the piece after it, at its start
    assert np.all(np.abs(s_end - s_beg) < 1e-10 * L) and np.all(np.abs(sd_end - sd_beg) < 1e-8 * L / T)
    t = np.linspace(0, T, 40001)
    s, sd, sdd = prof.evaluate(t)
    assert sd.min() > -1e-12 * L / T
    np.testing.assert_allclose(np.gradient(s, t)[1:-1], sd[1:-1], atol=1e-3 * sd.max())
    np.testing.assert_allclose(np.cumsum(sdd[:-1] * np.diff(t)), sd[1:], atol=1e-2 * sd.max())
    tj = joint_times(path, prof)
    _, sd_j, _ = prof.evaluate(tj)
    if LAWS[name].stops_at_joints:
        assert np.abs(sd_j).max() < 1e-12 * sd.max()
    else:
        assert sd_j.min() > 0.3 * sd.max()   # passes the poles at speed
    assert prof.minimum_duration == pytest.approx(T, rel=1e-12)


@pytest.mark.parametrize("name", [n if n == "min-jerk" else pytest.param(n, marks=pytest.mark.slow) for n in SCALED])
def test_scaled_minimum_duration(name, path, profiles):
    """At T_min the brute-force peak utilisation is 1; just below it the law is refused naming the limit and
    the shortest duration (which is accepted when given back); rates scale as 1/T and torques as 1/T^2."""
    law = get_law(name)
    tmin = profiles[name].duration
    assert 1 - 1e-6 < _utilisation(path, profiles[name]) <= 1 + 1e-9
    with pytest.raises(InputError, match=r"needs .* > max_rotor_(rate|torque) = .*shortest feasible duration is") \
            as err:
        law.profile(path, LIMITS, 0.99 * tmin)
    shortest = float(re.search(r"duration is (\S+) s", str(err.value)).group(1))
    assert tmin <= shortest <= tmin * (1 + 1e-5)
    assert law.profile(path, LIMITS, shortest).duration == shortest
    r0, q0 = unit_peaks(path, law.profile(path, Limits(), tmin))
    r1, q1 = unit_peaks(path, law.profile(path, Limits(), 2 * tmin))
    assert r1 == pytest.approx(r0 / 2, rel=1e-6) and q1 == pytest.approx(q0 / 4, rel=1e-6)


@pytest.mark.slow
def test_time_optimal_within_limits_with_one_active(profiles, path, time_optimal_3000):
    """Every sample within the limits (to 1e-6), one limit active (>= 99 %) on almost all of the time, and
    faster than every other law at its own shortest duration."""
    prof = profiles["time-optimal"]
    m = time_optimal_3000
    util = LIMITS.utilisation(m.series.rotor_rates, m.series.rotor_torques)
    assert util.max() <= 1 + 1e-6
    assert np.mean(util > 0.99) > 0.9
    ur, uq = peak_utilisation(path, prof, LIMITS, per_piece=32)  # twice as dense as the law's own check
    assert max(ur, uq) <= 1 + 1e-6
    for name in SCALED:
        assert profiles[name].duration > prof.duration


@pytest.mark.slow
def test_time_optimal_against_the_phase_plane(profiles, path):
    """The law's duration (grid of 2000 intervals, stretched to meet the limits between nodes) against the
    phase-plane integration on a grid eight times finer: a little longer (conservative), within 1e-3."""
    pp = references.phase_plane_topp(path.grid(16000), LIMITS.max_rotor_rate, LIMITS.max_rotor_torque)
    rel = profiles["time-optimal"].duration / pp["duration"] - 1
    assert 0 < rel < 1e-3


@pytest.mark.slow
def test_time_optimal_other_durations(profiles, path):
    law = get_law("time-optimal")
    tstar = profiles["time-optimal"].duration
    slow = law.profile(path, LIMITS, 1.5 * tstar)
    assert slow.duration == pytest.approx(1.5 * tstar) and slow.minimum_duration == pytest.approx(tstar)
    ur, uq = peak_utilisation(path, slow, LIMITS)
    assert uq == pytest.approx(1 / 1.5**2, rel=1e-3)
    with pytest.raises(InputError, match="max_rotor_torque = 0.05 N m the shortest feasible duration is"):
        law.profile(path, LIMITS, 0.99 * tstar)
    with pytest.raises(InputError, match="needs max_rotor_torque"):
        law.profile(path, Limits(300.0, None), None)


@pytest.mark.parametrize("name", [n if n == "min-jerk" else pytest.param(n, marks=pytest.mark.slow) for n in SCALED])
def test_rotor_rates_alone_reach_the_target(name, motions, plan):
    """The rotor rates, sampled by the law's own rule, drive (6)-(10) with omega from (11) (CVODES, cubic
    spline through the samples) onto the target to 1e-5 R. (time-optimal: test_cli_time_optimal_json, whose
    command makes this plan's motion, the same samples, and runs the same simulation.)"""
    m = motions[name]
    sim = simulate_rotors(ROBOT, m.series.time, m.series.rotor_rates, plan.goal)
    assert sim.position_error < 1e-5 and sim.arrival_error < 1e-5


@pytest.mark.slow
def test_time_optimal_rates_drive_the_printed_equations_onto_the_target(time_optimal_3000, plan):
    """The same with scipy's DOP853 on the printed (2), (6)-(10), (11) and scipy's not-a-knot spline (rtol 1e-9:
    its final state is within 1e-7 of rtol 1e-11's, 100 times below the tolerance, at a third of the cost)."""
    m = time_optimal_3000
    f = references.rotor_driven_rhs(ROBOT.j_xx, ROBOT.j_zz, ROBOT.rotor_inertia_axial, ROBOT.radius,
                                    CubicSpline(m.series.time, m.series.rotor_rates, bc_type="not-a-knot"))
    sol = solve_ivp(f, (0, m.duration), np.zeros(5), method="DOP853", rtol=1e-9, atol=1e-11)
    g = plan.goal
    err = np.hypot(sol.y[0, -1] - g.u_a, sol.y[1, -1] - g.v_a) / ROBOT.radius
    assert err < 1e-5 and abs(references.wrap(sol.y[2, -1] - g.psi)) < 1e-5


@pytest.mark.slow
def test_torques_are_rates_of_axial_momentum(motions, path):
    """tau_i = J_r d/dt (n_i . omega + phi_i_dot), with the printed axes, by central differences away from
    the torque steps; the trapezoid integral of the samples (the replay rule of rollplan.execution.actuation)
    tracks the momentum to O(h x step) per pole passage."""
    m = motions["smooth-cruise"]
    assert m.series.time.size > 40000
    n1, n2, _ = references.axes(m.series.state[:, 3], m.series.state[:, 4], m.series.state[:, 2])
    jr, dt = ROBOT.rotor_inertia_axial, m.series.time[1] - m.series.time[0]
    tj = joint_times(path, m.profile)
    far = np.all(np.abs(m.series.time[:, None] - tj[None, :]) > 3 * dt, axis=1)[1:-1]
    sd = m.profile.evaluate(tj)[1]
    steps = np.abs(path.evaluate(path.joints, "right").B - path.evaluate(path.joints, "left").B) * sd[:, None] ** 2
    for i, n in enumerate((n1, n2)):
        h = jr * (np.sum(n * m.series.omega, axis=1) + m.series.rotor_rates[:, i])
        tau = m.series.rotor_torques[:, i]
        fd = np.gradient(h, m.series.time)[1:-1]
        assert np.abs(fd - tau[1:-1])[far].max() < 1e-5 * np.abs(tau).max()
        trap = np.concatenate([[0.0], np.cumsum(0.5 * (tau[1:] + tau[:-1]) * np.diff(m.series.time))])
        assert np.abs(trap - h).max() < dt * steps[:, i].sum() + 1e-6 * np.abs(h).max()


@pytest.mark.slow
def test_torque_steps_at_poles_for_nonstop_laws(profiles, path, motions):
    """Passing a pole at speed s' the torque steps by (B+ - B-) s'^2: finite, present, seen in the samples."""
    prof = profiles["smooth-cruise"]
    tj = joint_times(path, prof)
    _, sd, sdd = prof.evaluate(tj)
    left, right = path.evaluate(path.joints, "left"), path.evaluate(path.joints, "right")
    step = (right.B - left.B) * sd[:, None] ** 2
    assert np.abs(step).max() > 0.1 * LIMITS.max_rotor_torque and np.all(sd > 0)
    m = motions["smooth-cruise"]
    i = np.searchsorted(m.series.time, tj[0])
    seen = m.series.rotor_torques[i + 1] - m.series.rotor_torques[i - 1]
    np.testing.assert_allclose(seen, step[0], atol=0.02 * np.abs(step[0]).max())


def test_actuate_times_a_plan_by_default_with_min_jerk(plan):
    """actuate: the default is min-jerk, resting at every joint at the times the duration gives."""
    mj = actuate(plan, rollplan.Robot(), 12.0)
    assert mj.timing == "min-jerk" and mj.minimum_duration is None
    np.testing.assert_allclose(mj.series.time[mj.rest_indices], [0, 3, 6, 9, 12], atol=1e-12)


@pytest.mark.slow
def test_actuate_times_a_plan(plan):
    """actuate: the default is min-jerk; with limits and no duration, the law's shortest duration."""
    m = actuate(plan, ROBOT, None, 10, "time-optimal")
    assert m.timing == "time-optimal" and m.duration == m.minimum_duration
    assert m.series.time.size == 4 * get_law("time-optimal").samples_per_piece + 1
    assert np.array_equal(m.rest_indices, [0, m.series.time.size - 1])
    assert m.series.segment[0] == 0 and m.series.segment[-1] == 3 and np.all(np.diff(m.series.segment) >= 0)
    traj = m.series.trajectory()
    assert traj.parameter == "t" and np.array_equal(traj.s, m.series.time)
    assert np.array_equal(traj.segment, m.series.segment)
    np.testing.assert_allclose(m.series.state[-1], [*plan.goal[:3], 0.0, 0.0], atol=1e-10)
    mj = actuate(plan, rollplan.Robot(), 12.0)
    assert mj.timing == "min-jerk" and mj.minimum_duration is None
    np.testing.assert_allclose(mj.series.time[mj.rest_indices], [0, 3, 6, 9, 12], atol=1e-12)


# ----------------------------------------------------------------------------- paths with corners, closed forms


class ConstantPath:
    """A TimingPath of pieces with constant coefficients: rates G s', torques A s'' + B s'^2 (each (2,))."""

    def __init__(self, lengths, A, B, G, corners=()):
        self.starts = np.concatenate([[0.0], np.cumsum(lengths)])
        self.length = float(self.starts[-1])
        self.corners = np.array([j + 1 in corners for j in range(len(lengths) - 1)], bool)
        self.A, self.B, self.G = (np.asarray(v, float) for v in (A, B, G))

    def coefficients(self, s, side="left"):
        n = np.size(s)
        return tuple(np.tile(v, (n, 1)) for v in (self.G, self.A, self.B))

    def grid(self, n):
        counts = [max(4, round(n * ell / self.length)) for ell in np.diff(self.starts)]
        s = np.concatenate([*(np.linspace(a, b, c + 1)[:-1] for a, b, c in zip(self.starts, self.starts[1:], counts)),
                            [self.length]])
        joints = np.cumsum(counts)[:-1]
        G, A, B = self.coefficients(s)
        return PathGrid(s, G, G, A, A, B, B, joints, joints[self.corners])


def test_scaled_laws_closed_form_with_and_without_corners():
    """Double integrator |a s''| <= tau (B = 0, G = 0): the quintic's peak s'' is 10/sqrt(3) L_r / T_r^2.
    min-jerk: every piece in T/P, T_min = P sqrt(10/sqrt(3) L_max / acc); nonstop-min-jerk: one quintic per
    stretch between corners in a time proportional to its length, T_min = L sqrt(10/sqrt(3) / (acc L_min))."""
    a, tau = 0.02, 0.05
    acc, lengths = tau / a, [0.7, 1.8, 1.1]
    lim = Limits(None, tau)
    smooth = ConstantPath(lengths, [a, 0.5 * a], [0.0, 0.0], [0.0, 0.0])
    cornered = ConstantPath(lengths, [a, 0.5 * a], [0.0, 0.0], [0.0, 0.0], corners=[2])
    L = sum(lengths)
    assert get_law("min-jerk").profile(smooth, lim).duration == pytest.approx(
        3 * math.sqrt(PEAK_QUINTIC * 1.8 / acc), rel=1e-7)
    assert get_law("nonstop-min-jerk").profile(smooth, lim).duration == pytest.approx(
        math.sqrt(PEAK_QUINTIC * L / acc), rel=1e-7)
    prof = get_law("nonstop-min-jerk").profile(cornered, lim)
    assert prof.duration == pytest.approx(L * math.sqrt(PEAK_QUINTIC / (acc * 1.1)), rel=1e-7)
    for law in (get_law("nonstop-min-jerk"), SmoothCruise(0.3), get_law("time-optimal")):
        prof = law.profile(cornered, lim)
        tj = joint_times(cornered, prof)
        sd = prof.evaluate(tj)[1]
        assert abs(sd[1]) < 1e-9 * prof.evaluate(np.linspace(0, prof.duration, 101))[1].max()   # rests at the corner
        assert sd[0] > 0                                                                          # not at the joint


def test_time_optimal_law_closed_form_with_a_corner():
    """Through the law (grid, stretch): bang-bang per stretch, 2 sqrt(L1/acc) + 2 sqrt(L2/acc) with a corner."""
    a, tau = 0.02, 0.05
    acc = tau / a
    path = ConstantPath([0.7, 1.8], [a, a], [0.0, 0.0], [0.0, 0.0], corners=[1])
    shortest = TimeOptimal(8000).profile(path, Limits(None, tau)).duration
    assert shortest == pytest.approx(2 * math.sqrt(0.7 / acc) + 2 * math.sqrt(1.8 / acc), rel=2e-4)


def test_bad_input(path, plan):
    law = get_law("min-jerk")
    for bad in (-1.0, 0.0, float("nan"), float("inf"), 1e300, 1e-9, "5", True):
        with pytest.raises(InputError, match="duration"):
            law.profile(path, LIMITS, bad)
    with pytest.raises(InputError, match="needs a duration, or limits"):
        law.profile(path, Limits(), None)
    with pytest.raises(InputError, match="limits"):
        law.profile(path, {"max_rotor_torque": 1.0}, 5.0)
    with pytest.raises(InputError, match="path"):
        law.profile(None, LIMITS, 5.0)
    with pytest.raises(InputError, match="ramp"):
        SmoothCruise(0.9)
    with pytest.raises(InputError, match="timing"):
        actuate(plan, ROBOT, 5.0, timing="fastest")
    with pytest.raises(InputError, match="samples"):
        actuate(plan, ROBOT, 12.0, samples=3)
    with pytest.raises(InputError, match="at most 1000000"):
        actuate(plan, ROBOT, 12.0, samples=2_000_000)
    assert round_up(11.4724114) == pytest.approx(11.4725) and round_up(6.0) == 6.0


# ----------------------------------------------------------------------------- the command: plan --timing

ROBOT_TOML = """radius = 0.1
mass_total = 1.2
mass_shell = 0.4
rotor_inertia_axial = 2.0e-4
rotor_inertia_transverse = 1.2e-4
max_rotor_rate = 300.0
max_rotor_torque = 0.05
"""


def _run(capsys, *argv):
    from rollplan.cli import main

    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:  # argparse's own checks
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


@pytest.fixture(scope="module")
def robot_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("robot") / "limited.toml"
    path.write_text(ROBOT_TOML)
    return path


@pytest.mark.slow
def test_cli_time_optimal_json(robot_file, tmp_path, capsys):
    """plan --timing time-optimal --json: time, rotor_rates, rotor_torques, duration; every sample within
    the limits, one limit active almost everywhere, the rates alone reach the target (rotor_simulation)."""
    out, fig = tmp_path / "to.json", tmp_path / "to.png"
    code, text, err = _run(capsys, "plan", "--robot", robot_file, "--to", 0.05, 0.08, "--psi", 0.5, "--steps", 2,
                           "--timing", "time-optimal", "--samples", 20000, "--json", out, "--timing-plot", fig)
    assert code == 0, err
    data = json.loads(out.read_text())
    t, rates, torques = (np.asarray(data[k]) for k in ("time", "rotor_rates", "rotor_torques"))
    uniform = 4 * max(get_law("time-optimal").samples_per_piece, 5000) + 1   # --samples 20000 over 4 pieces
    breaks = np.asarray(data["torque_breaks"])   # each step of the torques is a time given twice
    assert t.size == uniform + 2 * breaks.size and np.array_equal(np.unique(t[np.r_[False, np.diff(t) == 0]]), breaks)
    assert rates.shape == torques.shape == (t.size, 2)
    assert data["duration"] == t[-1] == data["minimum_duration"] and data["timing"] == "time-optimal"
    util = LIMITS.utilisation(rates, torques)
    assert util.max() <= 1 + 1e-6 and np.mean(util > 0.99) > 0.9
    assert data["rotor_simulation"]["position_error"] < 1e-5 and data["rotor_simulation"]["arrival_error"] < 1e-5
    assert data["robot"]["max_rotor_torque"] == 0.05 and data["segment"][-1] == 3
    assert "shortest feasible duration with timing time-optimal is" in text and "100.0% of the limit" in text
    assert fig.stat().st_size > 10000


@pytest.mark.slow
def test_cli_refuses_a_duration_beyond_the_limits(robot_file, capsys):
    """A too short --duration exits 2 naming the limit and the shortest feasible duration; that duration
    is then accepted."""
    code, _, err = _run(capsys, "plan", "--robot", robot_file, "--to", 0.0, 0.1, "--duration", 3)
    assert code == 2 and "max_rotor_torque = 0.05 N m" in err and "Traceback" not in err
    assert len(err.strip().splitlines()) == 1
    shortest = re.search(r"shortest feasible duration is (\S+) s", err).group(1)
    code, text, err = _run(capsys, "plan", "--robot", robot_file, "--to", 0.0, 0.1, "--duration", shortest)
    assert code == 0 and "timing min-jerk" in text, err
    code, _, err = _run(capsys, "plan", "--robot", robot_file, "--to", 0.0, 0.1, "--duration", 3,
                        "--timing", "time-optimal")
    assert code == 2 and "shortest feasible duration is" in err


@pytest.mark.parametrize("argv, match", [
    (["--timing", "time-optimal"], "needs max_rotor_torque"),              # the default robot has no limits
    (["--timing", "smooth-cruise"], "needs a duration, or limits"),
    (["--timing", "fastest"], "invalid choice"),
    (["--duration", "1e300"], "duration"),
    (["--timing-plot", "x.png"], "--timing-plot needs"),
    (["--k", "2.5", "--timing", "min-jerk", "--duration", "5"], "--robot"),
])
def test_cli_timing_errors(argv, match, capsys, tmp_path):
    code, _, err = _run(capsys, "plan", "--to", 0.0, 0.1, *[a.replace("x.png", str(tmp_path / "x.png"))
                                                             for a in argv])
    assert code == 2 and match in err and "Traceback" not in err


@pytest.mark.slow
def test_cli_plan_file_with_limits_round_trip(robot_file, tmp_path, capsys):
    """A plan file keeps the robot's limits; simulate reads it (and plan files without them, see test_cli). Timed
    by min-jerk, the law with the fewest samples a piece (the smallest file): the limits kept do not depend on it."""
    from rollplan.io import load_rotor_plan

    out = tmp_path / "p.json"
    assert _run(capsys, "plan", "--robot", robot_file, "--to", 0.0, 0.1, "--timing", "min-jerk",
                "--json", out)[0] == 0
    assert load_rotor_plan(out).robot == ROBOT
    code, text, _ = _run(capsys, "simulate", out)
    # simulate prints the position error in the unit in use (m with a robot): 1e-5 R is 1e-5 * radius metres
    assert code == 0 and float(re.search(r"position (\S+) m", text).group(1)) < 1e-5 * ROBOT.radius


def test_timing_figure_follows_the_colour_and_unit_conventions():
    """The timing figure draws the rotors in the rotor colours with torques in N m (as the console and the JSON),
    the limits at their values in N m, and each law in its colour."""
    from matplotlib.colors import to_rgba

    from rollplan.plots.colors import LAW, ROTOR
    from rollplan.plots.timing import plot_timing

    p = rollplan.plan((0.0, 0.1, 0.0), robot=ROBOT)
    m = actuate(p, ROBOT, 2.0 * actuate(p, ROBOT, timing="min-jerk").minimum_duration, timing="min-jerk")
    fig = plot_timing(m)
    torques = next(ax for ax in fig.axes if ax.get_ylabel() == "motor torque [N m]")
    lines = [ln for ln in torques.get_lines() if len(ln.get_xdata()) > 2]
    assert [to_rgba(ln.get_color()) for ln in lines] == [to_rgba(c) for c in ROTOR]
    assert np.allclose(lines[0].get_ydata(), m.series.rotor_torques[:, 0])
    limits = sorted(ln.get_ydata()[0] for ln in torques.get_lines() if len(ln.get_xdata()) == 2)
    assert limits == pytest.approx([-ROBOT.max_rotor_torque, ROBOT.max_rotor_torque])
    phase = fig.axes[-1]
    assert to_rgba(next(ln for ln in phase.get_lines() if ln.get_label() == "min-jerk").get_color()) == \
        to_rgba(LAW["min-jerk"])
