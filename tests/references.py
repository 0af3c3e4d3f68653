"""Independent references for the tests: the paper's printed equations and closed forms, in numpy.

Nothing here imports rollplan. Each formula is typed once, from the paper as printed (misprints
corrected and said so), and is what the tests compare rollplan's symbolic model and planners with (the one
exception: :func:`rotor_driven_rhs` repeats (2), (6)-(10) in scalar arithmetic for speed, checked against
:func:`orientation` and :func:`montana` by tests/test_references.py):

* :func:`orientation` -- (2), composed from elementary rotations; :func:`axes` -- its columns
  n_1, n_2, n_3 as printed in (3)-(5);
* :func:`montana` -- Montana's contact kinematics (6)-(10); :func:`omega_from_rates` -- (6), (7),
  (10) inverted for the angular velocity; :func:`rotor_driven_rhs` -- (6)-(10) driven by rotor rates
  through (11); :func:`torque_driven_rhs` -- (6)-(10) driven by motor torques, (11) and the rotors'
  axial momenta solved together as one linear system; :func:`momentum_about_contact` -- the angular
  momentum of shell and rotors about the contact point from a sampled motion alone;
* :func:`realizability` -- the left side of the realizability condition (13);
* :func:`inertia_ratio` -- (14); :func:`composite_inertias` -- Jxx, Jzz of Section II; :func:`psi_dot` -- (20);
* :func:`rotor_drive` -- the robot driven by sampled rotor rates alone: omega from (11), then (6)-(10), by
  DOP853 with the rates interpolated by scipy's not-a-knot cubic spline (:func:`scalar_spline`: a spline
  evaluated at one point in plain Python);
* :func:`curve_rhs` -- the curve ODE (28)-(30) with c_u, c_v of (26); :func:`circle` -- the circle
  (35) rotated by gamma (31); :func:`rhs` and :func:`trace` -- (28)-(30) along the figure eight,
  integrated by scipy's DOP853 (an integrator that shares no code with rollplan);
* :func:`n_step_gain` -- (33)-(34); :func:`shift_36` -- the closed form (36);
* :func:`rotor_terms` -- omega (18), (19), (13), the rotor rates (11) and the rotors' axial spins
  along a figure eight, per unit contact arc length, with psi by DOP853 on the printed (28)-(30);
* :func:`phase_plane_topp` -- the classic time-optimal timing of a path under torque and rate
  limits by forward/backward integration of the extremals in the phase plane (Bobrow, Dubowsky and
  Gibson 1985; Shin and McKay 1985; Pfeiffer and Johanni 1987), with the maximum velocity curve by
  bisection (:func:`torque_mvc`);
* :func:`contact_point` -- (1); :func:`rolling_18_19` -- (18), (19);
  :func:`rates_15_16_20` -- (15), (16), (20) for any contact path;
  :func:`chart_rates` -- (24)-(27);
  :func:`integrate_contact_path` -- (15), (16), (20) along a contact path given in time, by DOP853
  (:func:`integrate_contact_paths`: many paths as one system);
  :func:`great_circle_path`, :func:`circle_path`, :func:`chart_path` -- contact paths typed here;
  :func:`polar_contact` -- (u_o, v_o) of a point given by polar angle and direction;
  :func:`composed_final` -- a composed motion integrated along its pieces (read from their curve names and
  parameters only); :func:`replay` -- (15), (16), (20) along a sampled contact path alone;
  :func:`optimal_control_length` -- the shortest rest-to-rest motion found by optimal control on the printed
  (15), (16), (20) (multiple shooting, RK4, IPOPT through CasADi; multistart over the whole turns of psi);
* :func:`wrap` -- an angle reduced to (-pi, pi]; :func:`rotate` -- a plane vector turned;
  :func:`two_pi_fraction` -- 2 pi as an exact fraction to many digits (Chudnovsky's series in
  integer arithmetic).

States are in rollplan's one order (u_a, v_a, psi, u_o, v_o); lengths in units of R unless a
radius is given, angles in rad.
"""

from __future__ import annotations

import math
from copy import deepcopy
from fractions import Fraction
from functools import lru_cache, wraps
from math import isqrt

import numpy as np
from scipy.integrate import solve_ivp


def _remembered(func):
    """``func`` (a pure function of numbers) computed once per process for each set of arguments, a copy of its
    result returned each time: the tests ask for the same reference again and again. Arguments that cannot be
    hashed (arrays) are computed every time."""
    cache = {}

    @wraps(func)
    def remembered(*args, **kwargs):
        try:
            key = (args, tuple(sorted(kwargs.items())))
            hash(key)
        except TypeError:
            return func(*args, **kwargs)
        if key not in cache:
            cache[key] = func(*args, **kwargs)
        return deepcopy(cache[key])

    return remembered

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
#: non-unit; the product (2) gives ``sin u_o cos v_o`` (docs/misprints.md).
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


def rotor_driven_rhs(j_xx, j_zz, j_r, radius, rates):
    """Right side ``f(t, x)`` of (6)-(10) with omega from the momentum integral (11), for scipy's solve_ivp.

    ``rates(t) -> (phi_1_dot, phi_2_dot)``; the state x in rollplan's order (u_a, v_a, psi, u_o, v_o);
    ``Jc omega = -J_r (n_1 phi_1_dot + n_2 phi_2_dot)`` with n_1, n_2 the columns of (2) and then Montana's
    (6)-(10), in scalar arithmetic (numpy's per-call cost on 3-vectors is ten times the arithmetic): the same
    expressions as :func:`axes` and :func:`montana`, checked against (2) composed from elementary rotations and
    :func:`montana` by tests/test_references.py.
    """

    def f(t, x):
        psi, u, v = float(x[2]), float(x[3]), float(x[4])
        r1, r2 = rates(t)
        cu, su, cv, sv, cp, sp = math.cos(u), math.sin(u), math.cos(v), math.sin(v), math.cos(psi), math.sin(psi)
        wx = -j_r * ((cu * cp + su * sv * sp) * r1 + cv * sp * r2) / j_xx
        wy = -j_r * ((-cu * sp + su * sv * cp) * r1 + cv * cp * r2) / j_xx
        wz = -j_r * (su * cv * r1 - sv * r2) / j_zz
        roll = wx * sp + wy * cp
        return np.array([radius * wy, -radius * wx, -wz - roll * math.tan(v), -roll / cv, -wx * cp + wy * sp])

    return f


