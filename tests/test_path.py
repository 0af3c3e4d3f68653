"""The contact path along its arc length (rollplan.execution.path): the rotor coefficients against the
paper's printed equations, smooth joints at the poles, and the grid.

References: omega, the rotor rates and axial spins from the printed (24)-(27), (18), (19), (13), (11)
with psi by DOP853 on the printed (28)-(30) (``references.rotor_terms``), central differences, the
contact point (1) as printed, the planner's own certificate.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import rollplan
from rollplan import InputError
from rollplan.execution.path import ArcLengthPiece, ContactPath, leaf_function

import references

ROBOT = rollplan.Robot()


@pytest.fixture(scope="module")
def path(asym_plan):
    return ContactPath.of_plan(asym_plan, ROBOT)


def _terms(plan, s, side="left"):
    R = ROBOT.radius
    return references.rotor_terms(plan.a / R, plan.b / R, plan.gamma, plan.k, ROBOT.j_xx, ROBOT.j_zz,
                                  ROBOT.rotor_inertia_axial, plan.steps, s, side)


def test_length_pieces_and_end(path, asym_plan):
    R = ROBOT.radius
    assert path.length == pytest.approx(2 * np.pi * 2 * (asym_plan.a + asym_plan.b) / R, rel=1e-14)
    assert path.length == pytest.approx(asym_plan.path_length / R, rel=1e-12)
    assert len(path.pieces) == 4 and path.joints.size == 3
    assert not path.corners.any()  # every pole of a figure eight is a smooth joint
    g = asym_plan.goal
    np.testing.assert_allclose(path.final_state[:3], [g.u_a / R, g.v_a / R, g.psi], atol=1e-9)


def test_coefficients_match_printed_equations(path, asym_plan):
    """W, G and A / J_r against (11), (13), (18)-(19), (24)-(27) as printed; B against d/ds of the printed spin."""
    jr = ROBOT.rotor_inertia_axial
    s = np.sort(np.random.default_rng(1).uniform(0.0, path.length, 6))
    ps = path.evaluate(s)
    w_ref, g_ref, a_ref = _terms(asym_plan, s)
    np.testing.assert_allclose(ps.W, w_ref, rtol=0, atol=1e-9 * np.abs(w_ref).max())
    np.testing.assert_allclose(ps.G, g_ref, rtol=0, atol=1e-9 * np.abs(g_ref).max())
    np.testing.assert_allclose(ps.A / jr, a_ref, rtol=0, atol=1e-9 * np.abs(a_ref).max())
    h = 1e-4
    b_ref = jr * (_terms(asym_plan, s + h)[2] - _terms(asym_plan, s - h)[2]) / (2 * h)
    np.testing.assert_allclose(ps.B, b_ref, rtol=0, atol=1e-6 * np.abs(b_ref).max())


def test_state_in_state_order_and_rotor_angles_integrate_G(path):
    s = np.linspace(0, path.length, 20001)
    ps = path.evaluate(s)
    assert np.abs(ps.state[[0, -1], 3:]).max() < 1e-12        # u_o = v_o = 0 at both ends (State order)
    u_o, v_o = ps.state[:, 3], ps.state[:, 4]
    # the contact point (1) on the unit sphere moves at unit speed: s is the arc length
    pts = np.column_stack([-np.sin(u_o) * np.cos(v_o), np.sin(v_o), -np.cos(u_o) * np.cos(v_o)])
    speed = np.linalg.norm(np.diff(pts, axis=0), axis=1) / np.diff(s)
    np.testing.assert_allclose(speed, 1.0, atol=1e-6)
    for i in range(2):
        trap = np.concatenate([[0.0], np.cumsum(0.5 * np.diff(s) * (ps.G[1:, i] + ps.G[:-1, i]))])
        assert np.abs(trap - ps.rotor_angles[:, i]).max() < 1e-6 * np.abs(ps.rotor_angles[:, i]).max()


def test_rates_continuous_and_torque_coefficient_jumps_at_poles(path, asym_plan):
    """Per unit s', omega (W), the rates (G) and A are continuous at a pole; B (the curvature) jumps.
    In the leaf parameter phi the rates per unit phi' jump by b / a: an artefact of that parameter."""
    sj = path.joints
    left, right = path.evaluate(sj, "left"), path.evaluate(sj, "right")
    # continuous up to rounding, which the joint's place s, divided by the small leaf radius, amplifies
    # (a jump would be of the order of |b / a - 1| > 0.1, as B's is)
    tol = 1e-10
    assert np.abs(left.W - right.W).max() < tol * np.abs(left.W).max()
    assert np.abs(left.G - right.G).max() < tol * np.abs(left.G).max()
    assert np.abs(left.A - right.A).max() < tol * np.abs(left.A).max()
    assert np.abs(left.B - right.B).min() > 0.5 * np.abs(left.B).max()
    # both sides against the printed equations (the reference takes the leaf of the side asked)
    for side, ps in (("left", left), ("right", right)):
        np.testing.assert_allclose(ps.G, _terms(asym_plan, sj, side)[1], atol=1e-9 * np.abs(ps.G).max())
    a, b = asym_plan.a, asym_plan.b
    np.testing.assert_allclose(right.G[0] * b / (left.G[0] * a), b / a, rtol=1e-10)
    assert abs(b / a - 1) > 0.1


