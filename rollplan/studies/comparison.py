"""A fair comparison of the geometric-phase plan and the optimal-control (collocation) optimum.

One problem for both (:class:`~rollplan.problem.Problem`): rest at the origin to a goal at the
pole, the same horizon T, the same contact bound, psi an angle for both, the same control class,
the same cost, measured by the same function on the same trajectory type.

* Contact bound. One value (:data:`CONTACT_BOUND` by default) for both. A circle of the figure
  eight of radius a through the south pole reaches the polar angle ``2 asin(a / R)``, so the
  geometric-phase (GP) planner keeps only branches with ``a, b <= R sin(bound / 2)``
  (:func:`leaf_radius_bound`); the collocation bounds the contact point at every collocation point.
* Rest to rest, acceleration-level controls for both. The GP path is timed by the rest-to-rest
  timing that minimises the compared cost (:func:`rollplan.execution.optimal_timing.optimal_timing`,
  ``s''`` constant on the same N intervals); the collocation
  (:mod:`rollplan.planners.collocation.rest`) controls the contact accelerations, constant on N
  intervals, with zero contact rates at both ends.
* psi is an angle. The collocation is solved from several starts with their own whole turns m of
  psi (multistart, :func:`compare`), and the best certified one is kept.
* Costs by name (:data:`COMPARED_COSTS`), every one measured by :func:`rollplan.measures.measure` on
  the :class:`~rollplan.timeseries.TimeSeries` of each side (the GP's from the exact path, the
  collocation's from the CVODES certification); both sides minimise :data:`MINIMISED_COSTS` of it (the
  path length by its energy form ``int |v|^2 dt``, whose minimizers on a fixed horizon are the shortest
  paths at constant speed).
* Both sides are solved through the registry (:func:`rollplan.planners.solve`): ``"geometric"`` with
  ``legs="one"``, ``"rest_to_rest"`` (and ``"minimum_time"`` for :func:`minimum_time`).

Starts of the multistart (each a :class:`Start`): ``gpI:m`` the collocation warm-started from the
timed GP branch I (the first ``branches`` admissible branches, shortest first) with its m whole turns;
``gpI:m->m2`` the best GP branch's motion with psi bent linearly in time to end at ``m2`` turns
(the nearest other m and m = 0); ``naive:m`` the straight line at rest.

Screening (N >= :data:`SCREEN_FROM`): every start is first solved on the coarse grid of
:data:`SCREEN_INTERVALS` intervals; on the full grid are solved ``gp0`` (from its timed GP branch, always) and each
other start whose coarse optimum is within :data:`SCREEN_MARGIN` of the least coarse optimum and not that of an
earlier start (the same turns, the same coarse optimum to :data:`SCREEN_SAME`), warm-started from its coarse
solution (a ``gpI:m`` start from its GP branch). The others are marked ``"Screened_Out"``.
"""

from __future__ import annotations

import logging
import math
import os
import threading
import time
from dataclasses import dataclass, replace
from functools import partial

import numpy as np

from .. import interrupts
from ..errors import InputError, NoPlanError, SolverError, check_choice, check_range, check_whole
from ..execution.actuation import actuate
from ..execution.optimal_timing import contact_rates, optimal_timing, timed_samples, timing_bound
from ..execution.path import ContactPath
from ..measures import measure
from ..planners import METHODS, solve
from ..planners.collocation.rest import (
    RestResult,
    RestToRestPlanner,
    check_horizon,
    check_intervals,
    guess_from_samples,
    naive_guess,
)
from ..planners.collocation.transcription import Guess
from ..planners.geometric import CURVE_CHOICES, Plan
from ..problem import K_MAX, Problem
from ..progress import report
from ..robot import Robot
from ..timeseries import TimeSeries

__all__ = ["CONTACT_BOUND", "COMPARED_COSTS", "MINIMISED_COSTS", "SIDE_KEYS", "TRAJECTORY_KEYS", "Start", "Side",
           "Comparison", "MAX_WORKERS", "SCREEN_FROM", "SCREEN_INTERVALS", "SCREEN_MARGIN", "SCREEN_SAME",
           "multistart_workers", "leaf_radius_bound", "robot_for_k", "branch_guess", "compare", "comparison_to_dict",
           "MinimumTime", "minimum_time"]

