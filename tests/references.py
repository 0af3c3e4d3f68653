"""Independent references for the tests: the paper's printed equations and closed forms, in numpy.

Nothing here imports rollplan. Each formula is typed once, from the paper as printed (misprints
corrected and said so), and is what the tests compare rollplan's symbolic model and planners with:

* :func:`orientation` -- (2), composed from elementary rotations; :func:`axes` -- its columns
  n_1, n_2, n_3 as printed in (3)-(5);
* :func:`montana` -- Montana's contact kinematics (6)-(10); :func:`omega_from_rates` -- (6), (7),
  (10) inverted for the angular velocity;
* :func:`realizability` -- the left side of the realizability condition (13);
* :func:`inertia_ratio` -- (14); :func:`composite_inertias` -- Jxx, Jzz of Section II; :func:`psi_dot` -- (20);
* :func:`rotor_drive` -- the robot driven by sampled rotor rates alone: omega from (11), then (6)-(10), by
  DOP853 with the rates interpolated by scipy's not-a-knot cubic spline;
* :func:`curve_rhs` -- the curve ODE (28)-(30) with c_u, c_v of (26); :func:`circle` -- the circle
  (35) rotated by gamma (31); :func:`rhs` and :func:`trace` -- (28)-(30) along the figure eight,
  integrated by scipy's DOP853 (an integrator that shares no code with rollplan);
* :func:`n_step_gain` -- (33)-(34); :func:`shift_36` -- the closed form (36);
* :func:`wrap` -- an angle reduced to (-pi, pi]; :func:`rotate` -- a plane vector turned;
  :func:`two_pi_fraction` -- 2 pi as an exact fraction to many digits (Chudnovsky's series in
  integer arithmetic).

States are in rollplan's one order (u_a, v_a, psi, u_o, v_o); lengths in units of R unless a
radius is given, angles in rad.
"""

from __future__ import annotations

from fractions import Fraction
from functools import lru_cache
from math import isqrt

import numpy as np
from scipy.integrate import solve_ivp

# ----------------------------------------------------------------------------- angles


def wrap(angle):
    """Angle(s) reduced to (-pi, pi] through the unit circle (not rollplan's formula)."""
    return np.angle(np.exp(1j * np.asarray(angle, float)))


def rotate(angle, vec):
    """Plane vector(s) ``vec = (x, y)`` turned by ``angle``: multiplication by exp(i angle)."""
    z = (np.asarray(vec[0], float) + 1j * np.asarray(vec[1], float)) * np.exp(1j * np.asarray(angle, float))
    return np.stack([z.real, z.imag])


@lru_cache(maxsize=4)
def two_pi_fraction(digits: int = 700) -> Fraction:
    """2 pi as a fraction, correct to ``digits`` decimals: Chudnovsky's series in integer arithmetic."""
    one = 10 ** (digits + 10)
    k, a_k, a_sum, b_sum = 1, one, one, 0
    c3_over_24 = 640320**3 // 24
    while a_k:
        a_k *= -(6 * k - 5) * (2 * k - 1) * (6 * k - 1)
        a_k //= k * k * k * c3_over_24
        a_sum += a_k
        b_sum += k * a_k
        k += 1
    total = 13591409 * a_sum + 545140134 * b_sum
    pi_scaled = (426880 * isqrt(10005 * one * one) * one) // total
    return Fraction(2 * pi_scaled, one)


# ----------------------------------------------------------------------------- orientation (2)-(5)


def _rx(a):
    return np.array([[1, 0, 0], [0, np.cos(a), -np.sin(a)], [0, np.sin(a), np.cos(a)]])


def _ry(a):
    return np.array([[np.cos(a), 0, np.sin(a)], [0, 1, 0], [-np.sin(a), 0, np.cos(a)]])


def _rz(a):
    return np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]])


def orientation(u_o, v_o, psi):
    """(2): ``Rz(psi)^T Rx(v_o)^T Ry(u_o)^T`` from elementary rotations (scalars)."""
    return _rz(psi).T @ _rx(v_o).T @ _ry(u_o).T


#: The printed third entry of n_1 in (3), ``cos u_o cos v_o``, is a misprint: it would make n_1
#: non-unit; the product (2) gives ``sin u_o cos v_o`` (README, list of misprints).
def printed_n1z(u_o, v_o):
    """The third entry of n_1 as printed in (3) (a misprint, see :func:`axes`)."""
    return np.cos(u_o) * np.cos(v_o)