def scalar_spline(spline, derivative=False):
    """A scipy ``CubicSpline`` of vector values (x of shape (n,), values (n, m)) evaluated at one point in plain
    Python: its cubic on the point's interval by Horner (outside the knots the end pieces, as scipy extrapolates).
    ``f(x) -> [m values]``, or ``(values, first derivatives)`` with ``derivative``. Equal to the spline's own
    evaluation to rounding (tests/test_references.py), at a fraction of its per-call cost."""
    from bisect import bisect_right

    knots, last = spline.x.tolist(), spline.x.size - 2
    c = spline.c.reshape(4, spline.c.shape[1], -1)
    c3, c2, c1, c0 = ([c[p, :, q].tolist() for q in range(c.shape[2])] for p in range(4))

    def piece(x):
        i = min(max(bisect_right(knots, x) - 1, 0), last)
        return i, x - knots[i]

    def f(x):
        i, d = piece(x)
        return [((a[i] * d + b[i]) * d + e[i]) * d + g[i] for a, b, e, g in zip(c3, c2, c1, c0)]

    def fd(x):
        i, d = piece(x)
        return ([((a[i] * d + b[i]) * d + e[i]) * d + g[i] for a, b, e, g in zip(c3, c2, c1, c0)],
                [(3 * a[i] * d + 2 * b[i]) * d + e[i] for a, b, e in zip(c3, c2, c1)])

    return fd if derivative else f


def torque_driven_rhs(j_xx, j_zz, j_r, radius, torques, friction=(0.0, 0.0)):
    """Right side ``f(t, z)`` of the torque-driven robot for solve_ivp, ``z = (state (5), p (2))``.

    ``torques(t) -> (tau_1, tau_2)``. At every instant omega and the rotor rates solve the 5x5
    linear system of the momentum integral (11), ``Jc omega + J_r (n_1 phi_1_dot + n_2 phi_2_dot) = 0``,
    and the axial momenta ``J_r (n_i . omega + phi_i_dot) = p_i`` (numpy's solve; not the closed
    form); then ``p_i' = tau_i - c_i phi_i_dot`` (Euler's law on the rotor axis with viscous bearing
    friction) and Montana's (6)-(10). Returns ``f`` and ``rates(z) -> (omega, phi_dot)``.
    """
    jc = np.diag([j_xx, j_xx, j_zz])
    c = np.asarray(friction, float)

    def rates(z):
        rot = orientation(z[3], z[4], z[2])
        a = np.zeros((5, 5))
        a[:3, :3] = jc
        a[:3, 3], a[:3, 4] = j_r * rot[:, 0], j_r * rot[:, 1]
        a[3, :3], a[4, :3] = j_r * rot[:, 0], j_r * rot[:, 1]
        a[3, 3] = a[4, 4] = j_r
        sol = np.linalg.solve(a, np.array([0.0, 0.0, 0.0, z[5], z[6]]))
        return sol[:3], sol[3:]

    def f(t, z):
        w, pd = rates(z)
        return np.concatenate([montana(w, z[3], z[4], z[2], radius), np.asarray(torques(t), float) - c * pd])

    return f, rates


def momentum_about_contact(t, state, rotor_rates, j_xx, j_zz, j_r, mass_total, radius):
    """Angular momentum of shell and rotors about the contact point, plane frame, from a sampled motion (N, 3).

    omega from ``R_dot R^T`` of the orientation (2) along the sampled (u_o, v_o, psi) (cubic splines),
    the centre's velocity from the sampled (u_a, v_a); ``L_P = Jzz omega + J_r (n_1 phi_1_dot + n_2
    phi_2_dot) + (C - P) x M v_C`` with ``C - P = R e_z``: the locked system's momentum about its centre
    (isotropic inertia Jzz, Section II) plus the rotors' relative spin plus the moment of the linear
    momentum. (``Jxx = Jzz + M R^2`` (14) is not used: ``j_xx`` is accepted for symmetry of the call.)
    """
    from scipy.interpolate import CubicSpline

    t, x = np.asarray(t, float), np.asarray(state, float)
    rot = np.array([orientation(u, v, p) for u, v, p in zip(x[:, 3], x[:, 4], x[:, 2])])
    rdot = CubicSpline(t, rot, axis=0)(t, 1)
    what = np.einsum("nij,nkj->nik", rdot, rot)
    omega = np.column_stack([what[:, 2, 1], what[:, 0, 2], what[:, 1, 0]])
    vc = np.column_stack([CubicSpline(t, x[:, :2], axis=0)(t, 1), np.zeros(t.size)])
    r = np.asarray(rotor_rates, float)
    lp = j_zz * omega + j_r * (rot[:, :, 0] * r[:, :1] + rot[:, :, 1] * r[:, 1:2])
    return lp + np.cross(np.array([0.0, 0.0, radius]), mass_total * vc), omega


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


def rotor_drive(robot: dict, t, rates, x0=None, rtol=1e-12, atol=1e-14, end=False):
    """States (N, 5) at the times ``t`` of the robot driven by the sampled rotor ``rates`` (N, 2) alone (with
    ``end``: the final state (5,) only, no samples between).

    ``robot`` holds the five parameters of Section II by rollplan's key names. omega from (11),
    ``Jc omega = -J_r (n_1 phi_1' + n_2 phi_2')`` with n_1, n_2 the columns of (2), drives (6)-(10)
    (:func:`rotor_driven_rhs`); DOP853 integrates them with the rates interpolated by scipy's not-a-knot cubic
    spline (:func:`scalar_spline`).
    """
    from scipy.interpolate import CubicSpline

    keys = ("radius", "mass_total", "mass_shell", "rotor_inertia_axial", "rotor_inertia_transverse")
    j_xx, j_zz = composite_inertias(*(robot[k] for k in keys))
    t = np.asarray(t, float)
    spline = scalar_spline(CubicSpline(t, np.asarray(rates, float), bc_type="not-a-knot"))
    f = rotor_driven_rhs(j_xx, j_zz, robot["rotor_inertia_axial"], robot["radius"], spline)
    x0 = np.zeros(5) if x0 is None else np.asarray(x0, float)
    sol = solve_ivp(f, (t[0], t[-1]), x0, method="DOP853", rtol=rtol, atol=atol, t_eval=None if end else t)
    assert sol.success, sol.message
    return sol.y[:, -1] if end else sol.y.T


