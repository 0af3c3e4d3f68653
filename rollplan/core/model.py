"""The symbolic model: the single source of truth for every planner.

Everything here is a CasADi expression built from the equations of Svinin,
Morinaga and Yamamoto (the paper), numbered as there:

* contact point on the sphere (1) and orientation matrix (2)-(5);
* Montana's contact kinematics (6)-(10);
* angular velocity from contact rates, :math:`\\hat\\omega = \\dot R R^T` (18)-(19);
* the dynamic-realizability condition (12)-(13), solved for :math:`\\omega_z`;
* the inertia ratio ``k`` (14) and the rotor rates from the momentum integral (11);
* the curve-parameterized ODE (28)-(30) for any spherical curve;
* the torque-driven dynamics: the left side of (11) (the angular momentum about
  the contact point), the rotors' axial momenta (P) and (11) solved for omega
  given those momenta, (O) of :func:`omega_from_momenta`.

Nothing is typed twice: (17) and (20) are *composed* from (10), (13), (18),
(19); (28)-(30) are composed from (6), (7), (10) with the contact rates of a
curve obtained by automatic differentiation of (24)-(25). The printed forms of
(20) and (28)-(30) are used only in the tests, as independent references.

Lengths are in units of the sphere radius unless a radius ``R`` is passed.
"""

from __future__ import annotations

from functools import lru_cache

import casadi as ca
import numpy as np

__all__ = [
    "rot_x",
    "rot_y",
    "rot_z",
    "contact_point",
    "orientation",
    "montana",
    "omega_from_contact_rates",
    "omega_z_realizable",
    "realizability_residual",
    "psi_dot_realizable",
    "inertia_ratio",
    "rotor_rates",
    "rotor_axial_spins",
    "contact_coordinates",
    "curve_contact",
    "curve_omega",
    "curve_rhs",
    "realizable_omega",
    "contact_rhs",
    "omega_from_rotor_rates",
    "contact_points",
    "orientations",
    "momentum_about_contact",
    "rotor_axial_momenta",
    "omega_from_momenta",
    "omega_line_element",
]


def rot_x(t):
    """Elementary rotation about x (active, right-handed)."""
    c, s = ca.cos(t), ca.sin(t)
    return ca.vertcat(ca.horzcat(1, 0, 0), ca.horzcat(0, c, -s), ca.horzcat(0, s, c))


def rot_y(t):
    """Elementary rotation about y (active, right-handed)."""
    c, s = ca.cos(t), ca.sin(t)
    return ca.vertcat(ca.horzcat(c, 0, s), ca.horzcat(0, 1, 0), ca.horzcat(-s, 0, c))


def rot_z(t):
    """Elementary rotation about z (active, right-handed)."""
    c, s = ca.cos(t), ca.sin(t)
    return ca.vertcat(ca.horzcat(c, -s, 0), ca.horzcat(s, c, 0), ca.horzcat(0, 0, 1))


def contact_point(u_o, v_o, R=1.0):
    """Contact point on the sphere in the body frame, eq. (1); south pole at u=v=0."""
    return R * ca.vertcat(-ca.sin(u_o) * ca.cos(v_o), ca.sin(v_o), -ca.cos(u_o) * ca.cos(v_o))


def orientation(u_o, v_o, psi):
    """Orientation of the body frame relative to the plane, eq. (2).

    ``R = Rz(psi)^T Rx(v_o)^T Ry(u_o)^T``; its columns are n1, n2, n3 of (3)-(5).
    """
    return rot_z(psi).T @ rot_x(v_o).T @ rot_y(u_o).T


def montana(omega, u_o, v_o, psi, R=1.0):
    """Contact-coordinate rates from the angular velocity, eqs. (6)-(10).

    Parameters
    ----------
    omega : (3,) angular velocity of the sphere in the plane frame [rad/s]
    u_o, v_o, psi : contact coordinates [rad]

    Returns
    -------
    (5,) rates of the state (u_a, v_a, psi, u_o, v_o): eqs. (6), (7), (10), (8), (9).
    """
    wx, wy, wz = omega[0], omega[1], omega[2]
    roll = wx * ca.sin(psi) + wy * ca.cos(psi)
    return ca.vertcat(
        R * wy,                                # (6)
        -R * wx,                               # (7)
        -wz - roll * ca.tan(v_o),              # (10)
        -roll / ca.cos(v_o),                   # (8)
        -wx * ca.cos(psi) + wy * ca.sin(psi),  # (9)
    )


def omega_from_contact_rates(u_o, v_o, psi, du_o, dv_o):
    """Rolling components (omega_x, omega_y) from the contact rates, eqs. (18)-(19)."""
    wx = -du_o * ca.cos(v_o) * ca.sin(psi) - dv_o * ca.cos(psi)
    wy = -du_o * ca.cos(v_o) * ca.cos(psi) + dv_o * ca.sin(psi)
    return ca.vertcat(wx, wy)


