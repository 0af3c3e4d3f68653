"""Direct-collocation optimal-control planner on the same symbolic model.

Problem. On a fixed horizon ``t in [0, T]`` (normalized time ``tau = t / T``)
find contact rates ``w(t) = (u_o_dot, v_o_dot)`` that minimize

    J = int_0^T L(x, w) dt

subject to the realizable contact kinematics ``x_dot = f(x, w; k)`` of
:func:`rollplan.model.contact_rhs`, i.e. Montana's (6)-(10) with the rolling
components (18)-(19) and the spin ``omega_z`` from the realizability condition
(13), so that (13) holds by construction. The state is
``x = (u_a, v_a, u_o, v_o, psi)``; the boundary conditions are

    x(0) = 0 (at rest at the origin),
    (u_a, v_a, u_o, v_o, psi)(T) = (u_a*, v_a*, 0, 0, psi* + 2 pi m),

with ``m`` (``turns``) the number of whole turns of psi, 0 by default and the
branch of the geometric-phase plan for the warm start (same final orientation).
The contact point stays within a polar angle ``contact_bound`` of the south
pole (75 deg by default): (8) and the spin (13) are singular on the equator.

Transcription. ``N`` intervals of equal length in ``tau``; on each, the state
is a polynomial of degree ``d`` through the interval's start and ``d``
Legendre or Radau points (:func:`casadi.collocation_points`), and the control
is constant. The collocation equations on each interval are those of the
``d``-stage Gauss-Legendre (order ``2d``) or Radau IIA (order ``2d - 1``)
implicit Runge-Kutta method, so with the control held fixed the end-of-interval
states converge at that order as ``N`` grows (``tests/test_collocation.py``).
The cost is integrated by the same quadrature. The NLP is built once (SX,
exact Hessian) per (N, d, scheme, cost); k, T and the robot inertias are NLP
parameters and the boundary values are variable bounds, so repeated solves
reuse it. IPOPT solves it.

Costs, by name in :data:`COSTS` (lengths in units of R inside the NLP):

``"path_length"``
    ``L = sqrt(eps + u_a_dot^2 + v_a_dot^2)``: the contact path length on the
    plane (which equals that on the sphere), smoothed at zero speed.
``"angular_velocity"``
    ``L = |omega|^2``, omega from (18), (19), (13) [rad^2/s^2].
``"rotor_effort"``
    ``L = phi1_dot^2 + phi2_dot^2``, the rotor rates of (11)
    (:func:`rollplan.model.rotor_rates`); needs a :class:`~rollplan.robot.Robot`.

Verification. Every solution is integrated again, with the optimized
piecewise-constant controls, by CVODES at tight tolerances (independent of the
transcription); its end point gives the residual to the target, and CVODES
quadratures give the path length and efforts that are reported. A solution
whose residual exceeds ``verify_tol`` is never returned: SolverError with
status ``"Verification_Failed"``.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import casadi as ca
import numpy as np

from . import model
from .errors import InputError, SolverError, check_finite, check_range, check_whole
from .geometric import Plan, _check_steps, _resolve_k_radius, plan as gp_plan, wrap
from .robot import Robot

__all__ = ["SCHEMES", "COSTS", "GUESSES", "Cost", "Guess", "CollocationStats", "CollocationTrajectory",
           "CollocationResult", "CollocationPlanner", "collocate", "collocation_coefficients"]

log = logging.getLogger(__name__)

#: Collocation point families accepted by :func:`casadi.collocation_points`.
SCHEMES = ("legendre", "radau")
#: Initial guesses by name.
GUESSES = ("naive", "warm")
#: Default bound on the contact point's polar angle from the south pole [rad] (75 deg).
#: (8) and (13) are singular on the equator (90 deg), where the spin (13) grows like
#: 1 / cos(polar angle); unbounded, path-length optima ride that singularity.
CONTACT_BOUND = math.radians(75.0)
#: Default smoothing eps of the path-length integrand [(R/s)^2].
SMOOTHING = 1e-4
#: Default largest verified residual of a returned solution.
TOLERANCE = 1e-6

# NLP parameter vector: k, T, eps, j_xx, j_zz, j_r
_NP = 6

_HINTS = {
    "Maximum_Iterations_Exceeded": "raise max_iter, or warm-start from the geometric-phase plan (guess='warm')",
    "Infeasible_Problem_Detected": "the boundary conditions look unreachable within the contact bound; "
                                   "try guess='warm', more intervals or a larger contact bound",
    "Restoration_Failed": "IPOPT lost feasibility; try guess='warm' or more intervals",
    "Error_In_Step_Computation": "the KKT system is singular; try guess='warm' or another cost",
    "Invalid_Number_Detected": "NaN/Inf in the model: the contact point reached the equator (u_o or v_o = pi/2); "
                               "lower the contact bound or try guess='warm'",
}


@dataclass(frozen=True)
class Cost:
    """A running cost ``L(x, w, xdot, omega, par)``; ``par = (k, T, eps, j_xx, j_zz, j_r)``."""

    name: str
    description: str
    unit: str
    needs_robot: bool
    integrand: Callable


def _path_length(x, w, xdot, omega, par):
    return xdot[0] ** 2 + xdot[1] ** 2


def _path_length_smooth(x, w, xdot, omega, par):
    return ca.sqrt(par[2] + xdot[0] ** 2 + xdot[1] ** 2)


def _angular_velocity(x, w, xdot, omega, par):
    return ca.sumsqr(omega)


def _rotor_effort(x, w, xdot, omega, par):
    return ca.sumsqr(model.rotor_rates(omega, x[2], x[3], x[4], par[3], par[4], par[5]))


#: Costs by name.
COSTS = {
    "path_length": Cost("path_length", "contact path length in its energy form int |v|^2 dt", "R^2/s", False,
                        _path_length),
    "path_length_smooth": Cost("path_length_smooth", "contact path length int sqrt(eps + |v|^2) dt", "R", False,
                               _path_length_smooth),
    "angular_velocity": Cost("angular_velocity", "angular-velocity energy int |omega|^2 dt", "rad^2/s", False,
                             _angular_velocity),
    "rotor_effort": Cost("rotor_effort", "rotor effort int (phi1_dot^2 + phi2_dot^2) dt (eq. 11)", "rad^2/s", True,
                         _rotor_effort),
}


@dataclass(frozen=True)
class Guess:
    """An initial guess in units of R, normalized time on N intervals.

    Attributes
    ----------
    states : ndarray, shape (N + 1, 5)
        (u_a, v_a, u_o, v_o, psi) at the interval boundaries.
    colloc : ndarray, shape (N, d, 5)
        The state at the collocation points.
    controls : ndarray, shape (N, 2)
        (u_o_dot, v_o_dot) on each interval [rad/s].
    name : str
    """

    states: np.ndarray
    colloc: np.ndarray
    controls: np.ndarray
    name: str


@dataclass(frozen=True)
class CollocationStats:
    """IPOPT's report and timings.

    Attributes
    ----------
    status : str
        IPOPT return status.
    success : bool
    iterations : int
    solve_time_s : float
        Wall time of the IPOPT call [s] (the NLP was built before).
    guess_time_s : float
        Wall time to build the initial guess (for ``"warm"`` it includes the
        geometric-phase plan) [s].
    verify_time_s : float
        Wall time of the CVODES verification [s].
    """

    status: str
    success: bool
    iterations: int
    solve_time_s: float
    guess_time_s: float
    verify_time_s: float


@dataclass(frozen=True)
class CollocationTrajectory:
    """The verified motion sampled on a uniform grid (CVODES, exact controls).

    ``t``, ``u_a``, ``v_a``, ``u_o``, ``v_o``, ``psi`` have shape (M,);
    ``omega`` and ``contact`` (M, 3). Time [s], lengths in the result's length
    unit, angles [rad], omega in the plane frame [rad/s], contact the contact
    point on the sphere in the body frame, eq. (1).
    """

    t: np.ndarray
    u_a: np.ndarray
    v_a: np.ndarray
    u_o: np.ndarray
    v_o: np.ndarray
    psi: np.ndarray
    omega: np.ndarray
    contact: np.ndarray


@dataclass(frozen=True)
class CollocationResult:
    """A verified direct-collocation solution.

    Attributes
    ----------
    cost : str
        Name in :data:`COSTS`.
    scheme : str
        ``"legendre"`` or ``"radau"``.
    degree : int
        Collocation degree d.
    intervals : int
        Number of intervals N.
    horizon : float
        T [s].
    k : float
        Inertia ratio (14).
    radius : float
        Sphere radius R [length unit].
    target : tuple of 3 float
        (u_a, v_a) [length unit] and psi [rad] as requested.
    turns : int
        m: psi is steered to ``target[2] + 2 pi m``.
    guess : str
        Name of the initial guess.
    contact_bound : float
        Largest polar angle of the contact point from the south pole [rad].
    t : ndarray, shape (N + 1,)
        Interval boundaries [s].
    states : ndarray, shape (N + 1, 5)
        Collocation states (u_a, v_a, u_o, v_o, psi) at ``t`` [length unit, rad].
    t_colloc : ndarray, shape (N * d,)
        Collocation times [s].
    states_colloc : ndarray, shape (N * d, 5)
        Collocation states at ``t_colloc``.
    controls : ndarray, shape (N, 2)
        (u_o_dot, v_o_dot), constant on each interval [rad/s].
    objective : float
        The optimal value of the (smoothed) cost as transcribed [cost unit; R
        units for lengths].
    path_length : float
        Contact path length, from the verification [length unit].
    effort : float
        Angular-velocity energy ``int |omega|^2 dt`` from the verification [rad^2/s].
    rotor_effort : float
        ``int |phi_dot|^2 dt`` from the verification [rad^2/s]; nan without a robot.
    peak_omega : float
        Largest ``|omega|`` on the verification grid [rad/s].
    final : ndarray, shape (5,)
        (u_a, v_a, psi, u_o, v_o) at T from the independent CVODES integration
        [length unit, rad] (same order as :attr:`rollplan.Plan.final`).
    residual : float
        Euclidean norm of ``final`` minus the target (lengths over R, psi
        wrapped to (-pi, pi]).
    max_defect : float
        Largest violation of the NLP's constraints (collocation equations,
        continuity, contact bound) at the solution [units of R, rad].
    stats : CollocationStats
    trajectory : CollocationTrajectory
        The verified motion on ``>= 1000`` points (by default).
    """

    cost: str
    scheme: str
    degree: int
    intervals: int
    horizon: float
    k: float
    radius: float
    target: tuple
    turns: int
    guess: str
    contact_bound: float
    t: np.ndarray
    states: np.ndarray
    t_colloc: np.ndarray
    states_colloc: np.ndarray
    controls: np.ndarray
    objective: float
    path_length: float
    effort: float
    rotor_effort: float
    peak_omega: float
    final: np.ndarray
    residual: float
    max_defect: float
    stats: CollocationStats
    trajectory: CollocationTrajectory


# ----------------------------------------------------------------------------- transcription


def collocation_coefficients(degree: int, scheme: str):
    """Coefficients of the collocation polynomial on [0, 1].

    Returns ``tau`` (d + 1,) = [0, tau_1..tau_d], ``C`` (d + 1, d + 1) with
    ``C[j, r]`` the derivative of the j-th Lagrange basis polynomial at
    ``tau[r]``, ``D`` (d + 1,) their values at 1 (continuity) and ``B`` (d + 1,)
    their integrals over [0, 1] (quadrature).
    """
    tau = np.append(0.0, ca.collocation_points(degree, scheme))
    C = np.zeros((degree + 1, degree + 1))
    D = np.zeros(degree + 1)
    B = np.zeros(degree + 1)
    for j in range(degree + 1):
        p = np.poly1d([1.0])
        for r in range(degree + 1):
            if r != j:
                p *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
        D[j] = p(1.0)
        dp = np.polyder(p)
        C[j] = [dp(t) for t in tau]
        B[j] = np.polyint(p)(1.0)
    return tau, C, D, B


def _point_functions(cost: Cost):
    """SX functions of the model at one point: dynamics, omega, cost integrand."""
    x = ca.SX.sym("x", 5)
    w = ca.SX.sym("w", 2)
    par = ca.SX.sym("par", _NP)
    xdot = model.contact_rhs(x, w, par[0])
    omega = model.realizable_omega(x[2], x[3], x[4], w[0], w[1], par[0])
    L = cost.integrand(x, w, xdot, omega, par)
    return ca.Function("point", [x, w, par], [xdot, L, omega], ["x", "w", "par"], ["xdot", "L", "omega"])


def _interval_function(point: ca.Function, degree: int, scheme: str) -> ca.Function:
    """Collocation equations of one interval of normalized length h.

    ``G(x0[5], xc[5 x d], w[2], h, par) -> (defect[5 x d], x_end[5], J)``,
    with ``defect_r = sum_j C[j, r] X_j - h T f(X_r, w)`` for r = 1..d.
    """
    tau, C, D, B = collocation_coefficients(degree, scheme)
    x0 = ca.SX.sym("x0", 5)
    xc = ca.SX.sym("xc", 5, degree)
    w = ca.SX.sym("w", 2)
    h = ca.SX.sym("h")
    par = ca.SX.sym("par", _NP)
    T = par[1]
    X = [x0] + [xc[:, j] for j in range(degree)]
    defects = []
    J = 0
    x_end = D[0] * x0
    for r in range(1, degree + 1):
        xp = sum(C[j, r] * X[j] for j in range(degree + 1))
        f, L, _ = point(X[r], w, par)
        defects.append(xp - h * T * f)
        x_end = x_end + D[r] * X[r]
        J = J + B[r] * L * h * T
    return ca.Function("interval", [x0, xc, w, h, par], [ca.horzcat(*defects), x_end, J],
                       ["x0", "xc", "w", "h", "par"], ["defect", "x_end", "J"])


def _ipopt_options(tol, max_iter, print_level=0):
    return {"print_time": False, "ipopt.print_level": print_level, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.constr_viol_tol": tol, "ipopt.max_iter": max_iter, "ipopt.mu_strategy": "adaptive"}


class CollocationPlanner:
    """Direct-collocation planner (problem class): the NLP is built once.

    Parameters
    ----------
    intervals : int
        N >= 1 intervals of equal length.
    degree : int
        Collocation degree d in 1..9.
    scheme : str
        ``"legendre"`` (Gauss points, order 2d) or ``"radau"`` (order 2d - 1).
    cost : str
        Name in :data:`COSTS`.
    contact_bound : float
        Bound on the polar angle of the contact point from the south pole [rad],
        in (0, pi/2): ``-z >= cos(bound)`` for the contact point (1) at every
        collocation point and interval end (hence also ``|u_o|, |v_o| <= bound``).
    verify_tol : float or None
        Largest verified residual of a returned solution; a larger one raises
        SolverError with status ``"Verification_Failed"``. None: report only.
    tol : float
        IPOPT's tolerance (also its constraint-violation tolerance).
    max_iter : int
        IPOPT's iteration limit.
    verify_samples : int
        Least number of points of the verified trajectory.
    """

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre", cost: str = "path_length",
                 contact_bound: float = CONTACT_BOUND, tol: float = 1e-10, max_iter: int = 500,
                 verify_samples: int = 1000, verify_tol: float | None = TOLERANCE) -> None:
        self.intervals = check_whole("intervals", intervals, 1)
        self.degree = check_whole("degree", degree, 1, 9)
        if scheme not in SCHEMES:
            raise InputError(f"scheme = {scheme!r} is not allowed: choose one of {', '.join(SCHEMES)}")
        if cost not in COSTS:
            raise InputError(f"cost = {cost!r} is not allowed: choose one of {', '.join(COSTS)}")
        self.scheme = scheme
        self.cost = COSTS[cost]
        self.contact_bound = check_range("contact_bound", contact_bound, 0.0, math.pi / 2, True, True)
        self.verify_tol = None if verify_tol is None else check_range("verify_tol", verify_tol, 0.0, None, True)
        self.tol = check_range("tol", tol, 0.0, None, low_open=True)
        self.max_iter = check_whole("max_iter", max_iter, 1)
        self.samples_per_interval = max(1, math.ceil(check_whole("verify_samples", verify_samples, 1) / self.intervals))
        self.point = _point_functions(self.cost)
        self.interval = _interval_function(self.point, self.degree, scheme)
        self.tau = collocation_coefficients(self.degree, scheme)[0]
        t0 = time.perf_counter()
        self._build()
        self.build_time_s = time.perf_counter() - t0
        self._verifier = None

    # -- NLP ----------------------------------------------------------------------------
    def _build(self) -> None:
        N, d = self.intervals, self.degree
        h = 1.0 / N
        par = ca.SX.sym("par", _NP)
        V, g, J = [], [], 0
        xk = ca.SX.sym("X0", 5)
        V.append(xk)
        x = ca.SX.sym("x", 5)
        depth = ca.Function("depth", [x], [-model.contact_point(x[2], x[3])[2]])  # cos(polar angle), eq. (1)
        for i in range(N):
            xc = ca.SX.sym(f"XC{i}", 5, d)
            w = ca.SX.sym(f"W{i}", 2)
            defect, x_end, Ji = self.interval(xk, xc, w, h, par)
            xk = ca.SX.sym(f"X{i + 1}", 5)
            V += [ca.vec(xc), w, xk]
            g += [ca.vec(defect), x_end - xk, depth.map(d)(xc).T, depth(xk)]
            J = J + Ji
        nlp = {"x": ca.vertcat(*V), "p": par, "f": J, "g": ca.vertcat(*g)}
        self.solver = ca.nlpsol("collocation", "ipopt", nlp, _ipopt_options(self.tol, self.max_iter))
        self._block = 5 * d + 2 + 5  # variables per interval after X0
        # constraint bounds: per interval 5d + 5 equalities, then d + 1 path constraints
        self._path_rows = np.concatenate([np.zeros(5 * d + 5, bool), np.ones(d + 1, bool)] * N)

    def _pack(self, guess: Guess) -> np.ndarray:
        N = self.intervals
        out = [guess.states[0]]
        for i in range(N):
            out += [guess.colloc[i].T.ravel(order="F"), guess.controls[i], guess.states[i + 1]]
        return np.concatenate(out)

    def _unpack(self, v: np.ndarray):
        N, d = self.intervals, self.degree
        states = np.zeros((N + 1, 5))
        colloc = np.zeros((N, d, 5))
        controls = np.zeros((N, 2))
        states[0] = v[:5]
        for i in range(N):
            blk = v[5 + i * self._block: 5 + (i + 1) * self._block]
            colloc[i] = blk[: 5 * d].reshape(d, 5)
            controls[i] = blk[5 * d: 5 * d + 2]
            states[i + 1] = blk[5 * d + 2:]
        return states, colloc, controls

    def _bounds(self, final):
        N, d = self.intervals, self.degree
        big, c = np.inf, self.contact_bound
        xb = np.array([big, big, c, c, big])
        wb = np.full(2, big)
        lb, ub = [np.zeros(5)], [np.zeros(5)]
        for i in range(N):
            lb += [np.tile(-xb, d), -wb]
            ub += [np.tile(xb, d), wb]
            if i == N - 1:
                lb.append(np.asarray(final, float))
                ub.append(np.asarray(final, float))
            else:
                lb.append(-xb)
                ub.append(xb)
        return np.concatenate(lb), np.concatenate(ub)

    # -- guesses ------------------------------------------------------------------------
    def _grid(self):
        """Normalized times of the interval starts (N,) and of the collocation points (N, d)."""
        N = self.intervals
        starts = np.arange(N) / N
        return starts, starts[:, None] + self.tau[None, 1:] / N

    def _check_guess(self, g: Guess) -> Guess:
        N, d = self.intervals, self.degree
        want = {"states": (N + 1, 5), "colloc": (N, d, 5), "controls": (N, 2)}
        for name, shape in want.items():
            arr = np.asarray(getattr(g, name), float)
            if arr.shape != shape or not np.all(np.isfinite(arr)):
                raise InputError(f"guess.{name} of shape {arr.shape} is not allowed: expected finite {shape}")
        return g

    def naive_guess(self, final) -> Guess:
        """Straight line: every state linear in time from 0 to ``final`` (u_o = v_o = 0), zero rates."""
        starts, tc = self._grid()
        final = np.asarray(final, float)
        s = np.append(starts, 1.0)
        return Guess(s[:, None] * final, tc[:, :, None] * final, np.zeros((self.intervals, 2)), "naive")

    def warm_guess(self, plan: Plan, horizon: float) -> Guess:
        """The geometric-phase plan with theta mapped to normalized time ``theta / (2 pi n)``.

        States are interpolated from the plan's CVODES samples; the rates on each
        interval are the mean rates of the plan over that interval.
        """
        tr = plan.trajectory(max(200, math.ceil(2 * self.intervals * self.degree / (2 * plan.steps))))
        tau = tr.theta / tr.theta[-1]
        cols = [tr.u_a / plan.radius, tr.v_a / plan.radius, tr.u_o, tr.v_o, tr.psi]
        interp = lambda s: np.stack([np.interp(s, tau, c) for c in cols], axis=-1)
        starts, tc = self._grid()
        states = interp(np.append(starts, 1.0))
        controls = np.diff(states[:, 2:4], axis=0) * self.intervals / horizon
        return Guess(states, interp(tc), controls, "warm")

    # -- solve --------------------------------------------------------------------------
    def solve(self, target, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
              horizon: float = 1.0, guess="warm", steps: int = 1, turns: int | None = None,
              smoothing: float = SMOOTHING) -> CollocationResult:
        """Solve the optimal-control problem to ``target = (u_a, v_a, psi)``; see :func:`collocate`."""
        k, radius = _resolve_k_radius(k, robot, radius)
        if self.cost.needs_robot and robot is None:
            raise InputError(f"cost = {self.cost.name!r} needs robot parameters: give a robot")
        if len(target) != 3:
            raise InputError(f"target = {target!r} is not allowed: give (u_a, v_a, psi)")
        u_t, v_t = (check_finite(n, x) / radius for n, x in zip(("u_a", "v_a"), target[:2]))
        psi_t = check_finite("psi", target[2])
        horizon = check_range("horizon", horizon, 0.0, None, low_open=True)
        smoothing = check_range("smoothing", smoothing, 0.0, None)
        if turns is not None:
            turns = check_whole("turns", turns, None)
        t0 = time.perf_counter()
        if isinstance(guess, Plan):
            warm_plan, guess_name = guess, "warm"
        elif guess == "warm":
            warm_plan = gp_plan((target[0], target[1], target[2]), _check_steps(steps), k=None if robot else k,
                                robot=robot, radius=radius)
            guess_name = "warm"
        elif guess == "naive" or isinstance(guess, Guess):
            warm_plan, guess_name = None, guess if isinstance(guess, str) else guess.name
        else:
            raise InputError(f"guess = {guess!r} is not allowed: choose one of {', '.join(GUESSES)}, a Plan or a Guess")
        if turns is None:
            turns = warm_plan.branch if warm_plan is not None else 0
        final = np.array([u_t, v_t, 0.0, 0.0, psi_t + 2 * math.pi * turns])
        if warm_plan is not None:
            g = self.warm_guess(warm_plan, horizon)
        elif isinstance(guess, Guess):
            g = self._check_guess(guess)
        else:
            g = self.naive_guess(final)
        guess_time = time.perf_counter() - t0
        par = self._par(k, horizon, smoothing, robot)
        lbx, ubx = self._bounds(final)
        x0 = np.clip(self._pack(g), lbx, ubx)
        lbg = np.where(self._path_rows, math.cos(self.contact_bound), 0.0)
        ubg = np.where(self._path_rows, np.inf, 0.0)
        t0 = time.perf_counter()
        sol = self.solver(x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=par)
        solve_time = time.perf_counter() - t0
        st = self.solver.stats()
        status, iters = str(st["return_status"]), int(st["iter_count"])
        log.info("collocation N=%d d=%d %s, %s guess: %s in %d iterations, %.3f s", self.intervals, self.degree,
                 self.scheme, guess_name, status, iters, solve_time)
        if not st["success"]:
            hint = _HINTS.get(status, "try guess='warm', more intervals or a longer horizon")
            if guess_name == "naive" and status in ("Infeasible_Problem_Detected", "Restoration_Failed"):
                hint = ("the naive guess rests at the south pole, where the linearized kinematics are not "
                        "controllable (displacement and psi need Lie brackets); use guess='warm'")
            raise SolverError(f"IPOPT did not solve the collocation problem (N = {self.intervals}, d = {self.degree}, "
                              f"{self.scheme}, cost {self.cost.name}, {guess_name} guess): {status} after {iters} "
                              f"iterations; hint: {hint}", status)
        v = np.array(sol["x"]).ravel()
        states, colloc, controls = self._unpack(v)
        t0 = time.perf_counter()
        ver = self.verify(controls, k, horizon, robot)
        verify_time = time.perf_counter() - t0
        target_r = np.array([u_t, v_t, final[4], 0.0, 0.0])
        reorder = lambda s: np.array([s[0], s[1], s[4], s[2], s[3]])
        residual = _residual(reorder(ver["xf"]), target_r)
        gval = np.array(sol["g"]).ravel()
        max_defect = float(np.max(np.maximum(lbg - gval, 0.0) + np.maximum(gval - ubg, 0.0)))
        if self.verify_tol is not None and not residual <= self.verify_tol:
            raise SolverError(f"the collocation solution (N = {self.intervals}, d = {self.degree}, {self.scheme}, cost "
                              f"{self.cost.name}) misses the target by {residual:.2e} > {self.verify_tol:.0e} when "
                              f"integrated by CVODES (IPOPT: {status}, {iters} iterations); hint: raise N or d, or "
                              f"lower contact_bound (now {self.contact_bound:.3g} rad)", "Verification_Failed")
        R = radius
        scale = np.array([R, R, 1.0, 1.0, 1.0])
        tgrid = np.arange(self.intervals + 1) / self.intervals * horizon
        _, tc = self._grid()
        X = ver["x"]
        traj = CollocationTrajectory(ver["t"], X[:, 0] * R, X[:, 1] * R, X[:, 2], X[:, 3], X[:, 4], ver["omega"],
                                     ver["contact"] * R)
        fin = reorder(ver["xf"]) * np.array([R, R, 1, 1, 1])
        stats = CollocationStats(status, True, iters, solve_time, guess_time, verify_time)
        return CollocationResult(
            self.cost.name, self.scheme, self.degree, self.intervals, horizon, k, radius,
            (float(target[0]), float(target[1]), psi_t), int(turns), guess_name, self.contact_bound, tgrid, states * scale,
            tc.ravel() * horizon, colloc.reshape(-1, 5) * scale, controls, float(sol["f"]),
            ver["length"] * R, ver["effort"], ver["rotor"], ver["peak"], fin, residual, max_defect, stats, traj)

    @staticmethod
    def _par(k, horizon, smoothing, robot):
        if robot is None:
            return np.array([k, horizon, smoothing, 1.0, 1.0, 1.0])
        return np.array([k, horizon, smoothing, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial])

    # -- verification ------------------------------------------------------------------
    def _verify_integrator(self):
        """CVODES over one interval of normalized length 1/N, ``samples_per_interval`` outputs.

        (One call per interval, with the interval's constant rates as a
        parameter, so that CVODES restarts at every control jump.)
        """
        if self._verifier is None:
            x = ca.SX.sym("x", 5)
            w = ca.SX.sym("w", 2)
            par = ca.SX.sym("par", _NP)
            T = par[1]
            xdot = model.contact_rhs(x, w, par[0])
            omega = model.realizable_omega(x[2], x[3], x[4], w[0], w[1], par[0])
            rotor = model.rotor_rates(omega, x[2], x[3], x[4], par[3], par[4], par[5])
            quad = ca.vertcat(ca.norm_2(xdot[:2]), ca.sumsqr(omega), ca.sumsqr(rotor))
            m = self.samples_per_interval
            grid = list(np.arange(1, m + 1) / (m * self.intervals))
            opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 100000}
            self._verifier = ca.integrator("verify", "cvodes", {"x": x, "p": ca.vertcat(w, par), "ode": T * xdot,
                                                                "quad": T * quad}, 0.0, grid, opts)
            self._omega = ca.Function("omega", [x, w, par], [omega])
            self._contact = ca.Function("contact", [x], [model.contact_point(x[2], x[3])])
        return self._verifier

    def verify(self, controls, k: float, horizon: float = 1.0, robot: Robot | None = None) -> dict:
        """Integrate contact_rhs from rest with piecewise-constant ``controls`` (N, 2) by CVODES.

        Returns a dict: ``t`` (M + 1,) [s], ``x`` (M + 1, 5) states in units of R,
        ``xf`` (5,), ``omega`` (M + 1, 3), ``contact`` (M + 1, 3) (unit sphere),
        ``length`` [R], ``effort`` [rad^2/s], ``rotor`` [rad^2/s] (nan without
        robot) and ``peak`` [rad/s].
        """
        F = self._verify_integrator()
        controls = np.asarray(controls, float)
        if controls.shape != (self.intervals, 2):
            raise InputError(f"controls of shape {controls.shape} are not allowed: expected ({self.intervals}, 2)")
        m = self.samples_per_interval
        par = self._par(k, horizon, 0.0, robot)
        x = np.zeros(5)
        xs, q = [x[:, None]], np.zeros(3)
        for w in controls:
            r = F(x0=x, p=np.concatenate([w, par]))
            xi = np.array(r["xf"])
            xs.append(xi)
            q += np.array(r["qf"])[:, -1]
            x = xi[:, -1]
        xs = np.hstack(xs)
        M = xs.shape[1] - 1
        u = np.repeat(controls, m, axis=0).T
        # omega at each sample with the rate of the sample interval ending there (the first at t = 0);
        # omega jumps with the control at interval boundaries, so the peak takes both sides
        om = np.array(self._omega.map(M + 1)(xs, np.hstack([u[:, :1], u]), par)).T
        om_left = np.array(self._omega.map(M)(xs[:, :-1], u, par)).T
        peak = float(max(np.linalg.norm(om, axis=1).max(), np.linalg.norm(om_left, axis=1).max()))
        contact = np.array(self._contact.map(M + 1)(xs)).T
        return {"t": np.arange(M + 1) / M * horizon, "x": xs.T, "xf": xs[:, -1].copy(), "omega": om,
                "contact": contact, "length": float(q[0]), "effort": float(q[1]),
                "rotor": float(q[2]) if robot is not None else float("nan"), "peak": peak}

    # -- the transcription as an integrator (for convergence studies) -------------------
    def simulate(self, controls, k: float, horizon: float = 1.0, x0=None) -> np.ndarray:
        """Solve the collocation equations interval by interval with fixed controls.

        This is the transcription used as a ``d``-stage implicit Runge-Kutta
        method (Gauss-Legendre or Radau IIA): no optimization. Returns the
        states at the interval boundaries, shape (N + 1, 5), units of R.
        """
        controls = np.asarray(controls, float)
        N, d = controls.shape[0], self.degree
        xc = ca.SX.sym("xc", 5, d)
        x0s = ca.SX.sym("x0", 5)
        w = ca.SX.sym("w", 2)
        h = ca.SX.sym("h")
        par = ca.SX.sym("par", _NP)
        defect, x_end, _ = self.interval(x0s, xc, w, h, par)
        res = ca.Function("res", [ca.vec(xc), ca.vertcat(x0s, w, h, par)], [ca.vec(defect)])
        rf = ca.rootfinder("sim", "newton", res, {"abstol": 1e-15, "abstolStep": 1e-16, "max_iter": 50,
                                                   "error_on_fail": False})
        end = ca.Function("end", [ca.vec(xc), x0s], [x_end])
        p = self._par(k, horizon, 0.0, None)
        x = np.zeros(5) if x0 is None else np.asarray(x0, float)
        out = [x]
        for i in range(N):
            z0 = np.tile(x, d)
            z = rf(z0, np.concatenate([x, controls[i], [1.0 / N], p]))
            x = np.array(end(z, x)).ravel()
            out.append(x)
        return np.array(out)


def _residual(final, target) -> float:
    err = np.array([final[0] - target[0], final[1] - target[1], wrap(final[2] - target[2]), final[3], final[4]])
    return float(np.linalg.norm(err))




@lru_cache(maxsize=8)
def _planner(intervals, degree, scheme, cost, contact_bound) -> CollocationPlanner:
    return CollocationPlanner(intervals, degree, scheme, cost, contact_bound)


def collocate(target, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
              cost: str = "path_length", intervals: int = 100, degree: int = 3, scheme: str = "legendre",
              horizon: float = 1.0, guess="warm", steps: int = 1, turns: int | None = None,
              smoothing: float = SMOOTHING, contact_bound: float = CONTACT_BOUND) -> CollocationResult:
    """Optimal realizable motion to a target by direct collocation.

    Minimizes ``int_0^T L dt`` subject to the contact kinematics (6)-(10) with
    omega from (18), (19) and the realizability condition (13)
    (:func:`rollplan.model.contact_rhs`), from rest at the origin to
    ``(u_a, v_a, psi) = target`` with ``u_o = v_o = 0``.

    Parameters
    ----------
    target : (u_a, v_a, psi)
        [length unit of ``radius``] and [rad].
    k : float, optional
        Inertia ratio (14), k >= 0. Or give ``robot``.
    robot : Robot, optional
        Sets k and the radius; needed for ``cost="rotor_effort"``.
    radius : float, optional
        Sphere radius (default 1, or the robot's).
    cost : str
        Name in :data:`COSTS`.
    intervals, degree, scheme
        N, d and ``"legendre"`` or ``"radau"``.
    horizon : float
        T > 0 [s].
    guess : ``"warm"``, ``"naive"``, a Plan or a Guess
        ``"warm"`` plans by geometric phase (``steps`` traces) first.
    steps : int
        Traces of the warm-start plan.
    turns : int, optional
        Whole turns m added to psi (default: the warm plan's branch, else 0).
    smoothing : float
        eps of the path-length integrand.
    contact_bound : float
        Bound on the contact point's polar angle from the south pole [rad].

    Returns
    -------
    CollocationResult

    Raises
    ------
    InputError
        Bad input.
    NoPlanError
        No geometric-phase plan for the warm start.
    SolverError
        IPOPT failed; ``.status`` is its return status.
    """
    return _planner(intervals, degree, scheme, cost, contact_bound).solve(
        target, k, robot, radius, horizon, guess, steps, turns, smoothing)
