"""Roots of a scalar function in a sign-changing bracket: Brent's method.

:func:`brent` is R. P. Brent's zeroin (Algorithms for Minimization without Derivatives,
Prentice-Hall 1973, ch. 4): inverse quadratic interpolation or the secant step when it stays inside
the bracket and shrinks it fast enough, bisection otherwise, so it converges superlinearly on smooth
functions and never slower than bisection. The bracket always holds a sign change.
"""

from __future__ import annotations

import math
from collections.abc import Callable

__all__ = ["brent"]

_EPS = 2.220446049250313e-16


def brent(f: Callable[[float], float], lo: float, hi: float, xtol: float = 1e-15, rtol: float = 4 * _EPS,
          maxiter: int = 200) -> float:
    """A root of ``f`` in ``[lo, hi]``, where ``f(lo)`` and ``f(hi)`` differ in sign (or one is zero),
    to within ``xtol + rtol |x|``.

    Raises
    ------
    ValueError
        ``f(lo)`` and ``f(hi)`` have the same sign, or a value is not finite.
    RuntimeError
        No convergence in ``maxiter`` iterations.
    """
    a, b = float(lo), float(hi)
    fa, fb = float(f(a)), float(f(b))
    if not (math.isfinite(fa) and math.isfinite(fb)):
        raise ValueError(f"f is not finite at the bracket [{a!r}, {b!r}]: {fa!r}, {fb!r}")
    if fa == 0.0:
        return a
    if fb == 0.0:
        return b
    if (fa > 0.0) == (fb > 0.0):
        raise ValueError(f"[{a!r}, {b!r}] does not bracket a root: f = {fa!r}, {fb!r}")
    c, fc = a, fa
    d = e = b - a
    for _ in range(maxiter):
        if (fb > 0.0) == (fc > 0.0):
            c, fc = a, fa
            d = e = b - a
        if abs(fc) < abs(fb):
            a, b, c = b, c, b
            fa, fb, fc = fb, fc, fb
        tol = 2.0 * rtol * abs(b) + 0.5 * xtol
        m = 0.5 * (c - b)
        if abs(m) <= tol or fb == 0.0:
            return b
        if abs(e) >= tol and abs(fa) > abs(fb):
            s = fb / fa
            if a == c:                       # secant
                p, q = 2.0 * m * s, 1.0 - s
            else:                            # inverse quadratic interpolation
                q, r = fa / fc, fb / fc
                p = s * (2.0 * m * q * (q - r) - (b - a) * (r - 1.0))
                q = (q - 1.0) * (r - 1.0) * (s - 1.0)
            if p > 0.0:
                q = -q
            else:
                p = -p
            if 2.0 * p < min(3.0 * m * q - abs(tol * q), abs(e * q)):
                e, d = d, p / q
            else:
                d = e = m                    # bisection
        else:
            d = e = m
        a, fa = b, fb
        b += d if abs(d) > tol else math.copysign(tol, m)
        fb = float(f(b))
        if not math.isfinite(fb):
            raise ValueError(f"f is not finite at {b!r}")
    raise RuntimeError(f"no convergence in {maxiter} iterations in [{lo!r}, {hi!r}]")