def realizability_residual(omega, u_o, v_o, psi, k):
    """Left side of the realizability condition (13), ``n3 . Jc omega / Jzz``."""
    n3 = orientation(u_o, v_o, psi)[:, 2]
    return k * (n3[0] * omega[0] + n3[1] * omega[1]) + n3[2] * omega[2]


def omega_z_realizable(omega_xy, u_o, v_o, psi, k):
    """The spin omega_z that makes (13) hold for given rolling components."""
    n3 = orientation(u_o, v_o, psi)[:, 2]
    return -k * (n3[0] * omega_xy[0] + n3[1] * omega_xy[1]) / n3[2]


def realizable_omega(u_o, v_o, psi, du_o, dv_o, k):
    """Full angular velocity of a dynamically realizable motion: (18), (19), (13)."""
    wxy = omega_from_contact_rates(u_o, v_o, psi, du_o, dv_o)
    return ca.vertcat(wxy, omega_z_realizable(wxy, u_o, v_o, psi, k))


def psi_dot_realizable(u_o, v_o, psi, du_o, dv_o, k):
    """psi-dot of a realizable motion, eq. (20), composed from (10), (13), (18), (19)."""
    w = realizable_omega(u_o, v_o, psi, du_o, dv_o, k)
    return montana(w, u_o, v_o, psi)[2]


def inertia_ratio(radius, mass_total, mass_shell, rotor_inertia_axial, rotor_inertia_transverse):
    """Inertia ratio k = Jxx/Jzz, eq. (14); also returns (Jxx, Jzz).

    ``Jzz = 2/3 m_o R^2 + 2 J_p + J_r`` and ``Jxx = Jzz + M R^2`` (Section II).
    Works on floats and on CasADi symbols alike.
    """
    j_zz = 2.0 / 3.0 * mass_shell * radius**2 + 2.0 * rotor_inertia_transverse + rotor_inertia_axial
    j_xx = j_zz + mass_total * radius**2
    return j_xx / j_zz, j_xx, j_zz


def rotor_rates(omega, u_o, v_o, psi, j_xx, j_zz, j_r):
    """Rotor rates (phi1_dot, phi2_dot) from the momentum integral (11).

    Pre-multiplying (11) by the orthonormal n1 and n2 gives
    ``phi_i_dot = -n_i . Jc omega / J_r`` with ``Jc = diag(Jxx, Jxx, Jzz)``.
    """
    rot = orientation(u_o, v_o, psi)
    jw = ca.vertcat(j_xx * omega[0], j_xx * omega[1], j_zz * omega[2])
    return ca.vertcat(-ca.dot(rot[:, 0], jw) / j_r, -ca.dot(rot[:, 1], jw) / j_r)


def rotor_axial_spins(omega, u_o, v_o, psi, j_xx, j_zz, j_r):
    """The rotors' absolute spins about their axes, ``n_i . omega + phi_i_dot`` (i = 1, 2), with (11).

    ``J_r`` times their time derivative is the motor torque about ``n_i``
    (:mod:`rollplan.execution.actuation`).
    """
    rot = orientation(u_o, v_o, psi)
    return (ca.vertcat(ca.dot(rot[:, 0], omega), ca.dot(rot[:, 1], omega))
            + rotor_rates(omega, u_o, v_o, psi, j_xx, j_zz, j_r))


def contact_coordinates(point, R=1.0):
    """(u_o, v_o) of a point on the sphere, by inverting (1) as in (24)-(25).

    Valid on the open lower hemisphere (z < 0), where |u_o| < pi/2.
    """
    x, y, z = point[0], point[1], point[2]
    return ca.atan2(-x, -z), ca.asin(y / R)


def curve_contact(point, theta, R=1.0):
    """Contact coordinates along a curve and their derivatives by the curve parameter.

    ``point`` is a CasADi expression in the symbol ``theta``; returns
    ``(u_o, v_o, du_o/dtheta, dv_o/dtheta)`` by inverting (1) as in (24)-(25)
    and differentiating automatically, which is (27).
    """
    u_o, v_o = contact_coordinates(point, R)
    return u_o, v_o, ca.jacobian(u_o, theta), ca.jacobian(v_o, theta)


def curve_omega(point, theta, psi, k, R=1.0):
    """Angular velocity per unit rate of theta along a curve, and the contact coordinates.

    The contact rates of :func:`curve_contact` in (18)-(19), with the spin from
    the realizability condition (13). Returns ``(omega (3,), u_o, v_o)``;
    the angular velocity of a motion along the curve is ``theta_dot`` times ``omega``.
    """
    u_o, v_o, du_o, dv_o = curve_contact(point, theta, R)
    return realizable_omega(u_o, v_o, psi, du_o, dv_o, k), u_o, v_o


