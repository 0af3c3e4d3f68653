"""Time-optimal path parameterisation (TOPP) of a fixed path under the rotors' rate and torque limits.

The problem
-----------
On a path with parameter s in [0, L] (:mod:`rollplan.execution.path`), with
``x = s'^2`` and ``u = s''`` (so ``dx/ds = 2 u``), the limits are
(:mod:`rollplan.execution.limits`)

    |G_i(s)| sqrt(x) <= max_rotor_rate,          |A_i(s) u + B_i(s) x| <= max_rotor_torque,

rest to rest, ``x(0) = x(L) = 0``, and at rest at every corner of the path; the
duration ``T = int_0^L ds / sqrt(x)`` is to be minimal. The constraints are linear in
(u, x) and T is convex in x: a convex problem (TOPP-RA, Pham and Pham 2018).

Discretisation
--------------
Nodes ``s_0 < ... < s_N`` (every joint a node), ``x_k`` at the nodes, ``u_k``
constant on ``[s_k, s_k+1]``, so ``x_k+1 = x_k + 2 (s_k+1 - s_k) u_k`` and the time
of the interval is exactly ``2 Delta_k / (sqrt(x_k) + sqrt(x_k+1))``; s(t) is a
quadratic in t on each interval. The torque rows are imposed at both ends of every
interval (TOPP-RA's "interpolation" scheme): ``(A, B)`` from the right at
``(s_k, u_k, x_k)`` and from the left at ``(s_k+1, u_k, x_k+1)``, so that the one-sided
values at a joint (``B`` jumps at the poles of a figure eight) are each used on their
own side. The rate bound is imposed at the nodes. Between nodes the limits can be
exceeded by O(Delta^2) (the time-optimal law of :mod:`rollplan.execution.timing`
stretches the profile to remove that).

Backends
--------
``"numpy"`` (default)
    TOPP-RA's two passes, backward (controllable sets) and greedy forward, written
    with numpy: for fixed x every torque row bounds u by an affine function of x, so
    each stage's LP in (u, x) is an interval cut out by pairs of rows (Helly in one
    dimension) and is solved in closed form; no LP solver.
``"toppra"``
    The TOPP-RA library (``pip install 'rollplan[toppra]'``; reachability analysis, seidel
    LP solver) on the same rows, as a custom linear constraint: the peer the tests and
    ``scripts/timing_table.py`` compare with. Not used by the command (its import takes
    seconds).
``"casadi"``
    The same discrete problem as a convex NLP for IPOPT,
    ``min sum 2 Delta_k / (c_k + c_k+1)`` s.t. ``c_k^2 <= x_k``, the rows above, x = 0 at
    the ends and corners (u eliminated): the global optimum of the discrete problem,
    which TOPP-RA's greedy forward pass meets only up to O(Delta) near points where some
    ``|A_i| < 2 Delta |B_i|``. IPOPT needs ``compl_inf_tol`` 1e-12 here: with its
    default it stops above the optimum.

Both grid methods solve the same discrete problem and agree to solver tolerance. The
independent check is the classic phase-plane integration of the tests
(``tests/references.py``), a different algorithm and discretisation.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from .. import interrupts
from ..errors import InputError, SolverError
from .limits import Limits, rate_bound, torque_bound
from .path import PathGrid

__all__ = ["BACKENDS", "GridProfile", "maximum_velocity_curve", "node_times", "solve_topp", "grid_violation",
           "toppra_available"]

log = logging.getLogger(__name__)

#: The solvers of :func:`solve_topp`.
BACKENDS = ("numpy", "toppra", "casadi")


@dataclass(frozen=True)
class GridProfile:
    """A rest-to-rest profile ``x = s'^2`` on a grid, with constant ``u = s''`` per interval.

    Attributes
    ----------
    s : ndarray, shape (N + 1,)
        Nodes [R].
    x : ndarray, shape (N + 1,)
        ``s'^2`` at the nodes [R^2/s^2]; 0 at both ends and at the corners.
    u : ndarray, shape (N,)
        ``s''`` on each interval [R/s^2].
    t : ndarray, shape (N + 1,)
        Time at the nodes [s].
    duration : float
        ``t[-1]`` [s].
    method : str
        The backend that solved it.
    solve_time : float
        Wall time of the solve [s] (the grid's evaluation excluded).
    mvc : ndarray, shape (N + 1,)
        The maximum velocity curve ``x_max(s)`` at the nodes (:func:`maximum_velocity_curve`).
    """

    s: np.ndarray
    x: np.ndarray
    u: np.ndarray
    t: np.ndarray
    duration: float
    method: str
    solve_time: float
    mvc: np.ndarray


def node_times(s: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Times at the nodes of a profile with constant ``s''`` per interval: ``dt = 2 ds / (sqrt(x_k) + sqrt(x_k+1))``."""
    r = np.sqrt(np.maximum(x, 0.0))
    den = r[:-1] + r[1:]
    if np.any(den <= 0):
        raise SolverError("the time-optimal profile stops inside the path (s' = 0 at two consecutive nodes)",
                          "stalled")
    return np.concatenate([[0.0], np.cumsum(2 * np.diff(s) / den)])


def maximum_velocity_curve(grid: PathGrid, limits: Limits) -> np.ndarray:
    """``x_max = s'^2`` allowed at the nodes by both limits, both one-sided values; 0 at the corners."""
    mvc = np.minimum.reduce([rate_bound(grid.G_left, limits), rate_bound(grid.G_right, limits),
                             torque_bound(grid.A_left, grid.B_left, limits),
                             torque_bound(grid.A_right, grid.B_right, limits)])
    mvc[grid.corners] = 0.0
    return mvc


def _rows(grid: PathGrid):
    """Torque rows of interval k: ``P_k u_k + Q_k x_k`` (at its start) and ``P'_k u_k + Q'_k x_k+1`` (at its end)."""
    return grid.A_right[:-1], grid.B_right[:-1], grid.A_left[1:], grid.B_left[1:]


def _rate_cap(grid: PathGrid, limits: Limits) -> np.ndarray:
    """Upper bound of x at the nodes from the rate limit, 0 at the ends and the corners."""
    cap = np.minimum(rate_bound(grid.G_left, limits), rate_bound(grid.G_right, limits))
    cap[grid.corners] = 0.0
    cap[0] = cap[-1] = 0.0
    return cap


def toppra_available() -> bool:
    """True if the optional ``toppra`` package imports (it takes seconds: call it only where toppra is wanted)."""
    try:
        import toppra  # noqa: F401
    except ImportError:
        return False
    return True


def _solve_toppra(grid: PathGrid, limits: Limits) -> np.ndarray:
    import toppra
    import toppra.algorithm
    import toppra.constraint

    s = grid.s
    n = s.size
    delta = np.diff(s)
    tau = limits.max_rotor_torque
    P0, Q0, P1, Q1 = _rows(grid)
    # stage k holds (u_k, x_k); the end row is rewritten with x_k+1 = x_k + 2 delta_k u_k
    a = np.zeros((n, 4))
    b = np.zeros((n, 4))
    a[:-1, :2], b[:-1, :2] = P0, Q0
    a[:-1, 2:], b[:-1, 2:] = P1 + 2 * delta[:, None] * Q1, Q1
    a[-1] = np.concatenate([grid.A_left[-1]] * 2)
    b[-1] = np.concatenate([grid.B_left[-1]] * 2)
    cap = _rate_cap(grid, limits)
    cap[0] = np.inf  # toppra starts and ends at rest by itself
    cap[-1] = np.inf
    xbound = np.column_stack([np.zeros(n), np.where(np.isfinite(cap), cap, 1e12)])

    class RotorConstraint(toppra.constraint.LinearConstraint):
        """``|a u + b x| <= tau`` (4 rows per stage) and ``0 <= x <= x_rate``, precomputed on the grid."""

        def __init__(self):
            super().__init__()
            self.identical = True
            self._format_string = "    rotor rate and torque limits\n"

        def compute_constraint_params(self, path, gridpoints, *args, **kwargs):
            if gridpoints.shape != s.shape or np.abs(gridpoints - s).max() > 1e-12 * s[-1]:
                raise ValueError("gridpoints differ from the path grid")
            F = np.vstack([np.eye(4), -np.eye(4)])
            return a, b, np.zeros((n, 4)), F, np.full(8, tau), None, xbound

    path = toppra.SplineInterpolator(s, s[:, None])
    algo = toppra.algorithm.TOPPRA([RotorConstraint()], path, gridpoints=s, solver_wrapper="seidel")
    _, sd, _ = algo.compute_parameterization(0.0, 0.0)
    if sd is None or np.any(~np.isfinite(sd)):
        raise SolverError(f"TOPP-RA failed: {algo.problem_data.return_code}", str(algo.problem_data.return_code))
    x = np.asarray(sd, float) ** 2
    x[0] = x[-1] = 0.0
    x[grid.corners] = 0.0
    return x


def _affine_u_bounds(a_rows: np.ndarray, b_rows: np.ndarray, tau: float):
    """Rows ``|a u + b x| <= tau`` as ``pl + q x <= u <= pu + q x`` (each shape (N, m)).

    A row with ``a = 0`` bounds x only (``|b| x <= tau``): it gets ``pl = -inf, pu = +inf``, and
    ``xcap`` (N,) holds the smallest such bound per stage.
    """
    zero = a_rows == 0
    a_safe = np.where(zero, 1.0, a_rows)
    q = np.where(zero, 0.0, -b_rows / a_safe)
    e = np.where(zero, np.inf, tau / np.abs(a_safe))
    b_safe = np.where(b_rows != 0, np.abs(b_rows), 1.0)
    xcap = np.where(zero & (b_rows != 0), tau / b_safe, np.inf).min(axis=1)
    return -e, e, q, xcap


def _solve_reachability(grid: PathGrid, limits: Limits) -> np.ndarray:
    """TOPP-RA's backward (controllable sets) and greedy forward pass, each stage LP in closed form.

    Stage k has the variables (u_k, x_k). For fixed x every torque row bounds u by an affine function of
    x, so the feasible x of a stage form an interval cut out by pairs of bounds (Helly in one dimension):
    the rows among themselves (for all stages at once), and each row with the reachability bounds
    ``K_k+1[0] <= x + 2 delta u <= K_k+1[1]`` in the backward pass.
    """
    s = grid.s
    n = s.size
    delta = np.diff(s)
    P0, Q0, P1, Q1 = _rows(grid)
    a_rows = np.hstack([P0, P1 + 2 * delta[:, None] * Q1])       # (N, 4)
    b_rows = np.hstack([Q0, Q1])
    pl, pu, q, xcap = _affine_u_bounds(a_rows, b_rows, limits.max_rotor_torque)
    # stage alone, pairs (i lower, j upper): (q_i - q_j) x <= pu_j - pl_i
    dq = q[:, :, None] - q[:, None, :]
    dp = pu[:, None, :] - pl[:, :, None]
    r = np.where(dq > 0, dp / np.where(dq > 0, dq, 1.0), np.inf)
    cap = _rate_cap(grid, limits)
    xhi = np.minimum.reduce([r.reshape(n - 1, -1).min(axis=1), xcap, cap[:-1]])
    d2 = (2 * delta).tolist()
    PL, PU, Q, XH = pl.tolist(), pu.tolist(), q.tolist(), xhi.tolist()
    rest = np.zeros(n, bool)
    rest[grid.corners] = True
    rest[0] = True
    K = [[0.0, 0.0] for _ in range(n)]
    for k in range(n - 2, -1, -1):
        klo, khi = K[k + 1]
        d = d2[k]
        lo, hi = 0.0, XH[k]
        for pli, pui, qi in zip(PL[k], PU[k], Q[k]):
            # pl + q x <= (khi - x) / d   and   (klo - x) / d <= pu + q x
            c = qi + 1.0 / d
            if c > 0:
                hi = min(hi, (khi / d - pli) / c)
            elif c < 0:
                lo = max(lo, (khi / d - pli) / c)
            c2 = -1.0 / d - qi
            if c2 > 0:
                hi = min(hi, (pui - klo / d) / c2)
            elif c2 < 0:
                lo = max(lo, (pui - klo / d) / c2)
        if not hi >= lo - 1e-12 * max(abs(hi), 1e-300) or (rest[k] and lo > 1e-12 * max(hi, 1e-300)):
            raise SolverError(f"no feasible velocity at s = {s[k]:.6g} (node {k}): the limits cannot be met on "
                              "this path", "uncontrollable")
        K[k] = [0.0, 0.0] if rest[k] else [lo, max(hi, lo)]
    x = np.zeros(n)
    xk = 0.0
    for k in range(n - 1):
        d = d2[k]
        klo, khi = K[k + 1]
        u_hi = min(*(pui + qi * xk for pui, qi in zip(PU[k], Q[k])), (khi - xk) / d)
        u_lo = max(*(pli + qi * xk for pli, qi in zip(PL[k], Q[k])), (klo - xk) / d)
        u = u_hi if u_hi >= u_lo else 0.5 * (u_lo + u_hi)  # rounding at a touching point
        xk = min(max(xk + d * u, 0.0), khi)
        x[k + 1] = xk
    x[-1] = 0.0
    return x


def _solve_casadi(grid: PathGrid, limits: Limits, tol: float = 1e-12) -> np.ndarray:
    import casadi as ca

    s = grid.s
    n = s.size
    delta = np.diff(s)
    tau = limits.max_rotor_torque
    X = ca.SX.sym("x", n)
    C = ca.SX.sym("c", n)
    u = (X[1:] - X[:-1]) / (2 * delta)
    g, lbg, ubg = [C**2 - X], [-np.inf * np.ones(n)], [np.zeros(n)]
    P0, Q0, P1, Q1 = _rows(grid)
    for i in range(P0.shape[1]):
        if not (P0[:, i].any() or Q0[:, i].any() or P1[:, i].any() or Q1[:, i].any()):
            continue    # a rotor without torque on this path: its rows are 0 <= tau
        g += [P0[:, i] * u + Q0[:, i] * X[:-1], P1[:, i] * u + Q1[:, i] * X[1:]]
        lbg += [-tau * np.ones(n - 1)] * 2
        ubg += [tau * np.ones(n - 1)] * 2
    nlp = {"x": ca.vertcat(X, C), "f": ca.sum1(2 * delta / (C[:-1] + C[1:])), "g": ca.vertcat(*g)}
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.max_iter": 500, "ipopt.mu_strategy": "adaptive", "ipopt.bound_relax_factor": 0.0,
            "ipopt.constr_viol_tol": 1e-12, "ipopt.compl_inf_tol": 1e-12, "ipopt.dual_inf_tol": 1e-10}
    solver = ca.nlpsol("topp_ipopt", "ipopt", nlp, opts)
    ub_x = np.minimum(_rate_cap(grid, limits), 1e12)
    mvc = np.minimum(maximum_velocity_curve(grid, limits), ub_x)
    inner = mvc[mvc > 0]
    x_guess = 1e-2 * np.minimum(mvc, inner.min() if inner.size else 1.0)
    c_guess = np.where(ub_x > 0, np.maximum(0.5 * np.sqrt(x_guess), 1e-6), 0.0)
    sol = interrupts.call(solver, x0=np.concatenate([x_guess, c_guess]), lbx=np.zeros(2 * n),
                          ubx=np.concatenate([ub_x, np.sqrt(ub_x)]), lbg=np.concatenate(lbg), ubg=np.concatenate(ubg))
    st = solver.stats()
    if not st["success"]:
        raise SolverError(f"IPOPT did not solve the time-optimal problem: {st['return_status']}", st["return_status"])
    x = np.clip(np.array(sol["x"]).ravel()[:n], 0.0, None)
    x[ub_x == 0] = 0.0
    return x


