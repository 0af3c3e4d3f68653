"""Rest-to-rest direct collocation: the contact accelerations are the controls.

On a fixed horizon find piecewise-constant contact accelerations ``a(t) = (u_o'', v_o'')`` minimizing
``J = int_0^T L dt`` subject to the realizable contact kinematics and ``(u_o', v_o')' = a``, with the state
``x = (u_a, v_a, psi, u_o, v_o, u_o', v_o')`` at rest at both ends: ``x(0) = (start, 0, 0)``,
``x(T) = (goal + (0, 0, 2 pi m, 0, 0), 0, 0)``. Solved in normalized time (T = 1) and scaled exactly
(``J(T) = J(1) T^p``, :data:`COST_POWERS`); 7 end conditions need :data:`MIN_INTERVALS` = 4 intervals. The
controls are corrected by Gauss-Newton (:func:`correct`) and certified by CVODES (:func:`certify`).

Problem, time scaling, costs, correction and certification: docs/design/collocation.md.
"""

from __future__ import annotations

import copy
import logging
import math
import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ... import interrupts
from ...core import model
from ...errors import InputError, SolverError, check_range, check_whole
from ...measures import cost_key, measure
from ...problem import Problem, State
from ...result import CERTIFICATE_TOLERANCE, Certificate, SolverStats, Trajectory
from ...result import certify as certificate_of
from ...robot import Robot
from ...timeseries import TimeSeries
from ..method import Method
from .costs import N_PAR
from .rest_nlp import RestTranscription
from .transcription import (
    CORRECTION_TOL,
    JACOBIAN_SUBSTEPS,
    CollocationRun,
    Guess,
    Transcription,
    check_contact_bound,
    fixed_step,
    gauss_newton,
    interval_derivatives,
    interval_nlp,
    ipopt_options,
    sensitivity_step,
)

__all__ = ["REST_COSTS", "RestResult", "NlpSolution", "RestToRestPlanner", "MinimumTimePlanner", "RestToRestMethod",
           "MinimumTimeMethod", "certify", "rest_parameters",
           "motion_function", "naive_guess", "guess_from_samples", "correct", "check_horizon",
           "polar_angles", "check_intervals", "TOLERANCE", "MIN_INTERVALS", "MAX_INTERVALS", "MEMORY_GB",
           "HORIZON_RANGE", "COST_POWERS", "REST_IPOPT_OPTIONS"]

log = logging.getLogger(__name__)

#: Running costs of the rest-to-rest problem, by name: ``L(xdot, omega, torque, par)`` (``"path_energy"`` was
#: ``"path_length"``: :data:`rollplan.measures.RENAMED_COSTS`).
REST_COSTS = {
    "path_energy": lambda xdot, omega, torque, par: xdot[0] ** 2 + xdot[1] ** 2,
    "angular_velocity": lambda xdot, omega, torque, par: ca.sumsqr(omega),
    "rotor_energy": lambda xdot, omega, torque, par: ca.sumsqr(torque / par[5]),
}

#: Largest certified residual (units of R, rad; the final rates in rad per horizon) of a returned solution.
TOLERANCE = CERTIFICATE_TOLERANCE
#: Least number of intervals: 2N controls for the 7 end conditions (docs/design/collocation.md).
MIN_INTERVALS = 4
#: Most intervals: the NLP is built symbolically and its memory (construction, IPOPT) grows with N; up to this
#: N a solve stays within about :data:`MEMORY_GB` GB.
MAX_INTERVALS = 2000
#: Memory [GB] that :data:`MAX_INTERVALS` keeps a solve within (named when a larger N is refused).
MEMORY_GB = 2
#: Horizons T [s] served (docs/design/collocation.md, time scaling).
HORIZON_RANGE = (1e-6, 1e6)
#: Power p of the scaling law ``J(T) = J(1) T^p`` of each cost.
COST_POWERS = {"path_energy": -1, "angular_velocity": -1, "rotor_energy": -3}
#: Most NLP solves with a backed-off bound (or backed-off limits) before giving up.
BACKOFF_TRIES = 4
#: Safety factor of a backoff: the bound (or limit) is lowered by this times the excess measured on the samples.
BACKOFF_FACTOR = 1.25
#: IPOPT options of the rest-to-rest NLP beyond :func:`.transcription.ipopt_options`: MUMPS orders its KKT
#: systems (banded blocks, one per interval) by approximate minimum degree, which factors them faster than
#: MUMPS's automatic choice of ordering.
REST_IPOPT_OPTIONS = {"ipopt.mumps_pivot_order": 0}
#: Fresh starts of IPOPT from the last iterate of a rest-to-rest solve that stalled (:data:`RESTART_STATUSES`).
#: A start resets the barrier parameter, the filter and the regularization of the KKT systems: near an optimum
#: whose constraint Jacobian is rank-deficient (a straight roll: the controls move the final yaw only to second
#: order) the line search can stall, and whether it does depends on round-off (docs/design/collocation.md).
IPOPT_RESTARTS = 1
#: The IPOPT statuses of a stalled solve, which a fresh start can change; never an interrupt
#: (``NonIpopt_Exception_Thrown``, ``User_Requested_Stop``), a local infeasibility or an invalid number.
RESTART_STATUSES = frozenset({"Restoration_Failed", "Maximum_Iterations_Exceeded", "Error_In_Step_Computation",
                              "Search_Direction_Becomes_Too_Small"})
_NEWTON_STEPS = 8


def check_intervals(intervals) -> int:
    """``intervals`` if a whole number in [:data:`MIN_INTERVALS`, :data:`MAX_INTERVALS`]; InputError naming the
    range (and, above it, the memory it keeps to) otherwise."""
    n = check_whole("intervals", intervals)
    if n > MAX_INTERVALS:
        raise InputError(f"intervals = {n} is not allowed: it must be a whole number in [{MIN_INTERVALS}, "
                         f"{MAX_INTERVALS}] (the limit keeps a solve within about {MEMORY_GB} GB of memory)")
    return check_whole("intervals", n, MIN_INTERVALS, MAX_INTERVALS)


