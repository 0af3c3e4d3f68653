"""Time law, omega, rotor rates, angles and torques (rollplan.execution.timing and .actuation).

References are independent of the code under test: the paper's printed n_1, n_2, n_3 (3)-(5) in
numpy (``references.axes``; n_1 = n_2 x n_3, the printed (3) has a typo in its third entry, see
test_paper_n1_typo), Montana's (6)-(10) as printed, finite differences of the sampled motion, the
full angular-momentum vector of an axisymmetric rotor, and scaling identities of the time law.
"""

import numpy as np
import pytest
from matplotlib.figure import Figure

import rollplan
from rollplan import InputError
from rollplan.execution.actuation import MIN_SAMPLES_PER_LEAF, actuate
from rollplan.execution.timing import MIN_JERK
from rollplan.plots.motion import plot_motion

import references

ROBOT = rollplan.Robot()


def contact(state):
    """(u_o, v_o, psi) columns of sampled states in State order (u_a, v_a, psi, u_o, v_o)."""
    return state[:, 3], state[:, 4], state[:, 2]


@pytest.fixture(scope="module")
def sym_plan():
    return rollplan.plan((0.0, 0.1, 0.0), 1, robot=ROBOT)  # h = 1 R, psi = 0: a = b


@pytest.fixture(scope="module")
def asym_plan():
    return rollplan.plan((0.05, 0.08, 0.5), 2, robot=ROBOT)


@pytest.fixture(scope="module")
def motion(asym_plan):
    return actuate(asym_plan, ROBOT, 8.0, 4000)


def test_paper_n1_typo():
    """The orientation (2) used by the model has n_1 = n_2 x n_3; the printed (3) has n_1z = cos u cos v."""
    import casadi as ca

    from rollplan.core import model

    u, v, psi = 0.3, -0.2, 0.7
    rot = np.array(ca.Function("r", [], [model.orientation(u, v, psi)])()["o0"])
    n1, n2, n3 = references.axes(u, v, psi)
    np.testing.assert_allclose(n1, np.cross(n2, n3), atol=1e-15)
    np.testing.assert_allclose(rot, np.column_stack([np.cross(n2, n3), n2, n3]), atol=1e-15)
    assert abs(n1[2] - np.sin(u) * np.cos(v)) < 1e-15
    assert abs(n1[2] - references.printed_n1z(u, v)) > 0.5


def test_rest_to_rest_profile_is_minimum_jerk(motion, asym_plan):
    """Each half-step's arc length follows 10 tau^3 - 15 tau^4 + 6 tau^5 (the minimum-jerk rest-to-rest law)."""
    tau = np.linspace(0, 1, 11)
    poly = np.polynomial.Polynomial(MIN_JERK)
    np.testing.assert_allclose(poly(tau), 10 * tau**3 - 15 * tau**4 + 6 * tau**5, atol=1e-15)
    np.testing.assert_allclose(poly.deriv()(tau), 30 * tau**2 * (1 - tau) ** 2, atol=1e-13)
    np.testing.assert_allclose(poly.deriv(2)(tau), 60 * tau * (1 - tau) * (1 - 2 * tau), atol=1e-13)
    # the motion's first half-step (2 s of 8): s = 2 pi a_R s(tau), closed form in time
    first = motion.series.time <= 2.0
    tau = motion.series.time[first] / 2.0
    leaf = 2 * np.pi * asym_plan.a / asym_plan.radius
    np.testing.assert_allclose(motion.s[first], leaf * (10 * tau**3 - 15 * tau**4 + 6 * tau**5), atol=1e-13)
    np.testing.assert_allclose(motion.s_dot[first], leaf * 30 * tau**2 * (1 - tau) ** 2 / 2.0, atol=1e-12)