def psi_dot(u_o, v_o, du_o, dv_o, k):
    """(20) as printed: ``psi' = (1 - k) sin v u' + k tan u / cos v v'``."""
    return (1 - k) * np.sin(v_o) * du_o + k * np.tan(u_o) / np.cos(v_o) * dv_o


# ----------------------------------------------------------------------------- curves (26)-(36)


def curve_rhs(point, dpoint, psi, k, radius=1.0):
    """(28)-(30) as printed, with c_u, c_v of (26): rates of (u_a, v_a, psi) for a contact point
    ``point = (x, y, z)`` moving at ``dpoint`` per unit curve parameter.

    (29) is printed with ``v^2`` under the root; it is ``y^2`` as in (28) (a misprint). ``point`` and ``dpoint``
    may also be of shape (3, N) (N curves at once; then ``psi`` is of shape (N,)).
    """
    m = math if np.ndim(psi) == 0 else np     # scalar arithmetic for one point: DOP853 calls this ~10^5 times
    x, y, z = point
    s = m.sqrt(radius**2 - y**2)
    p = z * dpoint[0] - x * dpoint[2]                                   # (z, 0, -x) . dpoint
    q = -x * y / s * dpoint[0] + s * dpoint[1] - y * z / s * dpoint[2]  # (-x y / s, s, -y z / s) . dpoint
    return np.array([
        -m.cos(psi) / s * p + m.sin(psi) / radius * q,
        m.sin(psi) / s * p + m.cos(psi) / radius * q,
        ((1 - k) * y * p / (radius**2 - y**2) + k * x * q / (z * s)) / radius,
    ])


def _circle_xyz(a, phi, side, gamma, m):
    """The point and d/dphi of :func:`circle` as tuples of their entries (``m``: math or numpy)."""
    d = m.sqrt(1 - a * a)
    s, c = m.sin(phi), m.cos(phi)
    p = (a * s, side * (-a * d * c + d * a), -a * a * c - d * d)
    dp = (a * c, side * a * d * s, a * a * s)
    cg, sg = m.cos(gamma), m.sin(gamma)         # Rz(gamma) (31)

    def turned(v):
        return cg * v[0] - sg * v[1], sg * v[0] + cg * v[1], v[2]

    return turned(p), turned(dp)


def circle(a, phi, side, gamma=0.0):
    """Point of the circle (35) of radius a (side +1: +y, -1: -y) turned by Rz(gamma) (31), and d/dphi."""
    scalar = np.ndim(a) == 0 and np.ndim(phi) == 0 and np.ndim(gamma) == 0
    p, dp = _circle_xyz(a, phi, side, gamma, math if scalar else np)
    return np.array(p), np.array(dp)


def rhs(phi, state, a, side, k, gamma):
    """(28)-(30) along the circle (35) rotated by gamma (R = 1): the right side for solve_ivp."""
    point, dpoint = _circle_xyz(a, phi, side, gamma, math)
    return curve_rhs(point, dpoint, state[2], k)


def leaf_end(a, side, k, gamma=0.0, x0=(0.0, 0.0, 0.0), rtol=1e-13, atol=1e-14):
    """(u_a, v_a, psi) after one leaf (circle a on ``side``) from ``x0``, by DOP853."""
    sol = solve_ivp(rhs, (0.0, 2 * np.pi), np.asarray(x0, float), method="DOP853", rtol=rtol, atol=atol,
                    args=(a, side, k, gamma))
    return sol.y[:, -1]


@_remembered
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


# ----------------------------------------------------------------------------- rotors along a figure eight


def rotor_terms_per_phi(r, side, gamma, k, jxx, jzz, jr, phi, psi):
    """omega, rotor rates and axial spins ``n_i . omega + phi_i_dot`` per unit phi_dot at one point of a leaf.

    The leaf is the circle (35) of radius r on ``side`` turned by gamma (31); contact coordinates
    (24)-(25), their rates (26)-(27), omega_x, omega_y (18)-(19), omega_z from (13), the rotor rates
    from (11) premultiplied by n_1, n_2 (units of R).
    """
    (x, y, z), ct = circle(r, phi, side, gamma)
    cv = np.sqrt(1 - y * y)
    u, v = np.arctan2(-x / cv, -z / cv), np.arcsin(y)
    c_u = np.array([z, 0.0, -x])
    c_v = np.array([-x * y / cv, cv, -y * z / cv])
    du, dv = c_u @ ct / cv**2, c_v @ ct
    wx = -du * np.cos(v) * np.sin(psi) - dv * np.cos(psi)
    wy = -du * np.cos(v) * np.cos(psi) + dv * np.sin(psi)
    n1, n2, n3 = axes(u, v, psi)
    w = np.array([wx, wy, -k * (n3[0] * wx + n3[1] * wy) / n3[2]])
    jw = np.array([jxx, jxx, jzz]) * w
    g = -np.array([n1 @ jw, n2 @ jw]) / jr
    return w, g, np.array([n1 @ w, n2 @ w]) + g


def rotor_terms(a, b, gamma, k, jxx, jzz, jr, steps, s_values, side="left"):
    """omega, rotor rates and axial spins per unit s' at contact arc lengths s of n figure eights (a, b).

    Leaf j (circle a on +y for even j, b on -y for odd j) runs over ``s = S_j + r_j phi``; psi comes
    from DOP853 on the printed (28)-(30). At a pole ``side`` takes the leaf that ends (left) or
    starts (right) there. Returns arrays (N, 3), (N, 2), (N, 2).
    """
    radii = [a if j % 2 == 0 else b for j in range(2 * steps)]
    starts = np.concatenate([[0.0], np.cumsum(2 * np.pi * np.array(radii))])
    ends = [np.zeros(3)]
    for j, r in enumerate(radii):
        ends.append(leaf_end(r, 1.0 if j % 2 == 0 else -1.0, k, gamma, ends[-1]))
    out = ([], [], [])
    for s in np.atleast_1d(s_values):
        j = int(np.searchsorted(starts[1:-1], s, side=side))
        phi, sign = (s - starts[j]) / radii[j], (1.0 if j % 2 == 0 else -1.0)
        x = ends[j]
        if phi > 0:
            x = solve_ivp(rhs, (0.0, phi), x, method="DOP853", rtol=1e-13, atol=1e-14,
                          args=(radii[j], sign, k, gamma)).y[:, -1]
        for acc, val in zip(out, rotor_terms_per_phi(radii[j], sign, gamma, k, jxx, jzz, jr, phi, x[2])):
            acc.append(val / radii[j])
    return tuple(np.array(v) for v in out)