def check_horizon(horizon) -> float:
    """``horizon`` [s] if in :data:`HORIZON_RANGE`; InputError naming the range otherwise."""
    return check_range("horizon", horizon, *HORIZON_RANGE)


def rest_parameters(k, horizon, robot=None) -> np.ndarray:
    """The NLP parameters ``(k, T, 0, j_xx, j_zz, j_r)`` (inertias 1 without a robot)."""
    if robot is None:
        return np.array([k, horizon, 0.0, 1.0, 1.0, 1.0])
    return np.array([k, horizon, 0.0, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial])


@lru_cache(maxsize=1)
def motion_function() -> ca.Function:
    """``(x[7], a[2], par) -> (xdot[7], omega[3], rotor_rates[2], torque[2])`` from the model.

    omega from (18), (19), (13); rotor rates from (11); the torque ``J_r d/dt`` of
    :func:`rollplan.core.model.rotor_axial_spins` along ``xdot`` (units of R for lengths).
    """
    x, acc, par = ca.SX.sym("x", 7), ca.SX.sym("a", 2), ca.SX.sym("par", N_PAR)
    k, jxx, jzz, jr = par[0], par[3], par[4], par[5]
    psi, u_o, v_o, r = x[2], x[3], x[4], x[5:7]
    xdot = ca.vertcat(model.contact_rhs(x[:5], r, k), acc)
    omega = model.realizable_omega(u_o, v_o, psi, r[0], r[1], k)
    rates = model.rotor_rates(omega, u_o, v_o, psi, jxx, jzz, jr)
    torque = jr * ca.jtimes(model.rotor_axial_spins(omega, u_o, v_o, psi, jxx, jzz, jr), x, xdot)
    return ca.Function("motion", [x, acc, par], [xdot, omega, rates, torque],
                       ["x", "a", "par"], ["xdot", "omega", "rates", "torque"])


