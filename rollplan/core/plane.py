"""Rigid motions of the contact plane: angles, rotations and the n-step law.

The small formulas every planner and study shares, each written once:

* :func:`wrap` -- an angle reduced to (-pi, pi]; :func:`wrap_exact` the same
  for one user-given angle of any size, reduced exactly (the float ``2 pi`` is
  off by 2.4e-16, which a large angle multiplies);
* :func:`rotate` -- a plane vector turned by an angle;
* :func:`n_step_sum` and :func:`n_step_gain` -- how the shifts of ``n``
  identical steps add up (Section III.B of the paper).

The n-step law. Along a figure eight psi' does not depend on the state and the
plane rates are those at psi = 0 turned by ``-psi`` ((28)-(30)), so a step
started at heading ``psi0`` makes the shift ``D`` of a step from zero turned by
``-psi0`` and turns psi by ``eta``. After ``n`` steps the displacement is
``D sum_{j<n} exp(-i j eta)`` and psi has turned by ``n eta``; its length is

    H_n = h |sin(n eta / 2) / sin(eta / 2)|,   h = |D|,

which is the paper's (33) read the right way up (the printed first fraction is
upside down), with the limit ``H_n = n h`` where ``sin(eta / 2) = 0`` (34).

The composition law (:func:`compose`, :func:`inverse`, :func:`relative`). The
n-step law is a case of a rule that holds along *any* contact path, on or off
the south pole. Write ``p = (u_a, v_a)`` (units of R) and
``w(t) = (-cos(v_o) u_o', v_o')``; then (15)-(16) read ``p' = Rot(-psi) w(t)``,
and the right side of (20) has neither ``p`` nor ``psi``. Let ``(p_c, Psi)`` be
the motion along a contact path ``c`` from the zero plane state ``p = 0,
psi = 0`` (the contact point at the path's own start). From ``(p0, psi0)`` the
motion along the same path is

    p(t) = p0 + Rot(-psi0) p_c(t),     psi(t) = psi0 + Psi(t):             (C)

both sides agree at t = 0, and the right side solves (15), (16), (20), since
``Rot(-psi0) Rot(-Psi) w = Rot(-psi) w``; the solution is unique. So a plane
state ``g = (p, psi)`` acts on zero-start motions by

    g * h = (p_g + Rot(-psi_g) p_h,  psi_g + psi_h),

the product of the group SE(2) for the pose ``(p, -psi)`` (at the pole the
orientation (2) is ``Rz(-psi)``, so ``(p, -psi)`` is the planar pose of the
ball). Consequences: the end state of a path made of consecutive pieces is the
product of the pieces' zero-start end states; a path traced backwards from its
end state returns to zero, so its element is the inverse (the right side of
(15), (16), (20) is linear in the contact rates); the contact coordinates
``(u_o, v_o)`` are not acted on, they are the path. ``tests/test_plane.py``
checks (C) against a direct integration of the printed equations.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np

__all__ = ["TWO_PI", "wrap", "wrap_exact", "rotate", "n_step_sum", "n_step_gain", "compose", "inverse", "relative"]

TWO_PI = 2.0 * math.pi


def wrap(angle):
    """Angle(s) wrapped to (-pi, pi] (float arithmetic; for computed angles of moderate size)."""
    return np.pi - np.mod(np.pi - np.asarray(angle, float), TWO_PI)


def _two_pi_decimal(digits: int) -> Decimal:
    """2 pi to ``digits`` significant digits (Machin's formula in decimal arithmetic)."""
    with localcontext() as ctx:
        ctx.prec = digits + 10

        def arctan_inv(x: int) -> Decimal:
            x2, term, total, n = x * x, Decimal(1) / x, Decimal(0), 0
            eps = Decimal(10) ** -(digits + 8)
            while abs(term) > eps:
                total += term / (2 * n + 1) * (-1) ** n
                term /= x2
                n += 1
            return total

        return +(8 * (4 * arctan_inv(5) - arctan_inv(239)))


# 2 pi to 400 digits: enough to reduce any finite double exactly to its nearest double.
_TWO_PI_DEC = _two_pi_decimal(400)


def wrap_exact(angle: float) -> tuple[float, int]:
    """``(w, m)`` with ``angle = w + 2 pi m`` exactly and ``w`` in [-pi, pi], rounded once.

    Reduces the double ``angle`` by the real number 2 pi in 400-digit decimal
    arithmetic, so the result is the double nearest the true remainder for
    every finite input (``wrap(1e16)`` in float arithmetic is off by 0.5 rad).
    ``m`` is an exact integer.
    """
    angle = float(angle)
    if -math.pi <= angle <= math.pi:   # the double pi is below the real one: already reduced, m = 0
        return angle, 0
    x = Decimal(angle)  # exact: every double is a finite decimal
    with localcontext() as ctx:
        ctx.prec = 400
        m = int((x / _TWO_PI_DEC).to_integral_value())  # nearest integer
        w = x - m * _TWO_PI_DEC
        if w > _TWO_PI_DEC / 2:  # rounding of the quotient can leave |w| just above pi
            w, m = w - _TWO_PI_DEC, m + 1
        elif w < -_TWO_PI_DEC / 2:
            w, m = w + _TWO_PI_DEC, m - 1
    return float(w), m


def rotate(angle, vec):
    """The plane vector(s) ``vec = (x, y)`` (first axis of length 2) turned by ``angle`` [rad]."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vec[0] - s * vec[1], s * vec[0] + c * vec[1]])


def n_step_sum(eta: float, steps: int) -> complex:
    """``sum_{j<n} exp(-i j eta)``: the displacement of n steps is the first step's shift times this."""
    return complex(np.exp(-1j * eta * np.arange(steps)).sum())


def n_step_gain(eta, steps: int, eps: float = 1e-12):
    """``|sin(n eta / 2) / sin(eta / 2)|``: n steps reach ``H_n = h`` times this (limit ``n``, (34))."""
    eta = np.asarray(eta, float)
    num, den = np.sin(steps * eta / 2), np.sin(eta / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.abs(den) < eps, float(steps), np.abs(num / den))


def compose(g, h) -> np.ndarray:
    """``g * h`` of the composition law (C) (module docstring): the plane state reached by the motion
    ``h`` (its end state from zero) started from the plane state ``g``.

    Parameters
    ----------
    g : array_like, shape (3,)
        Plane state ``(u_a, v_a, psi)`` [units of R, rad].
    h : array_like, shape (3,) or (3, N)
        End state(s) of motions from zero.

    Returns
    -------
    ndarray, shape of ``h``
        ``(p_g + Rot(-psi_g) p_h, psi_g + psi_h)``; psi is not wrapped.
    """
    g, h = np.asarray(g, float), np.asarray(h, float)
    p = rotate(-g[2], h[:2])
    if h.ndim == 1:
        return np.array([g[0] + p[0], g[1] + p[1], g[2] + h[2]])
    return np.vstack([g[:2, None] + p, g[2] + h[2]])


def inverse(g) -> np.ndarray:
    """``g^-1 = (-Rot(psi_g) p_g, -psi_g)``: the end state, from zero, of the motion ``g`` traced backwards."""
    g = np.asarray(g, float)
    p = rotate(g[2], g[:2])
    return np.array([-p[0], -p[1], -g[2]])


def relative(g, h) -> np.ndarray:
    """``g^-1 * h``: what a motion must do, from zero, to take the plane state ``g`` to ``h``."""
    return compose(inverse(g), h)