# ----------------------------------------------------------------------------- time-optimal timing (phase plane)


def accel_bounds(A, B, x, tau):
    """``[alpha, beta]``: the s'' allowed by ``|A_i s'' + B_i x| <= tau`` for every row i at one point.

    ``A``, ``B`` (m,); rows with ``A_i = 0`` do not bound s''. Empty (alpha > beta) above the torque
    part of the maximum velocity curve.
    """
    lo, hi = -np.inf, np.inf
    for ai, bi in zip(A, B):
        if ai != 0.0:
            low, high = sorted(((-tau - bi * x) / ai, (tau - bi * x) / ai))
            lo, hi = max(lo, low), min(hi, high)
    return lo, hi


def torque_mvc(A, B, tau, top=1e12, iterations=120):
    """Largest x = s'^2 at which some s'' meets every torque row, by bisection (A, B: (N, m)); inf if > top.

    The feasible x form an interval [0, x_max] (the set {(u, x)} is convex and holds (0, 0)).
    """
    A, B = np.asarray(A, float), np.asarray(B, float)

    def feasible(x):
        xc = x[:, None]
        nz = A != 0
        safe = np.where(nz, A, 1.0)
        l1, l2 = (-tau - B * xc) / safe, (tau - B * xc) / safe
        lo = np.where(nz, np.minimum(l1, l2), -np.inf).max(axis=1)
        hi = np.where(nz, np.maximum(l1, l2), np.inf).min(axis=1)
        alone = np.where(~nz, np.abs(B) * xc <= tau, True).all(axis=1)
        return (lo <= hi) & alone

    n = A.shape[0]
    lo, hi = np.zeros(n), np.full(n, top)
    unbounded = feasible(hi)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        ok = feasible(mid)
        lo, hi = np.where(ok, mid, lo), np.where(ok, hi, mid)
    return np.where(unbounded, np.inf, lo)


def phase_plane_topp(grid, max_rate, max_torque):
    """Time-optimal rest-to-rest timing of a path by extremal integration in the phase plane (s, x = s'^2).

    The classic numerical-integration method in its limit-curve form: the backward
    maximum-deceleration extremal ``dx/ds = 2 alpha`` from (L, 0), clipped to the maximum velocity
    curve (MVC), gives the limit curve K (the largest x from which the end, and every rest point on
    the way, can be reached); it leaves the MVC by itself at the tangent, singular and jump points, so
    no switch-point search is needed. Then the forward maximum-acceleration extremal
    ``dx/ds = 2 beta`` from (0, 0), clipped to K. Heun steps on the nodes, with the one-sided
    coefficients at the joints; no LP, no NLP.

    Parameters
    ----------
    grid
        Any object with ``s`` (N,), ``G_left``, ``G_right``, ``A_left``, ``A_right``, ``B_left``,
        ``B_right`` (N, m) and ``corners`` (node indices where the motion must be at rest).
    max_rate, max_torque : float or None

    Returns
    -------
    dict
        ``s``, ``x`` (the profile), ``K``, ``mvc``, ``duration`` (``sum 2 ds / (sqrt(x_k) + sqrt(x_k+1))``).
    """
    s = np.asarray(grid.s, float)
    n = s.size
    h = np.diff(s)
    tau = max_torque
    mvc = np.full(n, np.inf)
    if max_rate is not None:
        g = np.maximum(np.abs(grid.G_left).max(axis=1), np.abs(grid.G_right).max(axis=1))
        mvc = np.minimum(mvc, np.where(g > 0, (max_rate / np.where(g > 0, g, 1.0)) ** 2, np.inf))
    tq_l, tq_r = torque_mvc(grid.A_left, grid.B_left, tau), torque_mvc(grid.A_right, grid.B_right, tau)
    mvc = np.minimum.reduce([mvc, tq_l, tq_r])
    mvc[list(grid.corners)] = 0.0
    mvc[0] = mvc[-1] = 0.0

    def bound(A, B, x, cap, upper):
        lo, hi = accel_bounds(A, B, min(x, cap), tau)
        if lo > hi:  # rounding just above the torque MVC: both ends are the touching point
            lo = hi = 0.5 * (lo + hi)
        return hi if upper else lo

    AL, AR, BL, BR = grid.A_left, grid.A_right, grid.B_left, grid.B_right
    K = np.zeros(n)
    for k in range(n - 2, -1, -1):
        a0 = bound(AL[k + 1], BL[k + 1], K[k + 1], tq_l[k + 1], upper=False)
        xp = min(max(K[k + 1] - 2 * h[k] * a0, 0.0), mvc[k])
        a1 = bound(AR[k], BR[k], xp, tq_r[k], upper=False)
        K[k] = min(max(K[k + 1] - h[k] * (a0 + a1), 0.0), mvc[k])
    x = np.zeros(n)
    for k in range(n - 1):
        b0 = bound(AR[k], BR[k], x[k], tq_r[k], upper=True)
        xp = min(max(x[k] + 2 * h[k] * b0, 0.0), K[k + 1])
        b1 = bound(AL[k + 1], BL[k + 1], xp, tq_l[k + 1], upper=True)
        x[k + 1] = min(max(x[k] + h[k] * (b0 + b1), 0.0), K[k + 1])
    r = np.sqrt(x)
    den = r[:-1] + r[1:]
    duration = float(np.sum(2 * h / den)) if np.all(den > 0) else np.inf
    return {"s": s, "x": x, "K": K, "mvc": mvc, "duration": duration}


# ----------------------------------------------------------------------------- any contact path: (15), (16), (20)