@dataclass(frozen=True)
class RestResult(CollocationRun):
    """A certified rest-to-rest collocation solution (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem, cost, transcription, horizon, turns, guess, contact_bound
        As in :class:`.transcription.CollocationRun` (``cost`` a name in :data:`REST_COSTS`).
    method : str
        ``"rest_to_rest"``, or ``"minimum_time"`` for a solution of :class:`MinimumTimePlanner`.
    duration : float
        T [s] (``horizon``): for minimum time, the minimum.
    controls : ndarray, shape (N, 2)
        Contact accelerations on each interval [rad/s^2], after the Newton correction (:func:`correct`).
    objective : float
        The cost of ``controls`` (CVODES quadrature; lengths in R; ``rotor_energy`` divided by J_r^2); the
        NLP's optimal value is ``stats.details["nlp_objective"]``, the contact bound the last NLP solved with
        ``stats.details["backed_off_bound"]``, the statuses of every start of IPOPT (fresh starts after a stall,
        :data:`IPOPT_RESTARTS`, and the solves with a backed-off bound) ``stats.details["ipopt_statuses"]``.
    motion : TimeSeries
        The certified motion (CVODES samples) [length unit].
    certificate : Certificate
    stats : SolverStats
    """

    controls: np.ndarray
    objective: float
    motion: TimeSeries
    certificate: Certificate
    stats: SolverStats

    @property
    def method(self) -> str:
        return "minimum_time" if self.cost == "minimum_time" else "rest_to_rest"

    @property
    def duration(self) -> float:
        return self.horizon

    @property
    def path_length(self) -> float:
        return measure(self.motion)["path_length"]

    def sample(self, samples: int | None = None) -> Trajectory:
        """The certified motion as a :class:`~rollplan.result.Trajectory` in time: ``samples`` samples in all,
        both ends included (evenly by index among the CVODES samples, integrated again more densely when
        there are fewer); None: every certified sample."""
        traj = self.motion.trajectory()
        if samples is None:
            return traj
        samples = check_whole("samples", samples, 2, 10**7)
        if samples > traj.s.size:
            N = self.transcription.intervals
            per = -(-(samples - 1) // N)
            start = np.concatenate([self.problem.scaled(self.problem.start).array(), [0.0, 0.0]])
            traj = certify(self.controls, start, self.problem, self.horizon, per + per % 2).trajectory()
        return traj.subsampled(samples)


@dataclass(frozen=True)
class NlpSolution:
    """IPOPT's solution of the rest-to-rest NLP before the correction and the certificate
    (:meth:`RestToRestPlanner.solve_nlp`; :meth:`RestToRestPlanner.finish` completes it).

    Attributes
    ----------
    problem, guess, horizon, turns, robot
        As given (``guess`` in normalized time; ``robot`` the one whose inertias are used, or None).
    start, final : ndarray, shape (7,)
        The boundary states (units of R, at rest).
    par : ndarray
        The NLP parameters (:func:`rest_parameters`, T = 1).
    where : str
        The problem and start, for messages.
    x : ndarray
        The NLP's solution in the decision vector of the full transcription (``transcription.unpack`` gives its
        states, collocation states and accelerations; the NLP solved is :attr:`RestToRestPlanner.rest_transcription`'s).
    objective : float
        The NLP's optimal value scaled to ``horizon`` (the ``nlp_objective`` of the finished result).
    status : str
    iterations : int
    solve_time_s : float
        IPOPT's wall time [s].
    statuses : tuple of str
        The statuses of IPOPT's starts: more than one where a start stalled and IPOPT started again from its last
        iterate (:data:`IPOPT_RESTARTS`).
    """

    problem: Problem
    guess: Guess
    horizon: float
    turns: int
    robot: Robot | None
    start: np.ndarray
    final: np.ndarray
    par: np.ndarray
    where: str
    x: np.ndarray
    objective: float
    status: str
    iterations: int
    solve_time_s: float
    statuses: tuple = ()


class RestToRestPlanner:
    """The rest-to-rest collocation NLP (docs/design/collocation.md, :mod:`.rest_nlp`), built once; IPOPT solves it.

    Parameters
    ----------
    intervals, degree, scheme
        The :class:`Transcription`: N in [:data:`MIN_INTERVALS`, :data:`MAX_INTERVALS`], d in 1..9, ``"legendre"`` or
        ``"radau"``.
    cost : str
        Name in :data:`REST_COSTS`.
    contact_bound : float
        Bound on the contact point's polar angle from the south pole [rad], in (0, pi/2).
    tol : float
        IPOPT's tolerance, in (0, 1e-2].
    max_iter : int
        IPOPT's iteration limit, per start of IPOPT (a stalled solve starts again: :data:`IPOPT_RESTARTS`).
    samples_per_interval : int
        CVODES samples per interval of the certified motion (even, >= 2).

    Attributes
    ----------
    transcription : Transcription
        The grid (nx = 7, nu = 2): the layout of guesses.
    rest_transcription : RestTranscription
        The NLP's decision vector and equations: the transcription with the closed-form states (u_o, v_o and
        the contact rates at the collocation points) and the accelerations eliminated (:mod:`.rest_nlp`).
    ipopt_options : dict
        The options of its IPOPT solver (:func:`.transcription.ipopt_options` and :data:`REST_IPOPT_OPTIONS`).
    """

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 cost: str = "angular_velocity", contact_bound: float = math.radians(80.0), tol: float = 1e-9,
                 max_iter: int = 150, samples_per_interval: int = 8) -> None:
        check_intervals(intervals)
        self.transcription = Transcription(intervals, degree, scheme, nx=7, nu=2)
        cost = self.cost = cost_key(cost, REST_COSTS)
        self.contact_bound = check_range("contact_bound", contact_bound, 0.0, math.pi / 2, True, True)
        self.tol = check_range("tol", tol, 0.0, 1e-2, low_open=True)
        self.max_iter = check_whole("max_iter", max_iter, 1, 100000)
        per = check_whole("samples_per_interval", samples_per_interval, 2, 10000)
        self.samples_per_interval = per + per % 2
        f = motion_function()
        x, w, par = ca.SX.sym("x", 7), ca.SX.sym("w", 2), ca.SX.sym("par", N_PAR)
        xdot, omega, _, torque = f(x, w, par)
        self.point = ca.Function("point", [x, w, par], [xdot, REST_COSTS[cost](xdot, omega, torque, par), omega])
        t0 = time.perf_counter()
        log.info("building the collocation NLP: N = %d, d = %d, cost %s", intervals, degree, cost)
        # minutes for a large N, in C++ that never returns to Python or in CasADi calls that swallow SIGINT:
        # built in a thread, so Ctrl-C acts at once
        self.rest_transcription = RestTranscription(self.transcription)
        nlp, self.path_rows = interrupts.call_in_thread(self.rest_transcription.contact_nlp, self.point, N_PAR)
        self.ipopt_options = {**ipopt_options(self.tol, self.max_iter), **REST_IPOPT_OPTIONS}
        derivatives = interrupts.call_in_thread(self.rest_transcription.contact_derivatives, self.point, N_PAR)
        self.solver = interrupts.call_in_thread(ca.nlpsol, "rest", "ipopt", nlp,
                                                {**self.ipopt_options, **derivatives})
        self.build_time_s = time.perf_counter() - t0

    def twin(self, options: dict | None = None) -> RestToRestPlanner:
        """This planner with its own IPOPT solver of the same NLP, its derivatives shared (not built again): for
        solves in another thread at the same time (a solver's statistics are those of its last call), or with
        other IPOPT ``options`` (added to :attr:`ipopt_options`)."""
        s = self.solver
        shared = {"grad_f": s.get_function("nlp_grad_f"), "jac_g": s.get_function("nlp_jac_g"),
                  "hess_lag": s.get_function("nlp_hess_l")}
        other = copy.copy(self)
        other.ipopt_options = {**self.ipopt_options, **(options or {})}
        other.solver = interrupts.call_in_thread(ca.nlpsol, s.name(), "ipopt", s.oracle(),
                                                 {**other.ipopt_options, **shared})
        return other

    def boundary(self, problem: Problem, turns: int) -> tuple[np.ndarray, np.ndarray]:
        """Start and final 7-states (units of R) at rest; InputError for a start or goal beyond the bound."""
        if not isinstance(problem, Problem):
            raise InputError(f"problem = {problem!r:.60} is not allowed: give a rollplan.Problem")
        turns = check_whole("turns", turns)
        check_contact_bound(problem, self.contact_bound)
        start = np.concatenate([problem.scaled(problem.start).array(), [0.0, 0.0]])
        final = np.concatenate([problem.scaled(problem.goal).array(), [0.0, 0.0]])
        final[2] += 2 * math.pi * turns
        return start, final

    def solve(self, problem: Problem, guess: Guess, horizon: float = 1.0, turns: int = 0,
              robot: Robot | None = None) -> RestResult:
        """Solve from ``guess`` (see :func:`guess_from_samples`, :func:`naive_guess`).

        ``guess`` is in time over ``horizon`` (rates in rad/s, accelerations in rad/s^2); the NLP is solved in
        normalized time and the result scaled to ``horizon`` exactly (docs/design/collocation.md), the controls
        corrected (:func:`correct`) and certified (:func:`certify`). The same as :meth:`finish` of
        :meth:`solve_nlp`.

        ``robot`` gives the inertias of the rotor rates and torques when the problem has none
        (default: the problem's robot; without either they are computed with unit inertias).

        Raises
        ------
        InputError
            Bad input.
        SolverError
            IPOPT failed (``.status`` is its status), the Newton correction did not meet the end conditions
            (``"Correction_Failed"``), the samples left the contact bound after :data:`BACKOFF_TRIES` solves
            (``"Bound_Violated"``) or the certified residual exceeds :data:`TOLERANCE` (``"Verification_Failed"``).
        """
        return self.finish(self.solve_nlp(problem, guess, horizon, turns, robot))

    def solve_nlp(self, problem: Problem, guess: Guess, horizon: float = 1.0, turns: int = 0,
                  robot: Robot | None = None) -> NlpSolution:
        """The first stage of :meth:`solve`: IPOPT's solution of the NLP from ``guess``, neither corrected nor
        certified. A multistart ranks its starts by :attr:`NlpSolution.objective` and passes only the best
        to :meth:`finish`.

        Raises
        ------
        InputError
            Bad input.
        SolverError
            IPOPT failed (``.status`` is its status).
        """
        start, final = self.boundary(problem, turns)
        if self.cost == "rotor_energy" and robot is None and problem.robot is None:
            raise InputError("cost = 'rotor_energy' needs robot parameters: give a robot "
                             "(the robot argument; --robot FILE.toml on the command line)")
        horizon = check_horizon(horizon)
        tr = self.transcription
        guess = normalized_guess(tr.check_guess(guess), horizon)
        robot = robot if robot is not None else problem.robot
        if robot is not None and not math.isclose(robot.k, problem.k, rel_tol=1e-12):
            raise InputError(f"robot has k = {robot.k:.12g}, the problem k = {problem.k:.12g}")
        par = rest_parameters(problem.k, 1.0, robot)      # normalized time (docs/design/collocation.md)
        where = f"rest-to-rest N = {tr.intervals}, d = {tr.degree}, cost {self.cost}, {guess.name} guess, m = {turns}"
        x0, lbx, ubx, lbg, ubg = self.rest_transcription.contact_bounds(guess, start, final, self.contact_bound,
                                                                        self.path_rows)
        v, f, iters, solve_time, statuses = self._ipopt(x0, lbx, ubx, lbg, ubg, par, where, 0)
        return NlpSolution(problem, guess, float(horizon), int(turns), robot, start, final, par, where, v,
                           f * horizon ** COST_POWERS[self.cost], statuses[-1], iters, solve_time, statuses)

    def _ipopt(self, x0, lbx, ubx, lbg, ubg, par, where: str, iters: int):
        """IPOPT's solution of the NLP from ``x0`` (its decision vector): ``(x in the full transcription's layout,
        f, iters + its iterations, wall time, the statuses of its starts: the last is the solution's)``. Where a
        solve stalls (:data:`RESTART_STATUSES`), IPOPT starts again from its last iterate, up to
        :data:`IPOPT_RESTARTS` times (each start up to ``max_iter`` iterations); SolverError if the last start
        fails."""
        t0 = time.perf_counter()
        x, statuses = x0, []
        for _ in range(1 + IPOPT_RESTARTS):
            sol = interrupts.call(self.solver, x0=x, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=par)
            st = self.solver.stats()
            statuses.append(str(st["return_status"]))
            iters += int(st["iter_count"])
            x = np.array(sol["x"]).ravel()
            if st["success"] or statuses[-1] not in RESTART_STATUSES or not np.all(np.isfinite(x)):
                break
        solve_time = time.perf_counter() - t0
        if not st["success"]:
            raise SolverError(f"IPOPT did not solve the collocation problem ({where}): {', then '.join(statuses)} "
                              f"after {iters} iterations; hint: warm-start from a geometric-phase plan", statuses[-1])
        return self.rest_transcription.full(x), float(sol["f"]), iters, solve_time, tuple(statuses)

    def finish(self, nlp: NlpSolution, fixed_steps: tuple[int, int] | None = None) -> RestResult:
        """The second stage of :meth:`solve`: the Newton correction and the CVODES certificate of ``nlp`` (a
        :meth:`solve_nlp` of this planner), the contact bound backed off and the NLP solved again (warm-started)
        when the samples leave it. ``fixed_steps``: the correction's integration (:func:`correct`).

        Raises
        ------
        SolverError
            As :meth:`solve`.
        """
        tr, c, where = self.transcription, self.contact_bound, nlp.where
        problem, guess, horizon, start, final, par = nlp.problem, nlp.guess, nlp.horizon, nlp.start, nlp.final, nlp.par
        v, f, status, iters, solve_time = nlp.x, nlp.objective / horizon ** COST_POWERS[self.cost], nlp.status, \
            nlp.iterations, nlp.solve_time_s
        statuses = list(nlp.statuses)
        bound = c
        for _ in range(BACKOFF_TRIES):
            controls, objective = correct(tr.unpack(v)[2], start, final, par, self.cost, where, fixed_steps)
            motion, end_rates = certify(controls, start, problem, 1.0, self.samples_per_interval, nlp.robot, True)
            excess = polar_angles(motion).max() - c
            if excess <= 0.0:
                break
            # the bound holds at the collocation points only: back it off (warm-started)
            bound -= BACKOFF_FACTOR * excess
            _, lbx, ubx, lbg, ubg = self.rest_transcription.contact_bounds(guess, start, final, bound, self.path_rows)
            v, f, iters, dt, more = self._ipopt(np.clip(self.rest_transcription.reduced(v), lbx, ubx), lbx, ubx,
                                                lbg, ubg, par, where, iters)
            solve_time += dt
            statuses += more
            status = more[-1]
        else:
            raise SolverError(f"the collocation solution ({where}) leaves the contact bound {c:.6g} rad between "
                              f"collocation points by {excess:.2e} rad after {BACKOFF_TRIES} backed-off solves; "
                              "hint: raise N", "Bound_Violated")
        # the end error after the correction, as the certificate's CVODES integration gives it
        end = np.r_[motion.state[-1] / np.array([problem.radius] * 2 + [1.0] * 3), end_rates] - final
        motion = scaled_motion(motion, horizon)
        cert = _certificate(problem, State(*motion.state[-1]), end_rates, where)
        scale = horizon ** COST_POWERS[self.cost]
        stats = SolverStats("ipopt", status, iters, solve_time, {"build_time_s": self.build_time_s,
                                                                 "backed_off_bound": float(bound),
                                                                 "nlp_objective": f * scale,
                                                                 "correction_error": float(np.abs(end).max()),
                                                                 "ipopt_statuses": tuple(statuses)})
        return RestResult(problem, self.cost, tr, horizon, nlp.turns, guess.name, c,
                          controls / horizon ** 2, objective * scale, motion, cert, stats)


