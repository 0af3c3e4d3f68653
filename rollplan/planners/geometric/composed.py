"""Full reconfiguration: plans between any two states ``(u_a, v_a, psi, u_o, v_o)``.

A start or goal off the south pole is served by a composed motion: an approach roll to the pole
(:mod:`.maneuvers`), figure eights pole to pole (one leg, :class:`.planner.GeometricPhasePlanner`; or a turn in
place, :mod:`.turn`; or two legs, :mod:`.legs`), and a departure roll. By the composition law (C) of
:mod:`rollplan.core.plane` the figure eights must realize, from zero, ``g_F = g_A^-1 * start^-1 * goal * g_B^-1``
(F), with ``g_A``, ``g_B`` the rolls' closed-form elements; the whole motion is then certified by one CVODES
integration from the start state (:func:`certify_path`). ``legs=`` (:data:`LEGS`) chooses between one and two
legs: ``"fallback"`` (default), ``"shortest"``, ``"one"``, ``"two"``. ``base="any"`` (:data:`BASES`) also tries one leg
of figure eights at base points off the pole (:mod:`.basepoint`) and keeps the shorter certified plan.
``polish="fast"`` (:data:`POLISHES`; the default of :func:`plan`) replaces a plan between full states by the fast
polish of :mod:`rollplan.planners.refined` when that is certified and shorter.

Derivation, the singular set, the choice of the legs: docs/design/composition.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from ...core.integrate import DEFAULT_NODES
from ...core.paths import PathIntegrator, allocate_samples, figure_eight_pieces
from ...core.plane import compose, inverse, relative, wrap, wrap_exact
from ...errors import InputError, NoPlanError, check_choice, check_flag, check_whole
from ...problem import Problem, State, arrival_residual, check_reach, check_steps
from ...result import DEFAULT_SAMPLES, Certificate, CertifiedMotion, SolverStats, Trajectory, certify
from ...robot import Robot
from ..method import Method, renamed_option, with_steps
from .basepoint import (
    LEAF_MIN,
    BasedLeg,
    arc_element,
    arc_piece,
    base_of,
    beside,
    leaf_bound,
    move_base,
    solve_leg,
)
from .legs import intermediate_state, second_leg, two_leg_candidates
from .maneuvers import StraightRoll
from .planner import CURVE_CHOICES, TOLERANCE, GeometricPhasePlanner, Plan, default_planner
from .refine import DEFAULT_ROOT_SOLVER, SOLVERS
from .turn import CircleTurn, turn_in_place

__all__ = ["LEGS", "BASES", "POLISHES", "BASE_FRACTIONS", "BASE_OFFSETS", "BASE_SOLVES", "BASE_MOVES", "IDENTITY_TOL",
           "ComposedPlan", "ComposedPlanner", "default_composed_planner", "as_composed",
           "certify_path", "sample_path", "plan"]

#: Policies for the legs of figure eights (docs/design/composition.md).
LEGS = ("fallback", "shortest", "one", "two")
#: Where the figure eights may be traced: ``"pole"`` (the south pole only) or ``"any"`` (docs/design/basepoint.md).
BASES = ("pole", "any")
#: The polish of a plan between full states: ``"fast"`` (:func:`rollplan.planners.refined.fast_polish`, the shorter
#: certified motion kept) or ``"off"`` (the figure-eight plan itself).
POLISHES = ("fast", "off")
#: Base points screened by ``base="any"`` besides the pole: fractions of the great-circle arc from the start
#: contact point (0) to the goal contact point (1), and offsets [rad] perpendicular to it (:func:`.basepoint.beside`).
BASE_FRACTIONS = (0.0, 0.25, 0.5, 0.75, 1.0)
BASE_OFFSETS = (-0.6, -0.3, 0.0, 0.3, 0.6)
#: How many screened base points get the local solve, and how many of their solutions the moved base point.
BASE_SOLVES = 3
BASE_MOVES = 2
#: A figure-eight target this close to zero (units of R and rad) is no motion at all.
IDENTITY_TOL = 1e-12


#: Largest shift of the contact point by one figure eight over the admissible leaf radii, about [R]
#: (under 4 R for every k; 3.8 R at k = 0.5): a target farther than this per step is named as the cause.
FAR_PER_STEP = 4.0


def _far_hint(problem: Problem, target) -> str:
    """The likely cause of a no-plan for a target many radii away (the unit, if lengths are in metres)."""
    d = math.hypot(target[0], target[1])
    if d <= FAR_PER_STEP * problem.steps:
        return ""
    hint = (f" (the target is {d:.3g} R away, {d / problem.steps:.3g} R per figure eight; one figure eight shifts "
            f"the contact point by at most about {FAR_PER_STEP:g} R")
    if problem.unit != "R":
        g, r = problem.goal, problem.radius
        hint += (f"; lengths are in metres here (R = {r:g} m): a target meant in units of R is "
                 f"(u_a, v_a) = ({g.u_a * r:g} m, {g.v_a * r:g} m)")
    return hint + ")"


@lru_cache(maxsize=1)
def _integrator() -> PathIntegrator:
    return PathIntegrator()


def _reduced(problem: Problem, name: str) -> tuple[State, int]:
    """The start or goal in units of R with psi reduced exactly to [-pi, pi], and the whole turns taken off.

    psi is an angle: the motion is planned and integrated in the reduced frame, so that a psi of any
    size costs no accuracy (``wrap_exact``), and reported in the frame of the given start.
    """
    state = problem.scaled(getattr(problem, name))
    psi, turns = wrap_exact(state.psi)
    return state._replace(psi=psi), turns


def certify_path(problem: Problem, pieces, tol: float = TOLERANCE) -> tuple:
    """The certificate of a composed motion: ``pieces`` integrated from ``problem.start`` against its goal.

    Returns ``(certificate, ends)``: ``ends`` (P + 1, 5) are the states at the start and after every
    piece, in units of R and in the reduced frame of :func:`_reduced` (psi of the start in [-pi, pi]).
    """
    start, turns = _reduced(problem, "start")
    ends = _integrator().ends(pieces, start.array(), problem.k)
    final = State(*(float(v) for v in ends[-1]))
    residual = arrival_residual(final, _reduced(problem, "goal")[0])
    final = final._replace(psi=final.psi + 2.0 * math.pi * turns).scaled(problem.radius)
    return certify(problem, final, PathIntegrator.name, tolerance=tol, residual=residual), ends


def sample_path(problem: Problem, pieces, samples: int) -> Trajectory:
    """A composed motion sampled by CVODES from ``problem.start``: ``samples`` samples in all.

    The samples are spread over the pieces in proportion to their lengths (at least 4 per piece
    when there are enough); ``segment`` numbers the pieces; ``s`` is the path parameter of
    :meth:`rollplan.core.paths.PathIntegrator.sample` (each piece spans pi; ``parameter`` "theta").
    """
    samples = check_whole("samples", samples, len(pieces) + 1, 10**7)
    start, turns = _reduced(problem, "start")
    R = problem.radius
    if not pieces:
        state = np.repeat(problem.start.array()[None, :], samples, axis=0)
        return Trajectory(np.zeros(samples), state, np.zeros(samples, int), R, "theta")
    counts = allocate_samples([p.length for p in pieces], samples)
    s, states, segment = _integrator().sample(pieces, start.array(), problem.k, counts)
    return Trajectory(s, states * [R, R, 1.0, 1.0, 1.0] + [0.0, 0.0, 2.0 * math.pi * turns, 0.0, 0.0], segment, R,
                      "theta")


@dataclass(frozen=True)
class ComposedPlan(CertifiedMotion):
    """A certified full-reconfiguration plan (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem : Problem
        What was solved.
    mode : str
        ``"empty"`` (start = goal), ``"rolls"`` (the rolls alone), ``"one"`` (one leg of figure
        eights), ``"turn"`` (pairs of circles turning in place), ``"two"`` (two legs).
    approach, departure : StraightRoll or None
        The rolls (None when the contact point is at the pole).
    target : ndarray, shape (3,)
        ``g_F`` of (F): what the figure eights do from zero [units of R, rad].
    legs : tuple of Plan
        The geometric-phase plans of the legs (each in its own problem's units).
    turn : CircleTurn or None
        The circle pairs of a turn in place [units of R].
    intermediate : ndarray or None
        The pole state between two legs, relative to the start of the figure eights [units of R, rad].
    pieces : tuple of CurvePiece
        The contact path, piece by piece [units of R].
    certificate : Certificate
        CVODES integration of the whole motion from the start state, and its residual.
    stats : SolverStats
        ``details`` names the mode and, for two legs, the candidates tried.
    path_length : float
        Contact path length [length unit].
    alternatives : tuple of ComposedPlan
        With ``all_solutions`` and one leg: the plans through the other certified branches.
    base : BasedLeg or None
        Mode ``"based"``: the figure eights at their base point (:class:`.basepoint.BasedLeg`).
    """

    method = "geometric"

    problem: Problem
    mode: str
    approach: StraightRoll | None
    departure: StraightRoll | None
    target: np.ndarray
    legs: tuple
    turn: CircleTurn | None
    intermediate: np.ndarray | None
    pieces: tuple
    certificate: Certificate
    stats: SolverStats
    path_length: float
    alternatives: tuple = ()
    base: BasedLeg | None = None

    @property
    def steps(self) -> int:
        return self.problem.steps

    @property
    def turns(self) -> int:
        """Whole turns m of psi: the motion ends at ``goal.psi + 2 pi m``."""
        return round((self.final.psi - self.goal.psi) / (2.0 * math.pi))

    def sample(self, samples: int = DEFAULT_SAMPLES) -> Trajectory:
        """The motion sampled by CVODES from the start state, ``samples`` in all (:func:`sample_path`)."""
        return sample_path(self.problem, self.pieces, samples)

    def lengths(self) -> dict:
        """Contact path length by kind of piece [length unit]."""
        out: dict = {}
        for p in self.pieces:
            out[p.kind] = out.get(p.kind, 0.0) + p.length * self.radius
        return out


def _pole_to_pole(problem: Problem) -> bool:
    """The paper's problem: from rest at the origin to a goal at the pole."""
    return tuple(problem.start) == tuple(State()) and problem.goal.at_pole


def _full_state(problem: Problem) -> bool:
    """The start or the goal contact point off the south pole."""
    return not (problem.start.at_pole and problem.goal.at_pole)


def as_composed(result) -> ComposedPlan:
    """A geometric-phase :class:`Plan` as a one-leg :class:`ComposedPlan` (its pieces and certificate);
    another geometric-phase result (a composed plan, a route) is returned as it is."""
    if not isinstance(result, Plan):
        if getattr(result, "method", None) == "geometric" and hasattr(result, "pieces"):
            return result
        raise InputError(f"{result!r:.60} is not allowed: give a geometric-phase plan")
    pieces = result.pieces
    goal = result.problem.scaled(result.goal)
    return ComposedPlan(result.problem, "one", None, None, np.array(goal[:3]), (result,), None, None, pieces,
                        result.certificate, result.stats, result.path_length)


class ComposedPlanner(Method):
    """Planner for any start and goal state (docs/design/composition.md); the method ``"geometric"`` of
    :data:`rollplan.planners.METHODS`.

    Parameters
    ----------
    root_solver : str
        Root solver of the figure eights, from :data:`.refine.SOLVERS` (its old name ``method`` still works,
        with a DeprecationWarning).
    nodes : int
        Chebyshev degree per panel of the spectral step map, in [4, 200].
    tol : float
        Largest certified residual of a returned plan, in (0, 1e-3].
    legs : str
        Policy in :data:`LEGS` (default ``"fallback"``).
    steps : int or None
        Figure eights per leg n (pairs of circles for a turn in place); None: the problem's ``steps``.
    all_solutions : bool
        Also return the other certified branches of one leg in ``alternatives``.
    branch : int or None
        Only the branch m of ``n eta = psi + 2 pi m`` of one leg (no fallback to two legs).
    base : str
        ``"pole"`` (default): figure eights at the south pole only. ``"any"``: also one leg of figure eights at
        the base points of :data:`BASE_FRACTIONS` along the great-circle arc from the start contact point to the
        goal contact point (local solves, :mod:`.basepoint`); the shorter certified plan is kept, so it is never
        longer than the ``"pole"`` plan. Slower (about a second warm per plan).
    refine : bool
        Polish the plan into a shorter certified motion (:func:`rollplan.planners.refined.refine`): a
        :class:`~rollplan.planners.refined.RefinedPlan`, or the plan with a note in ``stats.details["refine"]``.
    polish : str
        ``"off"`` (default here): the figure-eight plan. ``"fast"`` (the default of :func:`plan`): between full states
        (the start or goal contact point off the pole), the fast polish (:func:`rollplan.planners.refined.fast_polish`),
        kept when certified and shorter; not with ``all_solutions`` or ``branch``, and ``refine`` (the full polish)
        takes its place.
    curve : str
        Leaf family of the figure eight (:data:`.planner.CURVE_CHOICES`): ``"circles"`` (the default) plans any
        start and goal; another family, or ``"best"`` (the shortest certified plan over all families), plans one leg
        from rest at the origin to a goal at the pole with ``base="pole"`` (an InputError for other problems).
    """

    name = "geometric"

    def __init__(self, root_solver: str | None = None, nodes: int = DEFAULT_NODES, tol: float = TOLERANCE,
                 legs: str = "fallback", *, steps: int | None = None, all_solutions: bool = False,
                 branch: int | None = None, method: str | None = None, base: str = "pole",
                 refine: bool = False, curve: str = "circles", polish: str = "off") -> None:
        self.base = check_choice("base", base, BASES)
        self.polish = check_choice("polish", polish, POLISHES)
        root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
        self.legs = check_choice("legs", legs, LEGS)
        check_choice(name, root_solver, SOLVERS)
        self.steps = None if steps is None else check_steps(steps)
        self.all_solutions = check_flag("all_solutions", all_solutions)
        self.refine = check_flag("refine", refine)
        if self.refine and self.all_solutions:
            raise InputError("refine and all_solutions do not combine: the polish returns one motion")
        self.branch = self._check_branch(branch)
        self.curve = check_choice("curve", curve, CURVE_CHOICES)
        default = nodes == DEFAULT_NODES and tol == TOLERANCE and self.curve == "circles"
        self.planner = default_planner(root_solver) if default else GeometricPhasePlanner(root_solver, nodes, tol,
                                                                                          curve=self.curve)
        self.root_solver = root_solver
        self.tol = self.planner.tol

    def _check_branch(self, branch):
        if branch is None:
            return None
        branch = check_whole("branch", branch)
        if self.legs == "two":
            raise InputError("branch selects a branch of one leg of figure eights; it does not apply to legs='two'")
        return branch

    def solve(self, problem: Problem, all_solutions: bool | None = None, branch: int | None = None):
        """Plan for ``problem``: a :class:`Plan` for a pole-to-pole problem from rest that one leg
        serves (unless ``legs`` asks otherwise), else a :class:`ComposedPlan`; see :func:`plan`.
        ``all_solutions`` and ``branch``, when given, override the planner's options for this solve.
        Ctrl-C stops it (KeyboardInterrupt), also inside a root solve (:mod:`rollplan.interrupts`)."""
        planner = self
        if all_solutions is not None or branch is not None:
            planner = self._with(all_solutions=check_flag("all_solutions", all_solutions)
                                 if all_solutions is not None else self.all_solutions,
                                 branch=self._check_branch(branch) if branch is not None else self.branch)
        return Method.solve(planner, problem)

    def _check(self, problem) -> Problem:
        problem = super()._check(problem)
        problem = with_steps(problem, self.steps)
        check_reach(problem.start, problem.goal, problem.radius)
        if self.curve != "circles" and (not _pole_to_pole(problem) or self.legs == "two" or self.base != "pole"):
            raise InputError(f"curve = {self.curve} plans one leg of figure eights from rest at the origin to a goal "
                             "at the pole (legs one, fallback or shortest; base pole); use curve = circles for other "
                             "problems")
        return problem

    def _leg(self, problem: Problem, all_solutions: bool = False, branch: int | None = None):
        """One leg of figure eights by the pole-to-pole planner."""
        return self.planner.solve(problem, all_solutions, branch)

    def _solve(self, problem: Problem):
        found = self._geometric(problem)
        if self.refine:
            from ..refined import refine

            return refine(found)
        if self.polish == "fast" and _full_state(problem) and not self.all_solutions and self.branch is None:
            from ..refined import fast_polish

            return fast_polish(found)
        return found

    def _geometric(self, problem: Problem):
        if self.base == "pole" or self.branch is not None:
            return self._solve_pole(problem)
        t0 = time.perf_counter()
        try:
            pole = self._solve_pole(problem)
        except NoPlanError:
            based = self._based(problem, t0, math.inf)
            if based is None:
                raise
            return based
        based = self._based(problem, t0, pole.path_length)
        return based if based is not None else pole

    def _based(self, problem: Problem, t0: float, bound: float) -> ComposedPlan | None:
        """The shortest certified plan with one leg of figure eights at a base point off the pole shorter than
        ``bound`` [length unit], or None (docs/design/basepoint.md).

        Every base point of :data:`BASE_FRACTIONS` x :data:`BASE_OFFSETS` with ``steps`` and ``steps + 1``
        figure eights is screened by the length of the pole plan for its target (the complete pole search); the
        :data:`BASE_SOLVES` best get the local solve at that base point, the :data:`BASE_MOVES` shortest of those
        the joint local solve that moves the base point too (:func:`.basepoint.move_base`); the results are
        certified shortest first.
        """
        start, goal = _reduced(problem, "start")[0], _reduced(problem, "goal")[0]
        k, R = problem.k, problem.radius
        if arrival_residual(start, goal) <= IDENTITY_TOL:
            return None
        cs, cg = base_of(start.u_o, start.v_o), base_of(goal.u_o, goal.v_o)
        move = relative(start[:3], goal[:3])
        screened, seen = [], set()
        for f in BASE_FRACTIONS:
            for d in BASE_OFFSETS:
                cb = beside(cs, cg, f, d)
                key = (round(cb[0], 12), round(math.cos(cb[1]), 12), round(math.sin(cb[1]), 12))
                if cb[0] == 0.0 or key in seen or leaf_bound(cb[0]) <= 10 * LEAF_MIN:
                    continue
                seen.add(key)
                first, last = arc_piece(cs, cb, "approach"), arc_piece(cb, cg, "departure")
                rolls = sum(p.length for p in (first, last) if p is not None)
                if rolls * R >= bound:
                    continue
                target = compose(compose(inverse(arc_element(first, k)), move), inverse(arc_element(last, k)))
                for n in (problem.steps, problem.steps + 1):
                    try:
                        carried = self._leg(Problem(tuple(target), k=k, steps=n))
                    except NoPlanError:
                        continue
                    screened.append((rolls + carried.path_length / carried.radius, f, d, n, cb, first, last,
                                     target, carried))
        screened.sort(key=lambda c: c[0])
        found, tried = [], []
        for _, f, d, n, cb, first, last, target, carried in screened[:BASE_SOLVES]:
            a0, b0 = carried.a / carried.radius, carried.b / carried.radius
            guesses = [(a0, b0, carried.gamma - cb[1])] + [(a0, b0, o) for o in
                                                           np.linspace(-math.pi, math.pi, 4, endpoint=False)]
            leg = solve_leg(target, cb, k, n, guesses)
            rolls = sum(p.length for p in (first, last) if p is not None)
            tried.append({"fraction": f, "offset": d, "steps": n, "found": leg is not None})
            if leg is not None:
                found.append((rolls + leg.length, f, d, first, leg, last, target))
        found.sort(key=lambda c: c[0])
        for _, f, d, _, leg, _, target in found[:BASE_MOVES]:
            moved = move_base(start, goal, cs, cg, k, leg)
            if moved is not None:
                leg, length = moved
                first, last = arc_piece(cs, (leg.sigma, leg.beta), "approach"), arc_piece((leg.sigma, leg.beta), cg,
                                                                                       "departure")
                found.append((length, f, d, first, leg, last, target))
        for length, f, d, first, leg, last, target in sorted(found, key=lambda c: c[0]):
            if length * R >= bound:
                break
            pieces = tuple(p for p in [first, *leg.pieces(), last] if p is not None)
            cert, _ = certify_path(problem, pieces, self.tol)
            if not cert.passed:
                continue
            stats = SolverStats("ipopt", leg.guarantee, 0, time.perf_counter() - t0,
                                {"mode": "based", "fraction": f, "offset": d, "screened": len(screened),
                                 "bases": tried})
            return ComposedPlan(problem, "based", None, None, np.asarray(target, float), (), None, None, pieces,
                                cert, stats, sum(p.length for p in pieces) * R, base=leg)
        return None

    def _solve_pole(self, problem: Problem):
        t0 = time.perf_counter()
        all_solutions, branch = self.all_solutions, self.branch
        start, goal = _reduced(problem, "start")[0], _reduced(problem, "goal")[0]
        one_only = self.legs == "one" or branch is not None or self.curve != "circles"
        if _pole_to_pole(problem) and self.legs != "two" and math.hypot(goal.u_a, goal.v_a) > IDENTITY_TOL:
            try:
                found = self._leg(problem, all_solutions, branch)
            except NoPlanError:
                if one_only:
                    raise
                return self._composed(problem, t0, False, None, "two")   # one leg has just failed
            if self.legs == "shortest" and self.curve == "circles":
                try:
                    other = self._composed(problem, t0, False, None, "two")
                except NoPlanError:
                    other = None
                if other is not None and other.path_length < found.path_length:
                    return other
            return found
        if arrival_residual(start, goal) <= IDENTITY_TOL:
            return self._result(problem, "empty", None, None, np.zeros(3), (), None, None, t0, {})
        return self._composed(problem, t0, all_solutions, branch, "one" if one_only else self.legs)

    # -- the composed motion ------------------------------------------------------------
    def _composed(self, problem, t0, all_solutions, branch, legs):
        """Rolls, figure eights for (F) by the policy ``legs``, certificate."""
        start, goal = _reduced(problem, "start")[0], _reduced(problem, "goal")[0]
        approach = StraightRoll.make(start.u_o, start.v_o, "approach")
        departure = StraightRoll.make(goal.u_o, goal.v_o, "departure")
        with np.errstate(over="ignore", invalid="ignore"):
            target = compose(compose(inverse(approach.element()), relative(start[:3], goal[:3])),
                             inverse(departure.element()))   # (F)
        if not np.all(np.isfinite(target)):
            raise NoPlanError(f"no plan for {problem.describe()}: the displacement from start to goal overflows "
                              "double precision")
        details: dict = {}
        if math.hypot(target[0], target[1]) <= IDENTITY_TOL and abs(float(wrap(target[2]))) <= IDENTITY_TOL:
            mode = "empty" if approach.empty and departure.empty else "rolls"
            return self._result(problem, mode, approach, departure, target, (), None, None, t0, details)
        try:
            mode, legs_found, turn, w = self._eights(problem, target, legs, all_solutions, branch, details)
        except NoPlanError as exc:
            raise NoPlanError(f"no plan for {problem.describe()}: the figure eights must do (u_a, v_a, psi) = "
                              f"({target[0]:.6g} R, {target[1]:.6g} R, {target[2]:.6g} rad) from rest at the pole; "
                              f"{exc}{_far_hint(problem, target)}") from None
        result = self._result(problem, mode, approach, departure, target, legs_found, turn, w, t0, details)
        if all_solutions and mode == "one":
            alts = []
            for alt in legs_found[0].alternatives:
                cand = self._result(problem, mode, approach, departure, target, (alt,), None, None, t0, {},
                                    check=False)
                if cand.certificate.passed:
                    alts.append(cand)
            result = replace(result, alternatives=tuple(alts))
        return result

    def _eights(self, problem, target, legs, all_solutions, branch, details):
        """``(mode, leg plans, turn, intermediate)`` of the figure eights for ``target`` (units of R)."""
        k, steps = problem.k, problem.steps
        pure_turn = math.hypot(target[0], target[1]) <= IDENTITY_TOL
        if pure_turn and legs in ("fallback", "shortest"):
            try:
                return "turn", (), turn_in_place(float(target[2]), k, steps), None
            except NoPlanError as exc:
                details["turn"] = str(exc)
        one = None
        if legs != "two":
            try:
                if pure_turn:
                    raise NoPlanError("one leg of identical figure eights turns in place for isolated angles "
                                      "only (three equations for two unknowns); try legs='fallback'")
                one = self._leg(Problem(tuple(target), k=k, steps=steps), all_solutions, branch)
            except NoPlanError as exc:
                if legs == "one":
                    raise
                details["one_leg"] = str(exc)
        if one is not None and legs in ("one", "fallback"):
            return "one", (one,), None, None
        two = self._two_legs(target, k, steps, details)
        if two is not None and (one is None or two[0].path_length + two[1].path_length < one.path_length):
            return "two", two[:2], None, two[2]
        if one is not None:
            return "one", (one,), None, None
        raise NoPlanError(f"neither one leg nor two legs of {steps} figure eight(s) with leaf radii in the admissible "
                          "range reach it; try more steps")

    def _two_legs(self, target, k, steps, details, count: int = 4):
        """The shortest exact pair of legs of the best candidates of :func:`.legs.two_leg_candidates`.

        Each leg is solved on the branch its candidate lies on (``branch=``, fast near a known
        root); only when no candidate gives a plan are all branches of the best one tried.
        """
        t0 = time.perf_counter()
        candidates = two_leg_candidates(target, k, steps, count)
        tried, best = [], None

        def attempt(c, restrict):
            w = intermediate_state(target, c.r1, c.r2, c.chi1)
            t2 = second_leg(target, w)
            b1 = round((c.chi1 - w[2]) / (2 * math.pi)) if restrict else None
            b2 = round((c.chi2 - t2[2]) / (2 * math.pi)) if restrict else None
            try:
                p1 = self._leg(Problem(tuple(w), k=k, steps=steps), branch=b1)
                p2 = self._leg(Problem(tuple(t2), k=k, steps=steps), branch=b2)
            except NoPlanError:
                tried.append({"estimate": c.length, "polished": c.polished, "found": False})
                return None
            tried.append({"estimate": c.length, "polished": c.polished, "found": True,
                          "length": p1.path_length + p2.path_length})
            return p1, p2, w

        for c in candidates:
            got = attempt(c, True)
            if got is not None and (best is None or got[0].path_length + got[1].path_length <
                                    best[0].path_length + best[1].path_length):
                best = got
        if best is None and candidates:
            best = attempt(candidates[0], False)
        details["two_legs"] = {"candidates": tried, "search_s": time.perf_counter() - t0}
        return best

    def _result(self, problem, mode, approach, departure, target, legs, turn, w, t0, details,
                check: bool = True) -> ComposedPlan:
        """Pieces, certificate and statistics of a composed plan; NoPlanError if the certificate fails."""
        approach = approach if approach is not None and not approach.empty else None
        departure = departure if departure is not None and not departure.empty else None
        pieces = [approach.piece()] if approach else []
        if turn is not None:
            pieces += turn.pieces()
        for leg in legs:
            R = leg.radius
            pieces += figure_eight_pieces(leg.a / R, leg.b / R, leg.gamma, leg.steps)
        pieces += [departure.piece()] if departure else []
        cert, _ = certify_path(problem, pieces, self.tol)
        if check and not cert.passed:
            raise NoPlanError(f"no certified plan for {problem.describe()}: the composed motion misses the goal by "
                              f"{cert.residual:.2e} > {self.tol:.0e}; try more steps")
        if legs:
            status = ", ".join(sorted({leg.stats.status for leg in legs}))
            iterations = sum(leg.stats.iterations for leg in legs)
        else:
            status, iterations = ("turn" if turn is not None else "closed form"), 0
        stats = SolverStats(self.root_solver if legs else "brentq" if turn is not None else "none", status,
                            iterations, time.perf_counter() - t0, {"mode": mode, **details})
        length = sum(p.length for p in pieces) * problem.radius
        return ComposedPlan(problem, mode, approach, departure, np.asarray(target, float), tuple(legs), turn, w,
                            tuple(pieces), cert, stats, length)


@lru_cache(maxsize=8)
def default_composed_planner(root_solver: str = DEFAULT_ROOT_SOLVER, legs: str = "fallback", base: str = "pole",
                             refine: bool = False, polish: str = "off") -> ComposedPlanner:
    """The shared composed planner of :func:`plan` for a root solver, a legs policy, a base policy and the polishes."""
    return ComposedPlanner(root_solver, legs=legs, base=base, refine=refine, polish=polish)


def plan(target, steps: int = 1, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
         all_solutions: bool = False, method: str | None = None, branch: int | None = None, start=None,
         legs: str = "fallback", *, root_solver: str | None = None, base: str = "pole", refine: bool = False,
         curve: str = "circles", polish: str = "fast"):
    """Plan an exact, dynamically realizable motion from ``start`` to ``target``, any two states.

    From rest at the origin to a goal at the south pole this is the paper's
    planner (:meth:`GeometricPhasePlanner.solve`): ``steps`` traces of a figure
    eight. Otherwise (a start or goal off the pole, a turn in place, a target
    one leg cannot reach) a composed motion: approach roll, figure eights for
    the target (F), departure roll (docs/design/composition.md). Between full
    states (the start or goal contact point off the pole) that plan is then
    polished by default (``polish="fast"``): a short rest-to-rest motion of the
    same model, certified the same way, replaces it when it is shorter.

    Parameters
    ----------
    target : State or sequence
        Goal ``(u_a, v_a, psi)`` (contact point at the pole) or ``(u_a, v_a, psi, u_o, v_o)``
        [length unit of ``radius``, rad].
    steps : int
        Figure eights per leg n >= 1 (pairs of circles for a turn in place).
    k : float, optional
        Inertia ratio (14), k >= 0. Or give ``robot``.
    robot : Robot, optional
        Robot parameters; sets k and, unless given, the radius.
    radius : float, optional
        Sphere radius R (default 1, or the robot's).
    all_solutions : bool
        Also return the other certified branches of one leg in ``alternatives``.
    method : str
        Deprecated name of ``root_solver``.
    branch : int, optional
        Only the branch m of ``n eta = psi + 2 pi m`` of one leg (no fallback to two legs).
    start : State or sequence, optional
        Start state (default zero: at rest at the origin, contact at the pole).
    legs : str
        ``"fallback"`` (default), ``"shortest"``, ``"one"`` or ``"two"`` (docs/design/composition.md).
    root_solver : str
        Root solver name from :data:`.refine.SOLVERS` (default ``"c"``: the C planner's search, polish and certificate).
    base : str
        ``"pole"`` (default) or ``"any"``: also figure eights at base points off the pole, the shorter plan kept
        (:class:`ComposedPlanner`).
    refine : bool
        Polish the plan into a shorter certified motion (:mod:`rollplan.planners.refined`): a
        :class:`~rollplan.planners.refined.RefinedPlan`, or the plan with a note in ``stats.details["refine"]``.
    curve : str
        Leaf family of the figure eight from :data:`.planner.CURVE_CHOICES` (default ``"circles"``; see
        :class:`ComposedPlanner`).
    polish : str
        ``"fast"`` (default): between full states, the fast polish (:func:`rollplan.planners.refined.fast_polish`)
        replaces the plan when certified and shorter (a :class:`~rollplan.planners.refined.RefinedPlan` with
        ``stats.details["polish"] == "fast"``; otherwise the plan, the reason in ``stats.details["refine"]``); not
        applied with ``all_solutions`` or ``branch``. ``"off"``: the figure-eight plan.

    Returns
    -------
    PlanResult
        A :class:`Plan` for the paper's problem when one leg serves it, else a
        :class:`ComposedPlan` (a :class:`~rollplan.planners.refined.RefinedPlan` when polished); all satisfy
        :class:`rollplan.result.PlanResult` with the same surface
        (``pieces``, ``legs``, ``mode``, ``alternatives``, ``sample(samples)``).

    Raises
    ------
    InputError
        Bad input, e.g. a contact point outside the region of :func:`rollplan.problem.check_contact`.
    NoPlanError
        No certified plan (more steps may help).
    SolverError
        The root solver broke down.
    """
    root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
    check_choice(name, root_solver, SOLVERS)
    check_choice("legs", legs, LEGS)
    check_choice("base", base, BASES)
    check_choice("polish", polish, POLISHES)
    problem = Problem(target, start=start if start is not None else State(), k=k, robot=robot, radius=radius,
                      steps=steps)
    refine = check_flag("refine", refine)
    if check_choice("curve", curve, CURVE_CHOICES) != "circles":
        return ComposedPlanner(root_solver, legs=legs, base=base, refine=refine, curve=curve, polish=polish).solve(
            problem, all_solutions, branch)
    return default_composed_planner(root_solver, legs, base, refine, polish).solve(problem, all_solutions, branch)