def rates_15_16_20(psi, u_o, v_o, du_o, dv_o, k, radius=1.0):
    """(15), (16), (20) as printed: rates of (u_a, v_a, psi) for the contact rates (du_o, dv_o)."""
    return np.array([-radius * np.cos(psi) * np.cos(v_o) * du_o + radius * np.sin(psi) * dv_o,
                     radius * np.sin(psi) * np.cos(v_o) * du_o + radius * np.cos(psi) * dv_o,
                     psi_dot(u_o, v_o, du_o, dv_o, k)])


def rolling_18_19(u_o, v_o, psi, du_o, dv_o):
    """(18), (19) as printed: the rolling components (omega_x, omega_y) from the contact rates."""
    return (-du_o * np.cos(v_o) * np.sin(psi) - dv_o * np.cos(psi),
            -du_o * np.cos(v_o) * np.cos(psi) + dv_o * np.sin(psi))


def contact_point(u_o, v_o):
    """(1) on the unit sphere: ``(-sin u cos v, sin v, -cos u cos v)``, shape (..., 3)."""
    return np.stack([-np.sin(u_o) * np.cos(v_o), np.sin(v_o), -np.cos(u_o) * np.cos(v_o)], axis=-1)


def chart_rates(point, dpoint):
    """``(u_o, v_o, u_o', v_o')`` of a point moving on the unit sphere at ``dpoint``: (24)-(27) as printed (also for
    N points at once, of shape (3, N))."""
    x, y, z = point
    s = np.sqrt(1 - y * y)
    v, u = np.arcsin(y), np.arctan2(-x / s, -z / s)                            # (24), (25)
    c_u_dot = z * dpoint[0] - x * dpoint[2]                                    # (26): c_u = (z, 0, -x)
    c_v_dot = -x * y / s * dpoint[0] + s * dpoint[1] - y * z / s * dpoint[2]   # c_v = (-x y / s, s, -y z / s)
    return u, v, c_u_dot / (s * s), c_v_dot                                    # (27)


def integrate_contact_path(path, x0, t_span, k, t_eval=None, rtol=1e-13, atol=1e-14):
    """(15), (16), (20) integrated by DOP853 from ``x0 = (u_a, v_a, psi)`` along ``path(t) -> (u, v, u', v')``.

    Returns scipy's solution object (``.y`` of shape (3, len(t_eval)))."""
    sol = solve_ivp(lambda t, x: rates_15_16_20(x[2], *path(t), k), t_span, np.asarray(x0, float),
                    method="DOP853", rtol=rtol, atol=atol, t_eval=t_eval)
    assert sol.success, sol.message
    return sol


def integrate_contact_paths(path, x0, t_span, k, rtol=1e-13, atol=1e-14):
    """:func:`integrate_contact_path` for N paths at once (``path(t)`` gives arrays of shape (N,), ``x0`` of shape
    (3, N)): the N copies of (15), (16), (20) as one system for DOP853, both tolerances divided by sqrt(3 N) (scipy
    controls a root mean square over the components). Returns the final states, shape (3, N)."""
    x0 = np.asarray(x0, float)
    scale = np.sqrt(x0.size)

    def f(t, flat):
        return rates_15_16_20(flat.reshape(3, -1)[2], *path(t), k).ravel()

    sol = solve_ivp(f, t_span, x0.ravel(), method="DOP853", rtol=rtol / scale, atol=atol / scale)
    assert sol.success, sol.message
    return sol.y[:, -1].reshape(x0.shape)


def rest_path_final(acc, T, k):
    """End point (u_a, v_a, psi) and end rates (u_o', v_o') of the contact path of piecewise-constant
    accelerations ``acc`` (N, 2) on N equal intervals of [0, T] from rest at the origin: positions and rates
    in closed form, (15), (16), (20) by :func:`integrate_contact_path` interval by interval."""
    acc = np.asarray(acc, float)
    N = acc.shape[0]
    h = T / N
    pos, vel = np.zeros((N + 1, 2)), np.zeros((N + 1, 2))
    for j in range(N):
        pos[j + 1] = pos[j] + vel[j] * h + acc[j] * h ** 2 / 2
        vel[j + 1] = vel[j] + acc[j] * h

    def path(t):
        i = min(int(t / h), N - 1)
        s = t - i * h
        return (*(pos[i] + vel[i] * s + acc[i] * s ** 2 / 2), *(vel[i] + acc[i] * s))

    y = np.zeros(3)
    for i in range(N):
        y = integrate_contact_path(path, y, (i * h, (i + 1) * h), k).y[:, -1]
    return y, vel[-1]


def great_circle_path(beta, sigma_0, sigma_1):
    """The great circle through the south pole in the direction beta, polar angle from sigma_0 to sigma_1
    as t runs over [0, 1]: a contact path for :func:`integrate_contact_path`."""
    def path(t):
        ang = sigma_0 + (sigma_1 - sigma_0) * t
        c = np.array([np.sin(ang) * np.cos(beta), np.sin(ang) * np.sin(beta), -np.cos(ang)])
        dc = (sigma_1 - sigma_0) * np.array([np.cos(ang) * np.cos(beta), np.cos(ang) * np.sin(beta), np.sin(ang)])
        return chart_rates(c, dc)

    return path


def circle_path(a, side, gamma):
    """The circle (35) of radius a (side +1: +y, -1: -y) rotated by gamma (31), t in [0, 2 pi]."""
    return lambda t: chart_rates(*circle(a, t, side, gamma))


def chart_path(u0, v0, cu, cv):
    """A smooth path in the chart, t in [0, 1]: ``u = u0 + sum cu_j sin(2 pi j t)``,
    ``v = v0 + sum cv_j (1 - cos(2 pi j t))``."""
    cu, cv = np.asarray(cu, float), np.asarray(cv, float)
    j = np.arange(1, cu.size + 1)

    def path(t):
        w = 2 * np.pi * j * t
        return (u0 + cu @ np.sin(w), v0 + cv @ (1 - np.cos(w)),
                cu @ (2 * np.pi * j * np.cos(w)), cv @ (2 * np.pi * j * np.sin(w)))

    return path