def _certificate(problem: Problem, fin: State, end_rates, where: str) -> Certificate:
    """The CVODES certificate of a rest-to-rest motion; SolverError ``"Verification_Failed"`` when its goal
    residual or its final rates ``end_rates`` (rad per horizon) exceed :data:`TOLERANCE`."""
    residual = problem.residual(fin)   # psi compared as an angle
    rest = float(np.abs(end_rates).max())
    cert = certificate_of(problem, fin, "cvodes", residual=max(residual, rest))
    if not cert.passed:
        raise SolverError(f"the collocation solution ({where}) misses the goal by {residual:.2e} and rest by "
                          f"{rest:.2e} > {TOLERANCE:.0e} when integrated by CVODES after the Newton correction; "
                          "hint: raise N or d", "Verification_Failed")
    return cert


def scaled_motion(motion: TimeSeries, horizon: float) -> TimeSeries:
    """A motion of normalized time (T = 1) on the horizon ``horizon`` [s] (docs/design/collocation.md, time scaling):
    times times T, velocities, omega and rotor rates divided by T, torques by T^2; the states unchanged."""
    T = float(horizon)
    return TimeSeries(motion.time * T, motion.state, velocity=motion.velocity / T, omega=motion.omega / T,
                      rotor_rates=motion.rotor_rates / T, rotor_torques=motion.rotor_torques / T ** 2,
                      radius=motion.radius)


