"""Rest-to-rest direct collocation: the contact accelerations are the controls.

Problem. On a fixed horizon ``t in [0, T]`` find contact accelerations
``a(t) = (u_o'', v_o'')``, constant on each of N equal intervals, that minimize
``J = int_0^T L dt`` subject to the realizable contact kinematics
(:func:`rollplan.core.model.contact_rhs`: (6)-(10) with (18), (19) and the spin
from (13)) and ``(u_o', v_o')' = a``. The state is
``x = (u_a, v_a, psi, u_o, v_o, u_o', v_o')``; the boundary conditions are the
problem's start and goal at rest,

    x(0) = (start, 0, 0),   x(T) = (goal + (0, 0, 2 pi m, 0, 0), 0, 0),

with ``m`` (``turns``) the whole turns of psi (psi is an angle: the caller solves
several m and keeps the best, :mod:`rollplan.studies.comparison`). The contact
rates, omega and the rotor rates are then continuous and zero at both ends, and
the motor torques ``tau_i = J_r d/dt (n_i . omega + phi_i_dot)`` are finite
(they step where the acceleration steps). The contact point stays within the
polar angle ``contact_bound`` of the south pole at every collocation point.

Costs by name (:data:`REST_COSTS`): ``"path_length"`` (``int |v|^2 dt``, the
energy form of the contact path length), ``"angular_velocity"``
(``int |omega|^2 dt``) and ``"rotor_energy"`` (``int |tau|^2 dt``, optimized as
``int |tau / J_r|^2 dt``, the same minimizer; needs a robot).

Transcription: :class:`.transcription.Transcription` with ``nx = 7, nu = 2``
(Gauss-Legendre or Radau collocation of degree d). Certification: CVODES
integrates the 7-state ODE again with the optimized accelerations, interval by
interval; its samples (both sides of every interval boundary) are the
:class:`rollplan.measures.TimedMotion` of the result, whose costs
:func:`rollplan.measures.measure` computes like those of any other motion.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ... import interrupts
from ...core import model
from ...errors import InputError, SolverError, check_range, check_whole
from ...measures import TimedMotion, measure
from ...problem import Problem, State
from ...result import Certificate, SolverStats, Trajectory
from ...robot import Robot
from .costs import N_PAR
from .transcription import CollocationRun, Guess, Transcription, check_contact_bound, ipopt_options

__all__ = ["REST_COSTS", "RestResult", "RestToRestPlanner", "MinimumTimePlanner", "certify", "rest_parameters",
           "motion_function", "naive_guess", "guess_from_samples"]

#: Running costs of the rest-to-rest problem, by name: ``L(xdot, omega, torque, par)``.
REST_COSTS = {
    "path_length": lambda xdot, omega, torque, par: xdot[0] ** 2 + xdot[1] ** 2,
    "angular_velocity": lambda xdot, omega, torque, par: ca.sumsqr(omega),
    "rotor_energy": lambda xdot, omega, torque, par: ca.sumsqr(torque / par[5]),
}

#: Largest certified residual (units of R, rad) of a returned solution.
TOLERANCE = 1e-6


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
    controls : ndarray, shape (N, 2)
        Contact accelerations on each interval [rad/s^2].
    objective : float
        The NLP's optimal value (lengths in R; ``rotor_energy`` divided by J_r^2).
    motion : TimedMotion
        The certified motion (CVODES samples) [length unit].
    certificate : Certificate
    stats : SolverStats
    """

    controls: np.ndarray
    objective: float
    motion: TimedMotion
    certificate: Certificate
    stats: SolverStats

    @property
    def path_length(self) -> float:
        return measure(self.motion)["path_length"]

    def sample(self, samples: int | None = None) -> Trajectory:
        """The certified motion as a :class:`~rollplan.result.Trajectory` in time."""
        return self.motion.trajectory()