def curve_rhs(point, theta, k, R=1.0):
    """Right side of the curve-parameterized ODE (28)-(30).

    The contact point follows ``point(theta)`` (a CasADi expression in the
    symbol ``theta``); the state is (u_a, v_a, psi). The angular velocity is
    :func:`curve_omega` and the state rates are Montana's (6), (7), (10).

    Returns
    -------
    rhs : casadi expression, (3,) in terms of ``theta``, a fresh symbol ``psi``
    psi : the state symbol psi used in ``rhs``
    """
    psi = ca.SX.sym("psi") if isinstance(theta, ca.SX) else ca.MX.sym("psi")
    w, u_o, v_o = curve_omega(point, theta, psi, k, R)
    return montana(w, u_o, v_o, psi, R)[:3], psi


def contact_rhs(state, rates, k, R=1.0):
    """Time derivative of the contact state for a realizable motion, (15)-(17) with (20).

    Parameters
    ----------
    state : (5,) (u_a, v_a, psi, u_o, v_o) [length unit of R, rad]
    rates : (2,) the contact rates (u_o_dot, v_o_dot) [rad/s], the free inputs
    k : inertia ratio

    Returns
    -------
    (5,) d/dt of the state. The angular velocity is (18)-(19) with the spin
    from (13), so the realizability condition holds by construction; the rates
    are Montana's (6)-(10), whose (8)-(9) give back ``rates``.
    """
    psi, u_o, v_o = state[2], state[3], state[4]
    w = realizable_omega(u_o, v_o, psi, rates[0], rates[1], k)
    return montana(w, u_o, v_o, psi, R)


@lru_cache(maxsize=1)
def _pose_function() -> ca.Function:
    u, v, psi = ca.SX.sym("u"), ca.SX.sym("v"), ca.SX.sym("psi")
    return ca.Function("pose", [u, v, psi], [contact_point(u, v), ca.reshape(orientation(u, v, psi), 9, 1)])


def contact_points(u_o, v_o) -> np.ndarray:
    """Contact points (1) on the unit sphere (body frame) for arrays of (u_o, v_o): shape (N, 3)."""
    u, v = np.atleast_1d(np.asarray(u_o, float)), np.atleast_1d(np.asarray(v_o, float))
    return np.array(_pose_function().map(u.size)(u[None, :], v[None, :], 0.0)[0]).T


def orientations(u_o, v_o, psi) -> np.ndarray:
    """Orientation matrices (2) for arrays of (u_o, v_o, psi): shape (N, 3, 3)."""
    u, v, p = (np.atleast_1d(np.asarray(x, float)) for x in (u_o, v_o, psi))
    flat = np.array(_pose_function().map(u.size)(u[None, :], v[None, :], p[None, :])[1]).T   # (N, 9), column-major
    return flat.reshape(-1, 3, 3).transpose(0, 2, 1)


def omega_from_rotor_rates(phi_dot, u_o, v_o, psi, j_xx, j_zz, j_r):
    """Angular velocity of the sphere from the rotor rates, by solving (11) for omega.

    ``Jc omega = -J_r (n1 phi1_dot + n2 phi2_dot)`` with ``Jc = diag(Jxx, Jxx, Jzz)``
    in the plane frame. The result satisfies (12)-(13) automatically.
    """
    rot = orientation(u_o, v_o, psi)
    m = -j_r * (rot[:, 0] * phi_dot[0] + rot[:, 1] * phi_dot[1])
    return ca.vertcat(m[0] / j_xx, m[1] / j_xx, m[2] / j_zz)


def momentum_about_contact(omega, phi_dot, u_o, v_o, psi, j_xx, j_zz, j_r):
    """Left side of (11): the total angular momentum of shell and rotors about the contact point.

    ``L_P = J_c omega + J_r (n_1 phi_1_dot + n_2 phi_2_dot)`` in the plane frame, ``J_c = diag(Jxx, Jxx, Jzz)``.

    Why it is conserved (and zero for a motion from rest, which is (11)): gravity acts at the
    centre C, vertically above the contact point P, and the contact force acts at P; the moving
    reference point P has the velocity of C, parallel to the linear momentum ``M v_C``. So no
    external moment about P changes ``L_P``. Friction in the rotor bearings and the motor torques
    are internal moments between rotor and shell and do not change it either.

    Composed from the model, not retyped: on the orthonormal axes n_1, n_2, n_3 of (2),
    ``n_i . J_c omega = -J_r g_i(omega)`` (i = 1, 2) with g the rotor rates of (11)
    (:func:`rotor_rates`) and ``n_3 . J_c omega = Jzz r(omega)`` with r the left side of (13)
    (:func:`realizability_residual`), hence

        L_P = J_r sum_i n_i (phi_i_dot - g_i(omega)) + Jzz r(omega) n_3:

    (11) holds exactly when the rotors turn at the rates of (11) and the motion satisfies (13).

    Parameters
    ----------
    omega : (3,) angular velocity of the shell, plane frame [rad/s]
    phi_dot : (2,) rotor rates relative to the shell [rad/s]
    u_o, v_o, psi : contact coordinates [rad]
    j_xx, j_zz, j_r : inertias [kg m^2]

    Returns
    -------
    (3,) CasADi expression [kg m^2/s].
    """
    rot = orientation(u_o, v_o, psi)
    g = rotor_rates(omega, u_o, v_o, psi, j_xx, j_zz, j_r)
    r = realizability_residual(omega, u_o, v_o, psi, j_xx / j_zz)
    return j_r * (rot[:, 0] * (phi_dot[0] - g[0]) + rot[:, 1] * (phi_dot[1] - g[1])) + j_zz * r * rot[:, 2]


