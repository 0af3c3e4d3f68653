"""The best rest-to-rest timing of a fixed path for a named cost, and the bound no timing can beat.

On a path with parameter s (the contact arc length, :class:`~rollplan.execution.path.ContactPath`)
omega is ``W(s) s'``, the rotor rates ``G(s) s'`` and the torques ``A(s) s'' + B(s) s'^2``.
:func:`optimal_timing` chooses ``s(t)`` on ``[0, T]`` in the control class of the rest-to-rest
collocation (:mod:`rollplan.planners.collocation.rest`): ``s''`` constant on each of N equal
time intervals, ``s(0) = 0``, ``s(T) = L``, ``s'(0) = s'(T) = 0``, ``s' >= 0``. On each interval
s and s' are then exact polynomials of t (no discretisation of the dynamics); the cost

* ``"angular_velocity"``: ``int |W(s)|^2 s'^2 dt``,
* ``"path_energy"``: ``int s'^2 dt`` (the energy form; every timing has the same length),
* ``"rotor_energy"``: ``int |A(s) s'' + B(s) s'^2|^2 dt`` (scaled by 1/J_r^2),

is integrated by 3-point Gauss-Legendre quadrature per interval with ``|W|^2``, A and B
interpolated by cubic B-splines on a table of the path, and IPOPT minimises it. What is reported of
the timed motion is measured again on the exact path (:func:`timed_samples`,
:func:`rollplan.measures.measure`), not taken from this NLP.

Bound. For ``int |omega|^2 dt`` Cauchy-Schwarz gives, for every timing of the path over T,
``int |W|^2 s'^2 dt >= (int |W| ds)^2 / T``, with equality only for ``s' = c / |W|``, which is
not at rest at the ends; :func:`timing_bound` computes it (Simpson per piece). For
``int s'^2 dt`` the bound is ``L^2 / T``. The rest-to-rest optimum exceeds the bound by the cost
of starting and stopping, which vanishes as N grows.

Time scaling. Every cost is homogeneous in T (``s(t) = s_1(t / T)`` scales the first two by
``1 / T``, the torque energy by ``1 / T^3``), so the timing is found for T = 1 and scaled exactly
(the NLP's tolerances then mean the same for every T).

Corners. A path with corners (where every motion must rest: a polygon's vertices, a Viviani figure
eight of unequal lobes) is timed stretch by stretch (:meth:`ContactPath.stretches`), each rest to
rest. A cost homogeneous of degree p in 1/T (p = 1 for the first two costs, 3 for the torque energy)
is ``c_i / T_i^p`` on stretch i, with ``c_i`` its optimum over a unit duration; the split of T that
minimises the sum is ``T_i = T c_i^(1/(p+1)) / sum_j c_j^(1/(p+1))`` (Lagrange), and the total
``(sum_i c_i^(1/(p+1)))^(p+1) / T^p``. Each stretch gets intervals in proportion to its length (at
least 4). The bound above still holds (a rest only adds cost).
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from .. import interrupts
from ..core import model
from ..errors import InputError, SolverError, check_range, check_whole
from ..measures import cost_key
from ..timeseries import TimeSeries
from .path import ContactPath
from .timing import TimeProfile

__all__ = ["TIMING_COSTS", "optimal_timing", "timing_bound", "timed_samples"]

#: Costs :func:`optimal_timing` minimises.
TIMING_COSTS = ("path_energy", "angular_velocity", "rotor_energy")


def _check(path, horizon, cost):
    if not isinstance(path, ContactPath):
        raise InputError(f"path = {path!r:.60} is not allowed: give a ContactPath")
    return check_range("horizon", horizon, 0.0, 1e6, low_open=True)


def _table(path: ContactPath, nodes: int) -> tuple:
    """s nodes, uniform within each piece (``2 m + 1`` per piece, joints shared), and the path there."""
    P = len(path.pieces)
    m = max(2, math.ceil(nodes / (2 * P)))
    s = np.concatenate([np.linspace(path.starts[j], path.starts[j + 1], 2 * m + 1)[:-1] for j in range(P)]
                       + [[path.length]])
    return s, m, path.evaluate(s, "left")


def timing_bound(path: ContactPath, horizon: float, cost: str, nodes: int = 4000) -> float | None:
    """The least cost of any timing of ``path`` over ``horizon`` (module docstring); None for ``rotor_energy``."""
    cost = cost_key(cost, TIMING_COSTS)
    horizon = _check(path, horizon, cost)
    if cost == "path_energy":
        return path.length ** 2 / horizon
    if cost == "rotor_energy":
        return None
    s, m, ps = _table(path, check_whole("nodes", nodes, 4, 10**7))
    w = np.linalg.norm(ps.W, axis=1)
    total = 0.0
    for j in range(len(path.pieces)):
        y = w[2 * m * j: 2 * m * (j + 1) + 1]
        h = (path.starts[j + 1] - path.starts[j]) / (2 * m)
        total += h / 3.0 * (y[0] + y[-1] + 4.0 * y[1:-1:2].sum() + 2.0 * y[2:-1:2].sum())
    return total ** 2 / horizon


def optimal_timing(path: ContactPath, horizon: float, cost: str, intervals: int = 100, nodes: int = 4000,
                   tol: float = 1e-10) -> TimeProfile:
    """The rest-to-rest timing of ``path`` over ``horizon`` [s] that minimises ``cost`` (module docstring).

    Returns
    -------
    TimeProfile
        Piecewise quadratic ``s(t)`` on ``intervals`` equal intervals, law ``"optimal-<cost>"``; on a path with
        corners, on about ``intervals`` intervals, equal within each stretch (module docstring, "Corners").

    Raises
    ------
    InputError
        Bad input.
    SolverError
        IPOPT failed.
    """
    cost = cost_key(cost, TIMING_COSTS)
    T = _check(path, horizon, cost)
    N = check_whole("intervals", intervals, 2, 100000)
    nodes = check_whole("nodes", nodes, 4, 10**7)
    parts = path.stretches()
    if len(parts) == 1:
        S_, V_, A_, _ = _unit_timing(path, cost, N, nodes, tol)
        coeffs = np.column_stack([S_[:-1], V_[:-1] / T, A_ / (2 * T ** 2)])
        return TimeProfile(np.arange(N + 1) / N * T, coeffs, f"optimal-{cost}", path.length)
    degree = 3 if cost == "rotor_energy" else 1
    units = [_unit_timing(q, cost, max(4, round(N * q.length / path.length)), max(4, round(nodes * q.length /
                                                                                                path.length)), tol)
             for q in parts]
    weights = np.array([max(u[3], 0.0) ** (1.0 / (degree + 1)) for u in units])
    shares = weights / weights.sum() if weights.sum() > 0 else np.array([q.length for q in parts]) / path.length
    breaks, coeffs, t0, s0 = [], [], 0.0, 0.0
    for (S_, V_, A_, _), share, q in zip(units, shares, parts):
        Ti, n = T * share, A_.size
        breaks.append(t0 + np.arange(n) / n * Ti)
        coeffs.append(np.column_stack([s0 + S_[:-1], V_[:-1] / Ti, A_ / (2 * Ti ** 2)]))
        t0, s0 = t0 + Ti, s0 + q.length
    breaks = np.concatenate([*breaks, [T]])
    return TimeProfile(breaks, np.vstack(coeffs), f"optimal-{cost}", path.length)


def _unit_timing(path: ContactPath, cost: str, N: int, nodes: int, tol: float) -> tuple:
    """``(S, V, A, cost)`` of the optimal rest-to-rest timing of a path without corners over a unit duration
    on N equal intervals (nodes of s, s' and the intervals' s'')."""
    horizon = 1.0    # solved in normalized time t / T, scaled exactly by the caller (module docstring)
    s_tab, _, ps = _table(path, nodes)
    L, h = path.length, horizon / N
    jr = path.robot.rotor_inertia_axial
    if cost == "angular_velocity":
        table = (np.linalg.norm(ps.W, axis=1) ** 2)[:, None]
    elif cost == "rotor_energy":
        table = np.hstack([ps.A, ps.B]) / jr
    else:
        table = np.zeros((s_tab.size, 1))
    interp = ca.interpolant("path_table", "bspline", [s_tab], table.ravel())
    sk, vk, ak = ca.MX.sym("s"), ca.MX.sym("v"), ca.MX.sym("a")
    tau = np.array(ca.collocation_points(3, "legendre"))
    weights = np.array(ca.collocation_coeff(list(tau))[2]).ravel()
    J = 0
    for tj, wj in zip(tau, weights):
        dt = tj * h
        s, v = sk + vk * dt + ak * dt ** 2 / 2, vk + ak * dt
        c = interp(ca.fmin(ca.fmax(s, 0.0), L))
        if cost == "angular_velocity":
            L_ = c[0] * v ** 2
        elif cost == "rotor_energy":
            tq = c[0:2] * ak + c[2:4] * v ** 2
            L_ = ca.sumsqr(tq)
        else:
            L_ = v ** 2
        J = J + wj * h * L_
    per = ca.Function("interval_cost", [sk, vk, ak], [J]).map(N)
    S, V, A = ca.MX.sym("S", N + 1), ca.MX.sym("V", N + 1), ca.MX.sym("A", N)
    g = ca.vertcat(S[1:] - S[:-1] - V[:-1] * h - A * h ** 2 / 2, V[1:] - V[:-1] - A * h)
    f = ca.sum2(per(S[:-1].T, V[:-1].T, A.T))
    nlp = {"x": ca.vertcat(S, V, A), "f": f, "g": g}
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.max_iter": 3000}
    solver = interrupts.call_in_thread(ca.nlpsol, "optimal_timing", "ipopt", nlp, opts)
    tt = np.linspace(0.0, 1.0, N + 1)
    s0 = L * (10 * tt ** 3 - 15 * tt ** 4 + 6 * tt ** 5)
    v0 = L * (30 * tt ** 2 - 60 * tt ** 3 + 30 * tt ** 4) / horizon
    a0 = np.diff(v0) / h
    lbs, ubs = np.zeros(N + 1), np.full(N + 1, L)
    lbs[-1] = L
    ubs[0] = 0.0
    lbv, ubv = np.zeros(N + 1), np.full(N + 1, np.inf)
    ubv[0] = ubv[-1] = 0.0
    sol = interrupts.call(solver, x0=np.concatenate([s0, v0, a0]), lbx=np.concatenate([lbs, lbv, np.full(N, -np.inf)]),
                          ubx=np.concatenate([ubs, ubv, np.full(N, np.inf)]), lbg=0.0, ubg=0.0)
    st = solver.stats()
    if not st["success"]:
        raise SolverError(f"IPOPT did not find the optimal timing ({cost}, N = {N}): {st['return_status']}",
                          str(st["return_status"]))
    x = np.array(sol["x"]).ravel()
    return x[: N + 1], x[N + 1: 2 * N + 2], x[2 * N + 2:], float(sol["f"])


@lru_cache(maxsize=1)
def _plane_rates() -> ca.Function:
    """``(omega, u_o, v_o, psi) -> (u_a_dot, v_a_dot, u_o_dot, v_o_dot)`` on the unit sphere, (6)-(9)."""
    w, u, v, p = ca.SX.sym("w", 3), ca.SX.sym("u"), ca.SX.sym("v"), ca.SX.sym("p")
    r = model.montana(w, u, v, p)
    return ca.Function("plane_rates", [w, u, v, p], [ca.vertcat(r[0], r[1], r[3], r[4])])


def contact_rates(omega, state) -> np.ndarray:
    """``(u_a_dot, v_a_dot, u_o_dot, v_o_dot)`` (N, 4) from omega (N, 3) and states (N, 5), Montana's (6)-(9)
    on the unit sphere (multiply the first two by R)."""
    omega, state = np.asarray(omega, float), np.asarray(state, float)
    return np.array(_plane_rates().map(omega.shape[0])(omega.T, state[:, 3], state[:, 4], state[:, 2])).T


def timed_samples(path: ContactPath, profile: TimeProfile, per: int = 8) -> TimeSeries:
    """The path run by ``profile`` sampled on every piece of the profile, both ends included (jumps of s''
    at the breaks appear as repeated times), as a :class:`~rollplan.timeseries.TimeSeries` [robot's unit]."""
    per = check_whole("per", per, 1, 10000)
    ts, ks = [], []
    for k in range(profile.coeffs.shape[0]):
        ts.append(np.linspace(profile.breaks[k], profile.breaks[k + 1], per + 1))
        ks.append(np.full(per + 1, k))
    t, piece = np.concatenate(ts), np.concatenate(ks)
    s, sd, sdd = profile.evaluate(t, piece)
    sd[0] = sd[-1] = 0.0
    ps = path.evaluate(np.clip(s, 0.0, path.length), "left")
    R = path.robot.radius
    omega = ps.W * sd[:, None]
    velocity = contact_rates(omega, ps.state)[:, :2] * R
    state = ps.state * np.array([R, R, 1.0, 1.0, 1.0])
    return TimeSeries(t, state, ps.segment, velocity, omega, ps.G * sd[:, None], ps.rotor_angles,
                      ps.A * sdd[:, None] + ps.B * sd[:, None] ** 2, radius=R)
