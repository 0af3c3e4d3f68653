"""Files of results: the JSON forms of results, and reading plan files back.

Writing goes through :mod:`rollplan.outputs` (atomic, locked, never over an
input; its names are re-exported here), reading through :mod:`rollplan.inputs`
(regular files, size and depth caps, finite numbers only).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .execution.plants import check_samples
from .inputs import load_json, show_path
from .outputs import check_figure_path, check_writable, save_figure, write_atomic, write_json
from .problem import State
from .robot import Robot, robot_from_mapping

__all__ = ["check_writable", "check_figure_path", "write_atomic", "write_json", "save_figure", "plan_to_dict",
           "motion_to_dict", "RotorPlan", "load_rotor_plan", "MAX_PLAN_BYTES"]

#: Largest plan file read back (a plan of 1000 steps timed with 10^6 samples fits).
MAX_PLAN_BYTES = 1 << 30


def _f(x):
    return [float(v) for v in np.asarray(x).ravel()]


def _rows(a):
    return [[float(v) for v in r] for r in np.asarray(a)]


def plan_to_dict(plan, traj=None, include_alternatives=True) -> dict:
    """A geometric-phase plan as the JSON object of ``rollplan plan --json``."""
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


def motion_to_dict(motion) -> dict:
    """The motion's keys of ``rollplan plan --duration T --json``: time series as lists of rows.

    ``state`` rows are in :class:`~rollplan.problem.State` order (u_a, v_a, psi, u_o, v_o).
    """
    return {
        "duration": motion.duration,
        "time": _f(motion.time),
        "omega": _rows(motion.omega),
        "rotor_rates": _rows(motion.rotor_rates),
        "rotor_angles": _rows(motion.rotor_angles),
        "rotor_torques": _rows(motion.rotor_torques),
        "state": _rows(motion.state),
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
    """

    robot: Robot
    time: np.ndarray
    rotor_rates: np.ndarray
    goal: State
    data: dict


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
    robot = robot_from_mapping(data["robot"], f"{where}: 'robot'", derived=("k",))
    tg = data["target"]
    if not isinstance(tg, dict):
        raise InputError(f"{where}: 'target' must be an object with u_a, v_a, psi")
    try:
        goal = State.of({n: tg[n] for n in ("u_a", "v_a", "psi")}, "target")
        t = np.asarray(data["time"], float)
        rates = np.asarray(data["rotor_rates"], float)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    except (TypeError, KeyError, ValueError):
        raise InputError(f"{where}: 'target', 'time' or 'rotor_rates' is malformed") from None
    try:
        t, rates = check_samples(t, rates)
    except InputError as exc:
        raise InputError(f"{where}: {exc}") from None
    return RotorPlan(robot, t, rates, goal, data)
