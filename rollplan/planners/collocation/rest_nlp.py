"""The rest-to-rest collocation NLP with its closed-form states eliminated.

In the rest-to-rest state ``x = (u_a, v_a, psi, u_o, v_o, r)`` the contact rates ``r = (u_o', v_o')`` obey
``r' = a`` with ``a`` constant on an interval, and ``(u_o, v_o)' = r``: linear equations, which the
collocation's own Runge-Kutta method (matrix ``A``, weights ``b``, nodes ``c`` of :func:`linear_stages`) solves
in closed form. On an interval of duration ``H = h T`` from ``(u_o, v_o, r0)`` at its start to the rates
``r1`` at its end (so ``a = (r1 - r0) / H``), at the collocation points ``j`` and at the end:

    r_j = r0 + c_j (r1 - r0),    (u_o, v_o)_j = (u_o, v_o) + H sum_l A_jl r_l,
    (u_o, v_o)_end = (u_o, v_o) + H sum_l b_l r_l

(for d >= 2 the exact values of the piecewise-quadratic motion). Only (u_a, v_a, psi) keep collocation unknowns
and the accelerations are the rates' differences: the NLP of :meth:`.transcription.Transcription.contact_nlp`
(nx = 7) with those unknowns and their equations solved exactly, 16 unknowns per interval instead of 30 (d = 3).

Details: docs/design/collocation.md (the rest-to-rest NLP).
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ...errors import InputError
from .transcription import Guess, Transcription, interval_derivatives, interval_nlp

__all__ = ["RestTranscription", "linear_stages"]

#: The states of the rest-to-rest state whose collocation values stay unknowns of the NLP (u_a, v_a, psi).
N_FREE = 3


def linear_stages(transcription: Transcription):
    """The Runge-Kutta form ``(A (d, d), b (d,), c (d,))`` of the collocation of ``transcription``: its
    equations for ``y' = g(t)`` have the solution ``y_j = y_0 + H sum_l A_jl g(t_l)`` at the points and
    ``y_end = y_0 + H sum_l b_l g(t_l)`` (``A = C^-T`` of the basis' derivatives at the points, ``b = A^T D``)."""
    tau, C, D, _ = transcription.coefficients()
    A = np.linalg.inv(C[1:, :].T)
    return A, A.T @ D[1:], tau[1:]


class RestTranscription:
    """The rest-to-rest NLP on the grid of ``transcription`` (nx = 7, nu = 2), the closed-form states eliminated
    (module docstring). Guesses and solutions keep the layout of :class:`.transcription.Guess`.

    Decision variables, in order: ``X_0`` (7), then per interval the collocation values of (u_a, v_a, psi)
    (3 x d, point by point) and ``X_{i+1}`` (7). Constraints per interval: the collocation equations of
    (u_a, v_a, psi) (3 x d), the continuity of (u_a, v_a, psi, u_o, v_o) (5), the contact bound at the d points
    and at the interval's end (d + 1 rows, :meth:`contact_nlp`).
    """

    def __init__(self, transcription: Transcription) -> None:
        if (transcription.nx, transcription.nu) != (7, 2):
            raise InputError(f"nx, nu = {transcription.nx}, {transcription.nu} is not allowed: the rest-to-rest "
                             "NLP has the 7-state (nx = 7) and the accelerations (nu = 2)")
        self.transcription = transcription
        self.A, self.b, self.c = linear_stages(transcription)

    @property
    def block(self) -> int:
        """Decision variables per interval after ``X_0``."""
        return N_FREE * self.transcription.degree + 7

    def stages(self, x0, r1, H):
        """``(uv, rates, uv_end, a)``: (u_o, v_o) and the rates at the d collocation points (lists), (u_o, v_o) at
        the end and the acceleration of the interval from ``x0`` (7) to the end rates ``r1`` in the duration ``H``
        (module docstring). CasADi or numpy."""
        r0 = x0[5:7]
        rates = [r0 + cj * (r1 - r0) for cj in self.c]
        uv = [x0[3:5] + H * sum(self.A[j, m] * rates[m] for m in range(len(rates))) for j in range(len(rates))]
        end = x0[3:5] + H * sum(bl * rl for bl, rl in zip(self.b, rates))
        return uv, rates, end, (r1 - r0) / H

    def interval_function(self, point: ca.Function, depth: ca.Function, n_par: int) -> ca.Function:
        """``G(x0[7], xc[3 x d], x1[7], h, par) -> (defect[3 x d], continuity[5], depth[d], J)`` of one interval of
        normalized length h: ``point(x, a, par) -> (xdot, L, omega)`` is the model at a point (T = par[1]),
        ``depth(x)`` the contact bound's function of a 7-state."""
        d = self.transcription.degree
        _, C, D, B = self.transcription.coefficients()
        x0, xc, x1 = ca.SX.sym("x0", 7), ca.SX.sym("xc", N_FREE, d), ca.SX.sym("x1", 7)
        h, par = ca.SX.sym("h"), ca.SX.sym("par", n_par)
        H = h * par[1]
        uv, rates, uv_end, a = self.stages(x0, x1[5:7], H)
        X = [x0[:N_FREE]] + [xc[:, j] for j in range(d)]
        defects, depths, J = [], [], 0
        x_end = D[0] * x0[:N_FREE]
        for r in range(1, d + 1):
            xr = ca.vertcat(xc[:, r - 1], uv[r - 1], rates[r - 1])
            f, L, _ = point(xr, a, par)
            defects.append(sum(C[j, r - 1] * X[j] for j in range(d + 1)) - H * f[:N_FREE])
            depths.append(depth(xr))
            x_end = x_end + D[r] * X[r]
            J = J + B[r - 1] * L * H
        cont = ca.vertcat(x_end - x1[:N_FREE], uv_end - x1[3:5])
        return ca.Function("rest_interval", [x0, xc, x1, h, par], [ca.horzcat(*defects), cont, ca.vertcat(*depths), J],
                           ["x0", "xc", "x1", "h", "par"], ["defect", "continuity", "depth", "J"])

    def interval_block(self, point: ca.Function, n_par: int) -> ca.Function:
        """``B(z, par) -> (g, J)`` of one interval: ``z = (X_i, xc_i, X_{i+1})`` (its slice of the decision
        vector), ``g`` its rows of the constraints (the collocation equations, the continuity, the contact bound
        at the d points and at the end), ``J`` its cost (:meth:`interval_function`, h = 1 / N)."""
        N, d = self.transcription.intervals, self.transcription.degree
        depth = self.transcription.contact_path()
        G = self.interval_function(point, depth, n_par)
        z, par = ca.SX.sym("z", N_FREE * d + 14), ca.SX.sym("par", n_par)
        x0, x1 = z[:7], z[N_FREE * d + 7:]
        defect, cont, depths, J = G(x0, ca.reshape(z[7:N_FREE * d + 7], N_FREE, d), x1, 1.0 / N, par)
        return ca.Function("rest_block", [z, par], [ca.vertcat(ca.vec(defect), cont, depths, depth(x1)), J],
                           ["z", "par"], ["g", "J"])

    def contact_nlp(self, point: ca.Function, n_par: int):
        """The NLP ``({"x", "p", "f", "g"}, path_rows)``: the contact bound ``-z >= cos(bound)`` (the depth of the
        contact point (1)) at every collocation point and interval end is in the rows ``path_rows`` marks,
        the other rows are equalities. ``|u_o|, |v_o| <= bound`` are bounds of the interval ends' variables only:
        at the collocation points the depth bound implies them where ``|u_o|, |v_o| < pi / 2`` (so about every
        feasible point of the full transcription both NLPs have the same feasible set and local optima)."""
        N, d = self.transcription.intervals, self.transcription.degree
        rows = np.concatenate([np.zeros(N_FREE * d + 5, bool), np.ones(d + 1, bool)] * N)
        return interval_nlp(self.interval_block(point, n_par), N, self.block), rows

    def contact_derivatives(self, point: ca.Function, n_par: int) -> dict:
        """The derivatives of :meth:`contact_nlp`'s NLP as options of :func:`casadi.nlpsol`, built interval by
        interval (:func:`.transcription.interval_derivatives`)."""
        return interval_derivatives(self.interval_block(point, n_par), self.transcription.intervals, self.block)

    def pack(self, guess: Guess) -> np.ndarray:
        """The decision vector of a guess (its collocation values of u_o, v_o and the rates, and its accelerations,
        are not unknowns)."""
        N, d = self.transcription.intervals, self.transcription.degree
        states = np.asarray(guess.states, float)
        free = np.asarray(guess.colloc, float)[:, :, :N_FREE].reshape(N, N_FREE * d)
        return np.concatenate([states[0], np.hstack([free, states[1:]]).ravel()])

    def unpack(self, v: np.ndarray, horizon: float = 1.0):
        """``(states (N + 1, 7), colloc (N, d, 7), controls (N, 2))`` of a decision vector, the eliminated values
        by the closed forms; ``horizon`` the T of the NLP's parameters (1 in normalized time)."""
        tr = self.transcription
        N, d = tr.intervals, tr.degree
        v = np.asarray(v, float)
        blocks = v[7:].reshape(N, self.block)
        states = np.vstack([v[:7], blocks[:, N_FREE * d:]])
        uv, rates, _, a = self.stages(states[:-1].T, states[1:, 5:7].T, horizon / N)
        linear = np.stack([np.vstack([u, r]).T for u, r in zip(uv, rates)], axis=1)     # (N, d, 4)
        colloc = np.concatenate([blocks[:, :N_FREE * d].reshape(N, d, N_FREE), linear], axis=2)
        return states, colloc, a.T

    def full(self, v: np.ndarray) -> np.ndarray:
        """The decision vector ``v`` of this NLP as that of the full transcription (normalized time)."""
        return self.transcription.pack(Guess(*self.unpack(v), ""))

    def reduced(self, x: np.ndarray) -> np.ndarray:
        """A decision vector ``x`` of the full transcription as that of this NLP (:meth:`full`'s inverse)."""
        return self.pack(Guess(*self.transcription.unpack(x), ""))

    def contact_bounds(self, guess: Guess, start, final, contact_bound: float, path_rows):
        """``(x0, lbx, ubx, lbg, ubg)`` of the NLP of :meth:`contact_nlp`: ``start``, ``final`` fixed,
        ``|u_o|, |v_o| <= contact_bound`` at the interval ends, the guess clipped into the bounds."""
        N, d = self.transcription.intervals, self.transcription.degree
        box = np.full(7, np.inf)
        box[3:5] = contact_bound
        free = np.full(N_FREE * d, np.inf)
        lb, ub = [np.asarray(start, float)], [np.asarray(start, float)]
        for i in range(N):
            last = i == N - 1
            lb += [-free, np.asarray(final, float) if last else -box]
            ub += [free, np.asarray(final, float) if last else box]
        lbx, ubx = np.concatenate(lb), np.concatenate(ub)
        x0 = np.clip(self.pack(guess), lbx, ubx)
        lbg = np.where(path_rows, math.cos(contact_bound), 0.0)
        ubg = np.where(path_rows, np.inf, 0.0)
        return x0, lbx, ubx, lbg, ubg
