"""The peer of the rest-to-rest collocation: the same optimal-control problem formulated in rockit.

rockit (``rockit-meco``, KU Leuven MECO, on CasADi; the optional extra ``peer``) transcribes an OCP
stated in continuous time by its own code (:class:`rockit.DirectCollocation`, Opti). The OCP given
to it is the one of :mod:`rollplan.planners.collocation.rest`, term by term:

* dynamics: ``x' = f(x, a)`` with ``f`` the model's own CasADi function
  (:func:`rollplan.planners.collocation.rest.motion_function`, built from
  :func:`rollplan.core.model.contact_rhs`): no equation is typed here;
* state ``x = (u_a, v_a, psi, u_o, v_o, u_o', v_o')``, control the contact accelerations ``a``,
  piecewise constant on the same N equal intervals of the same horizon T;
* cost: the same running cost by name (:data:`~rollplan.planners.collocation.rest.REST_COSTS`),
  ``ocp.integral`` (the collocation quadrature of rockit);
* boundary conditions: the same start and final 7-states at rest
  (:meth:`~rollplan.planners.collocation.rest.RestToRestPlanner.boundary`);
* the contact bound: ``-z >= cos(bound)`` for the contact point (1)
  (:func:`rollplan.core.model.contact_point`) on the control grid and at the collocation points, and
  ``|u_o|, |v_o| <= bound`` there, as in :meth:`.transcription.Transcription.contact_bounds`;
* transcription: rockit's direct collocation with the same degree d and the same points (Legendre or
  Radau, :func:`casadi.collocation_points`), one collocation polynomial per control interval (M = 1);
* solver: IPOPT with the same options (the planner's ``ipopt_options``), started from the same guess
  (its states at the interval boundaries and collocation points, its accelerations).

Both NLPs are then the same finite-dimensional problem written by two independent codes (ordering,
scaling and the form of the boundary conditions differ: rockit imposes them as constraints, rollplan
as variable bounds), so their optima must agree to the solvers' tolerance; :func:`peer_rest_to_rest`
measures by how much, and the solve times of both, side by side (the optima compared are the NLPs'
values, before rollplan's Newton correction). The peer's controls are then corrected by the same
Newton steps (:func:`rollplan.planners.collocation.rest.correct`) and certified by the same CVODES
integration as rollplan's (:func:`rollplan.planners.collocation.rest.certify`).
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .. import interrupts
from ..core import model
from ..errors import InputError, SolverError, check_whole
from ..measures import measure
from ..planners.collocation.rest import (
    REST_COSTS,
    TOLERANCE,
    RestToRestPlanner,
    certify,
    check_horizon,
    correct,
    motion_function,
    naive_guess,
    rest_parameters,
)
from ..planners.collocation.transcription import Guess
from ..problem import Problem, State
from ..robot import Robot
from .comparison import branch_guess

__all__ = ["PeerResult", "PeerComparison", "rockit_solve", "peer_rest_to_rest"]


def _rockit():
    try:
        import rockit
    except ImportError:
        raise InputError("the peer needs rockit: pip install 'rollplan[peer]' (the package rockit-meco)") from None
    return rockit


@dataclass(frozen=True)
class PeerResult:
    """rockit's solution of the rest-to-rest OCP.

    Attributes
    ----------
    objective : float
        The optimal value of rockit's NLP (units of R; ``rotor_energy`` divided by J_r^2, as rollplan's).
    controls : ndarray, shape (N, 2)
        Contact accelerations on each interval [rad/s^2], after the Newton correction.
    iterations : int
        IPOPT iterations.
    first_s : float
        Wall time of the first solve: rockit's transcription, the solver's construction and the solve [s].
    solve_s : list of float
        Wall times of the repeated solves from the same guess (``ocp.solve()`` with the solver built) [s].
    residual : float
        Residual to the goal of the CVODES integration of ``controls`` (units of R, rad).
    costs : dict
        :func:`rollplan.measures.measure` of that integrated motion.
    """

    objective: float
    controls: np.ndarray
    iterations: int
    first_s: float
    solve_s: list
    residual: float
    costs: dict
    #: CPU times of the repeated solves [s] (the process's, so also rockit's Python bookkeeping).
    solve_cpu_s: tuple = ()


def _guess_function(guess: Guess, transcription, horizon: float) -> ca.Function:
    """The guess's states as a piecewise-linear function of t through its values at the interval boundaries
    and collocation points (so rockit, which evaluates it at those times, starts from the same states)."""
    starts, tc = transcription.grid()
    times = np.concatenate([np.append(starts, 1.0), tc.ravel()]) * horizon
    values = np.concatenate([guess.states, guess.colloc.reshape(-1, guess.colloc.shape[-1])])
    times, first = np.unique(times, return_index=True)   # Radau's last point is the next interval's start
    return ca.interpolant("peer_guess", "linear", [times], values[first].ravel())


def rockit_solve(planner: RestToRestPlanner, problem: Problem, guess: Guess, horizon: float = 1.0, turns: int = 0,
                 robot: Robot | None = None, repeats: int = 1) -> PeerResult:
    """Solve the OCP of ``planner`` (its N, d, scheme, cost, contact bound, tolerance and iteration limit) for
    ``problem`` with rockit, from ``guess`` (module docstring); then ``repeats`` more solves from the same
    guess to time them.

    Raises
    ------
    InputError
        Bad input, or rockit is not installed.
    SolverError
        IPOPT failed inside rockit, or the CVODES integration of its controls, after the Newton correction,
        misses the goal by more than :data:`rollplan.planners.collocation.rest.TOLERANCE`.
    """
    rockit = _rockit()
    start, final = planner.boundary(problem, turns)
    tr = planner.transcription
    guess = tr.check_guess(guess)
    repeats = check_whole("repeats", repeats, 0, 1000)
    horizon = check_horizon(horizon)
    robot = robot if robot is not None else problem.robot
    if planner.cost == "rotor_energy" and robot is None:
        raise InputError("cost = 'rotor_energy' needs robot parameters: give a robot "
                         "(the robot argument; --robot FILE.toml on the command line)")
    par = rest_parameters(problem.k, horizon, robot)
    bound = planner.contact_bound

    ocp = rockit.Ocp(T=float(horizon))
    x = ocp.state(7)
    a = ocp.control(2)
    xdot, omega, _, torque = motion_function()(x, a, par)
    ocp.set_der(x, xdot)
    ocp.add_objective(ocp.integral(REST_COSTS[planner.cost](xdot, omega, torque, par)))
    ocp.subject_to(ocp.at_t0(x) == start)
    ocp.subject_to(ocp.at_tf(x) == final)
    depth = -model.contact_point(x[3], x[4])[2]
    for grid in ("control", "integrator_roots"):
        ocp.subject_to(depth >= math.cos(bound), grid=grid)
        ocp.subject_to(-bound <= (x[3] <= bound), grid=grid)
        ocp.subject_to(-bound <= (x[4] <= bound), grid=grid)
    ocp.set_initial(x, _guess_function(guess, tr, horizon)(ocp.t))
    ocp.set_initial(a, guess.controls.T)
    ocp.method(rockit.DirectCollocation(N=tr.intervals, M=1, degree=tr.degree, scheme=tr.scheme))
    ocp.solver("ipopt", {**planner.ipopt_options, "expand": True})

    def solve():
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            sol = interrupts.call(ocp.solve)
        except RuntimeError as exc:
            raise SolverError(f"rockit/IPOPT did not solve the rest-to-rest problem: {exc}",
                              "rockit_failed") from None
        return sol, time.perf_counter() - t0, time.process_time() - c0

    sol, first, _ = solve()
    timed = [solve()[1:] for _ in range(repeats)]
    times = [t for t, _ in timed]
    controls = np.asarray(sol.sample(a, grid="control")[1], float)[:-1].reshape(tr.intervals, 2)
    controls = correct(controls * horizon ** 2, start, final, rest_parameters(problem.k, 1.0, robot), planner.cost,
                       "rockit's")[0] / horizon ** 2
    motion = certify(controls, start, problem, horizon, planner.samples_per_interval, robot)
    residual = problem.residual(State(*motion.state[-1]))
    if residual > TOLERANCE:
        raise SolverError(f"rockit's solution misses the goal by {residual:.2e} when integrated by CVODES",
                          "Verification_Failed")
    return PeerResult(float(sol.value(ocp.objective)), controls, int(sol.stats["iter_count"]), first, times,
                      float(residual), measure(motion), tuple(c for _, c in timed))


@dataclass(frozen=True)
class PeerComparison:
    """rollplan's rest-to-rest collocation and rockit's on one problem from one guess.

    Attributes
    ----------
    target : tuple
    intervals, degree : int
    guess : str
        Name of the common guess.
    objective, peer_objective : float
        The NLP optima of rollplan and of rockit (before the Newton correction).
    relative_difference : float
        ``|peer - ours| / |ours|``.
    control_difference : float
        Largest difference of the (corrected) accelerations on an interval [rad/s^2].
    iterations, peer_iterations : int
    build_s : float
        rollplan's NLP and solver construction [s].
    solve_s : list of float
        rollplan's IPOPT wall times of ``repeats + 1`` solves [s] (the first with any backed-off solve).
    peer : PeerResult
    residual : float
        rollplan's certified residual.
    """

    target: tuple
    intervals: int
    degree: int
    guess: str
    objective: float
    peer_objective: float
    relative_difference: float
    control_difference: float
    iterations: int
    peer_iterations: int
    build_s: float
    solve_s: list
    peer: PeerResult
    residual: float
    #: rollplan's CPU times of the same solves (IPOPT from the guess, without the correction) [s].
    solve_cpu_s: tuple = ()

    def row(self) -> dict:
        """A flat dict of the numbers (for tables and JSON): medians of the solve times."""
        p = self.peer
        return {"target": list(self.target), "N": self.intervals, "d": self.degree, "guess": self.guess,
                "objective": self.objective, "peer_objective": p.objective,
                "relative_difference": self.relative_difference, "control_difference": self.control_difference,
                "iterations": self.iterations, "peer_iterations": p.iterations, "build_s": self.build_s,
                "peer_first_s": p.first_s, "solve_median_s": statistics.median(self.solve_s),
                "peer_solve_median_s": statistics.median(p.solve_s) if p.solve_s else p.first_s,
                "solve_cpu_median_s": statistics.median(self.solve_cpu_s) if self.solve_cpu_s else math.nan,
                "peer_solve_cpu_median_s": statistics.median(p.solve_cpu_s) if p.solve_cpu_s else math.nan,
                "residual": self.residual, "peer_residual": p.residual}


def peer_rest_to_rest(problem: Problem, guess: Guess | str = "naive", horizon: float = 1.0, turns: int = 0,
                      intervals: int = 20, degree: int = 3, scheme: str = "legendre", cost: str = "angular_velocity",
                      contact_bound: float = math.radians(80.0), robot: Robot | None = None,
                      repeats: int = 3) -> PeerComparison:
    """Solve the rest-to-rest OCP of ``problem`` by rollplan (:class:`RestToRestPlanner`) and by rockit
    (:func:`rockit_solve`) from the same guess (``"naive"`` for :func:`naive_guess`, ``"gp"`` for
    :func:`rollplan.studies.comparison.branch_guess` with its turns m, or a :class:`Guess` of this
    transcription), ``repeats + 1`` times each, and compare the optima and the solve times.

    Raises
    ------
    InputError, SolverError
    """
    t0 = time.perf_counter()
    planner = RestToRestPlanner(intervals, degree, scheme, cost, contact_bound)
    build = time.perf_counter() - t0
    if isinstance(guess, str) and guess == "gp":
        guess, turns = branch_guess(problem, planner, horizon, robot)
    elif isinstance(guess, str) and guess == "naive":
        guess = naive_guess(planner.transcription, *planner.boundary(problem, turns))
    elif not isinstance(guess, Guess):
        raise InputError(f"guess = {guess!r:.40} is not allowed: give 'naive', 'gp' or a Guess")
    nlps, cpu = [], []
    for _ in range(check_whole("repeats", repeats, 0, 1000) + 1):
        c0 = time.process_time()
        nlps.append(planner.solve_nlp(problem, guess, horizon, turns, robot))
        cpu.append(time.process_time() - c0)
    r = planner.finish(nlps[0])     # the repeats reach the same NLP solution: the first is corrected and certified
    peer = rockit_solve(planner, problem, guess, horizon, turns, robot, repeats)
    nlp = r.stats.details["nlp_objective"]
    return PeerComparison(tuple(problem.goal)[:3], planner.transcription.intervals, planner.transcription.degree,
                          guess.name, nlp, peer.objective, abs(peer.objective - nlp) / abs(nlp),
                          float(np.abs(peer.controls - r.controls).max()), r.stats.iterations, peer.iterations, build,
                          [r.stats.time_s] + [n.solve_time_s for n in nlps[1:]], peer, r.residual, tuple(cpu))