class RestToRestPlanner:
    """The rest-to-rest collocation NLP (module docstring), built once; IPOPT solves it.

    Parameters
    ----------
    intervals, degree, scheme
        The :class:`Transcription`: N >= 1, d in 1..9, ``"legendre"`` or ``"radau"``.
    cost : str
        Name in :data:`REST_COSTS`.
    contact_bound : float
        Bound on the contact point's polar angle from the south pole [rad], in (0, pi/2).
    tol : float
        IPOPT's tolerance, in (0, 1e-2].
    max_iter : int
        IPOPT's iteration limit.
    samples_per_interval : int
        CVODES samples per interval of the certified motion (even, >= 2).
    """

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 cost: str = "angular_velocity", contact_bound: float = math.radians(80.0), tol: float = 1e-9,
                 max_iter: int = 150, samples_per_interval: int = 8) -> None:
        self.transcription = Transcription(intervals, degree, scheme, nx=7, nu=2)
        if not isinstance(cost, str) or cost not in REST_COSTS:
            raise InputError(f"cost = {cost!r} is not allowed: choose one of {', '.join(REST_COSTS)}")
        self.cost = cost
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
        nlp, self.path_rows = self.transcription.contact_nlp(self.point, N_PAR)
        self.solver = ca.nlpsol("rest", "ipopt", nlp, ipopt_options(self.tol, self.max_iter))
        self.build_time_s = time.perf_counter() - t0

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

        ``robot`` gives the inertias of the rotor rates and torques when the problem has none
        (default: the problem's robot; without either they are computed with unit inertias).

        Raises
        ------
        InputError
            Bad input.
        SolverError
            IPOPT failed (``.status`` is its status) or the certified residual exceeds :data:`TOLERANCE`
            (status ``"Verification_Failed"``).
        """
        start, final = self.boundary(problem, turns)
        if self.cost == "rotor_energy" and robot is None and problem.robot is None:
            raise InputError("cost = 'rotor_energy' needs robot parameters: give a robot")
        horizon = check_range("horizon", horizon, 0.0, 1e6, low_open=True)
        tr = self.transcription
        guess = tr.check_guess(guess)
        robot = robot if robot is not None else problem.robot
        if robot is not None and not math.isclose(robot.k, problem.k, rel_tol=1e-12):
            raise InputError(f"robot has k = {robot.k:.12g}, the problem k = {problem.k:.12g}")
        par = rest_parameters(problem.k, horizon, robot)
        c = self.contact_bound
        x0, lbx, ubx, lbg, ubg = tr.contact_bounds(guess, start, final, c, self.path_rows)
        t0 = time.perf_counter()
        sol = interrupts.call(self.solver, x0=x0, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg, p=par)
        solve_time = time.perf_counter() - t0
        st = self.solver.stats()
        status, iters = str(st["return_status"]), int(st["iter_count"])
        where = f"rest-to-rest N = {tr.intervals}, d = {tr.degree}, cost {self.cost}, {guess.name} guess, m = {turns}"
        if not st["success"]:
            raise SolverError(f"IPOPT did not solve the collocation problem ({where}): {status} after {iters} "
                              "iterations; hint: warm-start from a geometric-phase plan", status)
        _, _, controls = tr.unpack(np.array(sol["x"]).ravel())
        motion = certify(controls, start, problem, horizon, self.samples_per_interval, robot)
        fin = State(*motion.state[-1])
        residual = problem.residual(fin)   # psi compared as an angle
        cert = Certificate("cvodes", fin, residual, 0.0, TOLERANCE)
        if not cert.passed:
            raise SolverError(f"the collocation solution ({where}) misses the goal by {residual:.2e} > "
                              f"{TOLERANCE:.0e} when integrated by CVODES; hint: raise N or d", "Verification_Failed")
        stats = SolverStats("ipopt", status, iters, solve_time, {"build_time_s": self.build_time_s})
        return RestResult(problem, self.cost, tr, float(horizon), int(turns), guess.name, c, controls,
                          float(sol["f"]), motion, cert, stats)


@lru_cache(maxsize=8)
def _interval_integrator(per: int) -> ca.Function:
    """CVODES over one interval of normalized length 1 with ``per`` outputs, the acceleration a parameter."""
    x, acc, par, h = ca.SX.sym("x", 7), ca.SX.sym("a", 2), ca.SX.sym("par", N_PAR), ca.SX.sym("h")
    xdot = motion_function()(x, acc, par)[0]
    grid = list(np.arange(1, per + 1) / per)
    opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 100000}
    return ca.integrator("rest_cert", "cvodes", {"x": x, "p": ca.vertcat(acc, par, h), "ode": h * xdot},
                         0.0, grid, opts)


def certify(controls, start, problem: Problem, horizon: float, per: int = 8, robot: Robot | None = None) -> TimedMotion:
    """CVODES integration of the 7-state ODE with piecewise-constant accelerations ``controls`` (N, 2)
    from ``start`` (7,) (units of R): the samples of every interval, both ends included, as a
    :class:`~rollplan.measures.TimedMotion` in the problem's length unit."""
    controls = np.asarray(controls, float)
    N = controls.shape[0]
    par = rest_parameters(problem.k, horizon, robot if robot is not None else problem.robot)
    h = horizon / N
    integ, f = _interval_integrator(per), motion_function()
    x = np.asarray(start, float)
    ts, xs, accs = [], [], []
    for i, a in enumerate(controls):
        out = np.array(integ(x0=x, p=np.concatenate([a, par, [h]]))["xf"])
        block = np.hstack([x[:, None], out])
        ts.append(np.linspace(i * h, (i + 1) * h, per + 1))
        xs.append(block)
        accs.append(np.repeat(a[:, None], per + 1, axis=1))
        x = out[:, -1]
    t = np.concatenate(ts)
    t[-1] = horizon
    X, A = np.hstack(xs), np.hstack(accs)
    xdot, omega, rates, torque = (np.array(v).T for v in f.map(X.shape[1])(X, A, par))
    R = problem.radius
    state = X[:5].T * np.array([R, R, 1.0, 1.0, 1.0])
    return TimedMotion(t, state, xdot[:, :2] * R, omega, rates, torque, R)


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
    collocation point and at both ends of every interval, with the interval's acceleration).

    Parameters
    ----------
    intervals, degree, scheme, contact_bound, tol, max_iter, samples_per_interval
        As in :class:`RestToRestPlanner`.
    """

    def __init__(self, intervals: int = 100, degree: int = 3, scheme: str = "legendre",
                 contact_bound: float = math.radians(80.0), tol: float = 1e-9, max_iter: int = 300,
                 samples_per_interval: int = 8) -> None:
        base = RestToRestPlanner(intervals, degree, scheme, "path_length", contact_bound, tol, max_iter,
                                 samples_per_interval)
        self.base = base
        tr = base.transcription
        N, d, nx, nu = tr.intervals, tr.degree, tr.nx, tr.nu
        nlp, rows = tr.contact_nlp(base.point, N_PAR)
        V, par = nlp["x"], nlp["p"]
        T = ca.SX.sym("T")
        limits = ca.SX.sym("limits", 2)   # max rate, max torque
        fixed = ca.SX.sym("fixed", N_PAR)
        sub = ca.vertcat(fixed[0], T, fixed[2:])
        g_dyn = ca.substitute(nlp["g"], par, sub)
        f = motion_function()
        lim = []
        block = nx * d + nu + nx
        for i in range(N):
            o = nx + i * block
            x0, xc = V[o - nx: o], [V[o + nx * j: o + nx * (j + 1)] for j in range(d)]
            w, x1 = V[o + nx * d: o + nx * d + nu], V[o + nx * d + nu: o + block]
            for xp in (x0, *xc, x1):
                _, _, rates, torque = f(xp, w, sub)
                lim += [rates / limits[0], torque / limits[1]]
        g_lim = ca.vertcat(*lim)
        self.n_dyn, self.n_lim, self.path_rows = g_dyn.numel(), g_lim.numel(), rows
        self.solver = ca.nlpsol("min_time", "ipopt", {"x": ca.vertcat(V, T), "p": ca.vertcat(fixed, limits),
                                                      "f": T, "g": ca.vertcat(g_dyn, g_lim)},
                                ipopt_options(tol, max_iter))

    def solve(self, problem: Problem, guess: Guess, duration_guess: float, robot: Robot, turns: int = 0):
        """Minimum-time rest-to-rest motion within ``robot``'s limits (both must be set), from ``guess``
        (normalized time) and ``duration_guess`` [s]. Returns ``(duration, RestResult)``.

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
        x0, lbx, ubx, lbg, ubg = tr.contact_bounds(tr.check_guess(guess), start, final, c, self.path_rows)
        x0 = np.append(x0, check_range("duration_guess", duration_guess, 0.0, 1e6, low_open=True))
        lbg, ubg = np.concatenate([lbg, -np.ones(self.n_lim)]), np.concatenate([ubg, np.ones(self.n_lim)])
        par = np.concatenate([rest_parameters(problem.k, 1.0, robot), [robot.max_rotor_rate, robot.max_rotor_torque]])
        t0 = time.perf_counter()
        sol = interrupts.call(self.solver, x0=x0, lbx=np.append(lbx, 1e-6), ubx=np.append(ubx, 1e6), lbg=lbg, ubg=ubg,
                              p=par)
        solve_time = time.perf_counter() - t0
        st = self.solver.stats()
        status, iters = str(st["return_status"]), int(st["iter_count"])
        if not st["success"]:
            raise SolverError(f"IPOPT did not solve the minimum-time problem: {status} after {iters} iterations",
                              status)
        v = np.array(sol["x"]).ravel()
        T = float(v[-1])
        _, _, controls = tr.unpack(v[:-1])
        motion = certify(controls, start, problem, T, base.samples_per_interval, robot)
        fin = State(*motion.state[-1])
        cert = Certificate("cvodes", fin, problem.residual(fin), 0.0, TOLERANCE)
        if not cert.passed:
            raise SolverError(f"the minimum-time solution misses the goal by {cert.residual:.2e} when integrated by "
                              "CVODES; hint: raise N", "Verification_Failed")
        stats = SolverStats("ipopt", status, iters, solve_time, {})
        return T, RestResult(problem, "minimum_time", tr, T, int(turns), guess.name, c, controls, T, motion, cert,
                             stats)
