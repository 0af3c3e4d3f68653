"""Files of results: the JSON forms of results, and reading plan files back.

Writing goes through :mod:`rollplan.outputs` (atomic, locked, never over an
input; its names are re-exported here), reading through :mod:`rollplan.inputs`
(regular files, size and depth caps, finite numbers only).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import InputError, show, show_limit
from .inputs import load_json, show_path
from .outputs import check_figure_path, check_writable, save_figure, write_atomic, write_json
from .planners.geometric.composed import as_composed
from .planners.geometric.planner import Plan
from .planners.refined import RefinedPlan
from .problem import State, check_contact
from .robot import Robot, robot_from_mapping
from .version import __version__

__all__ = ["check_writable", "check_figure_path", "write_atomic", "write_json", "save_figure", "plan_to_dict",
           "UNITS", "tagged", "composed_to_dict", "refined_to_dict", "route_to_dict", "motion_to_dict", "RotorPlan",
           "load_rotor_plan", "MAX_PLAN_BYTES", "MAX_PLAN_SAMPLES", "PLAN_FILE_VERSIONS", "check_plan_data"]

#: Largest plan file read back (a plan of 1000 steps timed with 10^6 samples fits).
MAX_PLAN_BYTES = 1 << 30
#: Most samples (rows of ``time``) of a plan file read back: the most ``rollplan plan`` writes (its
#: MAX_SAMPLES, 10^6) and room for the repeated times of the torques' steps.
MAX_PLAN_SAMPLES = 1_100_000


#: Units of every JSON output except the length (``tagged`` adds it): SI, angles in radians.
UNITS = {"angle": "rad", "time": "s", "angular_rate": "rad/s", "torque": "N m", "mass": "kg",
         "inertia": "kg m^2",
         "residual": "Euclidean norm of the arrival error (u_a/R, v_a/R, psi wrapped, u_o, v_o): lengths in R, "
                     "angles in rad"}


def tagged(obj: dict, length_unit: str) -> dict:
    """``obj`` with the fields ``version`` (of rollplan) and ``units`` (``length``: ``"R"`` or ``"m"``,
    and :data:`UNITS`) in front: the form of every JSON document rollplan writes."""
    return {"version": __version__, "units": {"length": length_unit, **UNITS}, **obj}


def _f(x):
    """The numbers of ``x`` (any shape) as a flat list of Python floats."""
    return np.asarray(x, dtype=float).ravel().tolist()


def _rows(a):
    """A 2-D array's rows as lists of Python floats (numpy's ``tolist``: the same values at C speed)."""
    a = np.asarray(a)
    if a.ndim == 2:
        return a.astype(float, copy=False).tolist()
    return [[float(v) for v in r] for r in a]


def plan_to_dict(plan, traj=None, include_alternatives=True) -> dict:
    """A geometric-phase plan as the JSON object of ``rollplan plan --json`` (a composed plan:
    :func:`composed_to_dict`)."""
    if not isinstance(plan, Plan):   # a composed plan or a route
        return composed_to_dict(plan, traj, include_alternatives)
    g = plan.goal
    d = {
        "k": plan.k,
        "radius": plan.radius,
        "steps": plan.steps,
        "target": {"u_a": g.u_a, "v_a": g.v_a, "psi": g.psi},
        "figure_eight": {"a": plan.a, "b": plan.b, "gamma": plan.gamma},
        "step": {"h": plan.h, "eta": plan.eta},
        "branch": plan.branch,
        "final": plan.final.as_dict(),
        "residual": plan.residual,
        "certificate": plan.certificate.as_dict(),
        "path_length": plan.path_length,
        "solver": plan.stats.as_dict(),
    }
    if traj is not None:
        d["trajectory"] = traj.as_dict()
    if include_alternatives and plan.alternatives:
        d["alternatives"] = [plan_to_dict(p, None, False) for p in plan.alternatives]
    return d


def _leg_to_dict(leg, radius) -> dict:
    """One leg of figure eights of a composed plan, lengths in the composed plan's unit."""
    scale = radius / leg.radius
    return {"kind": "figure_eights", "steps": leg.steps, "a": leg.a * scale, "b": leg.b * scale,
            "gamma": leg.gamma, "branch": leg.branch, "h": leg.h * scale, "eta": leg.eta,
            "target": {n: float(v) * (scale if n != "psi" else 1.0) for n, v in zip(("u_a", "v_a", "psi"), leg.goal)},
            "path_length": leg.path_length * scale, "residual": leg.residual}


