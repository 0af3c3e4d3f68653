"""Many pole-to-pole plans per call: :func:`plan_many` plans a list of targets at one k and one number of steps
in the C planner (``<prefix>_plan_many``: search, polish and certificate of each target, many targets per call),
and returns the certified plans as arrays, with a status per target."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ...core.plane import wrap_exact
from ...errors import InputError, NoPlanError, check_whole
from ...problem import Problem, State, check_k
from ...result import CERTIFICATE_TOLERANCE, Certificate, SolverStats
from ...robot import Robot
from .compiled_search import NO_PLAN, NOT_CERTIFIED, OK, certified_plans
from .planner import Plan, default_planner
from .refine import DEFAULT_ROOT_SOLVER

__all__ = ["STATUSES", "PlanMany", "plan_many"]

#: Status of a target in :attr:`PlanMany.status`.
STATUSES = ("ok", "no plan", "not certified", "incomplete")
_STATUS = {OK: "ok", NO_PLAN: "no plan", NOT_CERTIFIED: "not certified"}


@dataclass(frozen=True)
class PlanMany:
    """Plans of many targets (:func:`plan_many`), one entry per target, in the order of the targets.

    Attributes
    ----------
    targets : ndarray, shape (N, 3)
        The targets ``(u_a, v_a, psi)`` as given [length unit, rad].
    k, radius : float
        Inertia ratio and sphere radius R of every plan.
    steps : int
        Figure eights per plan.
    status : ndarray of str, shape (N,)
        ``"ok"`` (a certified plan), ``"no plan"`` (no root of (32)-(33) in ``0 < a, b <= A_MAX R``, or the target
        is the start point), ``"not certified"`` (roots, none passed the certificate) or ``"incomplete"`` (the
        search could not be completed). Only ``"ok"`` entries hold a plan.
    a, b, gamma, h, eta, path_length : ndarray, shape (N,)
        As in :class:`.planner.Plan` [length unit, rad]; NaN where there is no plan.
    branch : ndarray of int, shape (N,)
        The branch m of ``n eta = psi + 2 pi m`` (psi as given); 0 where there is no plan (dtype object, exact
        integers, when one is beyond int64).
    residual, error_bound : ndarray, shape (N,)
        The certificate of each plan: the residual of the RK8 integration of the whole motion
        (``<prefix>_certify``) to the target and the bound of its error (their sum is at most
        :data:`~rollplan.result.CERTIFICATE_TOLERANCE`); where the certificate rejected every root, those of the
        best rejected one; NaN where there was no root.
    final : ndarray, shape (N, 3)
        Final ``(u_a, v_a, psi)`` of that integration [length unit, rad]; NaN where there is no plan.
    branches, roots : ndarray of int, shape (N,)
        Branches searched and roots tried per target.
    time_s : float
        Wall time of the call [s].
    """

    targets: np.ndarray
    k: float
    steps: int
    radius: float
    status: np.ndarray
    a: np.ndarray
    b: np.ndarray
    gamma: np.ndarray
    h: np.ndarray
    eta: np.ndarray
    path_length: np.ndarray
    branch: np.ndarray
    residual: np.ndarray
    error_bound: np.ndarray
    final: np.ndarray
    branches: np.ndarray
    roots: np.ndarray
    time_s: float

    def __len__(self) -> int:
        return len(self.status)

    @property
    def ok(self) -> np.ndarray:
        """True for the targets with a certified plan."""
        return self.status == "ok"

    def plan(self, i: int) -> Plan:
        """The plan of target ``i`` as a :class:`.planner.Plan` (the same values, no new solve); NoPlanError
        naming the status for a target without a plan."""
        i = check_whole("i", i, -len(self), len(self) - 1)
        problem = Problem(tuple(self.targets[i]), k=self.k, radius=self.radius, steps=self.steps)
        if self.status[i] != "ok":
            raise NoPlanError(f"no plan for {problem.describe()}: {self.status[i]} (plan_many)")
        final = tuple(float(x) for x in self.final[i])
        cert = Certificate("rk8", State(final[0], final[1], final[2], 0.0, 0.0),
                           float(self.residual[i]), float(self.error_bound[i]), CERTIFICATE_TOLERANCE)
        details = {"candidates": int(self.roots[i]), "solves": 1, "branches": int(self.branches[i]),
                   "roots": int(self.roots[i]), "search": "compiled"}
        stats = SolverStats(DEFAULT_ROOT_SOLVER, "ok", 0, self.time_s / max(len(self), 1), details)
        return Plan(problem, float(self.a[i]), float(self.b[i]), float(self.gamma[i]), int(self.branch[i]),
                    float(self.h[i]), float(self.eta[i]), float(self.path_length[i]), cert, stats, (),
                    default_planner())

    def plans(self) -> list:
        """:meth:`plan` of every target, None where there is no plan."""
        return [self.plan(i) if s == "ok" else None for i, s in enumerate(self.status)]


def _targets(targets) -> np.ndarray:
    try:
        t = np.array(targets, dtype=float)
    except (TypeError, ValueError):
        raise InputError("targets is not allowed: give a sequence of (u_a, v_a, psi) rows of numbers") from None
    if t.ndim != 2 or t.shape[1] != 3:
        raise InputError(f"targets of shape {t.shape} is not allowed: give N rows (u_a, v_a, psi), shape (N, 3)")
    bad = np.flatnonzero(~np.isfinite(t).all(axis=1))
    if bad.size:
        raise InputError(f"targets[{bad[0]}] = {tuple(t[bad[0]])} is not allowed: give finite numbers")
    return t


def plan_many(targets, k: float | None = None, steps: int = 1, *, robot: Robot | None = None,
              radius: float | None = None, progress=None) -> PlanMany:
    """Plan many targets at one inertia ratio and number of steps, many targets per call into the C planner.

    Each target is planned as :func:`rollplan.plan` plans a pole-to-pole target with the default root solver
    (the shortest certified plan: the C search, its polish and the RK8 certificate, ``<prefix>_plan_many``), but
    without a Python object per plan: the results are arrays. A target without a certified plan is reported by
    its status; no uncertified plan is ever returned.

    Parameters
    ----------
    targets : array_like, shape (N, 3)
        Goals ``(u_a, v_a, psi)`` from rest at the origin, contact point at the pole [length unit of
        ``radius``, rad].
    k : float, optional
        Inertia ratio (14), in [0, K_MAX]. Or give ``robot``.
    steps : int
        Figure eights per plan n >= 1.
    robot : Robot, optional
        Robot parameters; sets k and, unless given, the radius.
    radius : float, optional
        Sphere radius R (default 1, or the robot's).
    progress : callable, optional
        ``progress(done, total)`` after each call into the C planner (256 targets per call).

    Returns
    -------
    PlanMany
        Arrays of the plans and a status per target (``"ok"``, ``"no plan"``, ``"not certified"``,
        ``"incomplete"``); :meth:`PlanMany.plan` gives one as a :class:`.planner.Plan`.

    Raises
    ------
    InputError
        Bad input (targets not of shape (N, 3) or not finite, k, steps, radius).
    SolverError
        The C planner cannot be built or loaded.

    Examples
    --------
    >>> import rollplan
    >>> r = rollplan.plan_many([(0.0, 1.0, 0.0), (0.5, 0.3, 0.4)], k=2.5, steps=2)
    >>> bool(r.ok.all()) and bool((r.residual + r.error_bound <= 1e-9).all())
    True
    """
    t = _targets(targets)
    probe = Problem((1.0, 0.0, 0.0), k=k, robot=robot, radius=radius, steps=steps)   # checks k, robot, radius
    k, R, steps = check_k(probe.k), probe.radius, probe.steps
    n = t.shape[0]
    scaled = np.column_stack([t[:, 0] / R, t[:, 1] / R, t[:, 2]])
    turns = [0] * n                                              # exact integers: psi may be any double
    for i in np.flatnonzero(np.abs(scaled[:, 2]) > math.pi):   # psi reduced exactly; branches stay relative to psi
        scaled[i, 2], turns[i] = wrap_exact(scaled[i, 2])
    start = np.hypot(scaled[:, 0], scaled[:, 1]) == 0.0          # the target is the start point: no motion to plan
    t0 = time.perf_counter()
    status, p, final = certified_plans(np.where(start[:, None], (1.0, 0.0, 0.0), scaled), steps, k, progress)
    elapsed = time.perf_counter() - t0
    ok = (status == OK) & ~start
    names = np.array([_STATUS.get(int(s), "incomplete") for s in status], dtype=object)
    names[start] = "no plan"
    names = names.astype(str)

    def only(x, fill=math.nan):
        return np.where(ok, x, fill)

    branch = [int(m) - turn if good else 0 for m, turn, good in zip(p["m"], turns, ok)]
    try:
        branch = np.array(branch, dtype=np.int64)
    except OverflowError:   # a branch beyond int64 (psi of 1e19 rad or more): exact Python integers
        branch = np.array(branch, dtype=object)
    rejected = ok | ((status == NOT_CERTIFIED) & ~start)
    a, b = only(p["a"]) * R, only(p["b"]) * R
    return PlanMany(t, k, steps, R, names, a, b, only(p["gamma"]), only(p["h"]) * R, only(p["eta"]),
                    2 * np.pi * steps * (a + b), branch,
                    np.where(rejected, p["residual"], math.nan), np.where(rejected, p["bound"], math.nan),
                    np.where(ok[:, None], final * [R, R, 1.0], math.nan), p["branches"].copy(), p["roots"].copy(),
                    elapsed)