def solve_topp(grid: PathGrid, limits: Limits, backend: str = "numpy") -> GridProfile:
    """Minimum-time rest-to-rest profile on a path grid under the limits (the discrete problem above).

    Parameters
    ----------
    grid : PathGrid
        Nodes and one-sided coefficients (``ContactPath.grid``).
    limits : Limits
        Needs ``max_rotor_torque``: with a rate limit alone the infimum is reached only by
        an infinite torque at the start (s' jumping from 0).
    backend : {"numpy", "toppra", "casadi"}

    Returns
    -------
    GridProfile

    Raises
    ------
    InputError
        No torque limit, or an unknown backend.
    SolverError
        The solver failed, or the limits cannot be met on the path.
    """
    if not isinstance(limits, Limits) or limits.max_rotor_torque is None:
        raise InputError("time-optimal timing needs max_rotor_torque: with a rate limit alone the fastest motion "
                         "needs an infinite torque at the start")
    if backend not in BACKENDS:
        raise InputError(f"backend = {backend!r} is not allowed: choose one of {', '.join(BACKENDS)}")
    t0 = time.perf_counter()
    solve = {"numpy": _solve_reachability, "toppra": _solve_toppra, "casadi": _solve_casadi}[backend]
    x = solve(grid, limits)
    dt = time.perf_counter() - t0
    u = np.diff(x) / (2 * np.diff(grid.s))
    t = node_times(grid.s, x)
    log.info("time-optimal (%s): N = %d, T = %.9g s in %.3f s", backend, grid.size - 1, t[-1], dt)
    return GridProfile(grid.s, x, u, t, float(t[-1]), backend, dt, maximum_velocity_curve(grid, limits))


def grid_violation(grid: PathGrid, profile: GridProfile, limits: Limits) -> dict:
    """Largest relative excess of each limit over the rows of the discrete problem (both ends of every interval)."""
    out = {"rate": 0.0, "torque": 0.0}
    r = np.sqrt(profile.x)
    if limits.max_rotor_rate is not None:
        g = np.maximum(np.abs(grid.G_left).max(axis=1), np.abs(grid.G_right).max(axis=1))
        out["rate"] = float((g * r).max() / limits.max_rotor_rate - 1)
    if limits.max_rotor_torque is not None:
        P0, Q0, P1, Q1 = _rows(grid)
        u = profile.u[:, None]
        t0 = np.abs(P0 * u + Q0 * profile.x[:-1, None]).max()
        t1 = np.abs(P1 * u + Q1 * profile.x[1:, None]).max()
        out["torque"] = float(max(t0, t1) / limits.max_rotor_torque - 1)
    return out
