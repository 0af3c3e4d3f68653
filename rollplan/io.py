"""Files of results: the JSON forms of results, and reading plan files back.

Writing goes through :mod:`rollplan.outputs` (atomic, locked, never over an
input; its names are re-exported here), reading through :mod:`rollplan.inputs`
(regular files, size and depth caps, finite numbers only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .inputs import load_json, show_path
from .outputs import check_figure_path, check_writable, save_figure, write_atomic, write_json
from .planners.geometric.composed import as_composed
from .problem import State, check_contact
from .robot import Robot, robot_from_mapping
from .version import __version__

__all__ = ["check_writable", "check_figure_path", "write_atomic", "write_json", "save_figure", "plan_to_dict",
           "UNITS", "tagged", "composed_to_dict", "route_to_dict", "motion_to_dict", "RotorPlan", "load_rotor_plan",
           "MAX_PLAN_BYTES"]

#: Largest plan file read back (a plan of 1000 steps timed with 10^6 samples fits).
MAX_PLAN_BYTES = 1 << 30


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
    return [float(v) for v in np.asarray(x).ravel()]


def _rows(a):
    return [[float(v) for v in r] for r in np.asarray(a)]


def plan_to_dict(plan, traj=None, include_alternatives=True) -> dict:
    """A geometric-phase plan as the JSON object of ``rollplan plan --json`` (a composed plan:
    :func:`composed_to_dict`)."""
    if hasattr(plan, "pieces"):
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
        "segments": [dict(p.as_dict(), length=p.length * R) for p in c.pieces],
        "final": c.final.as_dict(), "residual": c.residual, "certificate": c.certificate.as_dict(),
        "path_length": c.path_length, "solver": c.stats.as_dict(),
    }
    if len(c.legs) == 1 and c.turn is None:
        leg = legs[0]
        d.update({"figure_eight": {"a": leg["a"], "b": leg["b"], "gamma": leg["gamma"]},
                  "step": {"h": leg["h"], "eta": leg["eta"]}, "branch": leg["branch"]})
    if traj is not None:
        d["trajectory"] = traj.as_dict()
    alternatives = getattr(plan, "alternatives", ())
    if include_alternatives and alternatives:
        d["alternatives"] = [plan_to_dict(p, None, False) for p in alternatives]
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
    """
    return {
        "timing": motion.timing,
        "duration": motion.duration,
        "minimum_duration": motion.minimum_duration,
        "time": _f(motion.time),
        "omega": _rows(motion.omega),
        "rotor_rates": _rows(motion.rotor_rates),
        "rotor_angles": _rows(motion.rotor_angles),
        "rotor_torques": _rows(motion.rotor_torques),
        "state": _rows(motion.state),
        "segment": [int(v) for v in motion.segment],
        "robot": motion.robot.as_dict(),
    }


@dataclass(frozen=True)
class RotorPlan:
    """What a rotor-driven simulation needs from a plan file.

    Attributes
    ----------
    robot : Robot
        The robot the plan was made for.
    time : ndarray, shape (N,)
        Sample times [s].
    rotor_rates : ndarray, shape (N, 2)
        Rotor rates [rad/s].
    goal : State
        Planned arrival [m, rad].
    data : dict
        The whole JSON object.
    start : State
        Start state [m, rad] (zero when the file has none).
    """

    robot: Robot
    time: np.ndarray
    rotor_rates: np.ndarray
    goal: State
    data: dict
    start: State = State()


def load_rotor_plan(path) -> RotorPlan:
    """Read a plan written by ``rollplan plan --duration T --json FILE``; InputError (naming the file) if it
    is not one: not a regular UTF-8 JSON file, or without the motion, or with a robot, target or samples
    that are not allowed."""
    where = f"plan file {show_path(path)}"
    data = load_json(path, "plan file", MAX_PLAN_BYTES)
    if not isinstance(data, dict):
        raise InputError(f"{where} is not a rollplan plan (a JSON object)")
    for key in ("time", "rotor_rates", "robot", "target"):
        if key not in data:
            hint = " (make it with: rollplan plan ... --duration T --json FILE)" if key != "target" else ""
            raise InputError(f"{where} has no key {key!r}{hint}")
    # plan files written before the motors' limits existed have no such keys: unlimited
    robot = robot_from_mapping(data["robot"], f"{where}: 'robot'", derived=("k",))
    tg = data["target"]
    if not isinstance(tg, dict):
        raise InputError(f"{where}: 'target' must be an object with u_a, v_a, psi")
    try:
        goal = State.of({n: tg[n] for n in ("u_a", "v_a", "psi")}, "target")
        if "goal" in data:
            goal = State.of(data["goal"], "goal")
        start = State.of(data["start"], "start") if "start" in data else State()
        for name, state in (("start", start), ("goal", goal)):   # the region plans start and end in
            check_contact(state.u_o, state.v_o, name)
        t = np.asarray(data["time"], float)
        rates = np.asarray(data["rotor_rates"], float)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    except (TypeError, KeyError, ValueError):
        raise InputError(f"{where}: 'target', 'start', 'goal', 'time' or 'rotor_rates' is malformed") from None
    from .execution.plants import check_samples  # the execution layer only when a rotor plan is read

    try:
        t, rates = check_samples(t, rates)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    return RotorPlan(robot, t, rates, goal, data, start)