def axes(u_o, v_o, psi):
    """n_1, n_2, n_3 of (3)-(5) as arrays (..., 3), with (3)'s third entry corrected to sin u cos v."""
    cu, su, cv, sv, cp, sp = np.cos(u_o), np.sin(u_o), np.cos(v_o), np.sin(v_o), np.cos(psi), np.sin(psi)
    n1 = np.stack([cu * cp + su * sv * sp, -cu * sp + su * sv * cp, su * cv], axis=-1)
    n2 = np.stack([cv * sp, cv * cp, -sv], axis=-1)
    n3 = np.stack([-su * cp + cu * sv * sp, su * sp + cu * sv * cp, cu * cv], axis=-1)
    return n1, n2, n3


# ----------------------------------------------------------------------------- kinematics (6)-(20)


def montana(omega, u_o, v_o, psi, radius=1.0):
    """Rates of (u_a, v_a, psi, u_o, v_o) from omega (..., 3): (6), (7), (10), (8), (9)."""
    w = np.asarray(omega, float)
    wx, wy, wz = w[..., 0], w[..., 1], w[..., 2]
    roll = wx * np.sin(psi) + wy * np.cos(psi)
    return np.stack([radius * wy, -radius * wx, -wz - roll * np.tan(v_o), -roll / np.cos(v_o),
                     -wx * np.cos(psi) + wy * np.sin(psi)], axis=-1)


def omega_from_rates(x, xdot, radius=1.0):
    """Angular velocity (N, 3) from states x and their rates xdot (N, 5): (6), (7), (10) solved for omega."""
    x, xdot = np.asarray(x, float), np.asarray(xdot, float)
    wy, wx = xdot[:, 0] / radius, -xdot[:, 1] / radius
    psi, v_o = x[:, 2], x[:, 4]
    roll = wx * np.sin(psi) + wy * np.cos(psi)
    return np.column_stack([wx, wy, -xdot[:, 2] - roll * np.tan(v_o)])


def realizability(n3, omega, k):
    """Left side of (13) divided by Jzz: ``k (n3x wx + n3y wy) + n3z wz`` (arrays (..., 3))."""
    n3, w = np.asarray(n3, float), np.asarray(omega, float)
    return k * (n3[..., 0] * w[..., 0] + n3[..., 1] * w[..., 1]) + n3[..., 2] * w[..., 2]


def inertia_ratio(radius, mass_total, mass_shell, rotor_inertia_axial, rotor_inertia_transverse):
    """(14) as printed: ``k = 1 + M R^2 / (2/3 m_o R^2 + 2 J_p + J_r)``."""
    return 1 + mass_total * radius**2 / (2 / 3 * mass_shell * radius**2 + 2 * rotor_inertia_transverse
                                         + rotor_inertia_axial)


def composite_inertias(radius, mass_total, mass_shell, rotor_inertia_axial, rotor_inertia_transverse):
    """(Jxx, Jzz) as printed under (11): ``Jzz = 2/3 m_o R^2 + 2 J_p + J_r``, ``Jxx = Jzz + M R^2``."""
    j_zz = 2 / 3 * mass_shell * radius**2 + 2 * rotor_inertia_transverse + rotor_inertia_axial
    return j_zz + mass_total * radius**2, j_zz


def rotor_drive(robot: dict, t, rates, x0=None, rtol=1e-12, atol=1e-14):
    """States (N, 5) at the times ``t`` of the robot driven by the sampled rotor ``rates`` (N, 2) alone.

    ``robot`` holds the five parameters of Section II by rollplan's key names. omega from (11),
    ``Jc omega = -J_r (n_1 phi_1' + n_2 phi_2')`` with n_1, n_2 the columns of (2), drives (6)-(10);
    DOP853 integrates them with the rates interpolated by scipy's not-a-knot cubic spline.
    """
    from scipy.interpolate import CubicSpline

    keys = ("radius", "mass_total", "mass_shell", "rotor_inertia_axial", "rotor_inertia_transverse")
    j_xx, j_zz = composite_inertias(*(robot[k] for k in keys))
    jc, jr, radius = np.array([j_xx, j_xx, j_zz]), robot["rotor_inertia_axial"], robot["radius"]
    t = np.asarray(t, float)
    spline = CubicSpline(t, np.asarray(rates, float), bc_type="not-a-knot")

    def f(time, x):
        psi, u, v = x[2], x[3], x[4]
        rot = orientation(u, v, psi)
        r1, r2 = spline(time)
        return montana(-jr * (rot[:, 0] * r1 + rot[:, 1] * r2) / jc, u, v, psi, radius)

    x0 = np.zeros(5) if x0 is None else np.asarray(x0, float)
    sol = solve_ivp(f, (t[0], t[-1]), x0, method="DOP853", rtol=rtol, atol=atol, t_eval=t)
    assert sol.success, sol.message
    return sol.y.T


