"""Accurate leaf map: turn and displacement of one leaf of the figure eight, over the whole domain.

One leaf (31), (35) is the circle of radius ``r`` through the south pole; traced from zero it turns psi by
``E(r, k) = 2 pi (1 - c) + 2 pi k c (1 - 1/s)`` (closed form of (30), :func:`turn`) and moves the contact
point by ``d(r, k) = rho(r) exp(-i E / 2)`` (real rho, :func:`signed_length`), integrated by a composite
Gauss-Legendre rule in chi (:func:`displacement`, accurate to 1e-13 up to ``(A_MAX, K_MAX)``). One figure
eight from zero turns by ``eta = E(a) - E(b)`` and shifts by ``h = |d(a) + exp(-i E(a)) conj(d(b))|``
(:func:`step_values`). ``c = sqrt(1 - r^2)``, ``s = sqrt(1 - 2 r^2)``; plain numpy on arrays of radii.

Derivation and structure (items 1-4, the turn, the Gauss rule): docs/design/leaf-map.md.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from ...core.curves import A_MAX
from ...core.families import circle_turn as turn
from ...problem import K_MAX

__all__ = ["ORDER", "BUCKETS", "panels_for", "gauss_nodes", "turn", "turn_dr", "turn_inverse", "turn_pieces",
           "root_phase", "radius_of_root_phase",
           "displacement", "signed_length", "leaf_values", "step_values"]

#: Gauss-Legendre nodes per panel.
ORDER = 48
#: ``(k_upper, panels)``: for ``k <= k_upper`` (and above the previous bucket) the rule uses
#: ``panels`` equal panels of :data:`ORDER` nodes in chi (docs/design/leaf-map.md).
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
    dE/dr inside (docs/design/leaf-map.md)."""
    q = 1.0 + (1.0 - 2.0 * A_MAX * A_MAX) ** -1.5
    if k >= 0.5:
        return ((0.0, A_MAX, -1),)
    if k * q <= 1.0:
        return ((0.0, A_MAX, 1),)
    s = (1.0 / k - 1.0) ** (-1.0 / 3.0)
    r_star = math.sqrt(0.5 * (1.0 - s * s))
    return ((0.0, r_star, 1), (r_star, A_MAX, -1))


def root_phase(r, k: float):
    """``(w, dw/dr)`` with ``w = sqrt(-E(r, k))`` for ``k > 1/2`` (docs/design/leaf-map.md), without
    cancellation: ``w = r sqrt(phi)``, ``dw/dr = (pi / c) (k (1 + s^-3) - 1) / sqrt(phi)``."""
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


#: Values (radii x nodes) per block of the leaf rule in :func:`displacement`: the block's arrays (256 KB each) stay in
#: the processor's cache (blocks of 2048 radii made the rule 10-45 % slower); the block changes the values by
#: round-off only (the order in which BLAS sums a block's rows).
BLOCK_VALUES = 32768


def displacement(r, k: float, derivative: bool = False, chunk: int | None = None):
    """Displacement ``d(r, k)`` (complex, ``u_a + i v_a``) of the +y leaf from zero, for an array of
    radii in ``[0, A_MAX]``; with ``derivative`` also ``dd/dr`` (the rule applied to the
    r-derivative of the integrand). Gauss-Legendre rule of docs/design/leaf-map.md, applied to ``chunk`` radii at
    a time (default: :data:`BLOCK_VALUES` values per block)."""
    r = np.atleast_1d(np.asarray(r, float))
    chi, w = gauss_nodes(panels_for(k))
    if chunk is None:
        chunk = max(1, BLOCK_VALUES // chi.size)
    elif not isinstance(chunk, (int, np.integer)) or isinstance(chunk, bool) or chunk < 1:
        raise ValueError(f"chunk = {chunk!r}: a number of radii per block, an integer >= 1, or None (the default)")
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
    (real ``rho``, item 3 of docs/design/leaf-map.md); with ``derivative`` also ``d rho / dr``."""
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
    """One figure eight (+y leaf a, then -y leaf b) rotated by gamma, from zero (item 4 of
    docs/design/leaf-map.md): ``(u_a + i v_a, eta)`` as arrays, ``eta = E(a) - E(b)``,
    ``u_a + i v_a = exp(i gamma) (d(a) + exp(-i E(a)) conj(d(b)))``."""
    a, b = np.atleast_1d(np.asarray(a, float)), np.atleast_1d(np.asarray(b, float))
    da, ea = leaf_values(a, k)
    db, eb = leaf_values(b, k)
    return np.exp(1j * gamma) * (da + np.exp(-1j * ea) * np.conj(db)), ea - eb
