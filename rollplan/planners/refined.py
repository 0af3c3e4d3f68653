"""The certified polish of a geometric plan (``refine=True``, ``rollplan plan --refine``).

The plan's contact path, timed rest to rest on every piece, warm-starts the rest-to-rest collocation
(:mod:`.collocation.rest`) of the same problem: contact accelerations piecewise constant on
:data:`INTERVALS` intervals, polar angle of the contact point at most :data:`CONTACT_BOUND`, cost the path
energy ``int |v|^2 dt`` (on a fixed horizon its minimizers are the shortest paths, run at constant speed).
The plan warm-starts it on its whole turns m of psi and on 0 turns (psi bent linearly in time), the straight
line from start to goal on the turns :data:`LINE_TURNS` (a long plan can lead IPOPT away from the short
motions); the NLP optima are corrected and certified best first (CVODES, the certificate of every plan). The
shortest certified motion is returned as a :class:`RefinedPlan` when it is shorter than the plan; otherwise
the plan itself, with the reason in ``stats.details["refine"]``.

The fast polish (:func:`fast_polish`, ``polish="fast"``: the default of :func:`rollplan.plan` between full states)
solves the same problem on :data:`FAST_INTERVALS` intervals from the straight line (run rest to rest,
:func:`line_guess`) on the whole turns of psi that bring the goal's psi nearest the start's, or on one turn more or
less where that start is not certified (:data:`FAST_TURNS`), and finishes it like the polish
(:meth:`.collocation.rest.RestToRestPlanner.finish`: Newton correction, CVODES certificate, the contact bound backed
off when the certified motion leaves it), the correction integrated by fixed steps (:data:`FIXED_STEPS`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

from .. import interrupts
from ..core.plane import wrap_exact
from ..errors import InputError, SolverError
from ..problem import Problem
from ..progress import report
from ..result import DEFAULT_SAMPLES, Certificate, CertifiedMotion, SolverStats, Trajectory
from ..timeseries import TimeSeries

__all__ = ["INTERVALS", "CONTACT_BOUND", "LINE_TURNS", "FAST_INTERVALS", "FAST_DEGREE", "FAST_TURNS", "FIXED_STEPS",
           "RefinedPlan", "warm_samples", "line_guess", "refine", "fast_polish"]

#: Intervals N of the polish's collocation (piecewise-constant contact accelerations).
INTERVALS = 60
#: Largest polar angle of the contact point from the south pole along the polished motion [rad] (80 deg).
CONTACT_BOUND = math.radians(80.0)
#: Whole turns m of psi of the straight-line starts (every state linear in time from the start to the goal).
LINE_TURNS = (-1, 0, 1)
#: A polished motion replaces the plan only when it is shorter by more than this fraction.
MIN_GAIN = 1e-6
#: Intervals N of the fast polish (``polish="fast"``) and the degree d of its collocation polynomials.
FAST_INTERVALS = 8
FAST_DEGREE = 3
#: Whole turns of psi of the fast polish's straight-line starts, relative to the turns m0 that bring the goal's psi
#: nearest the start's, tried in this order until one is certified (the goal's psi may be written with any turns).
FAST_TURNS = (0, -1, 1)
#: IPOPT options of the fast polish beyond those of the collocation NLP: the start and goal are kept as
#: constraints rather than removed from the NLP (fewer iterations on the small NLP).
FAST_IPOPT_OPTIONS = {"ipopt.fixed_variable_treatment": "make_constraint"}
#: Steps per interval of the eighth-order formula that integrate the fast polish's Newton correction: of the end
#: state, and of its Jacobian (:func:`.collocation.rest.correct`); the CVODES certificate checks the result.
FIXED_STEPS = (16, 2)


@dataclass(frozen=True)
class RefinedPlan(CertifiedMotion):
    """A geometric plan shortened by the polish (satisfies :class:`rollplan.result.PlanResult`).

    Attributes
    ----------
    problem : Problem
    unrefined : PlanResult
        The geometric plan that warm-started the polish.
    collocation : RestResult
        The certified rest-to-rest motion (horizon 1 s, ``turns`` whole turns of psi).
    certificate : Certificate
        CVODES integration of the polished motion from the start state (its final rates included).
    stats : SolverStats
        ``details``: the unrefined length and time, the starts tried and their NLP optima.
    path_length : float
        Contact path length of the polished motion [length unit].
    """

    method = "geometric"
    mode = "refined"

    problem: Problem
    unrefined: object
    collocation: object
    certificate: Certificate
    stats: SolverStats
    path_length: float

    @property
    def steps(self) -> int:
        return self.problem.steps

    @property
    def pieces(self) -> tuple:
        """``()``: the polished motion is not made of closed-form pieces."""
        return ()

    @property
    def legs(self) -> tuple:
        return ()

    @property
    def alternatives(self) -> tuple:
        return ()

    @property
    def unrefined_length(self) -> float:
        return self.unrefined.path_length

    @property
    def motion(self) -> TimeSeries:
        """The certified motion in time (CVODES samples) [length unit]."""
        return self.collocation.motion

    @property
    def turns(self) -> int:
        return self.collocation.turns

    def sample(self, samples: int = DEFAULT_SAMPLES) -> Trajectory:
        """The motion sampled in time (parameter ``"t"``), ``samples`` in all (:meth:`RestResult.sample`);
        ``segment`` numbers the intervals of constant contact acceleration (a sample at a joint belongs to the
        interval that ends there)."""
        tr = self.collocation.sample(samples)
        N = self.collocation.transcription.intervals
        seg = np.clip(np.ceil(tr.s / self.collocation.horizon * N - 1e-9).astype(int) - 1, 0, N - 1)
        return replace(tr, segment=seg)


def _turns(plan) -> int:
    return round((plan.final.psi - plan.goal.psi) / (2.0 * math.pi))


def _rest_law(tau):
    """``(s, ds/dtau)`` of the rest-to-rest time law ``s(tau) = tau - sin(2 pi tau) / (2 pi)`` on [0, 1]."""
    tau = np.asarray(tau, float)
    return tau - np.sin(2.0 * np.pi * tau) / (2.0 * np.pi), 1.0 - np.cos(2.0 * np.pi * tau)


def line_guess(tr, start, final, name: str):
    """The straight line in the state from ``start`` to ``final`` (7,: at rest) run rest to rest by
    :func:`_rest_law`: a :class:`~.collocation.transcription.Guess` of the transcription ``tr`` (normalized time),
    the contact rates the law's, the accelerations their differences over each interval."""
    from .collocation.transcription import Guess

    start, final = np.asarray(start, float), np.asarray(final, float)
    d = final - start

    def states(tau):
        s, ds = _rest_law(tau)
        x = start + s[..., None] * d
        x[..., 5:7] = ds[..., None] * d[3:5]
        return x

    starts, tc = tr.grid()
    nodes = states(np.append(starts, 1.0))
    return Guess(nodes, states(tc), np.diff(nodes[:, 5:7], axis=0) * tr.intervals, name)


