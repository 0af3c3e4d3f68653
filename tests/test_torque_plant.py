"""The torque-driven plant and its model functions (issue 13): against the printed equations solved by
numpy, a closed form (Sherman-Morrison), scipy's DOP853, the rate-driven plant, and the conservation of
the angular momentum about the contact point."""

import time

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

import rollplan
from rollplan import InputError
from rollplan.core import model
from rollplan.execution.actuation import actuate
from rollplan.execution.feedback import joints
from rollplan.execution.plants import disturbance, input_function, run_rates, run_torques

import references

ROBOT = rollplan.default_robot()
J = (ROBOT.j_xx, ROBOT.j_zz, ROBOT.rotor_inertia_axial)
angle = st.floats(-1.2, 1.2)


def num(expr) -> np.ndarray:
    return np.array(ca.evalf(expr)).ravel()


def axes(u, v, psi) -> np.ndarray:
    """(3, 3) with columns n_1, n_2, n_3 as printed in (3)-(5)."""
    return np.column_stack(references.axes(u, v, psi))


@settings(max_examples=60, deadline=None)
@given(u=angle, v=angle, psi=st.floats(-4, 4), p1=st.floats(-0.02, 0.02), p2=st.floats(-0.02, 0.02))
def test_omega_from_momenta_solves_11_with_the_axial_momenta(u, v, psi, p1, p2):
    """(O) of the model against (a) numpy's solve of the 5x5 system (11) + (P) and (b) Sherman-Morrison."""
    jxx, jzz, jr = J
    om, pd = (num(e) for e in model.omega_from_momenta(ca.DM([p1, p2]), u, v, psi, jxx, jzz, jr))
    _, rates = references.torque_driven_rhs(jxx, jzz, jr, 1.0, None)
    w_ref, pd_ref = rates(np.array([0.0, 0.0, psi, u, v, p1, p2]))
    np.testing.assert_allclose(om, w_ref, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(pd, pd_ref, rtol=1e-9, atol=1e-9)
    n = axes(u, v, psi)
    dinv = np.diag(1 / np.array([jxx - jr, jxx - jr, jzz - jr]))
    n3 = n[:, 2]
    ainv = dinv - jr * np.outer(dinv @ n3, n3 @ dinv) / (1 + jr * n3 @ dinv @ n3)
    np.testing.assert_allclose(om, -ainv @ (n[:, 0] * p1 + n[:, 1] * p2), rtol=1e-10, atol=1e-13)


def test_matrix_of_O_is_positive_definite_with_bounded_spectrum():
    """A = J_c - J_r (I - n_3 n_3^T) has its eigenvalues in [Jzz - J_r, Jxx] for every orientation."""
    jxx, jzz, jr = J
    for u, v, psi in np.random.default_rng(1).uniform(-1.5, 1.5, (200, 3)):
        n3 = axes(u, v, psi)[:, 2]
        ev = np.linalg.eigvalsh(np.diag([jxx, jxx, jzz]) - jr * (np.eye(3) - np.outer(n3, n3)))
        assert ev.min() >= jzz - jr - 1e-15 and ev.max() <= jxx + 1e-15


@settings(max_examples=40, deadline=None)
@given(u=angle, v=angle, psi=st.floats(-4, 4), r1=st.floats(-50, 50), r2=st.floats(-50, 50),
       w=st.lists(st.floats(-3, 3), min_size=3, max_size=3))
def test_momentum_about_contact_is_the_left_side_of_11(u, v, psi, r1, r2, w):
    """The composed L_P equals J_c omega + J_r (n_1 phi_1_dot + n_2 phi_2_dot) with the printed axes; the solved
    forms of (11) (omega from rates, rates from omega) make it vanish."""
    jxx, jzz, jr = J
    n = axes(u, v, psi)
    direct = np.array([jxx, jxx, jzz]) * np.array(w) + jr * (n[:, 0] * r1 + n[:, 1] * r2)
    got = num(model.momentum_about_contact(ca.DM(w), ca.DM([r1, r2]), u, v, psi, jxx, jzz, jr))
    np.testing.assert_allclose(got, direct, atol=1e-15 * (1 + abs(r1) + abs(r2)) + 1e-16)
    w11 = model.omega_from_rotor_rates(ca.DM([r1, r2]), u, v, psi, jxx, jzz, jr)
    lp = num(model.momentum_about_contact(w11, ca.DM([r1, r2]), u, v, psi, jxx, jzz, jr))
    assert np.abs(lp).max() < 1e-15 * max(1.0, abs(r1) + abs(r2))


@settings(max_examples=40, deadline=None)
@given(u=angle, v=angle, psi=st.floats(-4, 4), w=st.lists(st.floats(-3, 3), min_size=3, max_size=3))
def test_omega_line_element_inverts_printed_montana(u, v, psi, w):
    R = 0.13
    rates = references.montana(np.array(w), u, v, psi, R)
    got = np.array(model.omega_line_element(R)([0.01, 0.02, psi, u, v])) @ rates[:3]
    np.testing.assert_allclose(got, w, atol=1e-12)


@pytest.fixture(scope="module")
def motion(asym_plan):
    return actuate(asym_plan, ROBOT, 10.0, samples=2000)


@pytest.fixture(scope="module")
def rate_run(motion):
    return run_rates(ROBOT, motion.series.time, motion.series.rotor_rates)


@pytest.fixture(scope="module")
def torque_run(motion):
    return run_torques(ROBOT, motion.series.time, motion.series.rotor_torques, breaks=joints(motion.series))


def test_torque_plant_reproduces_the_rate_plant(asym_plan, motion, rate_run, torque_run):
    """Driven by a plan's torques (T), the torque plant follows the rate plant, rotor rates included, and
    arrives; its momenta return to zero at every rest point."""
    R = ROBOT.radius
    assert np.abs(torque_run.series.state - rate_run.series.state).max() / R < 1e-7
    rates = motion.series.rotor_rates
    assert np.abs(torque_run.series.rotor_rates - rates).max() < 1e-6 * np.abs(rates).max()
    assert np.abs(torque_run.series.rotor_angles - motion.series.rotor_angles).max() < 1e-6
    assert rollplan.problem.arrival_residual(torque_run.series.state[-1], asym_plan.goal, R) < 1e-7
    momenta = torque_run.series.rotor_momenta
    assert np.abs(momenta[motion.rest_indices]).max() < 1e-9 * np.abs(momenta).max()


@pytest.mark.slow
def test_one_spline_across_the_joints_converges_only_as_h2(asym_plan):
    """Timed torques have a kink at every joint: one spline through them converges as h^2; split, far better."""
    errs = {}
    for n in (1601, 3201):
        m = actuate(asym_plan, ROBOT, 10.0, samples=n)
        assert m.series.time.size == n
        ref = run_rates(ROBOT, m.series.time, m.series.rotor_rates).series.state
        one = run_torques(ROBOT, m.series.time, m.series.rotor_torques).series.state
        split = run_torques(ROBOT, m.series.time, m.series.rotor_torques, breaks=joints(m.series)).series.state
        errs[n] = (np.abs(one - ref).max(), np.abs(split - ref).max())
    assert 3.0 < errs[1601][0] / errs[3201][0] < 5.0
    assert errs[3201][1] < 0.01 * errs[3201][0]


def test_torque_plant_with_friction_matches_dop853_on_the_printed_equations():
    """Smooth torque pulses and bearing friction: the plant against DOP853 on (11), (P), (6)-(10) solved by numpy."""
    c = (2e-5, 4e-5)
    t = np.linspace(0.0, 3.0, 301)
    tau = np.column_stack([2e-3 * np.sin(np.pi * t / 3) ** 2, -1e-3 * np.sin(2 * np.pi * t / 3)])
    run = run_torques(ROBOT, t, tau, disturbances=[disturbance("friction", c=c)])
    spline = CubicSpline(t, tau, axis=0)
    f, rates = references.torque_driven_rhs(*J, ROBOT.radius, spline, c)
    sol = solve_ivp(f, (0, 3), np.zeros(7), method="DOP853", rtol=1e-12, atol=1e-14, t_eval=t)
    assert np.abs(run.series.state - sol.y[:5].T).max() < 1e-9
    np.testing.assert_allclose(run.series.rotor_momenta, sol.y[5:].T, atol=1e-12)
    pd = np.array([rates(z)[1] for z in sol.y.T])
    np.testing.assert_allclose(run.series.rotor_rates, pd, atol=1e-7 * np.abs(pd).max())


def _lp(run, rates):
    lp, omega = references.momentum_about_contact(run.series.time, run.series.state, rates, ROBOT.j_xx, ROBOT.j_zz,
                                                  ROBOT.rotor_inertia_axial, ROBOT.mass_total, ROBOT.radius)
    return lp, omega, np.abs(ROBOT.rotor_inertia_axial * rates).max()


def test_momentum_about_contact_is_conserved_on_the_rate_plant(rate_run):
    lp, _, scale = _lp(rate_run, rate_run.series.rotor_rates)
    assert np.abs(lp).max() < 1e-6 * scale


def test_momentum_about_contact_is_conserved_on_the_torque_plant(motion, torque_run):
    """Rotor rates from p = int tau (scipy, not the plant): phi_dot = p / J_r - n . omega."""
    m = motion
    p = np.zeros((m.series.time.size, 2))
    edges = [0, *joints(m.series), m.series.time.size - 1]
    for a, b in zip(edges[:-1], edges[1:]):
        t = m.series.time[a:b + 1]
        p[a:b + 1] = p[a] + CubicSpline(t, m.series.rotor_torques[a:b + 1], axis=0).antiderivative()(t)
    _, omega, _ = _lp(torque_run, np.zeros((m.series.time.size, 2)))
    x = torque_run.series.state
    n = np.array([axes(u, v, s) for u, v, s in zip(x[:, 3], x[:, 4], x[:, 2])])
    rates = p / ROBOT.rotor_inertia_axial - np.einsum("nji,nj->ni", n[:, :, :2], omega)
    lp, _, scale = _lp(torque_run, rates)
    assert np.abs(lp).max() < 1e-6 * scale


def test_friction_keeps_the_momentum_and_brings_the_robot_to_rest(motion):
    """Bearing friction is internal: L_P stays zero while it drains the rotors, so the robot coasts to rest."""
    m = motion
    t = np.concatenate([m.series.time, m.series.time[-1] + np.linspace(0, 30, 301)[1:]])
    tq = np.vstack([m.series.rotor_torques, np.zeros((300, 2))])
    run = run_torques(ROBOT, t, tq, breaks=[*joints(m.series), m.series.time.size - 1],
                      disturbances=[disturbance("friction", c=(2e-5, 4e-5))])
    lp, _, scale = _lp(run, run.series.rotor_rates)
    assert np.abs(lp).max() < 1e-6 * scale
    assert np.abs(run.series.rotor_momenta[m.series.time.size - 1]).max() > 1e-4
    assert np.abs(run.series.omega[-1]).max() < 1e-3 * np.abs(run.series.omega).max()


def test_disturbances_by_name_and_seed(motion):
    t, r = motion.series.time[:401], motion.series.rotor_rates[:401]
    meas = disturbance("measurement", sigma_length=1e-3, sigma_angle=2e-3, seed=7)
    a = run_rates(ROBOT, t, r, disturbances=[meas])
    b = run_rates(ROBOT, t, r, disturbances=[meas])
    c = run_rates(ROBOT, t, r, disturbances=[meas], segment=1)
    np.testing.assert_array_equal(a.measured, b.measured)
    assert not np.array_equal(a.measured, c.measured)
    np.testing.assert_array_equal(a.series.state, run_rates(ROBOT, t, r).series.state)   # noise never touches the truth
    d = a.measured - a.series.state
    assert d[:, :2].std() == pytest.approx(1e-3 * ROBOT.radius, rel=0.15)
    assert d[:, 2:].std() == pytest.approx(2e-3, rel=0.15)
    tq = motion.series.rotor_torques[:401]
    noisy = run_torques(ROBOT, t, tq, disturbances=[disturbance("torque_noise", sigma=1e-4)])
    assert noisy.commanded is not None and not np.allclose(noisy.series.state, run_torques(ROBOT, t, tq).series.state)
    with pytest.raises(InputError, match="not known"):
        disturbance("wind", speed=3)
    with pytest.raises(InputError, match="wind"):
        disturbance("friction", wind=3)
    with pytest.raises(InputError, match="does not apply"):
        run_rates(ROBOT, t, r, disturbances=[disturbance("friction", c=1e-5)])
    with pytest.raises(InputError, match="does not apply"):
        run_torques(ROBOT, t, r, disturbances=[disturbance("rate_noise", sigma=1.0)])
    with pytest.raises(InputError, match=">= 0"):
        disturbance("torque_noise", sigma=-1)
    with pytest.raises(InputError, match="finite"):
        disturbance("measurement", sigma_length=float("nan"))
    with pytest.raises(InputError, match="twice"):
        run_rates(ROBOT, t, r, disturbances=[meas, meas])
    with pytest.raises(InputError, match="shape"):
        run_torques(ROBOT, t, r[:-1])
    with pytest.raises(InputError, match="finite"):
        run_torques(ROBOT, t, np.where(t[:, None] > 1, np.nan, r))


def test_input_function_is_the_pieces_or_linear():
    t = np.linspace(0, 2, 21)
    y = np.column_stack([np.abs(t - 1.0), t ** 2])
    tt = np.linspace(0, 2, 77)
    got = np.array(input_function(t, y, breaks=[10]).map(tt.size)(tt[None, :])).T
    expect = np.where((tt < 1.0)[:, None], CubicSpline(t[:11], y[:11])(tt), CubicSpline(t[10:], y[10:])(tt))
    np.testing.assert_allclose(got, expect, atol=1e-12)
    lin = np.array(input_function(t, y, interpolation="linear").map(tt.size)(tt[None, :])).T
    np.testing.assert_allclose(lin, np.column_stack([np.interp(tt, t, y[:, 0]), np.interp(tt, t, y[:, 1])]),
                               atol=1e-14)
    with pytest.raises(InputError, match="4 samples"):
        input_function(t, y, breaks=[2])
    with pytest.raises(InputError, match="not known"):
        input_function(t, y, interpolation="cubic")


def test_linear_input_steps_at_a_time_given_twice():
    """The replay rule of plan files: linear between rows, a step at a time given twice (to the second row's
    value, at that time), the end pieces extended. Against numpy's interp on each piece between the steps,
    at the samples, a hair before each step, at random times and outside the span; a time given twice at
    either end opens no piece, and three rows at one time step from the first to the last."""
    rng = np.random.default_rng(5)
    t = np.r_[0.0, 0.0, np.sort(rng.uniform(0.1, 3.9, 40)), 4.0, 4.0]
    t[[6, 20, 21]] = t[5], t[19], t[19]            # steps at t[5] (two rows) and t[19] (three rows)
    y = rng.normal(size=(t.size, 2))
    pieces = [(1, 5), (6, 19), (21, t.size - 2)]    # first and last row of each piece of strictly increasing times
    tt = np.r_[t, np.nextafter(t, -np.inf), rng.uniform(-1.0, 5.0, 400)]
    piece = np.clip(np.searchsorted(t[[a for a, _ in pieces]], tt, side="right") - 1, 0, len(pieces) - 1)
    expect = np.empty((tt.size, 2))
    for k, (a, b) in enumerate(pieces):
        tp, yp, at = t[a:b + 1], y[a:b + 1], piece == k
        for i in range(2):
            inside = np.interp(tt[at], tp, yp[:, i])
            lo, hi = (yp[1, i] - yp[0, i]) / (tp[1] - tp[0]), (yp[-1, i] - yp[-2, i]) / (tp[-1] - tp[-2])
            expect[at, i] = np.where(tt[at] < tp[0], yp[0, i] + lo * (tt[at] - tp[0]),
                                     np.where(tt[at] > tp[-1], yp[-1, i] + hi * (tt[at] - tp[-1]), inside))
    got = np.array(input_function(t, y, interpolation="linear").map(tt.size)(tt[None, :])).T
    np.testing.assert_allclose(got, expect, rtol=0, atol=1e-12)


def test_rate_spline_is_scipys_not_a_knot_spline_on_uneven_times():
    """Plan files put the torque steps' times between the uniform samples: CasADi's default solver of the spline's
    coefficients (iterative least squares) stopped at 5e-13 of the rates there, and slowly. Against scipy's
    not-a-knot CubicSpline at the samples and between them."""
    from rollplan.execution.plants import rate_spline

    rng = np.random.default_rng(3)
    t = np.unique(np.r_[np.linspace(0.0, 1.0, 4001), rng.uniform(0.0, 1.0, 300)])
    y = np.column_stack([np.sin(9 * t), t * np.cos(5 * t)])
    x = np.r_[t, rng.uniform(0.0, 1.0, 500)]
    got = np.array(rate_spline(t, y).map(x.size)(x[None, :])).T
    assert np.abs(got - CubicSpline(t, y, axis=0)(x)).max() < 2e-14


def _steps_series(n, seed=7):
    """n uneven sample times over 2 s with three torque steps (times given twice) and smooth torques between."""
    rng = np.random.default_rng(seed)
    t = np.sort(np.r_[0.0, rng.uniform(0.0, 2.0, n - 2), 2.0])
    t = np.sort(np.r_[t, t[[n // 4, n // 2, 3 * n // 4]]])
    tau = np.column_stack([2e-3 * np.sin(np.pi * t) ** 2, -1e-3 * np.cos(3 * t)])
    rep = np.nonzero(np.diff(t) == 0)[0] + 1
    tau[rep] += rng.normal(size=(rep.size, 2)) * 1e-3
    return t, tau


def _interval_by_interval(t, tau, friction=(0.0, 0.0)):
    """DOP853 on the printed equations, restarted at every sample: the torque linear over each interval, from the
    last row at its start time to the first row at its end time. States and momenta at the distinct times."""
    new = np.r_[True, np.diff(t) != 0]
    tk, first, last = t[new], tau[new], tau[np.r_[new[1:], True]]
    z, out = np.zeros(7), [np.zeros(7)]
    for k in range(tk.size - 1):
        a, b, qa, qb = tk[k], tk[k + 1], last[k], first[k + 1]
        line = lambda s, a=a, b=b, qa=qa, qb=qb: qa + (s - a) / (b - a) * (qb - qa)  # noqa: E731
        f, _ = references.torque_driven_rhs(*J, ROBOT.radius, line, friction)
        z = solve_ivp(f, (a, b), z, method="DOP853", rtol=1e-13, atol=1e-16).y[:, -1]
        out.append(z)
    return tk, first, last, np.array(out)


def test_linear_torque_replay_is_exact_for_the_momenta_and_matches_dop853():
    """The replay rule (linear between rows, a step at a time given twice) has a kink at every sample: CVODES
    took six steps a sample there and drifted 3e-9 of the momenta from their exact value, the trapezoid rule
    of the torques. Now the momenta are that rule to rounding, and the state is DOP853's, restarted at every
    sample, on the printed equations; a coarse series (few samples: more RK4 steps per interval) too."""
    for n in (400, 25):
        t, tau = _steps_series(n)
        run = run_torques(ROBOT, t, tau, interpolation="linear")
        tk, first, last, ref = _interval_by_interval(t, tau)
        exact = np.vstack([np.zeros(2), np.cumsum(0.5 * (last[:-1] + first[1:]) * np.diff(tk)[:, None], axis=0)])
        scale = np.abs(exact).max()
        assert np.abs(run.series.rotor_momenta - exact).max() < 1e-13 * scale, n
        assert np.abs(run.commanded_momenta - exact).max() < 1e-13 * scale, n
        np.testing.assert_allclose(run.series.time, tk)
        assert np.abs(run.series.state - ref[:, :5]).max() < 1e-11, n


def test_a_replay_of_many_chunks_is_as_accurate_as_of_one():
    """The linear replay goes through the samples RK_CHUNK intervals at a time, choosing the RK4 steps per interval
    again in each chunk. Torques linear over the whole span, sampled over more than two chunks: the replay's input
    is one line, so DOP853 on the printed equations runs it without a restart; the states within 1e-11 of its at
    every sample (as test_linear_torque_replay_is_exact_for_the_momenta_and_matches_dop853 asks of one chunk), the
    momenta the line's integral to rounding."""
    from rollplan.execution.plants import RK_CHUNK

    duration, q0, q1 = 6.0, np.array([9e-3, -6e-3]), np.array([-3e-3, 7.5e-3])
    t = np.linspace(0.0, duration, 2 * RK_CHUNK + 501)
    run = run_torques(ROBOT, t, q0 + np.outer(t / duration, q1 - q0), interpolation="linear")
    f, _ = references.torque_driven_rhs(*J, ROBOT.radius, lambda s: q0 + (q1 - q0) * s / duration)
    ref = solve_ivp(f, (0.0, duration), np.zeros(7), method="DOP853", t_eval=t, rtol=1e-13, atol=1e-16).y.T
    assert np.abs(ref[:, 3]).max() > 5.0   # the robot rolls on over every chunk
    assert np.abs(run.series.state - ref[:, :5]).max() < 1e-11
    exact = np.outer(t, q0) + np.outer(t**2 / (2 * duration), q1 - q0)
    assert np.abs(run.series.rotor_momenta - exact).max() < 1e-13 * np.abs(exact).max()


def test_samples_far_apart_for_the_motion_are_replayed_by_cvodes_to_the_printed_equations(caplog):
    """Five rows over 10 s of torques that turn the robot many times between rows: 64 RK4 steps per interval miss
    by far (their estimate is above 1e-2), so the plant integrates the same linear inputs by CVODES and still ends
    where DOP853, restarted at every sample, ends on the printed equations."""
    import logging

    t = np.linspace(0.0, 10.0, 5)
    tau = np.column_stack([0.05 * np.sin(np.arange(5) * 1.7), 0.05 * np.cos(np.arange(5) * 2.3)])
    with caplog.at_level(logging.INFO, logger="rollplan.execution.plants"):
        run = run_torques(ROBOT, t, tau, interpolation="linear")
    assert "far apart" in caplog.text and "CVODES" in caplog.text
    ref = _interval_by_interval(t, tau)[3]
    assert np.abs(ref[-1, :5]).max() > 10.0   # the motion is long between rows
    assert np.abs(run.series.state - ref[:, :5]).max() < 1e-6 * np.abs(ref[:, :5]).max()


@pytest.mark.slow
def test_ctrl_c_while_cvodes_runs_the_torque_plant_is_a_keyboard_interrupt():
    """Spline inputs (and linear ones too far apart for RK4) are integrated by CVODES, which swallows a Ctrl-C
    (rollplan.interrupts): the plant raises KeyboardInterrupt within a second, not a solver failure."""
    from test_interrupts import interrupt_after

    t = np.linspace(0.0, 800.0, 40001)
    tau = np.column_stack([2e-3 * np.sin(0.7 * t), -1e-3 * np.cos(1.3 * t)])
    timer = interrupt_after(0.5)
    with pytest.raises(KeyboardInterrupt):
        run_torques(ROBOT, t, tau, interpolation="spline")
    assert timer.sent and time.perf_counter() - timer.sent[0] < 1.0