def normalized_guess(g: Guess, horizon: float) -> Guess:
    """``g`` (rates in rad/s, accelerations in rad/s^2 over ``horizon``) in normalized time ``tau = t / T``."""
    s = np.array([1.0] * 5 + [horizon] * 2)
    return Guess(np.asarray(g.states, float) * s, np.asarray(g.colloc, float) * s,
                 np.asarray(g.controls, float) * horizon ** 2, g.name)


def polar_angles(motion: TimeSeries) -> np.ndarray:
    """Polar angle of the contact point from the south pole at every sample of ``motion`` [rad]: from (1),
    ``acos(cos u_o cos v_o)``."""
    return np.arccos(np.clip(np.cos(motion.state[:, 3]) * np.cos(motion.state[:, 4]), -1.0, 1.0))


@lru_cache(maxsize=16)
def _newton_step(cost: str, jacobians: bool = True, substeps: int | None = None) -> ca.Function:
    """:func:`.transcription.sensitivity_step` of the 7-state ODE (with ``substeps``, its
    :func:`.transcription.fixed_step`), the quadrature the cost ``cost`` (0 for a name not in :data:`REST_COSTS`,
    e.g. minimum time)."""
    x, acc, par = ca.SX.sym("x", 7), ca.SX.sym("a", 2), ca.SX.sym("par", N_PAR)
    xdot, omega, _, torque = motion_function()(x, acc, par)
    quad = REST_COSTS[cost](xdot, omega, torque, par) if cost in REST_COSTS else ca.SX(0.0)
    if substeps is not None:
        return fixed_step("rest_newton", x, acc, par, xdot, quad, substeps, jacobians)
    return sensitivity_step("rest_newton", x, acc, par, xdot, quad, jacobians)


def correct(controls, start, final, par, cost: str = "path_energy", where: str = "rest-to-rest",
            fixed_steps: tuple[int, int] | None = None):
    """Minimum-norm Gauss-Newton correction (:func:`.transcription.gauss_newton`) of piecewise-constant
    accelerations in normalized time (T = 1) until the motion from ``start`` (7,), integrated by CVODES, ends at
    ``final`` (7,: the goal at rest) to :data:`.transcription.CORRECTION_TOL`. ``par`` are :func:`rest_parameters`
    with T = 1. The Jacobian of the end state is that of :data:`.transcription.JACOBIAN_SUBSTEPS` steps per
    interval of the eighth-order formula (:func:`.transcription.fixed_step`, a small fraction of the cost of CVODES's
    sensitivities); the end error, which alone decides the result, is CVODES's. Where that correction stops short
    of the tolerance it goes on with CVODES's sensitivities. With ``fixed_steps = (n, m)`` the motion is
    integrated instead by ``n`` steps per interval of the eighth-order formula, the Jacobian by ``m``: a cheaper
    correction, for few intervals, that the CVODES certificate (:func:`certify`) checks like any other.

    Returns
    -------
    (controls, cost)
        The corrected controls (N, 2) and the integral of ``REST_COSTS[cost]`` along them (T = 1; 0 for a cost
        not in :data:`REST_COSTS`, e.g. minimum time).

    Raises
    ------
    SolverError
        ``"Correction_Failed"``: the end conditions are not met to :data:`TOLERANCE` after the steps.
    """
    n, m = fixed_steps if fixed_steps is not None else (None, JACOBIAN_SUBSTEPS)
    a, q, size, _ = gauss_newton(_newton_step(cost, True, m), controls, start, final, par, CORRECTION_TOL,
                                 _NEWTON_STEPS, _newton_step(cost, False, n),
                                 None if fixed_steps is not None else _newton_step(cost, True, None))
    if not size <= TOLERANCE:
        raise SolverError(f"the Newton correction of the collocation solution ({where}) leaves an end-condition "
                          f"error of {size:.2e} > {TOLERANCE:.0e}; hint: raise N or d", "Correction_Failed")
    return a, q


