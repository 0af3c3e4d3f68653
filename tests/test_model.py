"""The symbolic model (rollplan.core.model): each relation derived from the ones before it, and identities.

The paper's printed formulas are the independent references (``tests/references.py``); where the
paper has a misprint the test says so.
"""

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan.core import model
from rollplan.core.curves import circle_point

import references

angle = st.floats(-1.2, 1.2)
rate = st.floats(-3.0, 3.0)
kk = st.floats(0.0, 12.0)


def num(x):
    return np.array(ca.DM(x), dtype=float).squeeze()


def vee(m):
    return np.array([m[2, 1], m[0, 2], m[1, 0]])


@settings(max_examples=60, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2))
def test_orientation_is_a_rotation(u, v, psi):
    r = num(model.orientation(u, v, psi))
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-14)
    assert np.linalg.det(r) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(r, references.orientation(u, v, psi), atol=1e-14)  # (2) from elementary rotations


@settings(max_examples=40, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2))
def test_columns_match_printed_3_to_5(u, v, psi):
    r = num(model.orientation(u, v, psi))
    # (3) as printed has n1z = cos u cos v, which would make n1 non-unit and equal to n3z;
    # the product (2) gives sin u cos v. Misprint in the paper (references.axes corrects it).
    n1, n2, n3 = references.axes(u, v, psi)
    assert np.allclose(r, np.column_stack([n1, n2, n3]), atol=1e-14)
    cu, su, cv = np.cos(u), np.sin(u), np.cos(v)
    if abs(su - cu) > 1e-3 and cv > 1e-3:
        assert abs(r[2, 0] - references.printed_n1z(u, v)) > 1e-6


@settings(max_examples=40, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), st.floats(0.1, 3.0))
def test_contact_point_1_is_the_lowest_point(u, v, psi, radius):
    """(1): the contact point in the body frame is R^T (0, 0, -R)."""
    r = num(model.orientation(u, v, psi))
    assert np.allclose(num(model.contact_point(u, v, radius)), r.T @ [0, 0, -radius], atol=1e-13)


def _omega_and_rates(u, v, psi, du, dv, dpsi):
    """omega from hat(omega) = Rdot R^T, by automatic differentiation of (2)."""
    q = ca.SX.sym("q", 3)
    rm = model.orientation(q[0], q[1], q[2])
    rdot = ca.jtimes(ca.vec(rm), q, ca.DM([du, dv, dpsi]))
    f = ca.Function("f", [q], [ca.reshape(rdot, 3, 3) @ rm.T])
    return vee(num(f([u, v, psi])))


@settings(max_examples=60, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), rate, rate, rate)
def test_18_19_and_17_from_rdot(u, v, psi, du, dv, dpsi):
    w = _omega_and_rates(u, v, psi, du, dv, dpsi)
    assert np.allclose(num(model.omega_from_contact_rates(u, v, psi, du, dv)), w[:2], atol=1e-12)
    # (17): psi_dot = -omega_z + sin v u_dot
    assert dpsi == pytest.approx(-w[2] + np.sin(v) * du, abs=1e-12)


@settings(max_examples=60, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), rate, rate, rate, st.floats(0.2, 2.0))
def test_montana_8_10_invert_the_angular_velocity(u, v, psi, du, dv, dpsi, radius):
    """Montana's (6)-(10) return the rates in State order (u_a, v_a, psi, u_o, v_o)."""
    w = _omega_and_rates(u, v, psi, du, dv, dpsi)
    rates = num(model.montana(w, u, v, psi, radius))
    assert np.allclose(rates[2:], [dpsi, du, dv], atol=1e-11)
    # (6)-(7): no slip, the centre moves with omega x (R e_z)
    assert np.allclose(rates[:2], np.cross(w, [0, 0, radius])[:2], atol=1e-12)
    assert np.allclose(rates, references.montana(w, u, v, psi, radius), atol=1e-12)  # as printed


@settings(max_examples=60, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), rate, rate, kk)
def test_20_from_10_13_18_19(u, v, psi, du, dv, k):
    printed = references.psi_dot(u, v, du, dv, k)
    ours = float(model.psi_dot_realizable(u, v, psi, du, dv, k))
    assert ours == pytest.approx(printed, abs=1e-10 * (1 + abs(printed)))
    w = model.realizable_omega(u, v, psi, du, dv, k)
    assert abs(float(model.realizability_residual(w, u, v, psi, k))) < 1e-12


@settings(max_examples=40, deadline=None)
@given(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0), st.floats(-3.2, 3.2), angle, angle, rate, rate, kk,
       st.floats(0.2, 2.0))