def psi_dot(u_o, v_o, du_o, dv_o, k):
    """(20) as printed: ``psi' = (1 - k) sin v u' + k tan u / cos v v'``."""
    return (1 - k) * np.sin(v_o) * du_o + k * np.tan(u_o) / np.cos(v_o) * dv_o


# ----------------------------------------------------------------------------- curves (26)-(36)


def curve_rhs(point, dpoint, psi, k, radius=1.0):
    """(28)-(30) as printed, with c_u, c_v of (26): rates of (u_a, v_a, psi) for a contact point
    ``point = (x, y, z)`` moving at ``dpoint`` per unit curve parameter.

    (29) is printed with ``v^2`` under the root; it is ``y^2`` as in (28) (a misprint).
    """
    x, y, z = point
    s = np.sqrt(radius**2 - y**2)
    p = np.array([z, 0.0, -x]) @ dpoint
    q = np.array([-x * y / s, s, -y * z / s]) @ dpoint
    return np.array([
        -np.cos(psi) / s * p + np.sin(psi) / radius * q,
        np.sin(psi) / s * p + np.cos(psi) / radius * q,
        ((1 - k) * y * p / (radius**2 - y**2) + k * x * q / (z * s)) / radius,
    ])


def circle(a, phi, side, gamma=0.0):
    """Point of the circle (35) of radius a (side +1: +y, -1: -y) turned by Rz(gamma) (31), and d/dphi."""
    d = np.sqrt(1 - a * a)
    s, c = np.sin(phi), np.cos(phi)
    p = np.array([a * s, side * (-a * d * c + d * a), -a * a * c - d * d])
    dp = np.array([a * c, side * a * d * s, a * a * s])
    rz = _rz(gamma)
    return rz @ p, rz @ dp


def rhs(phi, state, a, side, k, gamma):
    """(28)-(30) along the circle (35) rotated by gamma (R = 1): the right side for solve_ivp."""
    point, dpoint = circle(a, phi, side, gamma)
    return curve_rhs(point, dpoint, state[2], k)


def leaf_end(a, side, k, gamma=0.0, x0=(0.0, 0.0, 0.0), rtol=1e-13, atol=1e-14):
    """(u_a, v_a, psi) after one leaf (circle a on ``side``) from ``x0``, by DOP853."""
    sol = solve_ivp(rhs, (0.0, 2 * np.pi), np.asarray(x0, float), method="DOP853", rtol=rtol, atol=atol,
                    args=(a, side, k, gamma))
    return sol.y[:, -1]


def trace(a, b, k, gamma=0.0, steps=1, rtol=1e-13, atol=1e-14):
    """(u_a, v_a, psi) after ``steps`` figure eights (a, b) rotated by gamma, from zero, by DOP853."""
    x = np.zeros(3)
    for _ in range(steps):
        for r, side in ((a, 1.0), (b, -1.0)):
            x = leaf_end(r, side, k, gamma, x, rtol, atol)
    return x


def n_step_gain(eta, steps):
    """(33)-(34): ``|sin(n eta / 2) / sin(eta / 2)|``, and ``n`` where ``sin(eta / 2) = 0``."""
    if abs(np.sin(eta / 2)) < 1e-12:
        return float(steps)
    return abs(np.sin(steps * eta / 2) / np.sin(eta / 2))


def shift_36(a):
    """(36): h/R of one symmetric figure eight under pure rolling (k = 0), ``a`` in units of R."""
    a = np.asarray(a, float)
    c = np.sqrt(1 - a * a)
    return 4 * a / c * np.sin(np.pi * c)