@lru_cache(maxsize=8)
def _interval_integrator(per: int) -> ca.Function:
    """CVODES over one interval of normalized length 1 with ``per`` outputs, the acceleration a parameter."""
    x, acc, par, h = ca.SX.sym("x", 7), ca.SX.sym("a", 2), ca.SX.sym("par", N_PAR), ca.SX.sym("h")
    xdot = motion_function()(x, acc, par)[0]
    grid = list(np.arange(1, per + 1) / per)
    opts = {"abstol": 1e-15, "reltol": 1e-14, "max_num_steps": 100000}
    return ca.integrator("rest_cert", "cvodes", {"x": x, "p": ca.vertcat(acc, par, h), "ode": h * xdot},
                         0.0, grid, opts)


def certify(controls, start, problem: Problem, horizon: float, per: int = 8, robot: Robot | None = None,
            end_rates: bool = False):
    """CVODES integration of the 7-state ODE with piecewise-constant accelerations ``controls`` (N, 2) [rad/s^2]
    from ``start`` (7,) (units of R, rates in rad/s): the samples of every interval, both ends included, as
    the :class:`~rollplan.timeseries.TimeSeries` in the problem's length unit.

    The integration runs in normalized time ``tau = t / T`` (accelerations times T^2) and the motion is
    scaled to T exactly (:func:`scaled_motion`). With ``end_rates`` also returns the final contact rates in
    rad per horizon (``T`` times rad/s).
    """
    controls = np.asarray(controls, float) * horizon ** 2
    N = controls.shape[0]
    par = rest_parameters(problem.k, 1.0, robot if robot is not None else problem.robot)
    h = 1.0 / N
    integ, f = _interval_integrator(per), motion_function()
    x = np.asarray(start, float) * np.array([1.0] * 5 + [horizon] * 2)
    ts, xs, accs = [], [], []
    for i, a in enumerate(controls):
        out = np.array(interrupts.call(integ, x0=x, p=np.concatenate([a, par, [h]]))["xf"])
        block = np.hstack([x[:, None], out])
        ts.append(np.linspace(i * h, (i + 1) * h, per + 1))
        xs.append(block)
        accs.append(np.repeat(a[:, None], per + 1, axis=1))
        x = out[:, -1]
    t = np.concatenate(ts)
    t[-1] = 1.0
    X, A = np.hstack(xs), np.hstack(accs)
    xdot, omega, rates, torque = (np.array(v).T for v in f.map(X.shape[1])(X, A, par))
    R = problem.radius
    state = X[:5].T * np.array([R, R, 1.0, 1.0, 1.0])
    motion = scaled_motion(TimeSeries(t, state, velocity=xdot[:, :2] * R, omega=omega, rotor_rates=rates,
                                      rotor_torques=torque, radius=R), horizon)
    return (motion, X[5:7, -1].copy()) if end_rates else motion


def naive_guess(tr: Transcription, start, final) -> Guess:
    """Every state linear in time from ``start`` to ``final`` (7,), zero accelerations."""
    starts, tc = tr.grid()
    lerp = lambda t: start + t[..., None] * (np.asarray(final) - start)  # noqa: E731
    return Guess(lerp(np.append(starts, 1.0)), lerp(tc), np.zeros((tr.intervals, 2)), "naive")


def guess_from_samples(tr: Transcription, t, x7, name: str) -> Guess:
    """A guess following samples ``x7`` (M, 7) at increasing times ``t`` (M,) from 0 to T (units of R):
    states interpolated at the grid, accelerations the rates' differences over each interval."""
    t, x7 = np.asarray(t, float), np.asarray(x7, float)
    keep = np.r_[True, np.diff(t) > 0]
    t, x7 = t[keep], x7[keep]
    tau = t / t[-1]
    interp = lambda s: np.stack([np.interp(s, tau, c) for c in x7.T], axis=-1)  # noqa: E731
    starts, tc = tr.grid()
    states = interp(np.append(starts, 1.0))
    controls = np.diff(states[:, 5:7], axis=0) / (t[-1] / tr.intervals)
    return Guess(states, interp(tc), controls, name)


