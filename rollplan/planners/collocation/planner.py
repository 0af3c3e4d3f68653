"""Direct-collocation optimal-control planner on the same symbolic model.

On a fixed horizon find contact rates ``w(t) = (u_o_dot, v_o_dot)`` minimizing ``J = int_0^T L(x, w) dt``
subject to the realizable contact kinematics ``x_dot = f(x, w; k)`` (Montana's (6)-(10) with (18)-(19) and the
spin from (13), :func:`rollplan.core.model.contact_rhs`), ``x(0) = start``,
``x(T) = goal + (0, 0, 2 pi m, 0, 0)``, the contact point within ``contact_bound`` of the south pole. The NLP
(:mod:`.transcription`, costs by name in :data:`.costs.COSTS`) is solved by IPOPT; the controls are corrected
by Gauss-Newton through CVODES and every solution is certified by an independent CVODES integration.

Problem, costs, correction and certification: docs/design/collocation.md.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ... import interrupts
from ...core import model
from ...core.plane import wrap_exact
from ...errors import InputError, SolverError, check_choice, check_range, check_whole
from ...measures import cost_key
from ...problem import Problem, State, check_steps
from ...result import CERTIFICATE_TOLERANCE, Certificate, Measures, SolverStats, Trajectory, certify
from ...robot import Robot
from ..geometric.composed import as_composed, default_composed_planner
from ..method import Method, with_steps
from .costs import COSTS, N_PAR, Cost
from .transcription import (
    CORRECTION_TOL,
    JACOBIAN_SUBSTEPS,
    SCHEMES,
    CollocationRun,
    Guess,
    Transcription,
    check_contact_bound,
    fixed_step,
    gauss_newton,
    ipopt_options,
    sensitivity_step,
)

__all__ = ["SCHEMES", "COSTS", "GUESSES", "CONTACT_BOUND", "SMOOTHING", "TOLERANCE", "Guess", "Certifier",
           "CollocationSolution", "CollocationResult", "CollocationPlanner", "collocate"]

log = logging.getLogger(__name__)

#: Default bound on the contact point's polar angle from the south pole [rad] (75 deg).
#: (8) and (13) are singular on the equator (90 deg), where the spin (13) grows like
#: 1 / cos(polar angle); unbounded, path-length optima ride that singularity.
CONTACT_BOUND = math.radians(75.0)
#: Default smoothing eps of the path-length integrand [(R/s)^2].
SMOOTHING = 1e-4
#: Default largest certified residual of a returned solution (units of R, rad), as for the geometric planner.
TOLERANCE = CERTIFICATE_TOLERANCE
#: Least number of intervals: 2N contact rates for the 5 end conditions.
MIN_INTERVALS = 3

_HINTS = {
    "Maximum_Iterations_Exceeded": "raise max_iter, or warm-start from the geometric-phase plan (guess='warm')",
    "Infeasible_Problem_Detected": "the boundary conditions look unreachable within the contact bound; "
                                   "try guess='warm', more intervals or a larger contact_bound",
    "Restoration_Failed": "IPOPT lost feasibility; try guess='warm' or more intervals",
    "Error_In_Step_Computation": "the KKT system is singular; try guess='warm' or another cost",
    "Invalid_Number_Detected": "NaN/Inf in the model: the contact point reached the equator (u_o or v_o = pi/2); "
                               "lower contact_bound or try guess='warm'",
}


@dataclass(frozen=True)
class CollocationSolution:
    """The NLP's solution on the collocation grid.

    Attributes
    ----------
    t : ndarray, shape (N + 1,)
        Interval boundaries [s].
    states : ndarray, shape (N + 1, 5)
        States (u_a, v_a, psi, u_o, v_o) at ``t`` [length unit, rad].
    t_colloc : ndarray, shape (N * d,)
        Collocation times [s].
    states_colloc : ndarray, shape (N * d, 5)
        States at ``t_colloc``.
    controls : ndarray, shape (N, 2)
        (u_o_dot, v_o_dot), constant on each interval [rad/s], after the Newton correction.
    objective : float
        The cost of ``controls`` (CVODES quadrature) [cost unit; lengths in R].
    max_defect : float
        Largest violation of the NLP's constraints at the solution [units of R, rad].
    """

    t: np.ndarray
    states: np.ndarray
    t_colloc: np.ndarray
    states_colloc: np.ndarray
    controls: np.ndarray
    objective: float
    max_defect: float


@dataclass(frozen=True)
class CollocationResult(CollocationRun):
    """A certified direct-collocation solution (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem, cost, transcription, horizon, turns, guess, contact_bound
        As in :class:`.transcription.CollocationRun` (``cost`` a name in :data:`COSTS`).
    solution : CollocationSolution
    measures : Measures
    certificate : Certificate
        CVODES integration with the optimized controls from the start state.
    stats : SolverStats
        IPOPT's status and iterations; ``time_s`` is the IPOPT call, ``details``
        the guess and certification times and ``uncorrected_error``, the largest end-state error of IPOPT's
        controls integrated by CVODES before the Newton correction (the transcription's error).
    trajectory : Trajectory
        The certified motion on a uniform time grid (``parameter == "t"``;
        ``segment`` is the collocation interval).
    omega : ndarray, shape (M, 3)
        Angular velocity at the samples of ``trajectory`` [rad/s], plane frame.
    """

    solution: CollocationSolution
    measures: Measures
    certificate: Certificate
    stats: SolverStats
    trajectory: Trajectory
    omega: np.ndarray

    @property
    def path_length(self) -> float:
        return self.measures.path_length

    def sample(self, samples: int | None = None) -> Trajectory:
        """The certified motion sampled by CVODES, ``samples`` samples in all, both ends included (evenly by
        index among the integration's samples); None: :attr:`trajectory` as certified."""
        if samples is None:
            return self.trajectory
        samples = check_whole("samples", samples, 2, 10**7)
        if samples <= self.trajectory.s.size:
            return self.trajectory.subsampled(samples)
        tr = self.transcription
        per = max(1, math.ceil((samples - 1) / tr.intervals))
        p = self.problem
        ver = _verifier(tr.intervals, per).verify(self.solution.controls, p.k, self.horizon, p.robot,
                                                  p.scaled(p.start).array())
        R = self.problem.radius
        return Trajectory(ver["t"], ver["x"] * np.array([R, R, 1.0, 1.0, 1.0]), ver["segment"], R,
                          "t").subsampled(samples)


def _point_function(cost: Cost) -> ca.Function:
    """The model at one point: ``(x, w, par) -> (xdot, L, omega)``."""
    x = ca.SX.sym("x", 5)
    w = ca.SX.sym("w", 2)
    par = ca.SX.sym("par", N_PAR)
    xdot = model.contact_rhs(x, w, par[0])
    omega = model.realizable_omega(x[3], x[4], x[2], w[0], w[1], par[0])
    return ca.Function("point", [x, w, par], [xdot, cost.integrand(x, w, xdot, omega, par), omega],
                       ["x", "w", "par"], ["xdot", "L", "omega"])


def _naive_guess(planner: CollocationPlanner, problem: Problem, start, final, horizon: float, warm_start):
    """Straight line: every state linear in time from ``start`` to ``final``, zero rates."""
    starts, tc = planner.transcription.grid()
    s = np.append(starts, 1.0)
    lerp = lambda t: start + t[..., None] * (final - start)  # noqa: E731
    return Guess(lerp(s), lerp(tc), np.zeros((planner.transcription.intervals, 2)), "naive")


def _check_warm_start(plan, problem: Problem) -> None:
    """InputError unless ``plan`` is a geometric-phase plan (of one leg or composed) for the same k,
    radius, start and goal."""
    if getattr(plan, "method", None) != "geometric" or not hasattr(plan, "problem"):
        raise InputError(f"warm_start = {plan!r:.60} is not allowed: give a geometric-phase Plan or ComposedPlan")
    same = (plan.problem.k == problem.k and plan.problem.radius == problem.radius
            and tuple(plan.problem.start) == tuple(problem.start)
            and np.allclose(plan.problem.goal, problem.goal, rtol=0.0, atol=1e-12 * problem.radius))
    if not same:
        raise InputError(f"warm_start was planned for another problem ({plan.problem.describe()}); "
                         f"this problem is {problem.describe()}")


def _geometric_plan(problem: Problem):
    """The geometric-phase plan of the problem (the warm start): one leg of figure eights from rest at the
    origin to a goal at the pole, else a composed plan (rolls, turns in place, two legs)."""
    return default_composed_planner().solve(problem)


def _whole_turns(plan) -> int:
    """Whole turns m of psi of a certified plan: its motion ends at ``goal.psi + 2 pi m``."""
    return round((plan.final.psi - plan.goal.psi) / (2 * math.pi))


def _warm_guess(planner: CollocationPlanner, problem: Problem, start, final, horizon: float, warm_start):
    """The geometric-phase plan ``warm_start`` with its path parameter mapped to time.

    States are interpolated from the plan's samples at normalized time ``s / s_end`` (every piece of
    the contact path, e.g. a leaf of a figure eight, takes the same time); the rates on each interval
    are the mean rates of the plan over that interval.
    """
    p = as_composed(warm_start)
    tr = planner.transcription
    pieces = max(len(p.pieces), 1)   # a polished plan is one motion without closed-form pieces
    per_piece = max(200, math.ceil(2 * tr.intervals * tr.degree / pieces))
    traj = p.sample(pieces * per_piece + 1)
    if traj.s[-1] == 0.0:   # the empty motion: stay at the start
        return _naive_guess(planner, problem, start, final, horizon, None)
    tau = traj.s / traj.s[-1]
    cols = traj.state / np.array([p.radius, p.radius, 1.0, 1.0, 1.0])
    interp = lambda s: np.stack([np.interp(s, tau, c) for c in cols.T], axis=-1)  # noqa: E731
    starts, tc = tr.grid()
    states = interp(np.append(starts, 1.0))
    controls = np.diff(states[:, 3:5], axis=0) * tr.intervals / horizon
    return Guess(states, interp(tc), controls, "warm")


#: Initial guesses by name: ``make(planner, problem, start, final, horizon, warm_start) -> Guess``
#: (start and final in units of R).
GUESSES = {"naive": _naive_guess, "warm": _warm_guess}


_UNSET = object()


class CollocationPlanner(Method):
    """Direct-collocation planner (problem class): the NLP is built once; the method ``"collocation"`` of
    :data:`rollplan.planners.METHODS`.

    Parameters
    ----------
    intervals, degree, scheme
        The :class:`Transcription`: N in [:data:`MIN_INTERVALS`, 100000], d in 1..9, ``"legendre"`` or
        ``"radau"``.
    cost : str
        Name in :data:`COSTS`.
    contact_bound : float
        Bound on the polar angle of the contact point from the south pole [rad],
        in (0, pi/2): ``-z >= cos(bound)`` for the contact point (1) at every
        collocation point and interval end (hence also ``|u_o|, |v_o| <= bound``).
    tol : float
        IPOPT's tolerance (also its constraint-violation tolerance), in (0, 1e-2].
    max_iter : int
        IPOPT's iteration limit, in [1, 100000].
    verify_samples : int
        Least number of points of the certified trajectory, in [1, 10^6].
    verify_tol : float or None
        Largest certified residual of a returned solution; a larger one raises
        SolverError with status ``"Verification_Failed"``. None: report only.
    horizon : float
        T > 0 [s].
    guess : str
        Initial guess, a name in :data:`GUESSES`.
    turns : int or None
        Whole turns m added to psi (None: the warm plan's, else 0).
    smoothing : float
        eps of the path-length integrand, >= 0.
    warm_start : Plan or ComposedPlan or None
        The geometric-phase plan the ``"warm"`` guess follows (None: planned for the problem).
    steps : int or None
        Figure eights of that warm plan (None: the problem's ``steps``).

    Attributes
    ----------
    solver : casadi.Function
        The IPOPT NLP solver (built once).
    path_rows : ndarray of bool
        Rows of the NLP's constraints that are the contact bound (the others are equalities).
    """

    name = "collocation"

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 cost: str = "path_energy", contact_bound: float = CONTACT_BOUND, tol: float = 1e-10,
                 max_iter: int = 500, verify_samples: int = 1000, verify_tol: float | None = TOLERANCE, *,
                 horizon: float = 1.0, guess: str = "warm", turns: int | None = None, smoothing: float = SMOOTHING,
                 warm_start=None, steps: int | None = None) -> None:
        for name, value in self._solve_options(horizon, guess, turns, smoothing, warm_start).items():
            setattr(self, name, value)
        self.steps = None if steps is None else check_steps(steps)
        check_whole("intervals", intervals, MIN_INTERVALS, 100000)
        self.transcription = Transcription(intervals, degree, scheme)
        self.cost = COSTS[cost_key(cost, COSTS)]
        self.contact_bound = check_range("contact_bound", contact_bound, 0.0, math.pi / 2, True, True)
        self.verify_tol = None if verify_tol is None else check_range("verify_tol", verify_tol, 0.0, None, True)
        self.tol = check_range("tol", tol, 0.0, 1e-2, low_open=True)
        self.max_iter = check_whole("max_iter", max_iter, 1, 100000)
        verify_samples = check_whole("verify_samples", verify_samples, 1, 10**6)
        self.samples_per_interval = max(1, math.ceil(verify_samples / self.transcription.intervals))
        self.point = _point_function(self.cost)
        t0 = time.perf_counter()
        nlp, self.path_rows = self.transcription.contact_nlp(self.point, N_PAR)
        self.solver = ca.nlpsol("collocation", "ipopt", nlp, {**ipopt_options(self.tol, self.max_iter),
                                                              **self.transcription.contact_derivatives(self.point,
                                                                                                       N_PAR)})
        self.build_time_s = time.perf_counter() - t0

    @staticmethod
    def _solve_options(horizon, guess, turns, smoothing, warm_start) -> dict:
        """The per-solve options, validated (the warm start against the problem at the solve)."""
        return {"horizon": check_range("horizon", horizon, 0.0, None, low_open=True),
                "guess": check_choice("guess", guess, GUESSES),
                "turns": None if turns is None else check_whole("turns", turns),
                "smoothing": check_range("smoothing", smoothing, 0.0, None), "warm_start": warm_start}

    # -- solve --------------------------------------------------------------------------
    def solve(self, problem: Problem, horizon=_UNSET, guess=_UNSET, turns=_UNSET, smoothing=_UNSET,
              warm_start=_UNSET) -> CollocationResult:
        """Solve the optimal-control problem for ``problem``; see :func:`collocate`.

        The arguments after ``problem``, when given, override the planner's options of the same names for
        this solve (the NLP is built once, in the constructor).
        """
        given = {"horizon": horizon, "guess": guess, "turns": turns, "smoothing": smoothing,
                 "warm_start": warm_start}
        planner = self
        if any(v is not _UNSET for v in given.values()):
            mine = {n: getattr(self, n) for n in given}
            planner = self._with(**self._solve_options(**{n: mine[n] if v is _UNSET else v
                                                          for n, v in given.items()}))
        return Method.solve(planner, problem)

    def _check(self, problem) -> Problem:
        problem = super()._check(problem)
        problem = with_steps(problem, self.steps)
        self._boundary(problem, 0 if self.turns is None else self.turns)   # bad input is refused before any work
        if self.warm_start is not None:
            _check_warm_start(self.warm_start, problem)
        return problem

    def _solve(self, problem: Problem) -> CollocationResult:
        t0 = time.perf_counter()
        warm_start, turns = self.warm_start, self.turns
        if self.guess == "warm" and warm_start is None:
            warm_start = _geometric_plan(problem)
        if turns is None:
            turns = _whole_turns(warm_start) if warm_start is not None else 0
        start, final = self._boundary(problem, turns)
        g = GUESSES[self.guess](self, problem, start, final, self.horizon, warm_start)
        return self._run(problem, g, self.horizon, turns, self.smoothing, time.perf_counter() - t0)

    def solve_from(self, problem: Problem, initial: Guess, horizon: float = 1.0, turns: int = 0,
                   smoothing: float = SMOOTHING) -> CollocationResult:
        """Solve from an explicit initial guess (e.g. a previous solution's arrays)."""
        problem = Method._check(self, problem)
        result = self._run(problem, self.transcription.check_guess(initial), horizon, turns, smoothing, 0.0)
        return result

    def _boundary(self, problem: Problem, turns) -> tuple:
        if not isinstance(problem, Problem):
            raise InputError(f"problem = {problem!r} is not allowed: give a rollplan.Problem")
        if self.cost.needs_robot and problem.robot is None:
            raise InputError(f"cost = {self.cost.name!r} needs robot parameters: give a robot "
                             "(the robot argument; --robot FILE.toml on the command line)")
        turns = check_whole("turns", turns)
        check_contact_bound(problem, self.contact_bound)
        start = problem.scaled(problem.start).array()
        final = problem.scaled(problem.goal).array()
        # psi is an angle: start and goal reduced exactly by whole turns (a psi of 1e8 keeps full accuracy);
        # the motion turns psi by goal - start + 2 pi turns, as given
        start[2], start_turns = wrap_exact(start[2])
        reduced, goal_turns = wrap_exact(final[2])
        final[2] = reduced + 2 * math.pi * (turns + goal_turns - start_turns)
        return start, final

    def _run(self, problem, g: Guess, horizon, turns, smoothing, guess_time) -> CollocationResult:
        start, final = self._boundary(problem, turns)
        horizon = check_range("horizon", horizon, 0.0, None, low_open=True)
        smoothing = check_range("smoothing", smoothing, 0.0, None)
        tr = self.transcription
        par = _parameters(problem.k, horizon, smoothing, problem.robot)
        x0, lbx, ubx, lbg, ubg = tr.contact_bounds(g, start, final, self.contact_bound, self.path_rows)
        t0 = time.perf_counter()
        sol = interrupts.call(self.solver, x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=par)
        solve_time = time.perf_counter() - t0
        st = self.solver.stats()
        status, iters = str(st["return_status"]), int(st["iter_count"])
        where = (f"N = {tr.intervals}, d = {tr.degree}, {tr.scheme}, cost {self.cost.name}, {g.name} guess")
        log.info("collocation %s: %s in %d iterations, %.3f s", where, status, iters, solve_time)
        if not st["success"]:
            hint = _HINTS.get(status, "try guess='warm', more intervals or a longer horizon")
            if g.name == "naive" and status in ("Infeasible_Problem_Detected", "Restoration_Failed"):
                hint = ("the naive guess rests at the south pole, where the linearized kinematics are not "
                        "controllable (displacement and psi need Lie brackets); use guess='warm'")
            raise SolverError(f"IPOPT did not solve the collocation problem ({where}): {status} after {iters} "
                              f"iterations; hint: {hint}", status)
        states, colloc, controls = tr.unpack(np.array(sol["x"]).ravel())
        t0 = time.perf_counter()
        # the Jacobian by eighth-order steps, the end error by CVODES (rest.correct)
        controls, objective, miss, uncorrected = gauss_newton(
            _newton_step(self.cost, True, JACOBIAN_SUBSTEPS), controls, start, final, par, CORRECTION_TOL,
            plain=_newton_step(self.cost, False), fallback=_newton_step(self.cost))
        ver = self.verify(controls, problem.k, horizon, problem.robot, start)
        verify_time = time.perf_counter() - t0
        R = problem.radius
        scale = np.array([R, R, 1.0, 1.0, 1.0])
        fin = State(*(ver["xf"] * scale))
        residual = problem.residual(fin)  # psi is compared as an angle: the turns do not count
        tol = self.verify_tol if self.verify_tol is not None else math.inf
        cert = certify(problem, fin, "cvodes", tolerance=tol, residual=residual)
        if not cert.passed:
            raise SolverError(f"the collocation solution ({where}) misses the goal by {residual:.2e} > {tol:.0e} "
                              f"when integrated by CVODES (IPOPT: {status}, {iters} iterations; Newton correction to "
                              f"{miss:.1e}); hint: raise N or d, "
                              f"or lower contact_bound (now {self.contact_bound:.3g} rad)", "Verification_Failed")
        gval = np.array(sol["g"]).ravel()
        max_defect = float(np.max(np.maximum(lbg - gval, 0.0) + np.maximum(gval - ubg, 0.0)))
        _, tc = tr.grid()
        solution = CollocationSolution(np.arange(tr.intervals + 1) / tr.intervals * horizon, states * scale,
                                       tc.ravel() * horizon, colloc.reshape(-1, 5) * scale, controls,
                                       objective, max_defect)
        measures = Measures(ver["length"] * R, ver["effort"], ver["rotor"], ver["peak"])
        traj = Trajectory(ver["t"], ver["x"] * scale, ver["segment"], R, "t")
        stats = SolverStats("ipopt", status, iters, solve_time,
                            {"guess_time_s": guess_time, "verify_time_s": verify_time,
                             "uncorrected_error": uncorrected})
        return CollocationResult(problem=problem, cost=self.cost.name, transcription=tr, horizon=horizon,
                                 turns=int(turns), guess=g.name, contact_bound=self.contact_bound, solution=solution,
                                 measures=measures, certificate=cert, stats=stats, trajectory=traj, omega=ver["omega"])

    @staticmethod
    def parameters(k, horizon, smoothing=SMOOTHING, robot=None) -> np.ndarray:
        """The NLP parameter vector ``(k, T, eps, j_xx, j_zz, j_r)`` (inertias 1 without a robot)."""
        return _parameters(k, horizon, smoothing, robot)

    # -- certification -------------------------------------------------------------------
    def verify(self, controls, k: float, horizon: float = 1.0, robot: Robot | None = None, x0=None) -> dict:
        """:meth:`Certifier.verify` with this planner's intervals and samples per interval."""
        return _verifier(self.transcription.intervals, self.samples_per_interval).verify(controls, k, horizon,
                                                                                         robot, x0)

    def simulate(self, controls, k: float, horizon: float = 1.0, x0=None) -> np.ndarray:
        """The transcription as an implicit Runge-Kutta method with fixed controls (:meth:`Transcription.simulate`)."""
        return self.transcription.simulate(self.point, N_PAR, controls, _parameters(k, horizon, 0.0, None), x0)


@lru_cache(maxsize=8)
def _newton_step(cost: Cost, jacobians: bool = True, substeps: int | None = None) -> ca.Function:
    """:func:`.transcription.sensitivity_step` of ``x' = T f(x, w)`` (normalized time), the quadrature ``T L``
    (with ``substeps``, its :func:`.transcription.fixed_step`)."""
    x, w, par = ca.SX.sym("x", 5), ca.SX.sym("w", 2), ca.SX.sym("par", N_PAR)
    xdot, L, _ = _point_function(cost)(x, w, par)
    if substeps is not None:
        return fixed_step("collocation_newton", x, w, par, par[1] * xdot, par[1] * L, substeps, jacobians)
    return sensitivity_step("collocation_newton", x, w, par, par[1] * xdot, par[1] * L, jacobians)


def _parameters(k, horizon, smoothing, robot) -> np.ndarray:
    """The NLP parameter vector ``(k, T, eps, j_xx, j_zz, j_r)`` (inertias 1 without a robot)."""
    if robot is None:
        return np.array([k, horizon, smoothing, 1.0, 1.0, 1.0])
    return np.array([k, horizon, smoothing, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial])


class Certifier:
    """CVODES integration of the model with piecewise-constant contact rates, interval by interval.

    One integrator call per interval of normalized length 1/N, with the interval's constant rates as a
    parameter, so that CVODES restarts at every control jump; ``samples_per_interval`` outputs each.
    Independent of the transcription: it integrates :func:`~rollplan.core.model.contact_rhs` itself.
    """

    def __init__(self, intervals: int, samples_per_interval: int) -> None:
        self.intervals = check_whole("intervals", intervals, 1, 100000)
        self.samples_per_interval = check_whole("samples_per_interval", samples_per_interval, 1, 10**6)
        intervals, samples_per_interval = self.intervals, self.samples_per_interval
        x = ca.SX.sym("x", 5)
        w = ca.SX.sym("w", 2)
        par = ca.SX.sym("par", N_PAR)
        T = par[1]
        xdot = model.contact_rhs(x, w, par[0])
        omega = model.realizable_omega(x[3], x[4], x[2], w[0], w[1], par[0])
        rotor = model.rotor_rates(omega, x[3], x[4], x[2], par[3], par[4], par[5])
        quad = ca.vertcat(ca.norm_2(xdot[:2]), ca.sumsqr(omega), ca.sumsqr(rotor))
        m = samples_per_interval
        grid = list(np.arange(1, m + 1) / (m * intervals))
        opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 100000}
        self._integrator = ca.integrator("verify", "cvodes", {"x": x, "p": ca.vertcat(w, par), "ode": T * xdot,
                                                              "quad": T * quad}, 0.0, grid, opts)
        self._omega = ca.Function("omega", [x, w, par], [omega])

    def verify(self, controls, k: float, horizon: float = 1.0, robot: Robot | None = None, x0=None) -> dict:
        """Integrate :func:`~rollplan.core.model.contact_rhs` from ``x0`` (default the zero state)
        with piecewise-constant ``controls`` (N, 2) by CVODES. The contact rates jump to the first
        control at t = 0: the motion does not start at rest (for rest to rest see :mod:`.rest`).

        Returns a dict: ``t`` (M + 1,) [s], ``x`` (M + 1, 5) states in units of R,
        ``segment`` (M + 1,) interval of each sample, ``xf`` (5,), ``omega`` (M + 1, 3),
        ``length`` [R], ``effort`` [rad^2/s], ``rotor`` [rad^2/s] (nan without
        robot) and ``peak`` [rad/s].
        """
        controls = np.asarray(controls, float)
        N, m = self.intervals, self.samples_per_interval
        if controls.shape != (N, 2):
            raise InputError(f"controls of shape {controls.shape} are not allowed: expected ({N}, 2)")
        par = _parameters(k, horizon, 0.0, robot)
        x = np.zeros(5) if x0 is None else np.asarray(x0, float)
        xs, q = [x[:, None]], np.zeros(3)
        for w in controls:
            r = interrupts.call(self._integrator, x0=x, p=np.concatenate([w, par]))
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
        segment = np.concatenate([[0], np.repeat(np.arange(N), m)])
        return {"t": np.arange(M + 1) / M * horizon, "x": xs.T, "segment": segment, "xf": xs[:, -1].copy(),
                "omega": om, "length": float(q[0]), "effort": float(q[1]),
                "rotor": float(q[2]) if robot is not None else float("nan"), "peak": peak}


@lru_cache(maxsize=8)
def _verifier(intervals: int, samples_per_interval: int) -> Certifier:
    return Certifier(intervals, samples_per_interval)


@lru_cache(maxsize=8)
def _planner(intervals, degree, scheme, cost, contact_bound) -> CollocationPlanner:
    return CollocationPlanner(intervals, degree, scheme, cost, contact_bound)


def collocate(target, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
              cost: str = "path_energy", intervals: int = 100, degree: int = 3, scheme: str = "legendre",
              horizon: float = 1.0, guess: str = "warm", steps: int = 1, turns: int | None = None,
              smoothing: float = SMOOTHING, contact_bound: float = CONTACT_BOUND, start=None,
              warm_start=None) -> CollocationResult:
    """Optimal realizable motion to a target by direct collocation.

    Minimizes ``int_0^T L dt`` subject to the contact kinematics (6)-(10) with
    omega from (18), (19) and the realizability condition (13)
    (:func:`rollplan.core.model.contact_rhs`), from ``start`` (default rest at
    the origin) to ``target``.

    Parameters
    ----------
    target : State or sequence
        Goal: (u_a, v_a, psi) [length unit of ``radius``, rad] with the contact
        point at the pole, or a full state (u_a, v_a, psi, u_o, v_o).
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
    guess : str
        Name in :data:`GUESSES`: ``"warm"`` plans by geometric phase (``steps``
        traces) first, or follows ``warm_start``; ``"naive"`` is a straight line.
    steps : int
        Traces of the warm-start plan.
    turns : int, optional
        Whole turns m added to psi (default: the warm plan's, else 0).
    smoothing : float
        eps of the path-length integrand.
    contact_bound : float
        Bound on the contact point's polar angle from the south pole [rad].
    start : State or sequence, optional
        Start state (default zero).
    warm_start : Plan or ComposedPlan, optional
        The geometric-phase plan the warm guess follows.

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
    problem = Problem(target, start=start if start is not None else State(), k=k, robot=robot, radius=radius,
                      steps=steps)
    return _planner(intervals, degree, scheme, cost, contact_bound).solve(
        problem, horizon, guess, turns, smoothing, warm_start)