def composed_to_dict(plan, traj=None, include_alternatives=True) -> dict:
    """A plan as the JSON object of ``rollplan plan --json``, for any start and goal.

    ``start``, ``goal``, ``final`` are states; ``mode`` says how the figure eights were found;
    ``approach``/``departure`` are the rolls (null at the pole); ``legs`` the legs of figure eights or
    the circle pairs of a turn in place; ``segments`` the pieces of the contact path, in the order of
    the trajectory's ``segment`` numbers. One-leg plans also carry the keys of a pole-to-pole plan
    (``figure_eight``, ``step``, ``branch``); ``target`` is the goal's ``(u_a, v_a, psi)``.
    """
    c = as_composed(plan)
    R = c.radius
    g = c.goal
    legs = [_leg_to_dict(leg, R) for leg in c.legs]
    if c.turn is not None:
        legs.append(c.turn.as_dict(R))
    roll = lambda r: None if r is None else {k: v * (R if k != "beta" else 1.0) for k, v in r.as_dict().items()}  # noqa: E731
    d = {
        "k": c.k, "radius": R, "steps": c.steps,
        "start": c.problem.start.as_dict(), "goal": g.as_dict(),
        "target": {"u_a": g.u_a, "v_a": g.v_a, "psi": g.psi},
        "mode": c.mode,
        "approach": roll(c.approach), "departure": roll(c.departure),
        "eights_target": {n: float(v) * (R if n != "psi" else 1.0) for n, v in zip(("u_a", "v_a", "psi"), c.target)},
        "intermediate": None if c.intermediate is None else _f(c.intermediate * [R, R, 1.0]),
        "legs": legs,
        "base": None if getattr(c, "base", None) is None else c.base.as_dict(R),
        "segments": [dict(p.as_dict(), length=p.length * R) for p in c.pieces],
        "final": c.final.as_dict(), "residual": c.residual, "certificate": c.certificate.as_dict(),
        "path_length": c.path_length, "solver": c.stats.as_dict(),
    }
    if len(c.legs) == 1 and c.turn is None:
        leg = legs[0]
        d.update({"figure_eight": {"a": leg["a"], "b": leg["b"], "gamma": leg["gamma"]},
                  "curve": getattr(c.legs[0], "curve", "circles"),
                  "step": {"h": leg["h"], "eta": leg["eta"]}, "branch": leg["branch"]})
    if traj is not None:
        d["trajectory"] = traj.as_dict()
    alternatives = getattr(plan, "alternatives", ())
    if include_alternatives and alternatives:
        d["alternatives"] = [plan_to_dict(p, None, False) for p in alternatives]
    return d


def refined_to_dict(plan, traj=None) -> dict:
    """A plan of ``rollplan plan --refine`` as its JSON object.

    Polished (a :class:`~rollplan.planners.refined.RefinedPlan`): ``mode`` ``"refined"``, the states, certificate,
    ``path_length`` and ``trajectory`` (in time, ``t``) of the polished motion, ``refined`` (its length, the
    unrefined length, whole turns of psi, intervals, contact bound) and ``unrefined`` (the plan it was polished
    from, as :func:`composed_to_dict`). Not polished: :func:`composed_to_dict` of the plan with ``refined``
    null and ``refine_note`` the reason. Both carry ``unrefined_length``.
    """
    if not isinstance(plan, RefinedPlan):
        d = composed_to_dict(plan, traj)
        d.update(refined=None, refine_note=plan.stats.details.get("refine", ""), unrefined_length=plan.path_length)
        return d
    det = plan.stats.details
    d = {"k": plan.k, "radius": plan.radius, "steps": plan.steps, "start": plan.problem.start.as_dict(),
         "goal": plan.goal.as_dict(), "mode": plan.mode, "final": plan.final.as_dict(), "residual": plan.residual,
         "certificate": plan.certificate.as_dict(), "path_length": plan.path_length,
         "unrefined_length": plan.unrefined_length, "solver": plan.stats.as_dict(),
         "refined": {"path_length": plan.path_length, "unrefined_length": plan.unrefined_length, "turns": plan.turns,
                     "intervals": det["intervals"], "contact_bound": det["contact_bound"],
                     "time_s": det["refine_time_s"]},
         "unrefined": composed_to_dict(plan.unrefined, None, False)}
    if traj is not None:
        d["trajectory"] = traj.as_dict()
    return d