class MinimumTimePlanner:
    """The rest-to-rest problem of :class:`RestToRestPlanner` with free final time: minimise T subject to
    ``|phi_i_dot| <= max_rotor_rate`` and ``|tau_i| <= max_rotor_torque`` (the robot's limits, at every
    collocation point and at both ends of every interval, with the interval's acceleration). The returned
    motion (corrected by :func:`correct` at its duration, certified like :meth:`RestToRestPlanner.solve`)
    respects the limits and the contact bound at every sample: when its samples exceed them the NLP is solved
    again with limits and bound backed off by :data:`BACKOFF_FACTOR` times the excess, warm-started
    (:data:`BACKOFF_TRIES`).

    Parameters
    ----------
    intervals, degree, scheme, contact_bound, tol, max_iter, samples_per_interval
        As in :class:`RestToRestPlanner`.
    """

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 contact_bound: float = math.radians(80.0), tol: float = 1e-9, max_iter: int = 300,
                 samples_per_interval: int = 8) -> None:
        base = RestToRestPlanner(intervals, degree, scheme, "path_energy", contact_bound, tol, max_iter,
                                 samples_per_interval)
        self.base = base
        tr = base.transcription
        N, d, nx, nu = tr.intervals, tr.degree, tr.nx, tr.nu
        stride = nx * d + nu + nx
        # one interval's rows: those of the rest-to-rest transcription at the free T, then the limits at its start,
        # its d points and its end; T the one variable shared by every interval (the NLP and its derivatives built
        # interval by interval)
        zt, p = ca.SX.sym("z", stride + nx + 1), ca.SX.sym("p", N_PAR + 2)
        z, T, fixed, limits = zt[:-1], zt[-1], p[:N_PAR], p[N_PAR:]   # limits: max rate, max torque
        sub = ca.vertcat(fixed[0], T, fixed[2:])
        g_dyn, _ = tr.interval_block(base.point, tr.contact_path(), N_PAR)(z, sub)
        w = z[nx * (d + 1): nx * (d + 1) + nu]
        f = motion_function()
        lim = []
        for xp in [z[nx * j: nx * (j + 1)] for j in range(d + 1)] + [z[stride:]]:
            _, _, rates, torque = f(xp, w, sub)
            lim += [rates / limits[0], torque / limits[1]]
        g_lim = ca.vertcat(*lim)
        block = ca.Function("min_time_block", [zt, p], [ca.vertcat(g_dyn, g_lim), T / N], ["z", "p"], ["g", "J"])
        self.n_lim, self.path_rows = g_lim.numel(), tr.path_rows()
        nlp = interrupts.call_in_thread(interval_nlp, block, N, stride, 1)
        derivatives = interrupts.call_in_thread(interval_derivatives, block, N, stride, 1)
        self.solver = interrupts.call_in_thread(ca.nlpsol, "min_time", "ipopt", nlp,
                                                {**ipopt_options(tol, max_iter), **derivatives})

    def _row_bounds(self, lbg, ubg) -> tuple[np.ndarray, np.ndarray]:
        """The bounds of the NLP's rows from those of the transcription's: each interval's rows, then its limits'
        rows in [-1, 1]."""
        N, ones = self.base.transcription.intervals, np.ones((self.base.transcription.intervals, self.n_lim))
        return (np.hstack([np.reshape(lbg, (N, -1)), -ones]).ravel(),
                np.hstack([np.reshape(ubg, (N, -1)), ones]).ravel())

    def solve(self, problem: Problem, guess: Guess, duration_guess: float, robot: Robot, turns: int = 0):
        """Minimum-time rest-to-rest motion within ``robot``'s limits (both must be set), from ``guess``
        (normalized time) and ``duration_guess`` [s]. Returns the :class:`RestResult` (its ``duration`` the
        minimum time).

        Raises
        ------
        InputError, SolverError
        """
        if not isinstance(robot, Robot) or robot.max_rotor_rate is None or robot.max_rotor_torque is None:
            raise InputError("minimum time needs a robot with max_rotor_rate and max_rotor_torque")
        base = self.base
        start, final = base.boundary(problem, turns)
        tr = base.transcription
        c = base.contact_bound
        guess = tr.check_guess(guess)
        x0, lbx, ubx, lbg, ubg = tr.contact_bounds(guess, start, final, c, self.path_rows)
        x0 = np.append(x0, check_range("duration_guess", duration_guess, 0.0, 1e6, low_open=True))
        lbg, ubg = self._row_bounds(lbg, ubg)
        limits = np.array([robot.max_rotor_rate, robot.max_rotor_torque])
        backed, bound, solve_time, iters = limits.copy(), c, 0.0, 0
        par1 = rest_parameters(problem.k, 1.0, robot)
        where = f"minimum time N = {tr.intervals}, d = {tr.degree}, {guess.name} guess, m = {turns}"
        for _ in range(BACKOFF_TRIES):
            t0 = time.perf_counter()
            sol = interrupts.call(self.solver, x0=x0, lbx=np.append(lbx, 1e-6), ubx=np.append(ubx, 1e6), lbg=lbg,
                                  ubg=ubg, p=np.concatenate([par1, backed]))
            solve_time += time.perf_counter() - t0
            st = self.solver.stats()
            status = str(st["return_status"])
            iters += int(st["iter_count"])
            if not st["success"]:
                raise SolverError(f"IPOPT did not solve the minimum-time problem: {status} after {iters} iterations",
                                  status)
            v = np.array(sol["x"]).ravel()
            T = float(v[-1])
            controls = correct(tr.unpack(v[:-1])[2] * T ** 2, start, final, par1, "minimum_time", where)[0] / T ** 2
            motion, end_rates = certify(controls, start, problem, T, base.samples_per_interval, robot, True)
            peaks = np.array([np.abs(motion.rotor_rates).max(), np.abs(motion.rotor_torques).max()])
            excess, polar = peaks - limits, polar_angles(motion).max() - c
            if np.all(excess <= 0.0) and polar <= 0.0:
                break
            # limits and bound hold at the collocation points only: back them off (warm-started)
            backed = backed - BACKOFF_FACTOR * np.maximum(excess, 0.0)
            if polar > 0.0:
                bound -= BACKOFF_FACTOR * polar
                _, lbx, ubx, lbg, ubg = tr.contact_bounds(guess, start, final, bound, self.path_rows)
                lbg, ubg = self._row_bounds(lbg, ubg)
            x0 = np.append(np.clip(v[:-1], lbx, ubx), T)
        else:
            raise SolverError(f"the minimum-time solution ({where}) exceeds the rotor limits by "
                              f"{max(np.max(excess / limits), 0.0):.2e} (relative) or the contact bound by "
                              f"{max(polar, 0.0):.2e} rad between collocation points after {BACKOFF_TRIES} backed-off "
                              "solves; hint: raise N", "Limits_Violated")
        cert = _certificate(problem, State(*motion.state[-1]), end_rates, where)
        stats = SolverStats("ipopt", status, iters, solve_time, {"backed_off_limits": tuple(backed),
                                                                 "backed_off_bound": bound})
        return RestResult(problem, "minimum_time", tr, T, int(turns), guess.name, c, controls, T, motion, cert,
                             stats)


