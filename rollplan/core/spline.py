"""Cubic spline interpolation with not-a-knot ends (the interpolant of scipy's ``CubicSpline`` default).

The spline through ``(x_i, y_i)`` is C2 and, with the not-a-knot condition, its third derivative is
continuous at ``x_1`` and ``x_{n-2}`` (two points: the line; three: the parabola). Its slopes ``s_i``
at the knots solve a tridiagonal system (de Boor, *A Practical Guide to Splines*, ch. IV), solved by
CasADi's sparse LU (CSparse), and each interval is the cubic Hermite polynomial of its end values and
slopes. Values are extrapolated with the end polynomials.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ..errors import InputError

__all__ = ["CubicSpline"]


class CubicSpline:
    """Not-a-knot cubic spline of ``y`` (first axis along ``x``) at strictly increasing ``x``.

    ``spline(xq, nu=0)`` evaluates the spline (``nu = 0``) or its first derivative (``nu = 1``);
    :meth:`antiderivative` gives the spline's integral from ``x[0]`` as a callable.
    """

    def __init__(self, x, y, axis: int = 0) -> None:
        if axis != 0:
            raise InputError(f"axis = {axis!r} is not allowed: the samples run along axis 0")
        x = np.asarray(x, float)
        y = np.asarray(y, float)
        if x.ndim != 1 or x.size < 2 or y.shape[:1] != x.shape or np.any(~(np.diff(x) > 0)):
            raise InputError("a cubic spline needs >= 2 strictly increasing points and one value row per point")
        self.x, self._shape = x, y.shape[1:]
        y = y.reshape(x.size, -1)
        n = x.size
        dx = np.diff(x)[:, None]
        slope = np.diff(y, axis=0) / dx
        if n == 2:
            s = np.vstack([slope, slope])
        elif n == 3:   # not-a-knot at both ends of two intervals: the parabola through the three points
            a = np.array([[1.0, 1.0, 0.0], [dx[1, 0], 2.0 * (dx[0, 0] + dx[1, 0]), dx[0, 0]], [0.0, 1.0, 1.0]])
            b = np.vstack([2.0 * slope[0], 3.0 * (dx[0] * slope[1] + dx[1] * slope[0]), 2.0 * slope[1]])
            s = np.linalg.solve(a, b)
        else:
            diag = np.empty(n)
            sup = np.empty(n - 1)           # A[i, i + 1]
            sub = np.empty(n - 1)           # A[i + 1, i]
            b = np.empty((n, y.shape[1]))
            diag[1:-1] = 2.0 * (dx[:-1, 0] + dx[1:, 0])
            sup[1:] = dx[:-1, 0]
            sub[:-1] = dx[1:, 0]
            b[1:-1] = 3.0 * (dx[1:] * slope[:-1] + dx[:-1] * slope[1:])
            d = x[2] - x[0]
            diag[0], sup[0] = dx[1, 0], d
            b[0] = ((dx[0] + 2.0 * d) * dx[1] * slope[0] + dx[0] ** 2 * slope[1]) / d
            d = x[-1] - x[-3]
            diag[-1], sub[-1] = dx[-2, 0], d
            b[-1] = (dx[-1] ** 2 * slope[-2] + (2.0 * d + dx[-1]) * dx[-2] * slope[-1]) / d
            nz = np.vstack([np.r_[0.0, sup], diag, np.r_[sub, 0.0]]).ravel(order="F")[1:-1]
            s = np.array(ca.solve(ca.DM(ca.Sparsity.banded(n, 1), nz), ca.DM(b), "csparse"))
        t = (s[:-1] + s[1:] - 2.0 * slope) / dx
        # p_i(x) = c0 (x - x_i)^3 + c1 (x - x_i)^2 + c2 (x - x_i) + c3 on [x_i, x_{i+1}]
        self._c = (t / dx, (slope - s[:-1]) / dx - t, s[:-1], y[:-1])

    def _where(self, xq):
        xq = np.asarray(xq, float)
        i = np.clip(np.searchsorted(self.x, xq.ravel(), side="right") - 1, 0, self.x.size - 2)
        return xq, i, (xq.ravel() - self.x[i])[:, None]

    def __call__(self, xq, nu: int = 0) -> np.ndarray:
        xq, i, h = self._where(xq)
        c0, c1, c2, c3 = (c[i] for c in self._c)
        if nu == 0:
            v = ((c0 * h + c1) * h + c2) * h + c3
        elif nu == 1:
            v = (3.0 * c0 * h + 2.0 * c1) * h + c2
        else:
            raise InputError(f"nu = {nu!r} is not allowed: 0 (values) or 1 (first derivative)")
        return v.reshape(xq.shape + self._shape)

    def antiderivative(self):
        """The integral of the spline from ``x[0]``, as a callable of ``xq``."""
        c0, c1, c2, c3 = self._c
        dx = np.diff(self.x)[:, None]
        full = (((c0 * dx / 4.0 + c1 / 3.0) * dx + c2 / 2.0) * dx + c3) * dx
        start = np.vstack([np.zeros((1, full.shape[1])), np.cumsum(full, axis=0)])

        def integral(xq):
            xq, i, h = self._where(xq)
            a0, a1, a2, a3 = (c[i] for c in self._c)
            v = start[i] + (((a0 * h / 4.0 + a1 / 3.0) * h + a2 / 2.0) * h + a3) * h
            return v.reshape(xq.shape + self._shape)

        return integral