def route_to_dict(route, traj=None) -> dict:
    """A route as the JSON object of ``rollplan route --json``: the waypoints, every leg (as
    :func:`composed_to_dict`, without trajectory), the waypoint residuals of the one-pass
    certificate, and the whole route's ``final``, ``residual`` and ``trajectory``."""
    d = {
        "k": route.k, "radius": route.radius, "steps": route.steps,
        "start": route.problem.start.as_dict(), "goal": route.goal.as_dict(),
        "target": {"u_a": route.goal.u_a, "v_a": route.goal.v_a, "psi": route.goal.psi},
        "waypoints": [{**w.state.as_dict(), "steps": w.steps, "label": w.label} for w in route.waypoints],
        "legs": [composed_to_dict(p, None, False) for p in route.plans],
        "waypoint_residuals": _f(route.waypoint_residuals),
        "final": route.final.as_dict(), "residual": route.residual, "certificate": route.certificate.as_dict(),
        "path_length": route.path_length, "solver": route.stats.as_dict(),
        "segments": [dict(p.as_dict(), length=p.length * route.radius, leg=int(i))
                     for p, i in zip(route.pieces, route.leg_of_piece)],
    }
    if traj is not None:
        d["trajectory"] = traj.as_dict()
    return d


def motion_to_dict(motion) -> dict:
    """The motion's keys of ``rollplan plan --duration T --json``: time series as lists of rows.

    ``state`` rows are in :class:`~rollplan.problem.State` order (u_a, v_a, psi, u_o, v_o);
    ``segment`` numbers the half-step of each sample; ``timing`` is the law's name and
    ``minimum_duration`` its shortest duration within the robot's limits (null without limits).
    ``torque_breaks`` lists the times at which the torques step; each is given twice in ``time``, the
    first row with the limit from the left, the second with the limit from the right
    (:func:`rollplan.execution.actuation.motion_samples`): replayed linearly between rows, with the
    step at a repeated time, the torques are the law's profile.
    """
    from .execution.actuation import motion_samples

    m = motion_samples(motion)
    return {
        "timing": motion.timing,
        "duration": motion.duration,
        "minimum_duration": motion.minimum_duration,
        "time": _f(m.time),
        "omega": _rows(m.omega),
        "rotor_rates": _rows(m.rotor_rates),
        "rotor_angles": _rows(m.rotor_angles),
        "rotor_torques": _rows(m.rotor_torques),
        "state": _rows(m.state),
        "segment": [int(v) for v in m.segment],
        "torque_breaks": _f(m.repeated_times()),
        "robot": motion.robot.as_dict(),
    }


@dataclass(frozen=True)
class RotorPlan:
    """What a rotor-driven simulation needs from a plan file (every key checked by :func:`check_plan_data`).

    Attributes
    ----------
    robot : Robot
        The robot the plan was made for.
    time : ndarray, shape (N,)
        Sample times [s], nondecreasing; a time given twice is a step of the torques (:data:`TORQUE_REPLAY`).
    rotor_rates : ndarray, shape (N, 2)
        Rotor rates [rad/s].
    goal : State
        Planned arrival [m, rad].
    data : dict
        The whole JSON object.
    start : State
        Start state [m, rad] (zero when the file has none).
    steps : int or None
        Figure eights of the plan (``steps``).
    duration : float or None
        ``duration`` [s] (the span of ``time``).
    rotor_torques : ndarray, shape (N, 2) or None
        Motor torques [N m].
    timing : str or None
        The timing law's name.
    torque_breaks : ndarray
        Times at which the torques step (``torque_breaks``) [s]; empty for files without the key.
    segment : ndarray, shape (N,), int, or None
        The piece of every sample (``segment``).
    kinds : tuple of str
        The kind of every piece (``segments``), () when the file does not give one per piece.
    """

    robot: Robot
    time: np.ndarray
    rotor_rates: np.ndarray
    goal: State
    data: dict
    start: State = State()
    steps: int | None = None
    duration: float | None = None
    rotor_torques: np.ndarray | None = None
    timing: str | None = None
    torque_breaks: np.ndarray = field(default_factory=lambda: np.zeros(0))
    segment: np.ndarray | None = None
    kinds: tuple = ()

    @property
    def distinct(self) -> np.ndarray:
        """Indices of the samples at distinct times (the first of a repeated time): where the rates are sampled."""
        keep = np.ones(self.time.size, bool)
        keep[1:] = np.diff(self.time) > 0
        return np.nonzero(keep)[0]