@lru_cache(maxsize=8)
def _rest_planner(intervals, degree, scheme, cost, contact_bound, tol, max_iter, samples_per_interval):
    return RestToRestPlanner(intervals, degree, scheme, cost, contact_bound, tol, max_iter, samples_per_interval)


@lru_cache(maxsize=4)
def _min_time_planner(intervals, degree, scheme, contact_bound, tol, max_iter, samples_per_interval):
    return MinimumTimePlanner(intervals, degree, scheme, contact_bound, tol, max_iter, samples_per_interval)


def _initial_guess(tr: Transcription, guess, start, final) -> Guess:
    """The guess ``"naive"`` (:func:`naive_guess`) or a :class:`Guess` as given (checked)."""
    if isinstance(guess, Guess):
        return tr.check_guess(guess)
    if guess != "naive":
        raise InputError(f"guess = {guess!r:.60} is not allowed: give 'naive' or a Guess (e.g. guess_from_samples)")
    return naive_guess(tr, start, final)


def _check_robot(robot) -> Robot | None:
    if robot is not None and not isinstance(robot, Robot):
        raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot or None")
    return robot


class RestToRestMethod(Method):
    """The method ``"rest_to_rest"`` of :data:`rollplan.planners.METHODS`: :class:`RestToRestPlanner` (its NLP
    built once per set of NLP options and shared) with the options of one solve.

    Parameters
    ----------
    intervals, degree, scheme, cost, contact_bound, tol, max_iter, samples_per_interval
        Of the NLP, as in :class:`RestToRestPlanner`.
    horizon : float
        T [s], in :data:`HORIZON_RANGE`.
    turns : int
        Whole turns m added to psi.
    guess : str or Guess
        ``"naive"`` (:func:`naive_guess`, the default) or a :class:`Guess` in time over ``horizon``
        (e.g. :func:`guess_from_samples` of a timed geometric-phase plan).
    robot : Robot or None
        Inertias of the rotor rates and torques when the problem has no robot.
    """

    name = "rest_to_rest"

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 cost: str = "angular_velocity", contact_bound: float = math.radians(80.0), tol: float = 1e-9,
                 max_iter: int = 150, samples_per_interval: int = 8, *, horizon: float = 1.0, turns: int = 0,
                 guess="naive", robot: Robot | None = None) -> None:
        self.planner = _rest_planner(check_intervals(intervals), degree, scheme, cost_key(cost, REST_COSTS),
                                     contact_bound, tol, max_iter, samples_per_interval)
        self.horizon, self.turns = check_horizon(horizon), check_whole("turns", turns)
        self.guess, self.robot = guess, _check_robot(robot)

    def _check(self, problem) -> Problem:
        problem = super()._check(problem)
        self.planner.boundary(problem, self.turns)
        return problem

    def _solve(self, problem: Problem) -> RestResult:
        start, final = self.planner.boundary(problem, self.turns)
        guess = _initial_guess(self.planner.transcription, self.guess, start, final)
        return self.planner.solve(problem, guess, self.horizon, self.turns, self.robot)


class MinimumTimeMethod(Method):
    """The method ``"minimum_time"`` of :data:`rollplan.planners.METHODS`: :class:`MinimumTimePlanner` (its NLP
    built once per set of NLP options and shared) with the options of one solve. The result's ``duration``
    is the minimum time.

    Parameters
    ----------
    intervals, degree, scheme, contact_bound, tol, max_iter, samples_per_interval
        Of the NLP, as in :class:`MinimumTimePlanner`.
    duration_guess : float
        First guess of the duration [s].
    turns : int
        Whole turns m added to psi.
    guess : str or Guess
        ``"naive"`` (the default) or a :class:`Guess` in normalized time.
    robot : Robot or None
        The robot whose ``max_rotor_rate`` and ``max_rotor_torque`` bound the motion (default: the problem's).
    """

    name = "minimum_time"

    def __init__(self, intervals: int = 60, degree: int = 3, scheme: str = "legendre",
                 contact_bound: float = math.radians(80.0), tol: float = 1e-9, max_iter: int = 300,
                 samples_per_interval: int = 8, *, duration_guess: float = 1.0, turns: int = 0, guess="naive",
                 robot: Robot | None = None) -> None:
        self.planner = _min_time_planner(check_intervals(intervals), degree, scheme, contact_bound, tol, max_iter,
                                         samples_per_interval)
        self.duration_guess = check_range("duration_guess", duration_guess, 0.0, 1e6, low_open=True)
        self.turns, self.guess, self.robot = check_whole("turns", turns), guess, _check_robot(robot)

    def _check(self, problem) -> Problem:
        problem = super()._check(problem)
        robot = self.robot if self.robot is not None else problem.robot
        if robot is None or robot.max_rotor_rate is None or robot.max_rotor_torque is None:
            raise InputError("minimum time needs a robot with max_rotor_rate and max_rotor_torque")
        self.planner.base.boundary(problem, self.turns)
        return problem

    def _solve(self, problem: Problem) -> RestResult:
        robot = self.robot if self.robot is not None else problem.robot
        start, final = self.planner.base.boundary(problem, self.turns)
        guess = _initial_guess(self.planner.base.transcription, self.guess, start, final)
        return self.planner.solve(problem, guess, self.duration_guess, robot, self.turns)