def test_continuous_torques_across_a_pole_need_a_stop(path):
    """Both torques continuous across a pole need A_i (u+ - u-) + (B_i+ - B_i-) x = 0 for i = 1, 2: one
    unknown jump of s'' for two equations, solvable with x = s'^2 > 0 only if dB_1 / A_1 = dB_2 / A_2. It is
    not: a motion with continuous torques stops at every pole; a motion with bounded torques need not."""
    left, right = path.evaluate(path.joints, "left"), path.evaluate(path.joints, "right")
    ratio = (right.B - left.B) / left.A
    assert np.all(np.abs(ratio[:, 0] - ratio[:, 1]) > 0.1 * np.abs(ratio).max(axis=1))


def test_grid(path):
    g = path.grid(400)
    np.testing.assert_allclose(g.s[g.joints], path.joints, rtol=0, atol=1e-14)
    assert g.s[0] == 0 and g.s[-1] == path.length and np.all(np.diff(g.s) > 0)
    assert g.corners.size == 0
    inner = np.setdiff1d(np.arange(g.size), g.joints)
    assert np.array_equal(g.B_left[inner], g.B_right[inner]) and np.array_equal(g.G_left[inner], g.G_right[inner])
    assert np.abs(g.G_left[g.joints] - g.G_right[g.joints]).max() < 1e-12 * np.abs(g.G_left).max()
    assert np.abs(g.B_left[g.joints] - g.B_right[g.joints]).min() > 0


def test_a_corner_is_detected_and_declared(asym_plan):
    """Two leaves of different radii traced by phi with the same scale: W per unit s' jumps by b/a at the
    joint, which is then a corner; a declared corner is one whatever W does."""
    ab = (asym_plan.a / ROBOT.radius, asym_plan.b / ROBOT.radius)
    gamma = asym_plan.gamma
    bad = ContactPath([ArcLengthPiece(leaf_function(0), ab, gamma, 2 * np.pi, ab[0]),
                       ArcLengthPiece(leaf_function(1), ab, gamma, 2 * np.pi, ab[0])], ROBOT)
    assert bad.corners.tolist() == [True]
    assert bad.grid(100).corners.tolist() == [bad.grid(100).joints[0]]
    declared = ContactPath([ArcLengthPiece(leaf_function(0), ab, gamma, 2 * np.pi, ab[0]),
                            ArcLengthPiece(leaf_function(1), ab, gamma, 2 * np.pi, ab[1], corner=True)], ROBOT)
    assert declared.corners.tolist() == [True]


def test_bad_input(path, asym_plan):
    with pytest.raises(InputError, match="outside"):
        path.evaluate([path.length * 1.01])
    with pytest.raises(InputError, match="outside"):
        path.evaluate([np.nan])
    with pytest.raises(InputError, match="side"):
        path.evaluate([0.1], "middle")
    with pytest.raises(InputError, match="k ="):
        ContactPath.of_plan(asym_plan, rollplan.Robot(mass_total=2.0))
    with pytest.raises(InputError, match="geometric-phase plan"):
        ContactPath.of_plan(None, ROBOT)
    with pytest.raises(InputError, match="piece"):
        ContactPath([], ROBOT)


def test_states_along_the_path_match_dop853_on_the_printed_equations(path, asym_plan):
    """(u_a, v_a, psi) inside every leaf and at its ends against DOP853 (rtol 1e-13) on the printed (28)-(30)
    along the circles (35), leaf after leaf; the path's end is its final state."""
    R = ROBOT.radius
    x = np.zeros(3)
    phis = np.linspace(0.0, 2 * np.pi, 41)
    for j in range(4):
        r, side = (asym_plan.a / R, 1.0) if j % 2 == 0 else (asym_plan.b / R, -1.0)
        ref = solve_ivp(references.rhs, (0.0, 2 * np.pi), x, method="DOP853", rtol=1e-13, atol=1e-14, t_eval=phis,
                        args=(r, side, asym_plan.k, asym_plan.gamma)).y.T
        for side_name in ("left", "right"):
            ps = path.evaluate(path.starts[j] + r * phis, side_name)
            np.testing.assert_allclose(ps.state[:, :3], ref, rtol=0, atol=1e-10)
        x = ref[-1]
    np.testing.assert_allclose(path.final_state[:3], x, rtol=0, atol=1e-10)


def test_the_state_at_a_joint_is_one_state_from_both_sides(path):
    """The integrated state (u_a, v_a, psi, the rotor angles) at a joint and at the end is the one the path found
    piece by piece, from either side and whatever other points are evaluated with it: the same numbers, to the bit
    (u_o, v_o come from each side's curve: equal to rounding)."""
    s = np.unique(np.r_[np.linspace(0.0, path.length, 97), path.joints])
    left, right = path.evaluate(s, "left"), path.evaluate(s, "right")
    at = np.isin(s, np.r_[path.joints, path.length])
    assert at.sum() == path.joints.size + 1
    assert np.array_equal(left.state[at, :3], right.state[at, :3])
    assert np.array_equal(left.rotor_angles[at], right.rotor_angles[at])
    np.testing.assert_allclose(left.state[at, 3:], right.state[at, 3:], rtol=0, atol=1e-15)
    alone = path.evaluate(path.joints, "left")
    assert np.array_equal(alone.state[:, :3], left.state[at, :3][:-1])
    assert np.array_equal(left.state[-1, :3], path.final_state[:3])
    assert np.array_equal(left.rotor_angles[-1], path.final_state[3:])
