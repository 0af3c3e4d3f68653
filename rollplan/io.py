"""Atomic file output and JSON conversion of results."""

from __future__ import annotations

import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .errors import InputError

__all__ = ["check_writable", "check_figure_path", "write_atomic", "write_json", "save_figure", "plan_to_dict"]


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
        raise InputError(f"figure path {str(path)!r} is not allowed: its extension {('.' + suffix) if suffix else '(none)'!r} "
                         f"is not a figure format; use one of {', '.join('.' + f for f in sorted(formats))}")
    return check_writable(path)


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
