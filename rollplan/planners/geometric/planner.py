"""Geometric-phase planner: exact, dynamically realizable plans by figure eights (Section III.B).

Trace the figure eight (31) rotated by gamma ``n`` times from rest at the origin to ``(u_a, v_a, psi)`` at the
pole: on each branch m solve ``eta(a, b) = (psi + 2 pi m) / n`` (32) and
``h(a, b) = h_des |sin(eta / 2) / sin(n eta / 2)|`` (33) ((34) where ``sin(eta / 2) = 0``), then gamma from
the geometry. The roots are enumerated completely by the C search (:mod:`.compiled_search`; without a C compiler
the planner stops with one line saying what to install), polished by a solver chosen by name (:mod:`.refine`) and
certified by an independent integration (:mod:`.certify`).

Derivation, the search, the polish and the certificate: docs/design/geometric-planner.md.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from dataclasses import dataclass, field, replace
from functools import cached_property, lru_cache
from typing import NamedTuple

import casadi as ca
import numpy as np

from ...core import families, model
from ...core.curves import A_MAX, rotated_point
from ...core.integrate import DEFAULT_NODES, spectral_step
from ...core.paths import figure_eight_pieces
from ...core.plane import n_step_sum, target_shift, wrap, wrap_exact
from ...errors import (
    InputError,
    NoPlanError,
    check_choice,
    check_finite,
    check_flag,
    check_range,
    check_whole,
)
from ...problem import Problem, State, arrival_residual, check_k, check_reach
from ...progress import report
from ...result import (
    CERTIFICATE_TOLERANCE,
    DEFAULT_SAMPLES,
    Certificate,
    CertifiedMotion,
    SolverStats,
    Trajectory,
    certify,
)
from ...robot import Robot
from ..method import Method, renamed_option
from .certify import CERTIFIERS, DEFAULT_CERTIFIER, CvodesCertifier
from .compiled_search import (
    NO_PLAN,
    NOT_CERTIFIED,
    OK,
    all_roots,
    certified_plan,
    certify_roots,
    check_family_k,
    family_plans,
    listed_roots,
    shortest_root,
)
from .leafmap import panels_for, step_values
from .refine import DEFAULT_ROOT_SOLVER, SOLVERS, leaf_step, polisher, step_residual
from .search_constants import NOT_A_ROOT

__all__ = ["TOLERANCE", "CURVE_CHOICES",
           "StepResult", "Plan", "GeometricPhasePlanner", "default_planner", "plan", "step"]

log = logging.getLogger(__name__)

#: Default tolerance of the certified residual (units of R and rad).
TOLERANCE = CERTIFICATE_TOLERANCE
#: The ``curve`` option of the planner: a leaf family of :data:`rollplan.core.families.FAMILIES`, or ``"best"``
#: (the shortest certified plan over all of them).
CURVE_CHOICES = (*families.FAMILIES, "best")
#: Most CVODES samples per leaf of :meth:`GeometricPhasePlanner.sample`.
_MAX_PER_LEAF = 100000
#: A polished root farther than this from the enumerated one (in a or b [R]) is not taken (the solver
#: left the root it was started at); the enumerated root is certified instead.
_POLISH_MOVE = 1e-6


class _Root(NamedTuple):
    """A root of (32)-(33) in units of R: leaf radii, rotation, branch, shift and turn of one step, and the
    leaf map's miss of the target there (``nan``: not yet evaluated)."""

    a: float
    b: float
    gamma: float
    m: int
    h: float
    eta: float
    miss: float = math.nan


@dataclass(frozen=True)
class StepResult:
    """What one trace of the figure eight does, from zero initial conditions.

    Attributes
    ----------
    a, b : float
        Leaf radii [units of R].
    k : float
        Inertia ratio.
    gamma : float
        Rotation of the figure eight about OZ [rad].
    shift : ndarray, shape (2,)
        Displacement (u_a, v_a) of the contact point [units of R].
    h : float
        Non-holonomic shift ``|shift|`` [units of R].
    eta : float
        Holonomy angle, the change of psi [rad].
    direction : float
        Direction of the shift, ``atan2(v_a, u_a)`` [rad].
    """

    a: float
    b: float
    k: float
    gamma: float
    shift: np.ndarray
    h: float
    eta: float
    direction: float