def polar_contact(sigma, beta):
    """(u_o, v_o) of the point at polar angle sigma from the south pole in the direction beta, by inverting (1)."""
    c = np.array([np.sin(sigma) * np.cos(beta), np.sin(sigma) * np.sin(beta), -np.cos(sigma)])
    return float(np.arctan2(-c[0], -c[2])), float(np.arcsin(c[1]))


def piece_path(piece):
    """The contact path of a piece of a composed plan and its parameter span, typed here from the piece's
    ``curve`` name, ``index``, ``params`` and ``gamma`` alone: the great circle (``"great_circle"``,
    polar angle from params[0] to params[1], direction gamma), a circle (35) of the figure eight
    (``"figure_eight"``: radius params[index], side +y for index 0, -y for 1) rotated by gamma (31), the same
    carried to a base point (``"based_figure_eight"``, :func:`based_circle_path`) or a great-circle arc between
    two points (``"arc"``, :func:`geodesic`)."""
    if piece.curve == "great_circle":
        return great_circle_path(piece.gamma, *piece.params), 1.0
    if piece.curve == "based_figure_eight":   # (a, b, sigma, orientation), beta = gamma
        a, b, sigma, orientation = piece.params
        r, side = (a, 1.0) if piece.index == 0 else (b, -1.0)
        return based_circle_path(r, side, sigma, orientation, piece.gamma), 2 * np.pi
    if piece.curve == "arc":   # great-circle arc between (sigma_0, beta_0) and (sigma_1, beta_1)
        g = geodesic(_unit_polar(*piece.params[:2]), _unit_polar(*piece.params[2:]))
        return (lambda t: chart_rates(*g(t))), 2 * np.pi
    assert piece.curve == "figure_eight", piece.curve
    return circle_path(piece.params[piece.index], 1.0 if piece.index == 0 else -1.0, piece.gamma), 2 * np.pi


def based_circle_path(a, side, sigma, orientation, beta, mirror=False):
    """The circle (35) of radius a (side +1: +y, -1: -y) turned by ``orientation`` about OZ, carried by Ry(-sigma)
    (the pole to polar angle sigma towards +x), then turned by beta about OZ: a closed contact path, t in
    [0, 2 pi], from and to its base point. ``mirror`` reflects it in the plane y = 0."""
    m = np.diag([1.0, -1.0 if mirror else 1.0, 1.0]) @ _rz(beta) @ _ry(-sigma)

    def path(t):
        p, dp = circle(a, t, side, orientation)
        return chart_rates(m @ p, m @ dp)

    return path


@_remembered
def based_eight(a, b, sigma, orientation, beta, k, steps=1, x0=(0.0, 0.0, 0.0), mirror=False):
    """(u_a, v_a, psi) after ``steps`` figure eights (circle a on +y, then b on -y) at the base point
    (sigma, beta) turned by ``orientation`` (:func:`based_circle_path`), by DOP853 on (15), (16), (20)."""
    x = np.asarray(x0, float)
    for _ in range(steps):
        for r, side in ((a, 1.0), (b, -1.0)):
            x = integrate_contact_path(based_circle_path(r, side, sigma, orientation, beta, mirror), x,
                                       (0.0, 2 * np.pi), k).y[:, -1]
    return x


def _unit_polar(sigma, beta):
    return np.array([np.sin(sigma) * np.cos(beta), np.sin(sigma) * np.sin(beta), -np.cos(sigma)])


def composed_final(pieces, start, k):
    """The end state (5,) of a composed motion from ``start`` (5,), units of R: (15), (16), (20) by DOP853
    along every piece (:func:`piece_path`), the contact point of the last piece's end."""
    x, contact = np.asarray(start, float)[:3], np.asarray(start, float)[3:]
    for piece in pieces:
        path, span = piece_path(piece)
        x = integrate_contact_path(path, x, (0.0, span), k).y[:, -1]
        contact = np.array(path(span)[:2])
    return np.concatenate([x, contact])


def replay(u_o, v_o, segment, x0, k, end=False):
    """(u_a, v_a, psi) at every sample of a sampled contact path, from (15), (16), (20) by DOP853 along
    cubic splines of the sampled (u_o, v_o) alone, one spline per segment (from the last sample of the
    one before), parametrized by the chord length of the contact points (1): shape (N, 3) (with ``end``: the
    final state (3,) only, no samples between)."""
    from scipy.interpolate import CubicSpline

    u, v, seg = (np.asarray(a) for a in (u_o, v_o, segment))
    out = np.zeros((u.size, 3))
    out[0] = x = np.asarray(x0, float)
    for j in range(int(seg.max()) + 1):
        idx = np.flatnonzero(seg == j)
        idx = np.r_[idx[0] - 1, idx[idx > 0]] if idx[0] > 0 else idx
        if idx.size < 2:
            continue
        c = contact_point(u[idx], v[idx])
        tau = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(c, axis=0), axis=1))]
        spline = scalar_spline(CubicSpline(tau, np.column_stack([u[idx], v[idx]])), derivative=True)

        def path(t, spline=spline):
            (uo, vo), (du, dv) = spline(t)
            return uo, vo, du, dv

        sol = integrate_contact_path(path, x, (0.0, tau[-1]), k, None if end else tau, rtol=1e-10, atol=1e-12)
        if not end:
            out[idx[1:]] = sol.y[:, 1:].T
        x = sol.y[:, -1]
    return x if end else out


# ----------------------------------------------------------------------------- other leaf families (any curve)


def curve_leaf_end(curve, x0, k, span=2 * np.pi, rtol=1e-13, atol=1e-14):
    """(u_a, v_a, psi) at the end of any curve ``curve(phi) -> (point, dpoint)`` (numpy, unit sphere, phi in
    [0, span]) from ``x0``: the printed (28)-(30) (:func:`curve_rhs`) by DOP853."""
    sol = solve_ivp(lambda t, x: curve_rhs(*curve(t), x[2], k), (0.0, span), np.asarray(x0, float),
                    method="DOP853", rtol=rtol, atol=atol)
    assert sol.success, sol.message
    return sol.y[:, -1]


