"""Routes: a sequence of waypoints, each leg a full-reconfiguration plan, chained and certified as one motion.

Leg ``i`` goes from the *certified* end state of leg ``i - 1`` (not the nominal
waypoint, so that errors do not accumulate; its contact point is the
waypoint's, which the departure roll reaches exactly) to waypoint ``i + 1``, by
:class:`.composed.ComposedPlanner`. The whole route is then certified by one
CVODES integration of all its pieces from the first waypoint
(:func:`.composed.certify_path`), and the state at every waypoint is reported
with its residual; a route any of whose residuals exceeds the tolerance is
never returned. An off-pole intermediate waypoint costs a roll out and back,
since the waypoint demands that contact point.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ...core.plane import wrap_exact
from ...errors import InputError, NoPlanError, show
from ...problem import Problem, State, arrival_residual, check_reach
from ...result import DEFAULT_SAMPLES, Certificate, CertifiedMotion, SolverStats, Trajectory
from ...robot import Robot
from ...waypoints import Waypoint
from ..method import renamed_option
from .composed import LEGS, as_composed, certify_path, default_composed_planner, sample_path
from .refine import DEFAULT_ROOT_SOLVER, SOLVERS

__all__ = ["Route", "plan_route", "check_legs"]


@dataclass(frozen=True)
class Route(CertifiedMotion):
    """A certified route (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem : Problem
        From the first waypoint to the last (k, radius; ``steps`` the default per leg).
    waypoints : tuple of Waypoint
    plans : tuple
        The plan of each leg (:class:`.planner.Plan` or :class:`.composed.ComposedPlan`).
    pieces : tuple of CurvePiece
        The whole contact path [units of R].
    leg_of_piece : ndarray of int
        The leg each piece belongs to.
    certificate : Certificate
        One CVODES integration of the whole route from the first waypoint, against the last.
    waypoint_residuals : ndarray
        Residual of that integration at every waypoint after the first (units of R and rad).
    stats : SolverStats
    path_length : float
        [length unit].
    """

    method = "geometric"
    alternatives = ()

    problem: Problem
    waypoints: tuple
    plans: tuple
    pieces: tuple
    leg_of_piece: np.ndarray
    certificate: Certificate
    waypoint_residuals: np.ndarray
    stats: SolverStats
    path_length: float

    @property
    def steps(self) -> int:
        return self.problem.steps

    @property
    def legs(self) -> tuple:
        """The legs of figure eights of every leg of the route, in order."""
        return tuple(leg for p in self.plans for leg in p.legs)

    def sample(self, samples: int = DEFAULT_SAMPLES) -> Trajectory:
        """The whole route sampled by CVODES from the first waypoint, ``samples`` in all."""
        return sample_path(self.problem, self.pieces, samples)


def check_legs(waypoints, radius: float, where: str = "") -> None:
    """InputError unless every leg of ``waypoints`` (Waypoint, lengths in units of ``radius``) is within reach
    (:func:`rollplan.problem.check_reach`); ``where`` (e.g. the file) starts the message."""
    for i, (a, b) in enumerate(zip(waypoints, waypoints[1:])):
        check_reach(a.state, b.state, radius, f"{where}waypoint {i + 2}", f"waypoint {i + 1}")


def plan_route(waypoints, steps: int = 1, k: float | None = None, robot: Robot | None = None,
               radius: float | None = None, legs: str = "fallback", method: str | None = None,
               progress: Callable | None = None, *, root_solver: str | None = None) -> Route:
    """Plan and certify a route through ``waypoints`` (module docstring).

    Parameters
    ----------
    waypoints : sequence of Waypoint or of states
        At least two; the first is the start. A state is 3 numbers (contact at the pole) or 5.
    steps : int
        Figure eights per leg where a waypoint does not say.
    k, robot, radius
        As for :func:`.composed.plan`.
    legs, root_solver
        The legs policy and root solver of every leg (:func:`.composed.plan`); ``method`` is the deprecated
        name of ``root_solver``.
    progress : callable, optional
        ``progress(done, total)`` after every leg.

    Raises
    ------
    InputError
        Bad input (a waypoint outside the region, fewer than two waypoints...).
    NoPlanError
        A leg has no plan (the message names it), or the route fails its certificate.
    """
    root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
    if not isinstance(root_solver, str) or root_solver not in SOLVERS:
        raise InputError(f"{name} = {show(root_solver)} is not allowed: choose one of {', '.join(SOLVERS)}")
    return _plan_route(waypoints, steps, k, robot, radius, legs, root_solver, progress)


def _plan_route(waypoints, steps, k, robot, radius, legs, method, progress) -> Route:
    t0 = time.perf_counter()
    if isinstance(waypoints, (str, bytes)) or not isinstance(waypoints, (Sequence, np.ndarray)):
        raise InputError(f"waypoints = {show(waypoints)} is not allowed: give a sequence of Waypoint or of states")
    if progress is not None and not callable(progress):
        raise InputError(f"progress = {show(progress)} is not allowed: give a function progress(done, total) or None")
    if not isinstance(legs, str) or legs not in LEGS:
        raise InputError(f"legs = {show(legs)} is not allowed: choose one of {', '.join(LEGS)}")
    wps = tuple(w if isinstance(w, Waypoint) else Waypoint(State.of(w, f"waypoint {i}"))
                for i, w in enumerate(waypoints))
    if len(wps) < 2:
        raise InputError(f"a route needs at least two waypoints (the first is the start), not {len(wps)}")
    whole = Problem(wps[-1].state, start=wps[0].state, k=k, robot=robot, radius=radius, steps=steps)
    check_legs(wps, whole.radius)
    planner = default_composed_planner(method, legs)
    plans, pieces, owner = [], [], []
    here = whole.start
    for i, w in enumerate(wps[1:]):
        leg = Problem(w.state, start=here, k=k, robot=robot, radius=radius, steps=w.steps or steps)
        try:
            p = planner.solve(leg)
        except NoPlanError as exc:
            raise NoPlanError(f"route leg {i + 1} (to waypoint {i + 2}{' ' + repr(w.label) if w.label else ''}): "
                              f"{exc}") from None
        plans.append(p)
        leg_pieces = as_composed(p).pieces
        pieces += leg_pieces
        owner += [i] * len(leg_pieces)
        here = State(*p.final[:3], *w.state[3:])   # the certified end; the contact point is the waypoint's
        if progress is not None:
            progress(i + 1, len(wps) - 1)
    cert, ends = certify_path(whole, pieces, planner.tol)
    owner = np.array(owner, int)
    residuals = []
    for i, w in enumerate(wps[1:]):
        done = np.flatnonzero(owner <= i)
        end = ends[done[-1] + 1] if done.size else ends[0]
        goal = whole.scaled(w.state)
        residuals.append(arrival_residual(end, goal._replace(psi=wrap_exact(goal.psi)[0])))   # psi of any size
    residuals = np.array(residuals)
    if not cert.passed or residuals.max() > planner.tol:
        raise NoPlanError(f"the route fails its certificate: worst waypoint residual {residuals.max():.2e} > "
                          f"{planner.tol:.0e}")
    stats = SolverStats(planner.root_solver, "ok", sum(p.stats.iterations for p in plans),
                        time.perf_counter() - t0, {"modes": [getattr(p, "mode", "one") for p in plans]})
    length = sum(p.path_length for p in plans)
    return Route(whole, wps, tuple(plans), tuple(pieces), owner, cert, residuals, stats, length)
