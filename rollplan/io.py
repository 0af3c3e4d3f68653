"""Files: atomic output, the JSON forms of results, and reading plan files back."""

from __future__ import annotations

import json
import os
import tempfile
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np

from .errors import InputError
from .execution.plants import check_samples
from .problem import State
from .robot import Robot
from .version import __version__

__all__ = ["check_writable", "check_figure_path", "write_atomic", "write_json", "save_figure", "plan_to_dict",
           "UNITS", "tagged",
           "motion_to_dict", "RotorPlan", "load_rotor_plan"]


def check_writable(path) -> Path:
    """The real path behind ``path`` (symlinks followed), or InputError unless it can be written.

    An existing target must be a regular file: a device, FIFO or socket is
    refused rather than replaced by the atomic rename.
    """
    p = Path(os.path.realpath(path)) if os.path.islink(path) else Path(path)
    folder = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        raise InputError(f"output path {str(path)!r} is a directory")
    if p.exists() and not p.is_file():
        raise InputError(f"output path {str(path)!r} is not allowed: it exists and is not a regular file")
    if not folder.is_dir():
        raise InputError(f"output path {str(p)!r} is not writable: folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise InputError(f"output path {str(p)!r} is not writable: no permission in {str(folder)!r}")
    return p


def write_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and an atomic rename.

    A symlink is written through: its target gets the data, the link stays.
    """
    p = check_writable(path)
    fd, tmp = tempfile.mkstemp(dir=p.parent if str(p.parent) else ".", prefix=f".{p.name}.", suffix=".tmp")
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.fchmod(fd, 0o666 & ~umask)  # mkstemp makes 0600; give the file the usual mode
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
        os.replace(tmp, p)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_json(path, obj) -> None:
    write_atomic(path, (json.dumps(obj, indent=1, allow_nan=False) + "\n").encode())


def check_figure_path(path) -> Path:
    """``check_writable`` plus a file format matplotlib can write, judged by the suffix."""
    from matplotlib.figure import Figure

    formats = Figure().canvas.get_supported_filetypes()
    suffix = Path(path).suffix.lstrip(".").lower()
    if suffix not in formats:
        ext = ("." + suffix) if suffix else "(none)"
        raise InputError(f"figure path {str(path)!r} is not allowed: its extension {ext!r} "
                         f"is not a figure format; use one of {', '.join('.' + f for f in sorted(formats))}")
    return check_writable(path)


def save_figure(fig, path, dpi=120) -> None:
    """Save a matplotlib figure atomically (format from the suffix)."""
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format=Path(path).suffix.lstrip(".") or "png", dpi=dpi)
    write_atomic(path, buf.getvalue())


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
    """Read a plan written by ``rollplan plan --duration T --json FILE``; InputError if it lacks the motion."""
    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except OSError as exc:
        raise InputError(f"plan file {str(path)!r} cannot be read: {exc.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"plan file {str(path)!r} is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(f"plan file {str(path)!r} is not a rollplan plan (a JSON object)")
    for key in ("time", "rotor_rates", "robot", "target"):
        if key not in data:
            hint = " (make it with: rollplan plan ... --duration T --json FILE)" if key != "target" else ""
            raise InputError(f"plan file {str(path)!r} has no key {key!r}{hint}")
    rob = data["robot"]
    names = [f.name for f in fields(Robot)]
    if not isinstance(rob, dict) or any(n not in rob for n in names):
        raise InputError(f"plan file {str(path)!r}: 'robot' must hold {', '.join(names)}")
    robot = Robot(**{n: rob[n] for n in names})
    tg = data["target"]
    try:
        goal = State(float(tg["u_a"]), float(tg["v_a"]), float(tg["psi"]))
        t = np.asarray(data["time"], float)
        rates = np.asarray(data["rotor_rates"], float)
    except (TypeError, KeyError, ValueError):
        raise InputError(f"plan file {str(path)!r}: 'target', 'time' or 'rotor_rates' is malformed") from None
    t, rates = check_samples(t, rates)
    return RotorPlan(robot, t, rates, goal, data)