def viviani(a, side=1.0):
    """The Viviani lobe of size a as a curve for :func:`curve_leaf_end`: the sphere cut by the cylinder
    ``(X - (1 - rho))^2 + Y^2 = rho^2``, ``rho = a^2``, touching it at (1, 0, 0), parametrized by the angle t about
    the cylinder's axis, ``Z = 2 sqrt(rho (1 - rho)) sin(t / 2) >= 0``, then turned by the rotation
    (X, Y, Z) -> (Y, side Z, -X) that takes the touching point to the south pole and the axis to +-y."""
    rho = a * a
    w = 2 * np.sqrt(rho * (1 - rho))

    def curve(t):
        big = np.array([1 - rho + rho * np.cos(t), rho * np.sin(t), w * np.sin(t / 2)])
        dbig = np.array([-rho * np.sin(t), rho * np.cos(t), w * np.cos(t / 2) / 2])
        return (np.array([big[1], side * big[2], -big[0]]), np.array([dbig[1], side * dbig[2], -dbig[0]]))

    return curve


def polar_point(sigma, beta, side=1.0):
    """Unit vector at polar distance sigma from the south pole, direction beta from +y towards +x, y times side."""
    return np.array([np.sin(sigma) * np.sin(beta), side * np.sin(sigma) * np.cos(beta), -np.cos(sigma)])


def polygon_corners(name, a, side=1.0):
    """Corners of the polygon leaf (pole first and last): ``triangle``, apex 60 degrees, legs D = 2 asin a;
    ``square``, the rhombus of four equal sides with 90 degrees at the pole and the far corner at D on the axis,
    its side corners at 45 degrees found by bisection on the equal-side condition (not by a formula)."""
    from scipy.optimize import brentq

    pole, d = np.array([0.0, 0.0, -1.0]), 2 * np.arcsin(a)
    if name == "triangle":
        return [pole, polar_point(d, np.pi / 6, side), polar_point(d, -np.pi / 6, side), pole]
    far = polar_point(d, 0.0, side)

    def gap(leg):
        p = polar_point(leg, np.pi / 4, side)
        return np.arccos(np.clip(p @ far, -1, 1)) - np.arccos(np.clip(p @ pole, -1, 1))

    leg = brentq(gap, 1e-9, d, xtol=1e-15)
    return [pole, polar_point(leg, np.pi / 4, side), far, polar_point(leg, -np.pi / 4, side), pole]


def geodesic(p, q):
    """Great-circle arc from unit p to unit q over t in [0, 2 pi], constant speed: p turned about the axis
    p x q by Rodrigues' formula; a curve for :func:`curve_leaf_end`. p and q may also be of shape (3, N): N arcs."""
    axis = np.cross(p, q, axis=0)
    angle = np.arctan2(np.linalg.norm(axis, axis=0), np.sum(p * q, axis=0))
    axis = axis / np.linalg.norm(axis, axis=0)
    across, along = np.cross(axis, p, axis=0), axis * np.sum(axis * p, axis=0)

    def curve(t):
        s = angle * t / (2 * np.pi)
        point = p * np.cos(s) + across * np.sin(s) + along * (1 - np.cos(s))
        dpoint = (-p * np.sin(s) + across * np.cos(s) + along * np.sin(s)) * angle / (2 * np.pi)
        return point, dpoint

    return curve


def family_leaf(name, a, side=1.0):
    """A leaf of family ``name`` (``circles`` (35), ``viviani``, ``triangle``, ``square``) as a list of curves
    (one per smooth piece), each over [0, 2 pi]."""
    if name == "circles":
        return [lambda t: circle(a, t, side)]
    if name == "viviani":
        return [viviani(a, side)]
    corners = polygon_corners(name, a, side)
    return [geodesic(p, q) for p, q in zip(corners, corners[1:])]


def family_leaves(name, sizes, side=1.0):
    """The leaves of family ``name`` for every size of the 1-D array ``sizes`` at once: a list of curves (one per
    smooth piece, as :func:`family_leaf`), each giving points and rates of shape (3, len(sizes))."""
    sizes = np.asarray(sizes, float)
    if name == "circles":
        return [lambda t: circle(sizes, t, side)]
    if name == "viviani":
        return [viviani(sizes, side)]
    corners = [polygon_corners(name, a, side) for a in sizes]
    stacked = [np.stack([c[j] for c in corners], axis=1) for j in range(len(corners[0]))]
    return [geodesic(p, q) for p, q in zip(stacked, stacked[1:])]


def curve_leaf_ends(curve, x0, k, span=2 * np.pi, rtol=1e-13, atol=1e-14):
    """:func:`curve_leaf_end` for N curves at once (``curve(phi)`` gives shape (3, N), ``x0`` of shape (3, N)):
    the N copies of (28)-(30) as one system for DOP853. scipy controls a root mean square over the components of
    the scaled error estimates, so both tolerances are divided by sqrt(3 N) (rtol not below scipy's floor, 100
    machine epsilons): check the result against :func:`curve_leaf_end` at a few of the curves."""
    x0 = np.asarray(x0, float)
    scale = np.sqrt(x0.size)
    rtol = max(rtol / scale, 100 * np.finfo(float).eps) * scale

    def f(t, flat):
        x = flat.reshape(3, -1)
        return curve_rhs(*curve(t), x[2], k).ravel()

    sol = solve_ivp(f, (0.0, span), x0.ravel(), method="DOP853", rtol=rtol / scale, atol=atol / scale)
    assert sol.success, sol.message
    return sol.y[:, -1].reshape(x0.shape)


