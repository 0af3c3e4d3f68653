"""Rigid motions of the contact plane: angles, rotations, the n-step law and the composition law.

:func:`wrap` and :func:`wrap_exact` reduce angles, :func:`rotate` turns a plane vector; n identical steps of
shift ``h`` and turn ``eta`` reach ``H_n = h |sin(n eta / 2) / sin(eta / 2)|`` (the paper's (33) the right way
up, (34) in the limit; :func:`n_step_sum`, :func:`n_step_gain`). Along any contact path, from
``(p0, psi0)``: ``p = p0 + Rot(-psi0) p_c``, ``psi = psi0 + Psi`` (C), so plane states compose as
``g * h = (p_g + Rot(-psi_g) p_h, psi_g + psi_h)`` (:func:`compose`, :func:`inverse`, :func:`relative`).

Derivation of both laws: docs/design/composition.md.
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np

__all__ = ["TWO_PI", "wrap", "wrap_exact", "rotate", "n_step_sum", "n_step_gain", "target_shift", "compose", "inverse",
           "relative"]

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


def target_shift(h_des, eta_m, steps: int):
    """Shift one step must produce on branches eta_m, from (33)-(34); nan where unreachable.

    ``h = h_des / |sin(n eta / 2) / sin(eta / 2)|`` (:func:`n_step_gain`); where ``sin(n eta / 2) = 0`` but
    ``sin(eta / 2) != 0`` the n shifts cancel and no h reaches a nonzero h_des.
    """
    gain = n_step_gain(eta_m, steps)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(gain < 1e-12, np.nan, h_des / np.where(gain < 1e-12, 1.0, gain))


def compose(g, h) -> np.ndarray:
    """``g * h`` of the composition law (C) (docs/design/composition.md): the plane state reached by the motion
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