def warm_samples(plan, samples: int = 3000) -> tuple[np.ndarray, np.ndarray]:
    """``(t, x7)`` of ``plan``'s contact path on the horizon [0, 1], units of R: every piece run rest to rest
    (``s(tau) = tau - sin(2 pi tau) / (2 pi)`` of its length, the contact rates zero at its ends) in a time
    proportional to its length; ``x7`` the state and the contact rates."""
    tr = plan.sample(samples)
    R = plan.problem.radius
    st = tr.state / np.array([R, R, 1.0, 1.0, 1.0])
    seg = tr.segment
    tau_tab = np.linspace(0.0, 1.0, 2001)
    f_tab = _rest_law(tau_tab)[0]
    blocks = []
    for j in range(int(seg.max()) + 1):
        idx = np.flatnonzero(seg == j)
        if idx.size == 0:
            continue
        idx = np.r_[idx[0] - 1, idx] if idx[0] > 0 else idx
        arc = np.r_[0.0, np.cumsum(np.hypot(np.diff(st[idx, 0]), np.diff(st[idx, 1])))]
        blocks.append((idx, arc))
    total = sum(arc[-1] for _, arc in blocks) or 1.0
    ts, xs, t0 = [], [], 0.0
    for idx, arc in blocks:
        if idx.size < 2 or arc[-1] <= 0.0:
            continue
        d = arc[-1] / total
        t = t0 + d * np.interp(arc / arc[-1], f_tab, tau_tab)
        keep = np.r_[True, np.diff(t) > 0]
        t, x = t[keep], st[idx][keep]
        rates = np.column_stack([np.gradient(x[:, 3], t), np.gradient(x[:, 4], t)]) if t.size > 1 else \
            np.zeros((t.size, 2))
        rates[0] = rates[-1] = 0.0
        ts.append(t)
        xs.append(np.column_stack([x, rates]))
        t0 += d
    t, x7 = np.concatenate(ts), np.concatenate(xs)
    t[-1] = 1.0
    return t, x7


