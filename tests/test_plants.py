"""The rotor-driven plant (rollplan.execution.plants): against a closed form, an independent
numpy/scipy implementation of (2), (6)-(10), (11), invariances, and the planner's motions."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline

import rollplan
from rollplan import InputError, State
from rollplan.execution.actuation import actuate
from rollplan.execution.plants import MAX_TURN, STILL_TURN, rate_spline, simulate_rotors

import references

ROBOT = rollplan.Robot()


def test_spline_is_not_a_knot_cubic():
    rng = np.random.default_rng(0)
    t = np.sort(rng.uniform(0, 5, 40))
    y = rng.normal(size=(40, 2))
    tt = np.linspace(t[0], t[-1], 777)
    ours = np.array(rate_spline(t, y).map(tt.size)(tt[None, :])).T
    np.testing.assert_allclose(ours, CubicSpline(t, y, bc_type="not-a-knot")(tt), atol=1e-10)


def test_constant_rotor_rate_closed_form():
    """phi_1_dot = c, phi_2_dot = 0 from rest: steady roll about n_1 = x, v_a = R J_r c t / Jxx, v_o = J_r c t / Jxx
    (states in State order (u_a, v_a, psi, u_o, v_o))."""
    c = 30.0
    T = 0.8 * ROBOT.j_xx / (ROBOT.rotor_inertia_axial * c)  # v_o reaches 0.8 rad
    t = np.linspace(0, T, 50)
    sim = simulate_rotors(ROBOT, t, np.column_stack([np.full(50, c), np.zeros(50)]))
    rate = ROBOT.rotor_inertia_axial * c / ROBOT.j_xx
    expected = np.column_stack([0 * t, ROBOT.radius * rate * t, 0 * t, 0 * t, rate * t])
    np.testing.assert_allclose(sim.series.state, expected, atol=1e-11)
    np.testing.assert_allclose(sim.series.omega, np.tile([-rate, 0, 0], (50, 1)), atol=1e-13)


def _numpy_rhs(robot, spline):
    """(6)-(10) with omega from (11): the printed equations and rotation matrices composed in numpy
    (``references``; independent of rollplan.core.model). State order (u_a, v_a, psi, u_o, v_o)."""
    return references.rotor_driven_rhs(robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, robot.radius, spline)


def test_against_scipy_dop853():
    t = np.linspace(0, 3, 301)
    rates = np.column_stack([20 * np.sin(2 * t) * t, -15 * np.sin(3 * t) + 5 * t])
    sim = simulate_rotors(ROBOT, t, rates)
    # (6)-(10) with omega from (11), the printed equations and (2) composed in numpy (references)
    ref = references.rotor_drive(ROBOT.as_dict(), t, rates)
    assert np.abs(ref[-1]).max() > 0.1  # a real motion
    np.testing.assert_allclose(sim.series.state, ref, atol=1e-9)


def _sines(t):
    """Rotor rates [rad/s] of two sines at the sample times ``t`` (the vanishing-rate tests scale them)."""
    return np.column_stack([40 * np.sin(3 * t), 30 * np.cos(2 * t)])


@pytest.mark.filterwarnings("ignore:invalid value encountered in scalar divide:RuntimeWarning")   # scipy's step
@settings(max_examples=25, deadline=None)                                                      # size at 0 / 0
@given(exponent=st.integers(-320, -20), u_o=st.floats(-0.6, 0.6), v_o=st.floats(-0.6, 0.6), psi=st.floats(-3, 3))
@example(exponent=-145, u_o=0.2, v_o=0.0, psi=0.0)
@example(exponent=-75, u_o=0.0, v_o=0.0, psi=0.0)
def test_vanishing_rotor_rates_leave_the_sphere_where_it_starts(exponent, u_o, v_o, psi):
    """Rates scaled down towards zero (down to subnormal numbers) turn the sphere by at most about their size: the
    states stay at the start within 1e-12, as scipy's DOP853 on the printed equations integrates them, whether the
    motion is integrated or below :data:`STILL_TURN`."""
    t = np.linspace(0, 4, 60)
    rates = _sines(t) * 10.0 ** exponent
    x0 = np.array([0.0, 0.0, psi, u_o, v_o])
    sim = simulate_rotors(ROBOT, t, rates, x0=x0)
    np.testing.assert_allclose(sim.series.state, np.tile(x0, (t.size, 1)), rtol=0, atol=1e-12)
    np.testing.assert_allclose(sim.series.state[-1], references.rotor_drive(ROBOT.as_dict(), t, rates, x0, end=True),
                               rtol=0, atol=1e-12)
    if 1e3 * 10.0 ** exponent < STILL_TURN:   # far below: not integrated, the start exactly
        assert np.array_equal(sim.series.state[-1], x0)


@pytest.mark.filterwarnings("ignore:invalid value encountered in scalar divide:RuntimeWarning")
@pytest.mark.parametrize("exponent", [-69, -70])
def test_a_stretch_of_vanishing_rates_before_a_motion_is_simulated(exponent):
    """Rates of about 1e-69 rad/s over the first three quarters, then a motion: CVODES failed on that stretch
    (CV_TOO_MUCH_WORK, exit 4 from ``rollplan simulate``) although the file as a whole turns the sphere by far more
    than STILL_TURN. The states match scipy's DOP853 on the printed equations at every sample."""
    t = np.linspace(0, 4, 200)
    rates = _sines(t) * 10.0 ** exponent
    rates[150:] *= 1e-3 / 10.0 ** exponent
    sim = simulate_rotors(ROBOT, t, rates)
    ref = references.rotor_drive(ROBOT.as_dict(), t, rates, np.zeros(5))
    assert np.abs(ref[-1]).max() > 1e-6   # the tail moves the sphere
    np.testing.assert_allclose(sim.series.state, ref, rtol=0, atol=1e-9)   # as test_against_scipy_dop853