log = logging.getLogger(__name__)

#: Default contact bound of both planners: largest polar angle of the contact point [rad] (80 deg).
CONTACT_BOUND = math.radians(80.0)
#: Costs a comparison can be made for: names in :data:`rollplan.measures.COSTS`, measured on both motions.
COMPARED_COSTS = ("path_length", "angular_velocity", "rotor_energy")
#: What the collocation and the GP timing minimise for each compared cost (names in
#: :data:`~rollplan.planners.collocation.rest.REST_COSTS` and
#: :data:`~rollplan.execution.optimal_timing.TIMING_COSTS`).
MINIMISED_COSTS = {"path_length": "path_energy", "angular_velocity": "angular_velocity",
                   "rotor_energy": "rotor_energy"}
#: Most starts of the multistart solved at the same time (:func:`multistart_workers`).
MAX_WORKERS = 2
#: Intervals of the coarse grid on which the starts are screened (module docstring).
SCREEN_INTERVALS = 10
#: Least N of the full grid for which the starts are screened.
SCREEN_FROM = 40
#: A screened start is solved on the full grid when its coarse optimum is at most ``1 + SCREEN_MARGIN`` times the
#: least coarse optimum (the coarse optima exceed the full grid's by about 10 %: the optimum converges at first order
#: in N from above).
SCREEN_MARGIN = 0.2
#: Relative difference below which two coarse optima of the same turns are the same optimum.
SCREEN_SAME = 1e-6
#: Keys of each side in the JSON of ``rollplan compare --json``.
SIDE_KEYS = ("path_length", "effort", "residual", "solve_time_s", "contact_bound", "trajectory")
#: Columns of each side's trajectory in that JSON.
TRAJECTORY_KEYS = ("t", "u_o", "v_o", "u_a", "v_a", "psi")


def leaf_radius_bound(contact_bound: float) -> float:
    """Largest leaf radius [R] of a figure eight whose contact point stays within ``contact_bound`` [rad]
    of the south pole: a circle of radius a through the pole reaches the polar angle ``2 asin(a)``."""
    return math.sin(contact_bound / 2.0)


def robot_for_k(k: float) -> Robot:
    """A robot of radius 1 with inertia ratio ``k`` (14) and ``J_zz = 1``: what the GP timing needs when only k
    is given (its omega does not depend on the inertias; its rotor rates and torques are in units of J_zz).

    k must lie in (1, :data:`~rollplan.problem.K_MAX`]: by (14) ``k = J_xx / J_zz = 1 + M R^2 / J_zz`` exceeds 1
    for every robot with mass, so no robot has ``k <= 1``."""
    k = check_range("k", k, 1.0, K_MAX, low_open=True)
    shell = min(0.5 * (k - 1.0), 0.75)          # m_o <= M = k - 1
    rotor = (1.0 - 2.0 / 3.0 * shell) / 3.0     # J_r = J_p: 2/3 m_o + 2 J_p + J_r = 1
    return Robot(radius=1.0, mass_total=k - 1.0, mass_shell=shell, rotor_inertia_axial=rotor,
                 rotor_inertia_transverse=rotor)


@dataclass(frozen=True)
class Start:
    """One start of the collocation's multistart and how it ended.

    Attributes
    ----------
    name : str
        ``gpI:m``, ``gpI:m->m2`` or ``naive:m`` (module docstring).
    turns : int
        Whole turns m of psi the collocation steers to.
    status : str
        IPOPT's status, ``"Verification_Failed"``, or ``"ok"``.
    cost : float or None
        The compared cost: of the kept start measured on its certified motion, of the other converged starts
        their NLP optimum (only the best NLP optimum is corrected and certified); None when it failed.
    start_cost : float or None
        The same cost of the timed GP branch it started from (``gpI:m`` starts only).
    solve_time_s : float
        IPOPT's time [s] (on both grids when screened).
    coarse_cost : float or None
        Its optimum on the coarse grid of the screening (module docstring); None when not screened or it failed
        there.
    """

    name: str
    turns: int
    status: str
    cost: float | None
    start_cost: float | None
    solve_time_s: float
    coarse_cost: float | None = None