def test_sampling(motion, asym_plan):
    n = motion.series.time.size
    assert n >= 2000 and n == 4 * 1000 + 1
    assert motion.series.omega.shape == (n, 3) and motion.series.rotor_rates.shape == (n, 2)
    assert motion.series.rotor_angles.shape == (n, 2) and motion.series.rotor_torques.shape == (n, 2)
    np.testing.assert_allclose(np.diff(motion.series.time), 8.0 / (n - 1), rtol=1e-9)
    assert motion.series.time[0] == 0 and motion.series.time[-1] == 8.0
    assert list(motion.series.time[motion.rest_indices]) == pytest.approx([0, 2, 4, 6, 8])
    few = actuate(asym_plan, ROBOT, 8.0, 10)
    assert few.series.time.size == 4 * MIN_SAMPLES_PER_LEAF + 1


def test_omega_zero_at_rest_points(motion):
    rest = motion.rest_indices
    assert np.all(motion.series.omega[rest] == 0) and np.all(motion.series.rotor_rates[rest] == 0)
    assert np.abs(motion.series.rotor_torques[rest]).max() < 1e-12 * np.abs(motion.series.rotor_torques).max()
    assert np.abs(motion.series.omega).max() > 0.1  # it does move in between
    # each leaf starts at the south pole
    assert np.abs(motion.series.state[rest, 3:5]).max() < 1e-12


def test_arrives_at_target(motion, asym_plan):
    g = asym_plan.goal
    assert motion.goal == g
    np.testing.assert_allclose(motion.series.state[-1], [g.u_a, g.v_a, g.psi, 0, 0], atol=1e-10)


def test_realizability_13_along_motion(motion):
    _, _, n3 = references.axes(*contact(motion.series.state))
    w = motion.series.omega
    res = references.realizability(n3, w, ROBOT.k)  # (13)
    assert np.abs(res).max() < 1e-13 * np.abs(w).max()
    # pure rolling (omega_z = 0) would violate it: the spin is really used
    assert np.abs(w[:, 2]).max() > 0.3 * np.abs(w[:, :2]).max()


def test_momentum_integral_11(motion):
    n1, n2, _ = references.axes(*contact(motion.series.state))
    jc_w = motion.series.omega * [ROBOT.j_xx, ROBOT.j_xx, ROBOT.j_zz]
    rates = motion.series.rotor_rates
    total = jc_w + ROBOT.rotor_inertia_axial * (n1 * rates[:, :1] + n2 * rates[:, 1:])
    assert np.abs(total).max() < 1e-14 * np.abs(jc_w).max() + 1e-18


def test_omega_drives_the_state_by_montana(motion):
    """Finite differences of the sampled contact coordinates equal Montana's (6)-(10) with the output omega."""
    t, x, w, R = motion.series.time, motion.series.state, motion.series.omega, ROBOT.radius
    u, v, psi = contact(x)
    rates = references.montana(w, u, v, psi, R)
    fd = np.gradient(x, t, axis=0, edge_order=2)
    scale = np.abs(rates).max(axis=0)
    assert np.all(np.abs(fd - rates).max(axis=0) < 2e-4 * scale)


def test_rotor_angles_integrate_rates(motion):
    t, r = motion.series.time, motion.series.rotor_rates
    trap = np.vstack([[0, 0], np.cumsum(0.5 * (r[1:] + r[:-1]) * np.diff(t)[:, None], axis=0)])
    assert np.abs(trap - motion.series.rotor_angles).max() < 1e-4 * np.abs(motion.series.rotor_angles).max()


def test_torques_equal_rate_of_rotor_angular_momentum(motion):
    """tau_i = n_i . dH_i/dt with the full H_i of an axisymmetric rotor (axial J_r, transverse J_p)."""
    jr, jp = ROBOT.rotor_inertia_axial, ROBOT.rotor_inertia_transverse
    t, w = motion.series.time, motion.series.omega
    n = references.axes(*contact(motion.series.state))
    for i in range(2):
        ni = n[i]
        axial = np.sum(ni * w, axis=1)
        H = jp * w + ((jr - jp) * axial + jr * motion.series.rotor_rates[:, i])[:, None] * ni
        dH = np.gradient(H, t, axis=0, edge_order=2)
        fd = np.sum(ni * dH, axis=1)
        tau = motion.series.rotor_torques[:, i]
        assert np.abs(fd - tau).max() < 2e-4 * np.abs(tau).max()  # O(h^2); J_r d(phi_dot)/dt alone is off by 2e-2