def family_traces(name, a, b, k):
    """:func:`family_trace` (gamma = 0, from zero) for the figure eights of the 1-D arrays of sizes ``a`` and ``b`` at
    once (:func:`family_leaves`, :func:`curve_leaf_ends`): the final states, shape (3, len(a))."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    x = np.zeros((3, a.size))
    for sizes, side in ((a, 1.0), (b, -1.0)):
        for piece in family_leaves(name, sizes, side):
            x = curve_leaf_ends(piece, x, k)
    return x


def repeat_eight(first, steps):
    """(u_a, v_a, psi) after ``steps`` equal figure eights from zero, given ``first``, the end of one of them from zero
    (of :func:`trace` or :func:`family_trace`, any curve): the right side of the printed (28)-(30) does not depend on
    (u_a, v_a), and psi only turns the rates of (u_a, v_a) by -psi, so a figure eight started at (u, v, psi) ends at
    ``(u + i v) + exp(-i psi) S``, ``psi + eta``, where ``(S, eta)`` is its end from zero."""
    shift, eta = complex(first[0], first[1]), float(first[2])
    end, psi = 0j, 0.0
    for _ in range(int(steps)):
        end += complex(math.cos(psi), -math.sin(psi)) * shift
        psi += eta
    return np.array([end.real, end.imag, psi])


@_remembered
def family_trace(name, a, b, k, gamma=0.0, x0=(0.0, 0.0, 0.0)):
    """(u_a, v_a, psi) after the figure eight of family ``name`` (leaf a on +y, leaf b on -y) rotated by gamma
    (31), by DOP853 on the printed (28)-(30) piece by piece."""
    x = np.asarray(x0, float)
    rz = _rz(gamma)
    for size, side in ((a, 1.0), (b, -1.0)):
        for piece in family_leaf(name, size, side):
            x = curve_leaf_end(lambda t, piece=piece: tuple(rz @ v for v in piece(t)), x, k)
    return x


# ----------------------------------------------------------------------------- optimal control on (15), (16), (20)


def printed_rates(x, acc, k):
    """d/dt of (u_a, v_a, psi, u_o, v_o, u_o', v_o') in CasADi: (15), (16), (20) as printed (R = 1), the
    accelerations ``acc``."""
    import casadi as ca

    psi, u, v, du, dv = x[2], x[3], x[4], x[5], x[6]
    return ca.vertcat(-ca.cos(psi) * ca.cos(v) * du + ca.sin(psi) * dv,        # (15)
                      ca.sin(psi) * ca.cos(v) * du + ca.cos(psi) * dv,         # (16)
                      (1 - k) * ca.sin(v) * du + k * ca.tan(u) / ca.cos(v) * dv,  # (20)
                      du, dv, acc[0], acc[1])


#: The contact bound of :func:`optimal_control_length`: 80 deg from the south pole [rad].
CONTACT_BOUND_80 = np.radians(80.0)


@lru_cache(maxsize=8)
def _optimal_control_nlp(intervals, substeps):
    """The NLP of :func:`optimal_control_length` with k as its parameter, and its RK4 step ``(x, a, k) -> (x
    after the interval, energy, length)``; built once per grid."""
    import casadi as ca

    x, a, k = ca.SX.sym("x", 7), ca.SX.sym("a", 2), ca.SX.sym("k")
    h = 1.0 / (intervals * substeps)

    def f(z):
        xdot = printed_rates(z, a, k)
        return xdot, xdot[0] ** 2 + xdot[1] ** 2, ca.sqrt(xdot[0] ** 2 + xdot[1] ** 2 + 1e-300)

    z, energy, length = x, 0.0, 0.0
    for _ in range(substeps):   # RK4, the integrals by the same stages
        k1, e1, l1 = f(z)
        k2, e2, l2 = f(z + h / 2 * k1)
        k3, e3, l3 = f(z + h / 2 * k2)
        k4, e4, l4 = f(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        energy += h / 6 * (e1 + 2 * e2 + 2 * e3 + e4)
        length += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4)
    step = ca.Function("step", [x, a, k], [z, energy, length])
    X, A = ca.SX.sym("X", 7, intervals + 1), ca.SX.sym("A", 2, intervals)
    Z, E, L = step.map(intervals)(X[:, :-1], A, k)
    g = [ca.vec(Z - X[:, 1:]), (ca.cos(X[3, :]) * ca.cos(X[4, :])).T]
    solver = ca.nlpsol("reference", "ipopt", {"x": ca.veccat(X, A), "p": k, "f": ca.sum2(E), "g": ca.vertcat(*g)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.max_iter": 500, "ipopt.tol": 1e-10})
    return solver, step


@_remembered
def optimal_control_length(start, goal, k, turns=(-1, 0, 1), intervals=60, substeps=4, bound=CONTACT_BOUND_80):
    """The shortest contact path [R] between the states ``start`` and ``goal`` (units of R) found by optimal control
    on (15), (16), (20) as printed (:func:`printed_rates`): contact accelerations constant on ``intervals`` equal
    intervals of [0, 1], rest at both ends, polar angle of the contact point at most ``bound`` at every node,
    minimum path energy ``int |(u_a', v_a')|^2 dt`` (on a fixed horizon its minimizers are the shortest paths at
    constant speed). Multiple shooting, ``substeps`` RK4 steps per interval, IPOPT from the straight line in the
    state on each whole number of turns m of psi in ``turns``. Returns ``(shortest, {m: length or None})``,
    the length the RK4 quadrature of the speed along the solution."""
    solver, step = _optimal_control_nlp(intervals, substeps)
    ng = 7 * intervals
    lbg = np.r_[np.zeros(ng), np.full(intervals + 1, np.cos(bound))]
    ubg = np.r_[np.zeros(ng), np.full(intervals + 1, np.inf)]
    lengths = {}
    for m in turns:
        x0 = np.r_[start, 0.0, 0.0]
        x1 = np.r_[goal, 0.0, 0.0]
        x1[2] += 2 * np.pi * m
        lbx = np.full((7, intervals + 1), -np.inf)
        ubx = np.full((7, intervals + 1), np.inf)
        lbx[:, 0] = ubx[:, 0] = x0
        lbx[:, -1] = ubx[:, -1] = x1
        guess = x0[:, None] + (x1 - x0)[:, None] * np.linspace(0.0, 1.0, intervals + 1)
        lb = np.r_[lbx.ravel(order="F"), np.full(2 * intervals, -np.inf)]
        ub = np.r_[ubx.ravel(order="F"), np.full(2 * intervals, np.inf)]
        sol = solver(x0=np.r_[guess.ravel(order="F"), np.zeros(2 * intervals)], p=k, lbx=lb, ubx=ub, lbg=lbg,
                     ubg=ubg)
        lengths[m] = None
        if solver.stats()["success"]:
            v = np.array(sol["x"]).ravel()
            Xs = v[:7 * (intervals + 1)].reshape((7, intervals + 1), order="F")
            As = v[7 * (intervals + 1):].reshape((2, intervals), order="F")
            lengths[m] = float(np.sum(np.array(step.map(intervals)(Xs[:, :-1], As, k)[2])))
    found = [v for v in lengths.values() if v is not None]
    return (min(found) if found else np.inf), lengths
