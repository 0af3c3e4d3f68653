"""Plans: the paper's case, asymmetric and multi-step plans, all checked by an
integration independent of the planner (scipy DOP853 over all n steps)."""

import numpy as np
import pytest

import rollplan
from rollplan import InputError, NoPlanError, Robot


def wrap(angle):
    """Angle to (-pi, pi] (typed here, not rollplan's)."""
    return np.angle(np.exp(1j * np.asarray(angle, float)))


def closed_form_36(a):
    return 4 * a / np.sqrt(1 - a * a) * np.sin(np.pi * np.sqrt(1 - a * a))


def reaches(p, scipy_trace, tol=1e-9):
    """The plan's target from an independent scipy integration of all steps."""
    x = scipy_trace(p.a / p.radius, p.b / p.radius, p.k, p.gamma, p.steps)
    err = [x[0] - p.target[0] / p.radius, x[1] - p.target[1] / p.radius, wrap(x[2] - p.target[2])]
    return np.abs(err).max()  # lengths in units of R, angle in rad


def test_paper_case_k25_shortest_solution(scipy_trace):
    """Section III.C: k = 2.5, h/R = 1 along v_a: a1 = 0.300429 R, gamma = 0.931883 rad."""
    p = rollplan.plan((0.0, 1.0, 0.0), k=2.5)
    assert p.a == pytest.approx(0.300429, abs=5e-7)
    assert p.b == pytest.approx(p.a, abs=1e-9)
    assert p.gamma == pytest.approx(0.931883, abs=5e-7)
    assert p.residual < 1e-9
    assert reaches(p, scipy_trace) < 1e-9


def test_paper_case_k25_all_solutions():
    """--all finds the paper's four symmetric solutions a1..a4 and gamma for a2."""
    p = rollplan.plan((0.0, 1.0, 0.0), k=2.5, all_solutions=True)
    plans = (p,) + p.alternatives
    sym = sorted(q.a for q in plans if abs(q.a - q.b) < 1e-9)
    for printed in (0.300429, 0.491471, 0.538682, 0.609147):
        assert min(abs(a - printed) for a in sym) < 5e-7
    a2 = min(plans, key=lambda q: abs(q.a - 0.491471))
    assert a2.gamma == pytest.approx(-0.69726, abs=5e-6)
    lengths = [q.path_length for q in plans]
    assert lengths == sorted(lengths)  # shortest first
    assert all(q.residual < 1e-9 for q in plans)


def test_pure_rolling_plan_matches_closed_form_36():
    """k = 0, psi = 0: a = b and h(a, a) = h_des from (36); the shortest root of (36) = 1."""
    p = rollplan.plan((1.0, 0.0, 0.0), k=0.0)
    assert p.a == pytest.approx(p.b, abs=1e-9)
    assert closed_form_36(p.a / p.radius) == pytest.approx(1.0, abs=1e-9)
    grid = np.linspace(1e-3, 0.69, 20000)
    first_root = grid[np.argmax(closed_form_36(grid) >= 1.0)]
    assert p.a == pytest.approx(first_root, abs=1e-4)


@pytest.mark.parametrize("target,steps,k", [
    ((0.5, 0.7, 0.8), 1, 2.5),       # asymmetric: psi != 0
    ((1.5, -0.5, 1.0), 3, 2.5),      # multi-step
    ((0.3, 0.2, -2.0), 2, 5.0),
    ((-0.8, -0.4, 0.0), 2, 1.7),     # psi = 0, n > 1: (34)
    ((2.0, 0.0, 3.0), 4, 10.0),
])
def test_plans_land_on_target(scipy_trace, target, steps, k):
    p = rollplan.plan(target, steps=steps, k=k)
    assert p.residual < 1e-9
    assert reaches(p, scipy_trace) < 1e-9
    assert p.steps == steps
    if target[2] != 0:
        assert abs(p.a - p.b) > 1e-6  # a turn needs unequal leaves
    # (32)-(33) against the independent reference: one step of (a, b) turns psi by eta and shifts
    # by h (printed (28)-(30), DOP853), with n eta = psi + 2 pi m and h |sin(n eta/2) / sin(eta/2)| = h_des
    one = scipy_trace(p.a, p.b, k, 0.0, 1)
    h, eta = np.hypot(one[0], one[1]), one[2]
    assert (p.h, p.eta) == pytest.approx((h, eta), abs=1e-10)
    assert steps * eta == pytest.approx(target[2] + 2 * np.pi * p.branch, abs=1e-9)
    gain = steps if abs(np.sin(eta / 2)) < 1e-12 else abs(np.sin(steps * eta / 2) / np.sin(eta / 2))  # (34)
    assert h * gain == pytest.approx(np.hypot(*target[:2]), abs=1e-9)


def test_final_state_is_independent_integration(scipy_trace):
    p = rollplan.plan((0.4, 0.9, 0.5), steps=2, k=3.0)
    x = scipy_trace(p.a, p.b, p.k, p.gamma, p.steps)
    assert np.allclose(p.final[:3], x, atol=1e-10)
    assert np.allclose(p.final[3:], 0.0, atol=1e-12)


def test_methods_agree():
    a = rollplan.plan((0.5, 0.7, 0.8), k=2.5, method="ipopt")
    b = rollplan.plan((0.5, 0.7, 0.8), k=2.5, method="newton")
    assert (a.a, a.b, a.gamma) == pytest.approx((b.a, b.b, b.gamma), abs=1e-9)