def test_rates_whose_spline_swings_far_beyond_the_samples_are_refused():
    """One sample 1e-12 s after another, at 1e3 rad/s: the samples' trapezoid turns the sphere by little, but the
    not-a-knot spline through them (scipy's, on a dense grid) by more than MAX_TURN; CVODES ran out of steps on it.
    Refused in one line naming the limit."""
    t = np.linspace(0, 3, 301)
    rates = np.column_stack([20 * np.sin(2 * t) * t, -15 * np.sin(3 * t) + 5 * t])
    t, rates = np.insert(t, 101, t[100] + 1e-12), np.insert(rates, 101, [1e3, 1e3], axis=0)
    gain = ROBOT.rotor_inertia_axial / ROBOT.j_zz
    trapezoid = (0.5 * (np.abs(rates[1:]) + np.abs(rates[:-1])).sum(axis=1) * np.diff(t)).sum() * gain
    grid = np.linspace(0, 3, 1_000_001)
    swing = np.abs(CubicSpline(t, rates, bc_type="not-a-knot")(grid)).sum(axis=1).mean() * 3 * gain
    assert trapezoid < MAX_TURN < swing
    with pytest.raises(InputError, match="more than 1e\\+06 rad") as err:
        simulate_rotors(ROBOT, t, rates)
    assert "\n" not in str(err.value)


def test_scaling_all_inertias_changes_nothing():
    """omega from (11) depends only on Jxx/J_r and Jzz/J_r: scale every mass and inertia alike."""
    t = np.linspace(0, 2, 201)
    rates = np.column_stack([10 * np.sin(3 * t), 8 * np.cos(2 * t) - 8])
    heavy = rollplan.Robot(0.1, 2 * 1.2, 2 * 0.4, 2 * 2.0e-4, 2 * 1.2e-4)
    a = simulate_rotors(ROBOT, t, rates)
    b = simulate_rotors(heavy, t, rates)
    np.testing.assert_allclose(a.series.state, b.series.state, atol=1e-11)


