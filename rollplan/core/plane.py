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
"""

from __future__ import annotations

import math
from decimal import Decimal, localcontext

import numpy as np

__all__ = ["TWO_PI", "wrap", "wrap_exact", "rotate", "n_step_sum", "n_step_gain"]

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
    x = Decimal(float(angle))  # exact: every double is a finite decimal
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
