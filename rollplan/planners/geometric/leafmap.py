"""Accurate leaf map: turn and displacement of one leaf of the figure eight, over the whole domain.

One leaf of the figure eight (31), (35) is the spherical circle of radius ``r`` (units of R)
through the south pole, traced once, ``phi in [0, 2 pi]``. Traced from zero state it moves the
contact point by the displacement ``d(r, k) = (u_a + i v_a)(2 pi)`` and turns psi by
``E(r, k) = psi(2 pi)``. Notation: ``c = sqrt(1 - r^2)``, ``s = sqrt(1 - 2 r^2)``,
``rho = r^2 / (c^2 + s)`` (``0 <= rho < 1`` for ``r < 1/sqrt(2)``).

Structure of (28)-(30) (each item is checked in ``tests/test_leafmap.py``):

1. (30) holds the curve only, not the state, so psi' depends on phi alone; (28)-(29) are the
   rates at psi = 0 turned by ``-psi``. A leaf started at heading ``psi0`` turns psi by ``E``
   and moves by ``Rot(-psi0) d``.
2. Mirror: the -y leaf is the +y leaf with ``y -> -y``; it turns psi by ``-E(r)`` and moves by
   ``conj(d(r))``.
3. Symmetry: the leaf is symmetric under the reflection in the plane through the pole and its
   centre (x -> -x, traced backwards), which makes ``exp(i E / 2) d`` real: ``d = rho(r)
   exp(-i E / 2)`` with a real, signed ``rho`` (:func:`signed_length`).
4. Hence one figure eight (+y leaf ``a``, then -y leaf ``b``) from zero turns psi by
   ``eta(a, b) = E(a) - E(b)`` and moves by ``S = d(a) + exp(-i E(a)) conj(d(b))``; the step's
   shift is ``h = |S| = |exp(i E(a)) d(a) + conj(d(b))|``. Rotating the curve by gamma about OZ
   turns the displacement by ``+gamma``. With item 3,
   ``h^2 = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta / 2)``: on a branch of (32), where eta is
   fixed, h depends on the two leaves only through rho.

Closed form of the turn. (30) is ``psi' = sin(v_o) u_o' + k w`` with ``w = (x y' - y x') / z`` on
the sphere; on the circle ``w = c - c / (c^2 + r^2 cos phi)``, whose integral is
``Phi = c phi - (c / s) chi(phi)``, ``chi(phi) = phi - 2 atan(rho sin phi / (1 + rho cos phi))``.
The rolling part is pure rolling of a small circle (its development is a circle: the heading of
the contact path turns at rate ``c`` and ``|(u_a', v_a')| = r``), so

    E(r, k) = 2 pi (1 - c) + 2 pi k c (1 - 1/s),                     dE/dr = (2 pi r / c) (1 - k (1 + s^-3)),
    u_a' + i v_a' = r exp(i theta(phi)),   theta = (1 - k) c phi + (k c / s) chi(phi).

The sign of dE/dr is that of ``1 - k (1 + s^-3)``, and ``1 + s^-3`` increases with r from 2 to
``Q = 1 + s(A_MAX)^-3``: E is strictly decreasing on (0, A_MAX] for every ``k >= 1/2``, strictly
increasing for ``k <= 1/Q``, and for ``1/Q < k < 1/2`` increasing up to its only interior maximum
``r* = sqrt((1 - s*^2) / 2)``, ``s* = (1/k - 1)^(-1/3)``, then decreasing (:func:`turn_pieces`; the
complete enumeration, :mod:`.enumerate`, works on these monotone pieces). For ``k > 1/2`` the
*root phase* ``w = sqrt(-E)`` is ``r sqrt(phi(r^2))`` with ``phi(u) = -E / u > 0`` smooth
(``phi(0) = pi (2 k - 1)``), so w is a smooth increasing coordinate on (0, A_MAX]
(:func:`root_phase`).

The displacement, in the variable ``chi`` (the argument of a Blaschke factor, inverse
``phi(chi) = chi + 2 atan(rho sin chi / (1 - rho cos chi))``,
``phi'(chi) = (1 - rho^2) / (1 - 2 rho cos chi + rho^2)``), is

    d(r, k) = r int_0^{2 pi} phi'(chi) exp(i [(1 - k) c phi(chi) + (k c / s) chi]) d chi,

an integrand analytic in the strip ``|Im chi| < ln(1/rho)`` (>= 0.44 up to A_MAX) whose fast
phase is linear in chi. It is integrated by the composite Gauss-Legendre rule of :data:`ORDER`
nodes on equal panels of ``[0, 2 pi]``, the number of panels per range of k (:data:`BUCKETS`)
chosen from the a-priori bound of the Gauss rule for analytic integrands on Bernstein ellipses
(Trefethen, SIAM Review 50 (2008), Thm 4.5) so that the value errs by less than 1e-13 and its
r-derivative by less than 1e-9 on ``(0, A_MAX] x [0, K_MAX]``; ``tests/test_leafmap.py`` checks
the map against scipy's DOP853 on the printed equations over that domain. The nodes do not depend
on ``(r, k)``, so ``dd/dr`` is the same rule applied to the r-derivative of the integrand.

Everything here is plain numpy on arrays of radii (pure functions), so that the C planner can
follow it line by line.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ...core.curves import A_MAX
from ...problem import K_MAX

__all__ = ["ORDER", "BUCKETS", "panels_for", "gauss_nodes", "turn", "turn_dr", "turn_inverse", "turn_pieces",
           "root_phase", "radius_of_root_phase",
           "displacement", "signed_length", "leaf_values", "step_values"]

#: Gauss-Legendre nodes per panel.
ORDER = 48
#: ``(k_upper, panels)``: for ``k <= k_upper`` (and above the previous bucket) the rule uses
#: ``panels`` equal panels of :data:`ORDER` nodes in chi (see the module docstring).
BUCKETS = ((5.0, 2), (10.0, 3), (20.0, 4), (30.0, 6), (40.0, 7), (50.0, 9), (75.0, 13), (100.0, 18))
assert BUCKETS[-1][0] >= K_MAX

_TWO_PI = 2.0 * math.pi


def panels_for(k: float) -> int:
    """Panels of the rule for inertia ratio ``k`` in ``[0, K_MAX]`` (k is validated by the caller)."""
    for k_upper, panels in BUCKETS:
        if k <= k_upper:
            return panels
    raise ValueError(f"k = {k!r} exceeds K_MAX = {K_MAX:g}")


@lru_cache(maxsize=16)
def gauss_nodes(panels: int, order: int = ORDER):
    """Nodes chi in (0, 2 pi) and weights of the composite Gauss-Legendre rule."""
    x, w = np.polynomial.legendre.leggauss(order)
    h = math.pi / panels
    centres = (2.0 * np.arange(panels) + 1.0) * h
    return (centres[:, None] + h * x[None, :]).ravel(), np.tile(h * w, panels)


def _consts(r):
    """``(c, s, rho)`` of radii ``r``, free of cancellation for small r."""
    c = np.sqrt(1.0 - r * r)
    s = np.sqrt(1.0 - 2.0 * r * r)
    return c, s, r * r / (c * c + s)


def turn(r, k):
    """Turn ``E(r, k)`` of psi over the +y leaf of radius r from zero [rad] (closed form).

    ``2 pi r^2 / (1 + c) - 4 pi k c r^2 / (s (1 + s))``, the same as
    ``2 pi (1 - c) + 2 pi k c (1 - 1/s)`` without cancellation at small r.
    """
    r = np.asarray(r, float)
    c, s, _ = _consts(r)
    return _TWO_PI * r * r / (1.0 + c) - 2.0 * _TWO_PI * k * c * r * r / (s * (1.0 + s))


def turn_dr(r, k):
    """``dE/dr = (2 pi r / c) (1 - k (1 + s^-3))`` [rad per R]."""
    r = np.asarray(r, float)
    c, s, _ = _consts(r)
    return _TWO_PI * r / c * (1.0 - k * (1.0 + 1.0 / (s * s * s)))


def _turn_u(u, k: float):
    """E and dE/du as functions of u = r^2 (``dE/du = (pi / c) (1 - k (1 + s^-3))``)."""
    c = np.sqrt(1.0 - u)
    s = np.sqrt(1.0 - 2.0 * u)
    return (_TWO_PI * u / (1.0 + c) - 2.0 * _TWO_PI * k * c * u / (s * (1.0 + s)),
            math.pi / c * (1.0 - k * (1.0 + 1.0 / (s * s * s))))


def turn_pieces(k: float) -> tuple:
    """The monotone pieces of E(., k) on [0, A_MAX]: ``((r_lo, r_hi, sign), ...)`` with ``sign`` that of
    dE/dr inside (module docstring)."""
    q = 1.0 + (1.0 - 2.0 * A_MAX * A_MAX) ** -1.5
    if k >= 0.5:
        return ((0.0, A_MAX, -1),)
    if k * q <= 1.0:
        return ((0.0, A_MAX, 1),)
    s = (1.0 / k - 1.0) ** (-1.0 / 3.0)
    r_star = math.sqrt(0.5 * (1.0 - s * s))
    return ((0.0, r_star, 1), (r_star, A_MAX, -1))


def root_phase(r, k: float):
    """``(w, dw/dr)`` with ``w = sqrt(-E(r, k))`` for ``k > 1/2`` (module docstring), without cancellation:
    ``w = r sqrt(phi)``, ``dw/dr = (pi / c) (k (1 + s^-3) - 1) / sqrt(phi)``."""
    r = np.asarray(r, float)
    c, s, _ = _consts(r)
    sq = np.sqrt(4.0 * math.pi * k * c / (s * (1.0 + s)) - _TWO_PI / (1.0 + c))
    return r * sq, math.pi / c * (k * (1.0 + 1.0 / (s * s * s)) - 1.0) / sq


def radius_of_root_phase(w, k: float, r0, steps: int = 2):
    """Radius with root phase w (``E(r) = -w^2``, ``k > 1/2``) by ``steps`` Newton steps in ``u = r^2``
    (E is smooth in u with ``dE/du < 0``) from the close start ``r0``, kept in ``[0, A_MAX]``."""
    u = np.asarray(r0, float) ** 2
    target = -np.asarray(w, float) ** 2
    for _ in range(steps):
        f, df = _turn_u(u, k)
        u = np.minimum(np.maximum(u - (f - target) / df, 0.0), A_MAX * A_MAX)
    return np.sqrt(u)


@lru_cache(maxsize=16)
def _turn_table(k: float):
    """E on 16385 values of u = r^2 in [0, A_MAX^2] (increasing u, decreasing E), for starts."""
    u = np.linspace(0.0, A_MAX * A_MAX, 16385)
    return u, turn(np.sqrt(u), k)


def turn_inverse(e, k: float):
    """Radius ``r in [0, A_MAX]`` with ``E(r, k) = e`` for ``k >= 1/2`` (E strictly decreasing);
    nan where ``e`` is outside ``[E(A_MAX), 0]``.

    Two Newton steps in ``u = r^2`` (E is smooth in u) from a tabulated inverse; where that has
    not reached rounding, safeguarded Newton, bisecting whenever a step leaves the bracket.
    """
    e = np.asarray(e, float)
    e_min = float(turn(A_MAX, k))
    inside = (e <= 0.0) & (e >= e_min)
    et = np.clip(np.where(inside, e, 0.0), e_min, 0.0)
    et = et.ravel()
    lo = np.zeros(et.shape)
    hi = np.full(et.shape, A_MAX * A_MAX)
    grid_u, grid_e = _turn_table(float(k))
    u = np.interp(-et, -grid_e, grid_u)                        # start: the tabulated inverse
    interior = inside.ravel() & (et > e_min) & (et < 0.0)
    u[et <= e_min] = A_MAX * A_MAX
    u[et >= 0.0] = 0.0
    for _ in range(2):                                          # Newton from the table, usually enough
        f, df = _turn_u(u, k)
        with np.errstate(divide="ignore", invalid="ignore"):
            nxt = np.clip(u - (f - et) / df, 0.0, A_MAX * A_MAX)
        u = np.where(interior & np.isfinite(nxt), nxt, u)
    f, _ = _turn_u(u, k)
    act = np.nonzero(interior & (np.abs(f - et) > 4e-16 * (1.0 + np.abs(et)) * (1.0 + k)))[0]
    for _ in range(80):
        if act.size == 0:
            break
        ua, la, ha = u[act], lo[act], hi[act]
        c = np.sqrt(1.0 - ua)
        s = np.sqrt(1.0 - 2.0 * ua)
        f = _TWO_PI * ua / (1.0 + c) - 2.0 * _TWO_PI * k * c * ua / (s * (1.0 + s)) - et[act]
        la = np.where(f > 0.0, ua, la)                           # E decreasing: root to the right
        ha = np.where(f > 0.0, ha, ua)
        df = math.pi / c * (1.0 - k * (1.0 + 1.0 / (s * s * s)))
        with np.errstate(divide="ignore", invalid="ignore"):
            nxt = ua - f / df
        bad = ~np.isfinite(nxt) | (nxt <= la) | (nxt >= ha)
        nxt = np.where(bad, 0.5 * (la + ha), nxt)
        lo[act], hi[act] = la, ha
        u[act] = np.where(f == 0.0, ua, nxt)
        go = (f != 0.0) & (np.abs(nxt - ua) > 1e-15 * nxt) & (ha - la > 1e-15 * ha)
        act = act[go]
    c = np.sqrt(1.0 - u)                                        # one last Newton step, inside the bracket
    s = np.sqrt(1.0 - 2.0 * u)
    f = _TWO_PI * u / (1.0 + c) - 2.0 * _TWO_PI * k * c * u / (s * (1.0 + s)) - et
    with np.errstate(divide="ignore", invalid="ignore"):
        nxt = u - f / (math.pi / c * (1.0 - k * (1.0 + 1.0 / (s * s * s))))
    u = np.where(np.isfinite(nxt) & (nxt >= lo) & (nxt <= hi), nxt, u).reshape(e.shape)
    return np.where(inside, np.sqrt(u), np.nan)


def displacement(r, k: float, derivative: bool = False, chunk: int = 2048):
    """Displacement ``d(r, k)`` (complex, ``u_a + i v_a``) of the +y leaf from zero, for an array of
    radii in ``[0, A_MAX]``; with ``derivative`` also ``dd/dr`` (the rule applied to the
    r-derivative of the integrand). Gauss-Legendre rule of the module docstring."""
    r = np.atleast_1d(np.asarray(r, float))
    chi, w = gauss_nodes(panels_for(k))
    cchi, schi = np.cos(chi), np.sin(chi)
    out = np.empty(r.size, complex)
    dout = np.empty(r.size, complex) if derivative else None
    for i in range(0, r.size, chunk):
        rr = r[i:i + chunk, None]
        c, s, rho = _consts(rr)
        den = 1.0 - rho * cchi
        q = den * den + (rho * schi) ** 2                      # 1 - 2 rho cos chi + rho^2
        phi = chi + 2.0 * np.arctan2(rho * schi, den)
        jac = (1.0 - rho * rho) / q
        theta = (1.0 - k) * c * phi + (k * c / s) * chi
        ct, st = np.cos(theta), np.sin(theta)                 # exp(i theta), in real arithmetic
        base = (jac * ct) @ w + 1j * ((jac * st) @ w)
        out[i:i + chunk] = rr[:, 0] * base
        if derivative:
            c_r, s_r = -rr / c, -2.0 * rr / s
            g = c * c + s
            rho_r = (2.0 * rr * g - rr * rr * (-2.0 * rr + s_r)) / (g * g)
            phi_rho = 2.0 * schi / q
            jac_rho = (-2.0 * rho * q - (1.0 - rho * rho) * (2.0 * rho - 2.0 * cchi)) / (q * q)
            theta_r = (1.0 - k) * (c_r * phi + c * phi_rho * rho_r) + k * chi * (c_r * s - c * s_r) / (s * s)
            re, im = jac_rho * rho_r, theta_r * jac              # (re + i im) exp(i theta)
            dterm = (re * ct - im * st) @ w + 1j * ((re * st + im * ct) @ w)
            dout[i:i + chunk] = base + rr[:, 0] * dterm
    return (out, dout) if derivative else out


def signed_length(r, k: float, derivative: bool = False):
    """``rho(r, k) = Re(exp(i E / 2) d)``: the displacement of the +y leaf is ``d = rho exp(-i E / 2)``
    (real ``rho``, item 3 of the module docstring); with ``derivative`` also ``d rho / dr``."""
    r = np.atleast_1d(np.asarray(r, float))
    half = np.exp(0.5j * turn(r, k))
    if not derivative:
        return (displacement(r, k) * half).real
    d, dd = displacement(r, k, derivative=True)
    return (d * half).real, ((dd + 0.5j * turn_dr(r, k) * d) * half).real


def leaf_values(r, k: float):
    """``(d, E)`` of the +y leaf of radii ``r``: complex displacement and turn (arrays)."""
    return displacement(r, k), turn(r, k)


def step_values(a, b, k: float, gamma: float = 0.0):
    """One figure eight (+y leaf a, then -y leaf b) rotated by gamma, from zero (item 4 of the
    module docstring): ``(u_a + i v_a, eta)`` as arrays, ``eta = E(a) - E(b)``,
    ``u_a + i v_a = exp(i gamma) (d(a) + exp(-i E(a)) conj(d(b)))``."""
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    da, ea = leaf_values(a, k)
    db, eb = leaf_values(b, k)
    return np.exp(1j * gamma) * (da + np.exp(-1j * ea) * np.conj(db)), ea - eb