def test_contact_rhs_in_state_order(u_a, v_a, psi, u, v, du, dv, k, radius):
    """contact_rhs takes and returns (u_a, v_a, psi, u_o, v_o): its (8)-(9) give back the contact
    rates, its psi' is the printed (20), and its omega satisfies (13) through the printed (6), (7), (10)."""
    x = [u_a, v_a, psi, u, v]
    xdot = num(model.contact_rhs(ca.DM(x), ca.DM([du, dv]), k, radius))
    assert np.allclose(xdot[3:], [du, dv], atol=1e-12)
    printed = references.psi_dot(u, v, du, dv, k)
    assert xdot[2] == pytest.approx(printed, abs=1e-10 * (1 + abs(printed)))
    w = references.omega_from_rates(np.array([x]), np.array([xdot]), radius)[0]
    n3 = references.axes(u, v, psi)[2]
    assert abs(references.realizability(n3, w, k)) < 1e-10 * (1 + np.abs(w).max())


def test_pure_rolling_is_not_realizable_in_general():
    """Section III: omega_z = 0 is realizable only when n3x wx + n3y wy = 0."""
    u, v, psi, du, dv, k = 0.3, 0.2, 0.4, 1.0, 0.5, 2.5
    wxy = model.omega_from_contact_rates(u, v, psi, du, dv)
    w = ca.vertcat(wxy, 0)
    assert abs(float(model.realizability_residual(w, u, v, psi, k))) > 1e-3


def test_inertia_ratio_14():
    radius, m_total, m_shell, j_r, j_p = 0.12, 1.5, 0.5, 3e-4, 2e-4
    k, j_xx, j_zz = model.inertia_ratio(radius, m_total, m_shell, j_r, j_p)
    assert k == pytest.approx(references.inertia_ratio(radius, m_total, m_shell, j_r, j_p), rel=1e-15)
    assert j_xx == pytest.approx(j_zz + m_total * radius**2)
    assert k > 1


@settings(max_examples=40, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), rate, rate, st.floats(1.0, 10.0))
def test_rotor_rates_satisfy_momentum_integral_11(u, v, psi, du, dv, k):
    j_zz, j_r = 2.0, 0.3
    j_xx = k * j_zz
    w = num(model.realizable_omega(u, v, psi, du, dv, k))
    phi = num(model.rotor_rates(w, u, v, psi, j_xx, j_zz, j_r))
    r = num(model.orientation(u, v, psi))
    total = np.diag([j_xx, j_xx, j_zz]) @ w + j_r * (r[:, 0] * phi[0] + r[:, 1] * phi[1])
    assert np.allclose(total, 0, atol=1e-11 * (1 + np.abs(w).max()))
    assert np.allclose(num(model.omega_from_rotor_rates(phi, u, v, psi, j_xx, j_zz, j_r)), w, atol=1e-11)


def test_contact_coordinates_invert_1():
    u, v = 0.4, -0.3
    uu, vv = model.contact_coordinates(model.contact_point(u, v))
    assert float(uu) == pytest.approx(u, abs=1e-15) and float(vv) == pytest.approx(v, abs=1e-15)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.02, 0.69), st.floats(0.0, 2 * np.pi), st.floats(-6.0, 6.0), kk, st.sampled_from([1.0, -1.0]))
def test_curve_ode_matches_printed_28_30_and_psi_prime_is_state_free(a, theta, psi, k, side):
    th = ca.SX.sym("th")
    pt = circle_point(a, th, side)
    rhs, psym = model.curve_rhs(pt, th, k)
    f = ca.Function("f", [th, psym], [rhs, pt, ca.jacobian(pt, th), ca.jacobian(rhs[2], psym)])
    val, c, dc, dpsi = (num(o) for o in f(theta, psi))
    assert np.allclose(val, references.curve_rhs(c, dc, psi, k), rtol=1e-9, atol=1e-10)
    assert abs(float(dpsi)) < 1e-9 * (1 + abs(val[2]))  # (20) has no psi


@settings(max_examples=40, deadline=None)
@given(st.floats(0.01, 0.69), st.floats(0.0, 2 * np.pi))
def test_circle_35_is_on_the_sphere_through_the_south_pole(a, theta):
    c = num(circle_point(a, theta))
    assert np.linalg.norm(c) == pytest.approx(1.0, abs=1e-14)
    assert np.allclose(num(circle_point(a, 0.0)), [0, 0, -1], atol=1e-15)
    # a circle of Euclidean radius a: all points at distance a from the centre of the circle
    centre = (num(circle_point(a, 0.0)) + num(circle_point(a, np.pi))) / 2
    assert np.linalg.norm(c - centre) == pytest.approx(a, abs=1e-13)
    assert np.allclose(c, references.circle(a, theta, 1.0)[0], atol=1e-15)  # the printed (35)