@dataclass(frozen=True)
class Side:
    """One side of a comparison: its motion and what it costs.

    Attributes
    ----------
    motion : TimeSeries
    costs : dict
        :func:`rollplan.measures.measure` of ``motion``.
    residual : float
        Certified residual to the goal (units of R, rad).
    solve_time_s : float
        Wall time of the whole side [s]: GP planning and timing of its branches; every start of the collocation.
    """

    motion: TimeSeries
    costs: dict
    residual: float
    solve_time_s: float


@dataclass(frozen=True)
class Comparison:
    """Both methods on one problem (module docstring).

    Attributes
    ----------
    problem : Problem
    robot : Robot
        The problem's robot, or :func:`robot_for_k` without one.
    horizon : float
        T [s].
    cost : str
        The compared cost, in :data:`COMPARED_COSTS`.
    contact_bound : float
        Of both planners [rad].
    plan : Plan
        The GP branch with the least compared cost among those timed.
    gp, collocation : Side
    result : RestResult
        The best collocation solution.
    starts : tuple of Start
    branches : tuple of (Plan, Side)
        Every timed GP branch within the bound, shortest first.
    bound : float or None
        For ``cost == "angular_velocity"``: the least ``int |omega|^2 dt`` of any timing of ``plan``'s path
        over T (:func:`rollplan.execution.optimal_timing.timing_bound`); None for the other costs (the
        path length does not depend on the timing; no bound is computed for the torque energy).
    """

    problem: Problem
    robot: Robot
    horizon: float
    cost: str
    contact_bound: float
    plan: object
    gp: Side
    collocation: Side
    result: RestResult
    starts: tuple
    branches: tuple
    bound: float | None

    @property
    def effort(self) -> tuple[float, float]:
        """The compared cost of the GP side and of the collocation side."""
        return self.gp.costs[self.cost], self.collocation.costs[self.cost]


def _nlp_options(intervals, degree, scheme, cost, contact_bound) -> dict:
    """The options of the method ``"rest_to_rest"`` that make its NLP (shared by every start)."""
    return {"intervals": intervals, "degree": degree, "scheme": scheme, "cost": cost, "contact_bound": contact_bound}


def _planner(intervals, degree, scheme, cost, contact_bound) -> RestToRestPlanner:
    """The NLP of the method ``"rest_to_rest"`` for these options (built once, shared with its solves)."""
    return METHODS["rest_to_rest"](**_nlp_options(intervals, degree, scheme, cost, contact_bound)).planner


def _branches(problem: Problem, robot: Robot, contact_bound: float, wanted: int, curve: str = "circles") -> list:
    """Up to ``wanted`` certified GP branches of one leg whose leaves stay within the bound: the planner's
    (the shortest), then its neighbours ``m +- 1, m +- 2, ...`` (at most ``2 wanted + 2`` branches tried), of the
    leaf family ``curve`` (for ``best``: the branches of the family of the shortest plan)."""
    amax = leaf_radius_bound(contact_bound) * problem.radius
    gp_problem = Problem(problem.goal, robot=robot, radius=problem.radius, steps=problem.steps)
    options = {} if curve == "circles" else {"curve": curve}
    gp_plan = lambda **kw: solve(gp_problem, "geometric", legs="one", **{**options, **kw})  # noqa: E731
    try:
        first = gp_plan()
    except NoPlanError as exc:
        raise NoPlanError(f"{exc} (the comparison needs a plan of one leg of figure eights)") from None
    if not isinstance(first, Plan):   # a turn in place or the empty motion: not one leg of figure eights
        raise NoPlanError(f"{problem.describe()} has no plan of one leg of figure eights (it is "
                          f"{'the start itself' if not first.pieces else 'a ' + first.mode + ' motion'}); "
                          "the comparison needs one")
    found = [first]
    if curve == "best":
        options = {"curve": first.curve}
    for d in range(1, wanted + 2):
        for m in (first.branch - d, first.branch + d):
            try:
                found.append(gp_plan(branch=m))
            except NoPlanError:
                continue
    ok = sorted((q for q in found if max(q.a, q.b) <= amax), key=lambda q: q.path_length)
    if not ok:
        raise NoPlanError(f"no geometric-phase plan for {problem.describe()} near branch {first.branch} keeps its "
                          f"leaves within a, b <= {amax / problem.radius:.6g} R (contact bound {contact_bound:.6g} "
                          "rad); raise --contact-bound or --steps")
    return ok[:wanted]