#: Oldest and newest ``version`` of a plan file this rollplan reads (the format has not changed since 0.1.0).
PLAN_FILE_VERSIONS = ("0.1.0", __version__)


def _version_tuple(text):
    parts = text.split(".") if isinstance(text, str) else []
    if not 1 <= len(parts) <= 4 or not all(p.isascii() and p.isdigit() and len(p) <= 6 for p in parts):
        return None
    return tuple(int(p) for p in parts) + (0,) * (4 - len(parts))


def _number(where, key, value, low, high, unit, low_open=False):
    """A JSON number (int or float, not a string or a bool) in the range; InputError naming file, key and value."""
    ok = isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
    ok = ok and (value > low if low_open else value >= low) and value <= high
    if not ok:
        span = f"{'(' if low_open else '['}{show_limit(low)}, {show_limit(high)}]"
        raise InputError(f"{where}: {key!r} = {show(value)} is not allowed: it must be a number in {span}{unit}")
    return float(value)


def _array(where, key, value, columns):
    """``value`` as a float array: a list of numbers (``columns`` None) or of rows of ``columns`` numbers."""
    try:
        a = np.asarray(value, float)
    except (TypeError, ValueError, OverflowError):
        a = None
    if a is None or (a.ndim != 1 if columns is None else (a.ndim != 2 or a.shape[1] != columns)):
        raise InputError(f"{where}: {key!r} is not allowed: it must be a list of numbers"
                         f"{f' (rows of {columns})' if columns else ''}")
    return a