@pytest.mark.parametrize("target, steps, duration", [((0.0, 0.1, 0.0), 1, 10.0),      # symmetric, a = b
                                                     ((0.05, 0.08, 0.5), 2, 6.0),     # asymmetric
                                                     ((-0.03, 0.06, -2.0), 3, 20.0)])  # asymmetric, 3 steps
def test_rotor_rates_reproduce_the_plan(target, steps, duration):
    """Rotor rates from (11), spline-interpolated, drive (6)-(10) along the planned contact coordinates."""
    p = rollplan.plan(target, steps, robot=ROBOT)
    if target[2] == 0:
        assert p.a == pytest.approx(p.b, rel=1e-9)
    else:
        assert abs(p.a - p.b) > 1e-3 * ROBOT.radius
    m = actuate(p, ROBOT, duration)
    assert m.series.time.size >= 2000
    sim = simulate_rotors(ROBOT, m.series.time, m.series.rotor_rates, p.goal)
    assert sim.arrival_error < 1e-6
    assert np.array_equal(sim.final, sim.series.state[-1])
    g, R = p.goal, ROBOT.radius   # the arrival error: lengths in units of R, psi wrapped, u_o and v_o
    want = [(sim.final[0] - g.u_a) / R, (sim.final[1] - g.v_a) / R, references.wrap(sim.final[2] - g.psi),
            sim.final[3], sim.final[4]]
    assert np.allclose(sim.error, want, rtol=0, atol=1e-15)
    assert sim.arrival_error == pytest.approx(np.linalg.norm(want), abs=1e-15)
    dev = np.abs(sim.series.state - m.series.state).max(axis=0)
    assert dev[:2].max() < 1e-6 * ROBOT.radius and dev[2:].max() < 1e-6
    np.testing.assert_allclose(sim.series.omega, m.series.omega, atol=1e-6 * np.abs(m.series.omega).max())


def test_wrong_k_misses_the_target():
    p = rollplan.plan((0.05, 0.08, 0.5), 2, robot=ROBOT)
    m = actuate(p, ROBOT, 6.0)
    heavier = rollplan.Robot(mass_total=1.3)  # k larger by ~7 %
    sim = simulate_rotors(heavier, m.series.time, m.series.rotor_rates, p.goal)
    assert sim.arrival_error > 1e-3


def test_bad_input():
    t = np.linspace(0, 1, 10)
    with pytest.raises(InputError, match="rates"):
        simulate_rotors(ROBOT, t, np.zeros((10, 3)))
    with pytest.raises(InputError, match="increase"):
        simulate_rotors(ROBOT, t[::-1], np.zeros((10, 2)))
    with pytest.raises(InputError, match="finite"):
        simulate_rotors(ROBOT, t, np.full((10, 2), np.nan))


@pytest.mark.slow
def test_many_steps_still_arrive():
    """Six steps (12 half-steps, >= 400 samples each): the spline-driven simulation still arrives within 1e-6 R."""
    p = rollplan.plan((0.3, -0.2, 2.0), 6, robot=ROBOT)
    m = actuate(p, ROBOT, 30.0)
    assert m.series.time.size == 12 * 400 + 1
    sim = simulate_rotors(ROBOT, m.series.time, m.series.rotor_rates, p.goal)
    assert sim.arrival_error < 1e-6


def test_restart_from_a_midway_state_continues_the_motion():
    """x0: the simulation of [t_m, T] started from the state at t_m equals the second half of the whole run
    (x0 in State order; the flow of (6)-(10), (11) composes)."""
    t = np.linspace(0, 2, 201)
    rates = np.column_stack([10 * np.sin(3 * t), 8 * np.cos(2 * t) - 8])
    whole = simulate_rotors(ROBOT, t, rates, goal=State(0.01, 0.02, 0.3))
    half = simulate_rotors(ROBOT, t[100:], rates[100:], x0=whole.series.state[100])
    np.testing.assert_allclose(half.series.state, whole.series.state[100:], atol=1e-8)
    assert half.error is None and half.arrival_error is None and whole.arrival_error > 0