def rotor_axial_momenta(omega, phi_dot, u_o, v_o, psi, j_r):
    """Absolute axial spin momenta of the rotors, ``p_i = J_r (n_i . omega + phi_i_dot)`` (P).

    Their time derivatives are the motor torques, (T) of :mod:`rollplan.execution.actuation`.
    """
    rot = orientation(u_o, v_o, psi)
    return j_r * (ca.vertcat(ca.dot(rot[:, 0], omega), ca.dot(rot[:, 1], omega)) + phi_dot)


def _affine_solve(residual, unknown):
    """The value of ``unknown`` that zeroes a residual affine in it: ``-J^-1 r(0)``, J by AD."""
    jac = ca.jacobian(residual, unknown)
    r0 = ca.substitute(residual, unknown, ca.DM.zeros(unknown.shape))
    return ca.solve(jac, -r0)


def omega_from_momenta(p, u_o, v_o, psi, j_xx, j_zz, j_r):
    """Angular velocity and rotor rates from the rotors' axial momenta: (11) with (P), solved.

    Substituting ``phi_i_dot = p_i / J_r - n_i . omega`` of (P) into (11) gives

        [J_c - J_r (n_1 n_1^T + n_2 n_2^T)] omega = -(n_1 p_1 + n_2 p_2),          (O)

    and since ``n_1 n_1^T + n_2 n_2^T = I - n_3 n_3^T`` the matrix is
    ``A = diag(Jxx - J_r, Jxx - J_r, Jzz - J_r) + J_r n_3 n_3^T``. With
    ``Jzz - J_r = 2/3 m_o R^2 + 2 J_p > 0`` (14) it is symmetric positive definite for every
    orientation, eigenvalues in ``[Jzz - J_r, Jxx]``: the inertia about the contact point with the
    rotors free to spin. Both solves (of (P) for phi_dot, of (11) for omega) are of affine maps,
    built by automatic differentiation of :func:`rotor_axial_momenta` and
    :func:`momentum_about_contact`; nothing is retyped.

    Returns
    -------
    omega : (3,) CasADi expression [rad/s], plane frame
    phi_dot : (2,) CasADi expression, rotor rates relative to the shell [rad/s]
    """
    sym = ca.MX if any(isinstance(v, ca.MX) for v in (p, u_o, v_o, psi, j_xx, j_zz, j_r)) else ca.SX
    w, pd = sym.sym("w", 3), sym.sym("pd", 2)
    pd_of_w = _affine_solve(rotor_axial_momenta(w, pd, u_o, v_o, psi, j_r) - p, pd)
    omega = _affine_solve(momentum_about_contact(w, pd_of_w, u_o, v_o, psi, j_xx, j_zz, j_r), w)
    return omega, ca.substitute(pd_of_w, w, omega)


@lru_cache(maxsize=8)
def omega_line_element(R: float = 1.0) -> ca.Function:
    """``L(x) -> (3, 3)`` with ``omega dt = L(x) d(u_a, v_a, psi)``: Montana's (6), (7), (10) inverted.

    Rows (6), (7), (10) of :func:`montana` are linear in omega, ``M_3(x) omega``, with
    ``det M_3 = -R^2`` wherever ``cos v_o != 0``; M_3 is taken by AD and inverted. ``int omega dt``
    along a measured motion is then a line integral along the state path, needing no time
    derivative of the data. ``x`` is a state (u_a, v_a, psi, u_o, v_o).
    """
    x, w = ca.SX.sym("x", 5), ca.SX.sym("w", 3)
    rates = montana(w, x[3], x[4], x[2], float(R))
    m3 = ca.jacobian(ca.vertcat(rates[0], rates[1], rates[2]), w)
    return ca.Function("omega_line_element", [x], [ca.inv(m3)], ["x"], ["L"])