def check_plan_data(data, where: str) -> RotorPlan:
    """Every key of a plan file that ``simulate`` and ``animate`` read, checked once; the :class:`RotorPlan`.

    ``where`` names the file. Each refusal is one InputError naming the file, the key, its value and
    what is allowed: ``version`` (a rollplan version within :data:`PLAN_FILE_VERSIONS`), ``robot``,
    ``target`` and ``goal`` (the same arrival when both are given), ``start``, ``steps`` (whole, in
    [1, MAX_STEPS]), ``time`` (nondecreasing, a time at most twice, at most :data:`MAX_PLAN_SAMPLES`
    samples), ``duration`` (its span), ``rotor_rates`` and ``rotor_torques`` (one row of two per sample, the
    rates equal at a repeated time), ``timing`` (a law's name) and ``torque_breaks`` (the repeated times).
    """
    from .execution.plants import check_samples  # the execution layer only when a rotor plan is read
    from .execution.timing import DURATION_RANGE, LAWS
    from .problem import check_steps

    if not isinstance(data, dict):
        raise InputError(f"{where} is not a rollplan plan (a JSON object)")
    for key in ("time", "rotor_rates", "robot", "target"):
        if key not in data:
            hint = " (make it with: rollplan plan ... --duration T --json FILE)" if key != "target" else ""
            raise InputError(f"{where} has no key {key!r}{hint}")
    # plan files written before the motors' limits existed have no such keys: unlimited
    robot = robot_from_mapping(data["robot"], f"{where}: 'robot'", derived=("k",))
    version = data.get("version")
    low, high = PLAN_FILE_VERSIONS
    v = _version_tuple(version)
    if v is None or not _version_tuple(low) <= v <= _version_tuple(high):
        raise InputError(f"{where}: 'version' = {show(version)} is not allowed: it must be the version of rollplan "
                         f"that wrote the file, from {low} to {high} (this one)")
    tg = data["target"]
    if not isinstance(tg, dict):
        raise InputError(f"{where}: 'target' = {show(tg)} is not allowed: it must be an object with u_a, v_a, psi")
    try:
        target = State.of({n: tg.get(n) for n in ("u_a", "v_a", "psi")}, "target")
        goal = State.of(data["goal"], "goal") if "goal" in data else target
        start = State.of(data["start"], "start") if "start" in data else State()
        for name, state in (("start", start), ("goal", goal)):   # the region plans start and end in
            check_contact(state.u_o, state.v_o, name)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    if not np.allclose(goal.array()[:3], target.array()[:3], rtol=1e-12, atol=1e-12 * robot.radius):
        raise InputError(f"{where}: 'target' = ({target.u_a!r}, {target.v_a!r}, {target.psi!r}) is not allowed: "
                         f"it must be the (u_a, v_a, psi) of 'goal' = ({goal.u_a!r}, {goal.v_a!r}, {goal.psi!r})")
    steps = None
    if "steps" in data:
        try:
            steps = check_steps(data["steps"])
        except InputError as exc:
            raise InputError(f"{where}: {exc}") from None
    t = _array(where, "time", data["time"], None)
    if t.ndim == 1 and t.size > MAX_PLAN_SAMPLES:
        raise InputError(f"{where}: 'time' has {t.size} samples: at most {MAX_PLAN_SAMPLES} are allowed (the "
                         "most 'rollplan plan --samples' writes)")
    rates = _array(where, "rotor_rates", data["rotor_rates"], 2)
    torques = None
    if "rotor_torques" in data:
        torques = _array(where, "rotor_torques", data["rotor_torques"], 2)
        if torques.shape != rates.shape:
            raise InputError(f"{where}: 'rotor_torques' has shape {torques.shape}: it must be that of "
                             f"'rotor_rates', {rates.shape}")
    try:
        keep = np.ones(t.size, bool)
        if t.ndim == 1 and t.size > 1:
            keep[1:] = np.diff(t) != 0
        distinct, _ = check_samples(t[keep], rates[keep] if rates.ndim == 2 and rates.shape[0] == t.size else rates)
        if torques is not None and not np.all(np.isfinite(torques)):
            raise InputError("rotor_torques must be finite numbers")
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    repeated = np.nonzero(~keep)[0]
    if repeated.size and (np.any(repeated[1:] - repeated[:-1] < 2) or np.any(rates[repeated] != rates[repeated - 1])):
        raise InputError(f"{where}: 'time' is not allowed: a time may be given twice only for a step of the torques, "
                         "with the same rotor rates")
    breaks = t[repeated]
    if "torque_breaks" in data:
        given = _array(where, "torque_breaks", data["torque_breaks"], None)
        if given.shape != breaks.shape or not np.array_equal(given, breaks):
            raise InputError(f"{where}: 'torque_breaks' = {show(data['torque_breaks'])} is not allowed: it must list "
                             "the times given twice in 'time'")
    duration = None
    if "duration" in data:
        lo, hi = DURATION_RANGE
        duration = _number(where, "duration", data["duration"], lo, hi, " s")
        span = float(t[-1] - t[0])
        if not math.isclose(duration, span, rel_tol=1e-9):
            raise InputError(f"{where}: 'duration' = {show(data['duration'])} is not allowed: it must be the span "
                             f"of 'time', {span!r} s")
    timing = data.get("timing")
    if timing is not None and timing not in LAWS:
        raise InputError(f"{where}: 'timing' = {show(timing)} is not allowed: choose one of {', '.join(LAWS)}")
    segment, kinds = None, ()
    if "segment" in data:
        seg = data["segment"]
        ok = isinstance(seg, list) and len(seg) == t.size and all(type(v) is int for v in seg)
        segment = np.asarray(seg, int) if ok else None
        if segment is None or np.any(np.diff(segment) < 0) or (segment.size and segment[0] < 0):
            raise InputError(f"{where}: 'segment' = {show(seg)} is not allowed: it must be one nondecreasing whole "
                             f"number >= 0 per sample ({t.size})")
        pieces = data.get("segments")
        if isinstance(pieces, list) and all(isinstance(p, dict) and isinstance(p.get("kind"), str) for p in pieces) \
                and len(pieces) == np.unique(segment).size:
            kinds = tuple(p["kind"] for p in pieces)
    return RotorPlan(robot, t, rates, goal, data, start, steps, duration, torques, timing, breaks, segment, kinds)


def load_rotor_plan(path) -> RotorPlan:
    """Read a plan written by ``rollplan plan --duration T --json FILE``; InputError (naming the file) if it
    is not one (:func:`check_plan_data`)."""
    where = f"plan file {show_path(path)}"
    return check_plan_data(load_json(path, "plan file", MAX_PLAN_BYTES), where)