def test_radius_and_robot_scale_lengths(scipy_trace):
    robot = Robot()
    unit = rollplan.plan((0.3, 0.4, 0.5), k=robot.k)
    metres = rollplan.plan((0.3 * robot.radius, 0.4 * robot.radius, 0.5), robot=robot)
    assert metres.k == pytest.approx(robot.k)
    assert metres.a == pytest.approx(unit.a * robot.radius, rel=1e-9)
    assert metres.gamma == pytest.approx(unit.gamma, abs=1e-9)
    assert metres.path_length == pytest.approx(unit.path_length * robot.radius, rel=1e-9)
    assert reaches(unit, scipy_trace) < 1e-9
    assert reaches(metres, scipy_trace) < 1e-9  # a / R, b / R against the target / R
    scaled = rollplan.plan((0.6, 0.8, 0.5), k=robot.k, radius=2.0)
    assert reaches(scaled, scipy_trace) < 1e-9


def test_trajectory_starts_at_rest_and_ends_on_target():
    p = rollplan.plan((0.5, 0.7, 0.8), k=2.5)
    t = p.trajectory(50)
    assert t.theta[0] == 0 and t.theta[-1] == pytest.approx(2 * np.pi * p.steps)
    assert np.allclose([t.u_a[0], t.v_a[0], t.psi[0], t.u_o[0], t.v_o[0]], 0)
    assert np.allclose([t.u_a[-1], t.v_a[-1], wrap(t.psi[-1] - 0.8)], [0.5, 0.7, 0], atol=1e-9)
    assert np.allclose(np.linalg.norm(t.contact, axis=1), p.radius)
    assert set(np.unique(t.leaf)) == {0, 1}


def test_unreachable_target_says_so():
    with pytest.raises(NoPlanError, match="more steps"):
        rollplan.plan((30.0, 0.0, 0.0), k=2.5)


@pytest.mark.parametrize("kwargs,match", [
    (dict(target=(np.nan, 1, 0), k=2.5), "u_a"),
    (dict(target=(0, np.inf, 0), k=2.5), "v_a"),
    (dict(target=(0, 1, 0), k=-1.0), "k = -1"),
    (dict(target=(0, 1, 0), k=2.5, steps=0), "steps = 0"),
    (dict(target=(0, 1, 0), k=2.5, steps=1.5), "steps = 1.5"),
    (dict(target=(0, 1, 0), k=2.5, radius=0.0), "radius = 0"),
    (dict(target=(0, 1, 0)), "k is missing"),
    (dict(target=(0, 1, 0), k=2.5, robot=Robot()), "either k or robot"),
    (dict(target=(0, 1), k=2.5), "target"),
    (dict(target=(0, 1, 0), k=2.5, method="bogus"), "method"),
])
def test_bad_input_is_one_clear_line(kwargs, match):
    with pytest.raises(InputError, match=match) as err:
        rollplan.plan(**kwargs)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("a,b", [(0.0, 0.3), (0.3, 0.7072), (-0.1, 0.3), (0.3, np.nan)])
def test_step_rejects_radii_outside_admissible_range(a, b):
    with pytest.raises(InputError, match="is not allowed"):
        rollplan.step(a, b, k=2.5)


@pytest.mark.parametrize("target,steps,k", [((0.5, 0.7, 0.8), 1, 2.5), ((0.3, 0.2, -2.0), 2, 5.0)])
def test_realizability_13_along_the_computed_motion(target, steps, k):
    """Finite differences of the orientation (2) along the CVODES trajectory give omega;
    n3 . Jc omega = 0 must hold there (and fails for another k: the check can fail)."""
    import casadi as ca

    from rollplan import model

    p = rollplan.plan(target, steps=steps, k=k)
    t = p.trajectory(samples_per_leaf=4000)
    q = ca.SX.sym("q", 3)
    rot = ca.Function("R", [q], [model.orientation(q[0], q[1], q[2])]).map(t.theta.size)
    mats = np.array(rot(np.vstack([t.u_o, t.v_o, t.psi]))).reshape(3, t.theta.size, 3).transpose(1, 0, 2)
    inner = (t.leaf[1:-1] == t.leaf[:-2]) & (t.leaf[1:-1] == t.leaf[2:]) & (np.diff(t.theta)[:-1] > 0)
    i = np.nonzero(inner)[0] + 1
    h = (t.theta[i + 1] - t.theta[i - 1])[:, None, None]
    w_hat = (mats[i + 1] - mats[i - 1]) / h @ mats[i].transpose(0, 2, 1)
    w = np.stack([w_hat[:, 2, 1], w_hat[:, 0, 2], w_hat[:, 1, 0]], axis=1)
    n3 = mats[i][:, :, 2]
    realizable = k * (n3[:, 0] * w[:, 0] + n3[:, 1] * w[:, 1]) + n3[:, 2] * w[:, 2]
    scale = np.abs(w).max()
    assert np.abs(realizable).max() < 1e-4 * scale
    other = (k + 1) * (n3[:, 0] * w[:, 0] + n3[:, 1] * w[:, 1]) + n3[:, 2] * w[:, 2]
    assert np.abs(other).max() > 1e-2 * scale