def _unrefined(plan, note: str):
    """``plan`` with ``note`` in ``stats.details["refine"]``."""
    return replace(plan, stats=replace(plan.stats, details={**plan.stats.details, "refine": note}))


def _shorter(plan, best, elapsed: float, details: dict, not_done: str, what: str, why: str):
    """The outcome of a polish of ``plan`` (:func:`refine`, :func:`fast_polish`): a :class:`RefinedPlan` of the
    certified motion ``best`` when it is shorter than ``plan`` by more than :data:`MIN_GAIN`, else ``plan`` with the
    reason (``not_done``: no start of ``what`` was certified, ``why`` each start's status; or not shorter)."""
    if best is None:
        return _unrefined(plan, f"{not_done}: no start of {what} was certified ({why})")
    if not best.path_length < plan.path_length * (1.0 - MIN_GAIN):
        return _unrefined(plan, f"{not_done}: {what}'s certified motion ({best.path_length:.6g}) is not "
                                f"shorter than the plan ({plan.path_length:.6g})")
    stats = SolverStats("ipopt", best.stats.status, best.stats.iterations, plan.stats.time_s + elapsed,
                        {**details, "turns": best.turns})
    return RefinedPlan(plan.problem, plan, best, best.certificate, stats, best.path_length)


def refine(plan, intervals: int = INTERVALS, contact_bound: float = CONTACT_BOUND):
    """The polish of the certified geometric ``plan`` (module docstring): a :class:`RefinedPlan` when a
    certified motion shorter than ``plan`` is found, else ``plan`` with the reason in
    ``stats.details["refine"]``. Ctrl-C stops it (KeyboardInterrupt)."""
    from .collocation.rest import RestToRestMethod, guess_from_samples, naive_guess

    t_start = time.perf_counter()
    problem = plan.problem
    if not plan.pieces:
        return _unrefined(plan, "not refined: the plan has no motion to shorten")
    planner = RestToRestMethod(intervals=intervals, cost="path_energy", contact_bound=contact_bound).planner
    try:
        planner.boundary(problem, 0)
    except InputError as exc:
        return _unrefined(plan, f"not refined: {exc}")
    m0 = _turns(plan)
    t, x7 = warm_samples(plan)
    tr = planner.transcription
    starts = []
    for m in sorted({m0, 0}, key=lambda m: abs(m - m0)):
        x = x7.copy()
        x[:, 2] += 2.0 * math.pi * (m - m0) * t
        name = f"plan:{m0}" + (f"->{m}" if m != m0 else "")
        starts.append((m, lambda x=x, name=name: guess_from_samples(tr, t, x, name)))
    for m in LINE_TURNS:
        starts.append((m, lambda m=m: replace(naive_guess(tr, *planner.boundary(problem, m)), name=f"line:{m}")))
    total = len(starts) + 1
    results, tried = [], []
    for i, (m, make) in enumerate(starts):
        guess = make()
        report("refine", i, total, stage=f"collocation from {guess.name}")
        try:
            nlp = interrupts.call(planner.solve_nlp, problem, guess, 1.0, m)
        except SolverError as exc:
            tried.append({"start": guess.name, "turns": m, "status": exc.status})
            continue
        results.append(nlp)
        tried.append({"start": guess.name, "turns": m, "status": nlp.status, "nlp_objective": nlp.objective,
                      "solve_time_s": nlp.solve_time_s})
    report("refine", total - 1, total, stage="correcting and certifying")
    best, failures = None, []
    for nlp in sorted(results, key=lambda r: r.objective):
        try:
            best = interrupts.call(planner.finish, nlp)
            break
        except SolverError as exc:
            failures.append(f"{nlp.guess.name}: {exc.status}")
    report("refine", total, total, stage="done")
    elapsed = time.perf_counter() - t_start
    details = {"unrefined_length": plan.path_length, "unrefined_time_s": plan.stats.time_s, "refine_time_s": elapsed,
               "intervals": intervals, "contact_bound": contact_bound, "starts": tried}
    why = ", ".join(failures) or ", ".join(f"{s['start']}: {s['status']}" for s in tried)
    return _shorter(plan, best, elapsed, details, "not refined", "the collocation", why)


