"""Atomic file output and JSON conversion of results."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["check_writable", "write_atomic", "write_json", "save_figure", "plan_to_dict"]


def check_writable(path) -> Path:
    """Raise InputError unless ``path`` can be created (its folder exists and is writable)."""
    p = Path(path)
    folder = p.parent if str(p.parent) else Path(".")
    if p.is_dir():
        raise InputError(f"output path {str(p)!r} is a directory")
    if not folder.is_dir():
        raise InputError(f"output path {str(p)!r} is not writable: folder {str(folder)!r} does not exist")
    if not os.access(folder, os.W_OK):
        raise InputError(f"output path {str(p)!r} is not writable: no permission in {str(folder)!r}")
    return p


def write_atomic(path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and an atomic rename."""
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


def save_figure(fig, path, dpi=120) -> None:
    """Save a matplotlib figure atomically (format from the suffix)."""
    import io

    buf = io.BytesIO()
    fig.savefig(buf, format=Path(path).suffix.lstrip(".") or "png", dpi=dpi)
    write_atomic(path, buf.getvalue())


def _f(x):
    return [float(v) for v in np.asarray(x).ravel()]


def plan_to_dict(plan, traj=None, include_alternatives=True) -> dict:
    """The plan as the JSON object of ``rollplan plan --json``."""
    d = {
        "k": plan.k,
        "radius": plan.radius,
        "steps": plan.steps,
        "target": {"u_a": plan.target[0], "v_a": plan.target[1], "psi": plan.target[2]},
        "figure_eight": {"a": plan.a, "b": plan.b, "gamma": plan.gamma},
        "step": {"h": plan.h, "eta": plan.eta},
        "branch": plan.branch,
        "final": dict(zip(("u_a", "v_a", "psi", "u_o", "v_o"), _f(plan.final))),
        "residual": plan.residual,
        "path_length": plan.path_length,
        "solver": {"method": plan.stats.method, "status": plan.stats.status, "iterations": plan.stats.iterations,
                   "candidates": plan.stats.candidates, "solves": plan.stats.solves, "time_s": plan.stats.time_s},
    }
    if traj is not None:
        d["trajectory"] = {n: _f(getattr(traj, n)) for n in ("theta", "u_o", "v_o", "u_a", "v_a", "psi")}
    if include_alternatives and plan.alternatives:
        d["alternatives"] = [plan_to_dict(p, None, False) for p in plan.alternatives]
    return d