def test_time_scaling(asym_plan, motion):
    """Doubling T halves rates and omega, quarters torques, keeps the path and rotor angles."""
    slow = actuate(asym_plan, ROBOT, 16.0, 4000)
    np.testing.assert_allclose(slow.series.time, 2 * motion.series.time, rtol=1e-12)
    np.testing.assert_allclose(slow.series.state, motion.series.state, atol=1e-11)
    np.testing.assert_allclose(slow.series.rotor_angles, motion.series.rotor_angles, atol=1e-9)
    np.testing.assert_allclose(slow.series.omega, motion.series.omega / 2, atol=1e-12)
    np.testing.assert_allclose(slow.series.rotor_rates, motion.series.rotor_rates / 2, atol=1e-10)
    np.testing.assert_allclose(slow.series.rotor_torques, motion.series.rotor_torques / 4, atol=1e-12)


def test_symmetric_plan_mirror(sym_plan):
    """a = b, psi = 0: the two half-steps mirror in time; the rotor rate magnitudes repeat."""
    assert sym_plan.a == pytest.approx(sym_plan.b, rel=1e-9)
    m = actuate(sym_plan, ROBOT, 10.0, 2000)
    r = np.abs(m.series.rotor_rates)
    np.testing.assert_allclose(r, r[::-1], atol=1e-8 * r.max())


def test_bad_input(asym_plan):
    with pytest.raises(InputError, match="duration"):
        actuate(asym_plan, ROBOT, 0.0)
    with pytest.raises(InputError, match="duration"):
        actuate(asym_plan, ROBOT, float("nan"))
    with pytest.raises(InputError, match="samples"):
        actuate(asym_plan, ROBOT, 1.0, 2)
    other = rollplan.Robot(mass_total=2.0)
    with pytest.raises(InputError, match="k ="):
        actuate(asym_plan, other, 1.0)


def test_plot_motion(motion, asym_plan):
    fig = plot_motion(motion, asym_plan, asym_plan.sample(20), "m")
    assert isinstance(fig, Figure)
    labels = [ax.get_ylabel() for ax in fig.axes]
    assert "angular velocity [rad/s]" in labels and "rotor rate [rad/s]" in labels
    assert "motor torque [N m]" in labels   # N m as in the console and the JSON
    assert all(ax.get_xlabel() == "time t [s]" for ax in fig.axes[:3])


@pytest.mark.parametrize("law", ["min-jerk", "nonstop-min-jerk"])   # joints on breaks; joints between them
def test_joint_times_are_the_full_bisections(asym_plan, law):
    """joint_times stops halving once no bracket changes and evaluates s alone: the same times, bit for bit, as
    100 halvings on the profile's evaluate with the same snapping to a break; position is evaluate's s."""
    from dataclasses import replace

    from rollplan.execution.limits import Limits
    from rollplan.execution.path import ContactPath
    from rollplan.execution.timing import get_law, joint_times

    robot = replace(ROBOT, max_rotor_rate=300.0, max_rotor_torque=0.05)
    path = ContactPath.of_plan(asym_plan, robot)
    prof = get_law(law).profile(path, Limits.of(robot))
    joints = path.starts[1:-1]
    lo, hi = np.zeros(joints.size), np.full(joints.size, prof.duration)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        below = prof.evaluate(mid)[0] < joints
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    near = prof.breaks[np.clip(np.searchsorted(prof.breaks, hi), 0, prof.breaks.size - 1)]
    expect = np.where(np.abs(prof.evaluate(near)[0] - joints) <= 1e-12 * path.length, near, hi)
    assert np.array_equal(joint_times(path, prof), expect)
    t = np.r_[np.random.default_rng(4).uniform(-1.0, prof.duration + 1.0, 300), prof.breaks]
    assert np.array_equal(prof.position(t), prof.evaluate(t)[0])