@lru_cache(maxsize=4)
def _fast_planner(intervals: int, degree: int, contact_bound: float):
    """The rest-to-rest collocation of the fast polish with its own IPOPT solver (:data:`FAST_IPOPT_OPTIONS`;
    built once per N, d and bound)."""
    from .collocation.rest import RestToRestMethod

    planner = RestToRestMethod(intervals=intervals, degree=degree, cost="path_energy",
                               contact_bound=contact_bound).planner
    return planner.twin(FAST_IPOPT_OPTIONS)


def fast_polish(plan, intervals: int = FAST_INTERVALS, contact_bound: float = CONTACT_BOUND):
    """The fast polish of the certified geometric ``plan`` (module docstring): a :class:`RefinedPlan`
    (``stats.details["polish"]`` is ``"fast"``) when its certified motion is shorter than ``plan``, else ``plan``
    with the reason in ``stats.details["refine"]``. Ctrl-C stops it (KeyboardInterrupt)."""
    t_start = time.perf_counter()
    problem = plan.problem
    if not plan.pieces:
        return _unrefined(plan, "not polished: the plan has no motion to shorten")
    planner = _fast_planner(intervals, FAST_DEGREE, contact_bound)
    try:
        start, final = planner.boundary(problem, 0)
    except InputError as exc:
        return _unrefined(plan, f"not polished: {exc}")
    tr = planner.transcription
    tried, best = [], None
    m0 = -wrap_exact(float(final[2] - start[2]))[1]
    for m in (m0 + dm for dm in FAST_TURNS):
        guess = line_guess(tr, *planner.boundary(problem, m), f"fast-line:{m}")
        entry = {"start": guess.name, "turns": m, "iterations": 0, "solve_time_s": 0.0}
        tried.append(entry)
        t0 = time.perf_counter()
        try:
            nlp = interrupts.call(planner.solve_nlp, problem, guess, 1.0, m)
        except SolverError as exc:   # IPOPT failed: its statistics are those of this solve
            entry.update(status=exc.status, iterations=int(planner.solver.stats()["iter_count"]),
                         solve_time_s=time.perf_counter() - t0)
            continue
        except RuntimeError as exc:   # e.g. an evaluation error in CasADi
            entry.update(status=f"Error: {exc}"[:200], solve_time_s=time.perf_counter() - t0)
            continue
        entry.update(status=nlp.status, iterations=nlp.iterations, solve_time_s=nlp.solve_time_s,
                     nlp_objective=nlp.objective)
        try:
            run = interrupts.call(planner.finish, nlp, FIXED_STEPS)
        except SolverError as exc:
            entry["status"] = exc.status
            continue
        except RuntimeError:   # an integration that fails: no motion from this start
            entry["status"] = "Correction_Failed"
            continue
        det = run.stats.details
        entry.update(status=run.stats.status, iterations=run.stats.iterations, solve_time_s=run.stats.time_s,
                     nlp_objective=det["nlp_objective"], correction_error=det["correction_error"],
                     residual=run.certificate.residual, backed_off_bound=det["backed_off_bound"])
        best = run   # the first certified start is kept
        break
    elapsed = time.perf_counter() - t_start
    details = {"polish": "fast", "unrefined_length": plan.path_length, "unrefined_time_s": plan.stats.time_s,
               "refine_time_s": elapsed, "intervals": intervals, "contact_bound": contact_bound, "starts": tried}
    why = ", ".join(f"{s['start']}: {s['status']}" for s in tried)
    return _shorter(plan, best, elapsed, details, "not polished", "the fast polish", why)