def _warm_samples(motion: TimeSeries, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """``(t, x7)`` of a timed GP motion: the state in units of R and the contact rates, (8)-(9)."""
    rates = contact_rates(motion.omega, motion.state)[:, 2:4]
    x7 = np.column_stack([motion.state / np.array([radius, radius, 1.0, 1.0, 1.0]), rates])
    return motion.time, x7


def _robot(problem: Problem, robot: Robot | None) -> Robot:
    """``robot``, else the problem's, else :func:`robot_for_k` scaled to the problem's radius."""
    if robot is not None or problem.robot is not None:
        return robot if robot is not None else problem.robot
    rob, radius = robot_for_k(problem.k), problem.radius
    if radius == 1.0:
        return rob
    return Robot(radius=radius, mass_total=rob.mass_total, mass_shell=rob.mass_shell,
                 rotor_inertia_axial=rob.rotor_inertia_axial * radius ** 2,
                 rotor_inertia_transverse=rob.rotor_inertia_transverse * radius ** 2)


def _timed(p, robot: Robot, horizon: float, planner: RestToRestPlanner, intervals: int | None = None):
    """``(path, motion)``: the GP plan ``p``'s path timed by the rest-to-rest timing minimising the planner's cost on
    its N intervals (or ``intervals``), sampled like the planner's certified motions."""
    path = ContactPath.of_plan(p, robot)
    timing = optimal_timing(path, horizon, planner.cost, intervals or planner.transcription.intervals)
    return path, timed_samples(path, timing, planner.samples_per_interval)


def _turns(p, problem: Problem) -> int:
    """Whole turns m of psi of the GP plan ``p``: its final psi is the goal's + 2 pi m."""
    return round((p.final.psi - problem.goal.psi) / (2 * math.pi))


def branch_guess(problem: Problem, planner: RestToRestPlanner, horizon: float = 1.0,
                 robot: Robot | None = None, curve: str = "circles") -> tuple[Guess, int]:
    """The warm start ``gp0:m`` of :func:`compare` for ``planner``: the shortest GP branch within its contact
    bound, timed by the rest-to-rest timing of its cost, as a guess of its transcription; and m.

    Raises
    ------
    InputError, NoPlanError
    """
    rob = _robot(problem, robot)
    p = _branches(problem, rob, planner.contact_bound, 1, check_choice("curve", curve, CURVE_CHOICES))[0]
    _, motion = _timed(p, rob, horizon, planner)
    m = _turns(p, problem)
    return guess_from_samples(planner.transcription, *_warm_samples(motion, problem.radius), f"gp0:{m}"), m


def compare(target, steps: int = 1, k: float | None = None, robot: Robot | None = None,
            radius: float | None = None, horizon: float = 1.0, cost: str = "angular_velocity",
            intervals: int = 100, degree: int = 3, scheme: str = "legendre",
            contact_bound: float = CONTACT_BOUND, branches: int = 2, naive: bool = True,
            workers: int | None = None, curve: str = "circles", screen: bool = True) -> Comparison:
    """Solve one problem by both methods, fairly (module docstring), and measure both.

    Parameters
    ----------
    target : sequence
        Goal ``(u_a, v_a, psi)`` at the pole [length unit, rad]; the start is rest at the origin.
    steps : int
        Figure eights n of the GP plan.
    k, robot, radius
        As in :class:`~rollplan.problem.Problem`; without a robot k > 1 is needed (:func:`robot_for_k`).
    horizon : float
        T [s] of both motions, in :data:`~rollplan.planners.collocation.rest.HORIZON_RANGE`.
    cost : str
        In :data:`COMPARED_COSTS`; ``"rotor_energy"`` needs a robot.
    intervals, degree, scheme
        N (of both the collocation and the GP timing) in [:data:`~rollplan.planners.collocation.rest.MIN_INTERVALS`,
        :data:`~rollplan.planners.collocation.rest.MAX_INTERVALS`], d and points of the collocation.
    contact_bound : float
        Of both planners [rad], in (0, pi/2).
    branches : int
        GP branches timed and used as warm starts (>= 1).
    naive : bool
        Also start the collocation from the straight line at rest.
    workers : int or None
        Starts solved at the same time, each worker with its own IPOPT solver of the one NLP (None:
        :func:`multistart_workers`).
    curve : str
        Leaf family of the GP plan (:data:`rollplan.planners.geometric.CURVE_CHOICES`; ``best``: the family of the
        shortest plan). Its timing rests at the path's corners (a polygon's vertices).
    screen : bool
        Screen the starts on the coarse grid when N >= :data:`SCREEN_FROM` (module docstring); False: every
        start solved on the full grid.

    Raises
    ------
    InputError, NoPlanError, SolverError
        Bad input; no GP plan within the bound; no start of the collocation converged.
    """
    if not isinstance(cost, str) or cost not in COMPARED_COSTS:
        raise InputError(f"cost = {cost!r:.40} is not allowed: choose one of {', '.join(COMPARED_COSTS)}")
    if cost == "rotor_energy" and robot is None:
        raise InputError("cost = 'rotor_energy' needs robot parameters: give a robot "
                         "(the robot argument; --robot FILE.toml on the command line)")
    if robot is None and k is not None:
        robot_for_k(k)                      # k in (1, K_MAX]: refused before any work
    problem = Problem(tuple(target), k=None if robot is not None else k, robot=robot, radius=radius, steps=steps)
    if not problem.start.at_pole or not problem.goal.at_pole or tuple(problem.start) != (0.0,) * 5:
        raise InputError("the comparison starts at rest at the origin and ends at the pole")
    contact_bound = check_range("contact_bound", contact_bound, 0.0, math.pi / 2, True, True)
    horizon = check_horizon(horizon)
    branches = check_whole("branches", branches, 1, 100)
    workers = multistart_workers() if workers is None else check_whole("workers", workers, 1, 64)
    curve = check_choice("curve", curve, CURVE_CHOICES)
    rob = _robot(problem, robot)
    check_intervals(intervals)
    nlp = _nlp_options(intervals, degree, scheme, MINIMISED_COSTS[cost], contact_bound)
    t0 = time.perf_counter()
    gp_plans = _branches(problem, rob, contact_bound, branches, curve)   # no plan: said before the NLP is built
    gp_time = time.perf_counter() - t0
    report("compare", 0, 3, stage="building the collocation NLP")
    screened = screen is not False and intervals >= SCREEN_FROM
    if screened:    # one NLP built at a time: CasADi's symbolics are not thread-safe (its evaluation is)
        full_planner = interrupts.call_in_thread(_planner, **nlp)   # checks N, d, scheme, bound
        full = lambda: full_planner   # noqa: E731
        planner = _planner(**{**nlp, "intervals": SCREEN_INTERVALS})
    else:
        planner = _planner(**nlp)   # checks N, d, scheme, bound

    t0 = time.perf_counter()
    timed = []
    report("compare", 1, 3, stage="timing the geometric-phase branches")
    for p in gp_plans:
        path, motion = _timed(p, rob, horizon, planner, intervals)
        timed.append((p, Side(motion, measure(motion), p.residual, 0.0), path))
    gp_time += time.perf_counter() - t0
    best_gp = min(range(len(timed)), key=lambda i: timed[i][1].costs[cost])
    plan, gp_side, gp_path = timed[best_gp]
    gp_side = Side(gp_side.motion, gp_side.costs, gp_side.residual, gp_time)

    turns_of = lambda q: _turns(q, problem)  # noqa: E731
    candidates = [(f"gp{i}:{turns_of(p)}", turns_of(p), *_warm_samples(side.motion, problem.radius),
                   side.costs[cost]) for i, (p, side, _) in enumerate(timed)]
    m0 = turns_of(plan)
    t_best, x_best = _warm_samples(gp_side.motion, problem.radius)
    for m2 in sorted({m0 - 1, m0 + 1, 0} - {m0}, key=abs):
        x2 = x_best.copy()
        x2[:, 2] += 2 * math.pi * (m2 - m0) * t_best / t_best[-1]
        candidates.append((f"gp{best_gp}:{m0}->{m2}", m2, t_best, x2, None))
    t1 = time.perf_counter()
    naive_turns = sorted({m0, 0}, key=abs) if naive else []
    jobs = [(name, m, partial(guess_from_samples, t=t, x7=x7, name=name), start_cost)
            for name, m, t, x7, start_cost in candidates]
    jobs += [(f"naive:{m}", m, partial(naive_guess, start=a, final=b), None)
             for m in naive_turns for a, b in [planner.boundary(problem, m)]]
    total = 3 + len(jobs) * (2 if screened else 1)
    finished = {}
    if screened:
        starts, results = _screened(full, planner, problem, rob, horizon, jobs, total, workers, finished)
        planner = full()
    else:
        starts, outs = _multistart(planner, problem, rob, horizon, jobs, (2, total, ""), workers)
        results = [(s.name, r) for s, r in zip(starts, outs) if r is not None]
    report("compare", total - 1, total, stage="correcting and certifying the best optimum")
    best, starts = _finish_best(planner, results, starts, finished)
    coll_time = time.perf_counter() - t1
    report("compare", total, total, stage="done")
    if best is None:
        worst = starts[0].status
        raise SolverError(f"no start of the collocation converged for {problem.describe()} (first: {worst})", worst)
    coll = Side(best.motion, measure(best.motion), best.residual, coll_time)
    return Comparison(problem, rob, float(horizon), cost, contact_bound, plan, gp_side, coll, best, tuple(starts),
                      tuple((p, s) for p, s, _ in timed),
                      timing_bound(gp_path, horizon, cost) if cost == "angular_velocity" else None)


def multistart_workers() -> int:
    """Starts of the multistart solved at the same time by default: one per core the process may use, at most
    :data:`MAX_WORKERS` (each worker's solver shares the NLP's derivatives, and a start is a fraction of a
    second, so more gain little)."""
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:      # not on Linux
        cores = os.cpu_count() or 1
    return max(1, min(cores, MAX_WORKERS))


def _screened(full, coarse, problem, robot, horizon, jobs, total, workers, finished):
    """The multistart of ``jobs`` screened on the coarse grid of ``coarse`` (module docstring): ``(starts,
    results)`` as :func:`_multistart`'s, the results those of the full grid (the planner ``full()``). The first
    start is solved on the full grid, and finished into ``finished``, with the screening, by a worker once
    ``full()`` is built."""
    log.info("screening %d starts on the coarse grid of N = %d", len(jobs), coarse.transcription.intervals)
    both, outs = _multistart(coarse, problem, robot, horizon, [(*jobs[0], full), *jobs],
                             (1, total, " on the coarse grid"), workers, finished)
    fine, cstarts, found = {jobs[0][0]: (both[0], outs[0])}, both[1:], {}
    for s, r in zip(cstarts, outs[1:]):
        if r is not None:
            found[s.name] = r
    least = min((r.objective for r in found.values()), default=None)
    chosen, fine_jobs = [jobs[0][0]], []
    for name, m, make_guess, start_cost in jobs[1:]:
        r = found.get(name)
        if r is None or r.objective > least + SCREEN_MARGIN * abs(least):
            continue
        if any(found[c].turns == m and abs(found[c].objective - r.objective) <= SCREEN_SAME * abs(r.objective)
               for c in chosen if c in found):
            continue
        if "->" in name or name.startswith("naive"):
            make_guess = partial(_refined_guess, r, coarse.transcription)
        chosen.append(name)
        fine_jobs.append((name, m, make_guess, start_cost, full))
    if fine_jobs:
        more, outs = _multistart(coarse, problem, robot, horizon, fine_jobs, (2 + len(jobs), total, ""), workers)
        fine.update((s.name, (s, r)) for s, r in zip(more, outs))
    starts, results = [], []
    for s in cstarts:
        coarse_cost = found[s.name].objective if s.name in found else None
        if s.name in fine:
            f, r = fine[s.name]
            starts.append(replace(f, solve_time_s=f.solve_time_s + s.solve_time_s, coarse_cost=coarse_cost))
            if r is not None:
                results.append((s.name, r))
        elif coarse_cost is None:
            starts.append(s)
        else:
            starts.append(replace(s, status="Screened_Out", cost=None, coarse_cost=coarse_cost))
    return starts, results


def _refined_guess(nlp, coarse_tr, tr) -> Guess:
    """A guess on ``tr`` following the coarse solution ``nlp`` (its states at the interval ends and the collocation
    points, in time over its horizon)."""
    states, colloc, _ = coarse_tr.unpack(nlp.x)
    starts, tc = coarse_tr.grid()
    t = np.concatenate([np.append(starts, 1.0), tc.ravel()])
    x7 = np.concatenate([states, colloc.reshape(-1, states.shape[1])])
    order = np.argsort(t, kind="stable")
    x7 = x7[order] / np.array([1.0] * 5 + [nlp.horizon] * 2)
    return guess_from_samples(tr, t[order] * nlp.horizon, x7, nlp.guess.name)


def _multistart(planner, problem, robot, horizon, jobs, progress, workers, finished=None):
    """IPOPT from every start of ``jobs`` (``(name, turns, make guess of a transcription, start cost)``, and
    optionally a function returning the planner of that start instead of ``planner``), by ``workers`` at once
    (the first with the planners' own solvers, the others with twins): ``(starts, solutions)`` in the order of
    ``jobs``, each solution the :class:`NlpSolution` or None (see :func:`_run`). ``progress``: the step of the
    first start, the total and what follows each start's name in the progress. With a dict ``finished``, the
    starts with their own planner are also finished (corrected and certified): their outcomes by name."""
    first, total, where = progress
    pending, lock = iter(range(len(jobs))), threading.Lock()
    workers = min(workers, len(jobs))

    def work(own):
        solvers, done = {}, []
        while True:
            with lock:
                i = next(pending, None)
            if i is None:
                return done
            name, m, make_guess, start_cost, *which = jobs[i]
            base = which[0]() if which else planner
            if id(base) not in solvers:     # a twin is built only by a worker that gets a start of that planner
                solvers[id(base)] = base if own else base.twin()
            solver = solvers[id(base)]
            report("compare", first + i, total, stage=f"collocation from {name}{'' if which else where}")
            out = []
            start = _run(solver, problem, robot, make_guess(tr=solver.transcription), horizon, m, start_cost, out, name)
            done.append((i, start, out[0][1] if out else None))
            if out and finished is not None and which:
                try:
                    finished[name] = interrupts.call(solver.finish, out[0][1])
                except SolverError as exc:
                    finished[name] = exc

    log.info("solving %d starts with %d worker(s)", len(jobs), workers)
    if workers == 1:
        finished = work(True)
    else:
        finished = [d for w in interrupts.call_in_threads([partial(work, w == 0) for w in range(workers)])
                    for d in w]
    finished.sort(key=lambda item: item[0])
    return [start for _, start, _ in finished], [r for _, _, r in finished]


def _run(planner, problem, robot, guess, horizon, turns, start_cost, results, name=None) -> Start:
    """IPOPT from one start (not corrected, not certified): its :class:`Start` with the NLP optimum as its
    cost; the solution appended to ``results`` as ``(index of the start, NlpSolution)``."""
    t0 = time.perf_counter()
    name = name or guess.name
    try:
        # Ctrl-C inside IPOPT ends that solve only: interrupts.call raises it, which stops the whole multistart
        r = interrupts.call(planner.solve_nlp, problem, guess, horizon, turns, robot)
    except SolverError as exc:
        return Start(name, turns, exc.status, None, start_cost, time.perf_counter() - t0)
    results.append((name, r))
    return Start(name, turns, "ok", r.objective, start_cost, r.solve_time_s)


def _finish_best(planner, results, starts, finished=None):
    """Correct and certify the converged starts in the order of their NLP optima until one passes:
    ``(RestResult or None, starts)`` with that start's cost measured on its certified motion and every start
    that failed the correction or the certificate marked with its status. ``finished``: the outcomes (RestResult
    or SolverError) of starts already finished, by name."""
    by_name = {s.name: i for i, s in enumerate(starts)}
    starts = list(starts)
    finished = finished or {}
    for name, nlp in sorted(results, key=lambda item: item[1].objective):
        i = by_name[name]
        try:
            best = finished.get(name) or interrupts.call(planner.finish, nlp)
            if isinstance(best, SolverError):
                raise best
        except SolverError as exc:
            starts[i] = replace(starts[i], status=exc.status, cost=None)
            continue
        starts[i] = replace(starts[i], cost=measure(best.motion)[planner.cost], solve_time_s=best.stats.time_s)
        return best, starts
    return None, starts


def _side(c: Comparison, side: Side) -> dict:
    cols = side.motion.columns()
    return {"path_length": side.costs["path_length"], "effort": side.costs[c.cost], "residual": side.residual,
            "solve_time_s": side.solve_time_s, "contact_bound": c.contact_bound,
            "trajectory": {key: cols[key] for key in TRAJECTORY_KEYS}}


def comparison_to_dict(c: Comparison) -> dict:
    """The JSON object of ``rollplan compare --json``: per side exactly :data:`SIDE_KEYS`; the rest under
    ``details``."""
    g, p, r = c.problem.goal, c.plan, c.result
    return {
        "target": {"u_a": g.u_a, "v_a": g.v_a, "psi": g.psi}, "k": c.problem.k, "radius": c.problem.radius,
        "horizon": c.horizon, "steps": c.problem.steps, "cost": c.cost,
        # the JSON keys of the sides (kept): "geometric_phase" is the method "geometric"
        "geometric_phase": _side(c, c.gp), "collocation": _side(c, c.collocation),
        "details": {
            "geometric_phase": {"costs": c.gp.costs, "figure_eight": {"a": p.a, "b": p.b, "gamma": p.gamma,
                                                                                 "curve": p.curve},
                                "branch": p.branch, "timing_bound": c.bound},
            "collocation": {"costs": c.collocation.costs, "turns": r.turns, "guess": r.guess,
                            "intervals": r.transcription.intervals, "degree": r.transcription.degree,
                            "scheme": r.transcription.scheme, "iterations": r.stats.iterations},
            "starts": [{"name": s.name, "turns": s.turns, "status": s.status, "cost": s.cost,
                        "start_cost": s.start_cost, "solve_time_s": s.solve_time_s, "coarse_cost": s.coarse_cost}
                       for s in c.starts],
        },
    }


@dataclass(frozen=True)
class MinimumTime:
    """Minimum time of both methods under the robot's rotor limits, rest to rest.

    Attributes
    ----------
    problem : Problem
    plan : Plan
        The GP plan (shortest branch within the contact bound).
    gp_duration : float
        Its time-optimal timing's duration (:mod:`rollplan.execution.timing`, ``"time-optimal"``) [s].
    duration : float
        The collocation's minimum time (free final time), warm-started from that timing [s].
    gp, collocation : Side
        Both motions (``costs["duration"]`` their durations).
    """

    problem: Problem
    plan: object
    gp_duration: float
    duration: float
    gp: Side
    collocation: Side


def minimum_time(target, robot: Robot, steps: int = 1, intervals: int = 60, degree: int = 3,
                 contact_bound: float = CONTACT_BOUND) -> MinimumTime:
    """Minimum time rest to rest under ``robot``'s ``max_rotor_rate`` and ``max_rotor_torque`` (both needed):
    the GP path's time-optimal timing against the collocation with free final time and the same limits
    at its collocation points, warm-started from the former, with the same contact bound.

    Raises
    ------
    InputError, NoPlanError, SolverError
    """
    problem = Problem(tuple(target), robot=robot, steps=steps)
    nlp = {"intervals": intervals, "degree": degree,
           "contact_bound": check_range("contact_bound", contact_bound, 0.0, math.pi / 2, True, True)}
    planner = METHODS["minimum_time"](**nlp).planner   # the NLP, built once (shared with the solve below)
    t0 = time.perf_counter()
    p = _branches(problem, robot, contact_bound, 1)[0]
    a = actuate(p, robot, timing="time-optimal")
    gp_time = time.perf_counter() - t0
    R, m = robot.radius, a.series
    rates = contact_rates(m.omega, m.state)[:, 2:4]
    x7 = np.column_stack([m.state / np.array([R, R, 1.0, 1.0, 1.0]), rates])
    gp_motion = replace(m, velocity=contact_rates(m.omega, m.state)[:, :2] * R)
    turns = round((p.final.psi - problem.goal.psi) / (2 * math.pi))
    guess = guess_from_samples(planner.base.transcription, m.time, x7, "gp-time-optimal")
    r = interrupts.call(solve, problem, "minimum_time", **nlp, guess=guess, duration_guess=a.duration, robot=robot,
                        turns=turns)
    return MinimumTime(problem, p, a.duration, r.duration, Side(gp_motion, measure(gp_motion), p.residual, gp_time),
                       Side(r.motion, measure(r.motion), r.residual, r.stats.time_s))