@dataclass(frozen=True)
class Plan(CertifiedMotion):
    """A certified geometric-phase plan (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem : Problem
        What was solved (goal, k, radius, steps n).
    a, b : float
        Leaf radii of the figure eight [length unit of the problem].
    gamma : float
        Rotation of the figure eight about OZ, eq. (31) [rad].
    branch : int
        m in ``n eta = psi + 2 pi m`` (psi as given).
    h : float
        Shift of one step [length unit].
    eta : float
        Holonomy angle of one step [rad].
    path_length : float
        Contact path length ``n (L(a) + L(b))`` [length unit] (equal on the sphere and on the plane), L the
        length of a leaf of the family (``2 pi a`` for circles, :func:`rollplan.core.families.leaf_length`).
    certificate : Certificate
        Independent integration of all n steps (:mod:`.certify`) and its residual.
    stats : SolverStats
        ``details`` holds ``candidates`` (roots polished and certified), ``solves`` (plans certified),
        ``branches`` (branches searched), ``roots`` and ``search`` (``"compiled"``; ``"numpy"`` from the
        tests' reference enumeration).
    alternatives : tuple of Plan
        The other certified solution branches, shortest first (``all_solutions`` only).
    pieces : tuple of CurvePiece
        The contact path, leaf by leaf [units of R].
    legs : tuple of Plan
        ``(self,)``: the plan is its own only leg.
    mode : str
        ``"one"``: one leg of figure eights (as :attr:`.composed.ComposedPlan.mode`).
    curve : str
        Leaf family of the figure eight (:data:`rollplan.core.families.FAMILIES`; ``"circles"`` is the paper's).
    """

    method = "geometric"
    mode = "one"

    problem: Problem
    a: float
    b: float
    gamma: float
    branch: int
    h: float
    eta: float
    path_length: float
    certificate: Certificate
    stats: SolverStats
    alternatives: tuple = ()
    _planner: GeometricPhasePlanner = field(default=None, repr=False, compare=False)
    curve: str = "circles"

    @property
    def steps(self) -> int:
        return self.problem.steps

    @property
    def pieces(self) -> tuple:
        R = self.radius
        return tuple(figure_eight_pieces(self.a / R, self.b / R, self.gamma, self.steps, family=self.curve))

    @property
    def legs(self) -> tuple:
        return (self,)

    def sample(self, samples: int = DEFAULT_SAMPLES, *, samples_per_leaf: int | None = None) -> Trajectory:
        """The plan sampled by CVODES, ``samples`` samples in all: the start, then the leaves' samples, spread
        evenly over the 2n leaves (the first leaves one more when they do not divide evenly), each leaf's last at
        its end; ``segment`` numbers the leaves. (``samples_per_leaf=q``, deprecated, is ``samples = 1 + 2 n q``.)"""
        leaves = len(self._planner.family_planner(self.curve).curve.pieces) * self.steps
        if samples_per_leaf is not None:
            warnings.warn("sample(samples_per_leaf=q) is deprecated: use sample(samples) with the samples in all, "
                          "1 + 2 n q", DeprecationWarning, stacklevel=2)
            samples = 1 + leaves * check_whole("samples_per_leaf", samples_per_leaf, 1, _MAX_PER_LEAF)
        samples = check_whole("samples", samples, leaves + 1, 1 + leaves * _MAX_PER_LEAF)
        per = -(-(samples - 1) // leaves)
        traj = self._planner.family_planner(self.curve).sample(self, per)
        base, extra = divmod(samples - 1, leaves)
        idx = [0]
        for j in range(leaves):
            n = base + (j < extra)
            idx += [j * per + round(per * (i + 1) / n) for i in range(n)]
        idx = np.array(idx)
        return Trajectory(traj.s[idx], traj.state[idx], traj.segment[idx], traj.radius, traj.parameter)


class GeometricPhasePlanner(Method):
    """Geometric-phase planner for repeated solves (problem class): one leg of figure eights from rest at the
    origin to a goal at the pole (a :class:`~rollplan.planners.method.Method`; the registered method
    ``"geometric"``, :class:`.composed.ComposedPlanner`, uses it for every leg).

    Builds nothing a plan does not use: the leaf map is plain numpy with per-k tables
    (in the C search); the compiled shooting residual and its solver
    (:func:`.refine.polisher`, per panel count of the leaf map), the certifier's compiled
    integration and the C search (:mod:`.compiled_search`) are built or loaded from the disk cache
    on first use. The spectral step map and its residual are not used by :meth:`solve`; they serve the
    atlas and the benchmarks.

    Parameters
    ----------
    root_solver : str
        Solver of the shooting problem (32)-(33) from :data:`.refine.SOLVERS`: ``"c"`` (the default: the C
        search's own Newton polish; with the default certifier and tol, search, polish and certificate run in one
        call of the C planner, :func:`.compiled_search.certified_plan`), ``"ipopt"`` or ``"newton"``, which
        polish each enumerated root again (started there, they need at most one or two iterations) before the
        certificate of :mod:`.certify`. (Its old name ``method`` still works, with a DeprecationWarning.)
    nodes : int
        Chebyshev degree per panel of the spectral step map, in [4, 200].
    tol : float
        Largest certified residual plus error bound a returned plan may have, in (0, 1e-3].
    certifier : str
        Certifier from :data:`.certify.CERTIFIERS`: ``"rk8"`` (the default: compiled RK8 with a
        step-doubling error bound) or ``"cvodes"``.
    compiled_search : bool
        Only True: the roots are searched by the compiled C search (every k, docs/design/geometric-planner.md).
        False (the numpy search, now the tests' reference) is refused with an InputError.
    all_solutions : bool
        Also return the other certified branches in ``Plan.alternatives``.
    branch : int or None
        Only the branch m of ``n eta = psi + 2 pi m`` (psi as given).
    curve : str
        Leaf family of the figure eight from :data:`CURVE_CHOICES`: ``"circles"`` (the default, the paper's
        (35)), ``"viviani"``, ``"triangle"``, ``"square"`` (docs/design/curve-families.md), or ``"best"``: the
        shortest certified plan (contact path length) over every family.
    """

    name = "geometric"

    def __init__(self, root_solver: str | None = None, nodes: int = DEFAULT_NODES, tol: float = TOLERANCE,
                 certifier: str = DEFAULT_CERTIFIER, compiled_search: bool = True, *, all_solutions: bool = False,
                 branch: int | None = None, method: str | None = None, curve: str = "circles") -> None:
        root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
        self.root_solver = check_choice(name, root_solver, SOLVERS)
        self.all_solutions = check_flag("all_solutions", all_solutions)
        self.branch = None if branch is None else check_whole("branch", branch)
        if not check_flag("compiled_search", compiled_search):
            raise InputError("compiled_search = False is not allowed: the C search is the planner's only search "
                             "(the numpy enumeration is the tests' reference, tests/reference_enumerate.py)")
        self.compiled_search = True
        self.tol = check_range("tol", tol, 0.0, 1e-3, low_open=True)
        self.nodes = check_whole("nodes", nodes, 4, 200)
        self.family = check_choice("curve", curve, CURVE_CHOICES)
        self.curve = families.figure_eight("circles" if self.family == "best" else self.family)
        self.certifier_name = check_choice("certifier", certifier, CERTIFIERS)
        self.certifier = CERTIFIERS[self.certifier_name]()

    @property
    def method(self) -> str:
        """Deprecated name of :attr:`root_solver` (``method`` names the planning method)."""
        warnings.warn("GeometricPhasePlanner.method is deprecated: use root_solver", DeprecationWarning, stacklevel=2)
        return self.root_solver

    @cached_property
    def cvodes(self) -> CvodesCertifier:
        """The CVODES integration that samples plans (:meth:`sample`) along the family's figure eight."""
        if isinstance(self.certifier, CvodesCertifier) and self.family in ("circles", "best"):
            return self.certifier
        return CvodesCertifier(curve="circles" if self.family == "best" else self.family)

    def family_planner(self, family: str) -> GeometricPhasePlanner:
        """The planner with the same options for the leaf family ``family`` (``self`` for its own)."""
        if family == self.family:
            return self
        cache = self.__dict__.setdefault("_family_planners", {})
        if family not in cache:
            cache[family] = GeometricPhasePlanner(self.root_solver, self.nodes, self.tol, self.certifier_name,
                                                  all_solutions=self.all_solutions, branch=self.branch,
                                                  curve=family)
        return cache[family]

    # -- the spectral step map (atlas, benchmarks; not used by solve) --------------------
    @cached_property
    def step_map(self) -> ca.Function:
        """The spectral step map of :mod:`rollplan.core.integrate` (the atlas)."""
        return spectral_step(self.curve, self.nodes)

    @cached_property
    def residual(self) -> ca.Function:
        return step_residual(self.step_map)

    # -- step map ------------------------------------------------------------------
    def step(self, a: float, b: float | None = None, *, k: float, gamma: float = 0.0) -> StepResult:
        """One trace of the figure eight (a, b) rotated by gamma, from zero state, by the accurate leaf map
        (:mod:`.leafmap`; within 1e-10 of an independent integration for 0 < a, b <= A_MAX, 0 <= k <= K_MAX)."""
        b = a if b is None else b
        a, b = (check_range(n, v, 0.0, A_MAX, low_open=True) for n, v in (("a", a), ("b", b)))
        k, gamma = check_k(k), check_finite("gamma", gamma)
        shift, eta = step_values(a, b, k, gamma)
        z = complex(shift[0])
        return StepResult(a, b, k, gamma, np.array([z.real, z.imag]), abs(z), float(eta[0]), math.atan2(z.imag, z.real))

    # -- solve -----------------------------------------------------------------------
    def solve(self, problem: Problem, all_solutions: bool | None = None, branch: int | None = None) -> Plan:
        """Plan for ``problem`` (start at rest at the origin, goal at the pole); see :func:`plan`.
        ``all_solutions`` and ``branch``, when given, override the planner's options for this solve."""
        planner = self
        if all_solutions is not None or branch is not None:
            planner = self._with(all_solutions=check_flag("all_solutions", all_solutions)
                                 if all_solutions is not None else self.all_solutions,
                                 branch=check_whole("branch", branch) if branch is not None else self.branch)
        return Method.solve(planner, problem)

    def _check(self, problem) -> Problem:
        problem = super()._check(problem)
        check_reach(problem.start, problem.goal, problem.radius)
        if tuple(problem.start) != tuple(State()) or not problem.goal.at_pole:
            raise InputError("the geometric-phase planner plans from rest at the origin (start = 0) to a goal "
                             "with the contact point at the south pole (u_o = v_o = 0)")
        return problem

    def _solve(self, problem: Problem) -> Plan:
        if self.family == "best":
            return self._solve_best(problem)
        t_start = time.perf_counter()
        all_solutions, branch = self.all_solutions, self.branch
        goal_r = problem.scaled(problem.goal)
        psi_des, turns = wrap_exact(goal_r.psi)  # psi is an angle; branch numbers stay relative to psi as given
        h_des = math.hypot(goal_r.u_a, goal_r.v_a)
        where = problem.describe()
        if h_des == 0.0:
            raise NoPlanError(f"no plan for {where}: the target is the start point, and rollplan plans "
                              "motions with a nonzero displacement")
        target = (goal_r.u_a, goal_r.v_a, psi_des)
        if self.family != "circles":
            check_family_k(self.family, problem.k)
            return self._solve_family(problem, None if branch is None else branch + turns, target, turns, t_start)
        solve = self._solve_compiled_all if all_solutions else self._solve_compiled
        if not all_solutions and self._in_c:
            solve = self._solve_in_c
        return solve(problem, None if branch is None else branch + turns, target, turns, t_start)

    def _solve_best(self, problem: Problem) -> Plan:
        """The shortest certified plan (contact path length) over every leaf family (ties: the first family of
        :data:`rollplan.core.families.FAMILIES`); NoPlanError naming each family's reason when none has one."""
        found, reasons = [], []
        for family in families.FAMILIES:
            planner = self.family_planner(family)
            try:
                if family != "circles":
                    check_family_k(family, problem.k)
                found.append(planner._solve(problem))
            except (NoPlanError, InputError) as exc:
                reasons.append(f"{family}: {exc}")
        if not found:
            raise NoPlanError(f"no plan for {problem.describe()} with any curve family ({'; '.join(reasons)})")
        return min(found, key=lambda p: p.path_length)

    def _solve_family(self, problem, branch, target, turns, t_start) -> Plan:
        """A leaf family other than the circles: the C search of the family (:mod:`.compiled_search`, complete
        enumeration for k >= 1/2) polishes its roots on the family's leaf map and certifies them on board; the plan
        is its certified root of smallest a + b (with ``all_solutions``: every certified root, sorted by contact path
        length), each certified again here by CVODES along the family's curve (:class:`.certify.CvodesCertifier`).
        The contact path length ``L(a) + L(b)`` of a non-circular leaf is increasing but not linear in its size, so
        the plan of smallest a + b is the shortest contact path unless another root has nearly the same a + b
        (docs/design/curve-families.md)."""
        k, steps = problem.k, problem.steps
        listed = family_plans(target[0], target[1], target[2], steps, k, self.family, branch, self.all_solutions)
        found, rejected = [], []
        for r in listed:
            cand = self._certified_family(problem, r, r.m - turns, target)
            if cand[1].passed:
                found.append(cand)
                if not self.all_solutions:
                    break
            else:
                rejected.append(cand[1].residual + cand[1].error_bound)
        if not found:
            self._raise_if_rejected(problem.describe(), rejected)
            raise _no_root(problem, f"curve {self.family}, the certified search of the C planner found none")
        details = {"candidates": len(listed), "solves": len(found),
                   "branches": listed[0].branches if listed else 0, "roots": len(listed), "search": "compiled",
                   "curve": self.family}
        elapsed = time.perf_counter() - t_start
        plans = [self._plan(problem, cand, replace(cand[2], time_s=elapsed, details=details)) for cand in found]
        plans.sort(key=lambda p: p.path_length)   # every root (all_solutions): the shortest contact path first
        return replace(plans[0], alternatives=tuple(plans[1:]))

    def _certified_family(self, problem, r, m, target_r):
        """The C search's certified plan ``r`` of the family certified again by CVODES: a tuple for :meth:`_plan`."""
        final_r = self.cvodes.final(r.a, r.b, problem.k, r.gamma, problem.steps)
        goal_r = problem.scaled(problem.goal)
        residual = arrival_residual(final_r, State(goal_r.u_a, goal_r.v_a, target_r[2]))
        cert = certify(problem, final_r.scaled(problem.radius), self.cvodes.name, error_bound=0.0,
                       tolerance=self.tol, residual=residual)
        stats = SolverStats(f"c-{self.family}", "polished in C", 0, 0.0)
        eta = (target_r[2] + 2.0 * math.pi * r.m) / problem.steps
        return _Root(r.a, r.b, r.gamma, m, r.h, eta, r.predicted), cert, stats

    def _raise_if_rejected(self, where: str, rejected: list) -> None:
        """NoPlanError naming the best certified residual when roots were found but none certified."""
        if rejected:
            raise NoPlanError(f"no certified plan for {where}: {len(rejected)} root(s) of (32)-(33) found, but "
                              f"their certified residual plus error bound (best {min(rejected):.1e}) exceeds "
                              f"{self.tol:.0e}; "
                              "try more steps")

    @property
    def _in_c(self) -> bool:
        """True when one call of the C planner does search, polish and certificate (the default root solver
        with the default certifier and tolerance, which the C certificate applies)."""
        return (self.root_solver == DEFAULT_ROOT_SOLVER and type(self.certifier) is CERTIFIERS[DEFAULT_CERTIFIER]
                and self.tol == CERTIFICATE_TOLERANCE)

    def _solve_in_c(self, problem, branch, target, turns, t_start) -> Plan:
        """The shortest certified plan (on ``branch`` if given) by one call of the C planner: the search, its
        Newton polish and its RK8 certificate (:func:`.compiled_search.certified_plan`)."""
        status, p, final = certified_plan(target[0], target[1], target[2], problem.steps, problem.k, branch)
        if status == OK:
            R = problem.radius
            # the figure eight ends at the pole (u_o = v_o = 0) by construction; the certificate integrates u_a,
            # v_a, psi
            cert = Certificate(self.certifier.name, State(final[0] * R, final[1] * R, final[2], 0.0, 0.0),
                               p.residual, p.bound, self.tol)
            details = {"candidates": int(p.roots), "solves": 1, "branches": int(p.branches), "roots": int(p.roots),
                       "search": "compiled"}
            stats = SolverStats(DEFAULT_ROOT_SOLVER, "ok", 0, time.perf_counter() - t_start, details)
            return Plan(problem, p.a * R, p.b * R, p.gamma, int(p.m) - turns, p.h * R, p.eta,
                        2 * np.pi * problem.steps * (p.a + p.b) * R, cert, stats, (), self)
        if status == NO_PLAN:
            raise _no_root(problem, f"{p.branches} branches searched completely")
        if status == NOT_CERTIFIED:
            self._raise_if_rejected(problem.describe(), [p.residual + p.bound])
        raise _no_root(problem, f"{p.branches} branches searched completely")

    def _solve_compiled(self, problem, branch, target, turns, t_start) -> Plan:
        """The shortest root (on ``branch`` if given) by the compiled C search, polished and certified here; when
        the certificate rejects it, every root (:func:`.compiled_search.all_roots`), certified shortest first
        (docs/design/geometric-planner.md)."""
        k, steps = problem.k, problem.steps
        found = shortest_root(target[0], target[1], target[2], steps, k, branch)
        if math.isnan(found.a):   # the complete search found no root
            raise _no_root(problem, f"{found.branches} branches searched completely")
        q = self._listed_root(found, target, steps)
        x, status, iters = self._polish(q, k)
        cand = self._certified(problem, x, found.m - turns, target, status, iters)
        if cand[1].passed:
            details = {"candidates": 1, "solves": 1, "branches": found.branches, "roots": found.roots,
                       "search": "compiled"}
            return self._plan(problem, cand, replace(cand[2], time_s=time.perf_counter() - t_start, details=details))
        rejected = [cand[1].residual + cand[1].error_bound] if self._log_rejected(q, cand, turns) else []
        listed = [r for r in all_roots(target[0], target[1], target[2], steps, k, branch)
                  if (r.m, r.a, r.b) != (found.m, found.a, found.b)]
        found_all, more, tried = self._certify_listed(problem, listed, target, turns, first_only=True)
        if not found_all:
            self._raise_if_rejected(problem.describe(), rejected + more)
            raise _no_root(problem, f"{found.branches} branches searched completely")
        details = {"candidates": 1 + tried, "solves": 1, "branches": found.branches, "roots": len(listed) + 1,
                   "search": "compiled"}
        cand = found_all[0]
        return self._plan(problem, cand, replace(cand[2], time_s=time.perf_counter() - t_start, details=details))

    def _solve_compiled_all(self, problem, branch, target, turns, t_start) -> Plan:
        """Every root of every branch (of ``branch`` if given) by the compiled C search
        (:func:`.compiled_search.listed_roots`), each certified by the C certificate (:meth:`_certify_in_c`) with
        the default root solver, certifier and tolerance, otherwise polished by the root solver and certified here;
        the certified ones, shortest first."""
        k, steps = problem.k, problem.steps
        in_c = self._in_c
        listed = (listed_roots if in_c else all_roots)(target[0], target[1], target[2], steps, k, branch)
        if not listed:   # the complete search found no root
            raise _no_root(problem, "the complete search found none")
        if in_c:
            found, rejected = self._certify_in_c(problem, listed, target, turns)
        else:
            found, rejected, _ = self._certify_listed(problem, listed, target, turns)
        if not found:
            self._raise_if_rejected(problem.describe(), rejected)
            raise _no_root(problem, f"{listed[0].branches} branches searched completely, no root certified")
        found.sort(key=lambda c: c[0].a + c[0].b)
        details = {"candidates": len(listed), "solves": len(found), "branches": listed[0].branches,
                   "roots": len(listed), "search": "compiled"}
        elapsed = time.perf_counter() - t_start
        plans = [self._plan(problem, cand, replace(cand[2], time_s=elapsed, details=details)) for cand in found]
        return replace(plans[0], alternatives=tuple(plans[1:]))

    def _certify_in_c(self, problem, listed, target, turns) -> tuple:
        """``(certified, rejected)``: the roots ``listed`` by the C search (polished there by Newton's method on
        the accurate leaf map) certified by the C certificate (:func:`.compiled_search.certify_roots`: fixed-step
        RK8 of the whole motion with step doubling), progress reported root by root; ``rejected`` as in
        :meth:`_certify_listed`."""
        total = len(listed)
        label = f"certify (k = {problem.k:g}, {total} roots)"
        shown = [0]

        def progress(done, total):
            for i in range(shown[0] + 1, done + 1):
                report(label, i, total)
            shown[0] = done

        report(label, 0, total)
        log.info("certifying %d roots in C", total)
        certs = certify_roots(listed, target[0], target[1], target[2], problem.steps, problem.k, progress)
        R = problem.radius
        found, rejected = [], []
        for r, c in zip(listed, certs):
            # the figure eight ends at the pole (u_o = v_o = 0) by construction; the certificate integrates u_a,
            # v_a, psi and measures its residual to the target with psi wrapped
            cert = Certificate(self.certifier.name, State(c.final[0] * R, c.final[1] * R, c.final[2], 0.0, 0.0),
                               c.residual, c.bound, self.tol)
            cand = (_Root(r.a, r.b, r.gamma, r.m - turns, r.h, r.eta, r.predicted), cert,
                    SolverStats(DEFAULT_ROOT_SOLVER, "ok", 0, 0.0))
            if cert.passed:
                found.append(cand)
            elif self._log_rejected(r, cand, turns):
                rejected.append(cert.residual + cert.error_bound)
        return found, rejected

    @staticmethod
    def _listed_root(r, target, steps) -> _Root:
        """The :class:`_Root` of a root ``r`` of the C search (branch turn and shift from the target)."""
        eta = (target[2] + 2.0 * math.pi * r.m) / steps
        return _Root(r.a, r.b, 0.0, r.m, float(target_shift(math.hypot(target[0], target[1]), eta, steps)), eta)

    def _certify_listed(self, problem, listed, target, turns, first_only: bool = False) -> tuple:
        """``(certified, rejected, tried)``: the roots ``listed`` (shortest first) polished and certified, stopping
        at the first certified one if ``first_only``; ``rejected`` the certified residuals plus bounds of the roots
        the certificate rejected, ``tried`` the number of roots certified."""
        found, rejected, tried = [], [], 0
        label = f"certify (k = {problem.k:g}, {len(listed)} roots)"
        for i, r in enumerate(listed):
            report(label, i, len(listed))
            tried += 1
            q = self._listed_root(r, target, problem.steps)
            x, status, iters = self._polish(q, problem.k)
            cand = self._certified(problem, x, r.m - turns, target, status, iters)
            if cand[1].passed:
                found.append(cand)
                if first_only:
                    break
            elif self._log_rejected(q, cand, turns):
                rejected.append(cand[1].residual + cand[1].error_bound)
        report(label, len(listed), len(listed))
        return found, rejected, tried

    def _log_rejected(self, q, cand, turns) -> bool:
        """Log a root ``q`` whose plan ``cand`` failed the certificate; True if it is a root the certificate
        rejected, False if the leaf map misses there by more than NOT_A_ROOT (a tangency of the table only)."""
        if cand[0].miss > NOT_A_ROOT * self.tol:   # a tangency of the search's table only
            log.info("branch m=%d (a=%.6f, b=%.6f): no root, the leaf map misses by %.2e",
                     q.m - turns, q.a, q.b, cand[0].miss)
            return False
        log.warning("branch m=%d (a=%.6f, b=%.6f) rejected: certified residual + bound %.2e > %.0e",
                    q.m - turns, q.a, q.b, cand[1].residual + cand[1].error_bound, self.tol)
        return True

    def _polish(self, q, k: float):
        """``((a, b), status, iterations)``: the enumerated root ``q`` polished by the shooting solver
        (:func:`.refine.polisher`) on the leaf map's residual of (32)-(33); the enumerated root itself
        (status prefixed ``enumerated:``) when the solver fails or leaves it."""
        x, status, iters, ok = polisher(self.root_solver, panels_for(k))([q.a, q.b], [k, q.eta, q.h], 1e-6, A_MAX)
        if ok and abs(x[0] - q.a) <= _POLISH_MOVE and abs(x[1] - q.b) <= _POLISH_MOVE:
            return (float(x[0]), float(x[1])), str(status), iters
        log.info("polish of branch m=%d (a=%.6f, b=%.6f) not taken (%s)", q.m, q.a, q.b, status)
        return (q.a, q.b), f"enumerated:{status}", iters

    def _certified(self, problem, x, m, target_r, status, iters, method=None):
        """Gamma from the geometry (docs/design/geometric-planner.md), then the certificate: a tuple for
        :meth:`_plan`."""
        a, b = float(x[0]), float(x[1])
        u, v, eta = leaf_step(panels_for(problem.k)).call([[a, b], problem.k])[0].nonzeros()
        shift = complex(u, v)
        total = shift * n_step_sum(eta, problem.steps)
        gamma = float(wrap(math.atan2(target_r[1], target_r[0]) - math.atan2(total.imag, total.real)))
        miss = math.hypot(abs(total) - math.hypot(target_r[0], target_r[1]),
                          float(wrap(problem.steps * eta - target_r[2])))
        final_r, bound, _ = self.certifier.certify(a, b, problem.k, gamma, problem.steps, self.tol)
        goal_r = problem.scaled(problem.goal)
        residual = arrival_residual(final_r, State(goal_r.u_a, goal_r.v_a, target_r[2]))   # psi reduced
        cert = certify(problem, final_r.scaled(problem.radius), self.certifier.name, error_bound=bound,
                       tolerance=self.tol, residual=residual)
        stats = SolverStats(method or self.root_solver, status, iters, 0.0)
        return _Root(a, b, gamma, m, abs(shift), eta, miss), cert, stats

    def _plan(self, problem, cand, stats) -> Plan:
        root, cert = cand[0], cand[1]
        R = problem.radius
        if self.family == "circles":
            length = 2 * np.pi * problem.steps * (root.a + root.b)
        else:
            length = problem.steps * (families.leaf_length(self.family, root.a)
                                      + families.leaf_length(self.family, root.b))
        return Plan(problem, root.a * R, root.b * R, root.gamma, root.m, root.h * R, root.eta, length * R, cert,
                    stats, (), self, self.family)

    # -- sampling -------------------------------------------------------------------
    def sample(self, p: Plan, samples_per_leaf: int = 200) -> Trajectory:
        """Sampled trajectory of a plan (CVODES), in the plan's units; ``segment`` = 2 step + leaf."""
        samples_per_leaf = check_whole("samples_per_leaf", samples_per_leaf, 1, 100000)
        ab = [p.a / p.radius, p.b / p.radius]
        phi, xs = self.cvodes.integrator.trace(ab, p.k, p.gamma, p.steps, samples_per_leaf)
        pieces = len(self.curve.pieces)
        segment = np.arange(phi.size) // samples_per_leaf
        leaf = segment % pieces
        pts = np.zeros((phi.size, 3))
        ph = ca.SX.sym("ph")
        for j, piece in enumerate(self.curve.pieces):
            sel = leaf == j
            f = ca.Function("pt", [ph], [rotated_point(piece, ph, ca.DM(ab), p.gamma)]).map(int(sel.sum()))
            pts[sel] = np.array(f(phi[sel][None, :])).T
        theta = 2 * np.pi * (segment // pieces) + (2 * np.pi / pieces) * (leaf + phi / (2 * np.pi))
        uv = _contact_coordinates().map(phi.size)(pts.T)
        state = np.column_stack([xs[:, 0] * p.radius, xs[:, 1] * p.radius, xs[:, 2], np.array(uv[0]).ravel(),
                                 np.array(uv[1]).ravel()])
        start = np.zeros((1, 5))
        return Trajectory(np.concatenate([[0.0], theta]), np.vstack([start, state]),
                          np.concatenate([[0], segment]).astype(int), p.radius, "theta")


def _no_root(problem: Problem, how: str) -> NoPlanError:
    """The error of a complete search without a root of (32)-(33); ``how`` says what was searched."""
    return NoPlanError(f"no plan for {problem.describe()}: no branch of (32)-(33) has a root with 0 < a, b <= "
                       f"{A_MAX} R ({how}); try more steps")


@lru_cache(maxsize=1)
def _contact_coordinates() -> ca.Function:
    """``point (3,) -> (u_o, v_o)`` of (24)-(25) (:func:`rollplan.core.model.contact_coordinates`)."""
    pt = ca.SX.sym("pt", 3)
    return ca.Function("uv", [pt], list(model.contact_coordinates(pt)))


@lru_cache(maxsize=4)
def default_planner(root_solver: str = DEFAULT_ROOT_SOLVER,
                    certifier: str = DEFAULT_CERTIFIER) -> GeometricPhasePlanner:
    """The shared planner of :func:`plan` and :func:`step` for a root solver and a certifier (built once per
    process)."""
    return GeometricPhasePlanner(root_solver, certifier=certifier)


def plan(target, steps: int = 1, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
         all_solutions: bool = False, method: str | None = None, branch: int | None = None, *,
         root_solver: str | None = None) -> Plan:
    """Plan an exact, dynamically realizable motion by tracing a figure eight n times.

    Solves (32)-(33) for the leaf radii (a, b) on every branch
    ``n eta = psi + 2 pi m`` and the rotation gamma of (31), so that ``steps``
    traces bring the robot from rest at the origin to ``target``.

    Parameters
    ----------
    target : (u_a, v_a, psi)
        Final contact point on the plane [length unit of ``radius``] and
        contact angle [rad].
    steps : int
        Number of traces n >= 1.
    k : float, optional
        Inertia ratio (14), k >= 0 (k = 0 is pure rolling). Or give ``robot``.
    robot : Robot, optional
        Robot parameters; sets k and, unless given, the radius.
    radius : float, optional
        Sphere radius R (default 1, or the robot's).
    all_solutions : bool
        Also return the other certified branches in ``Plan.alternatives``.
    method : str
        Deprecated name of ``root_solver``.
    branch : int, optional
        Only the branch m of ``n eta = psi + 2 pi m`` (psi as given).
    root_solver : str
        Root solver name from :data:`.refine.SOLVERS` (default ``"c"``: search, polish and certificate in
        one call of the C planner).

    Returns
    -------
    Plan
        The certified plan with the shortest contact path.

    Raises
    ------
    InputError
        Bad input.
    NoPlanError
        No certified plan exists in the admissible range ``0 < a, b <= A_MAX R``.
    """
    root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
    check_choice(name, root_solver, SOLVERS)
    problem = Problem(target, k=k, robot=robot, radius=radius, steps=steps)
    return default_planner(root_solver).solve(problem, all_solutions, branch)


def step(a: float, b: float | None = None, *, k: float, gamma: float = 0.0) -> StepResult:
    """What one figure eight does: shift h(a, b), holonomy eta(a, b), eqs. (28)-(31)."""
    return default_planner().step(a, b, k=k, gamma=gamma)
