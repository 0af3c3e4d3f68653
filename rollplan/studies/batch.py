"""Batch planning: many targets from a CSV file, in parallel, one JSON line each.

Every row of the targets file is planned with :func:`rollplan.planners.geometric.plan`,
which solves (32)-(33) for the figure eight (31) and verifies the plan by an
independent CVODES integration of (28)-(30). The file is CSV with a header;
columns ``u_a, v_a`` are required, ``psi`` (default 0), ``steps`` (default 1)
and ``k`` (default :data:`~rollplan.problem.DEFAULT_K`, the paper's case) are
optional, and an empty cell takes the default too; more columns are carried
along. Blank lines and lines starting with ``#`` are skipped (they are not data
rows). The output is JSON Lines, one object per row, in input order:

* a plan: :func:`rollplan.io.plan_to_dict` (no trajectory, no alternatives)
  plus ``"index"`` (0-based data row), ``"input"`` (the row as read),
  ``"status": "ok"``, and ``"version"`` and ``"units"`` (:func:`rollplan.io.tagged`);
* a failure: ``"index"``, ``"input"``, ``"status": "failed"``, ``"error"``
  (the exception's class name) and ``"reason"`` (its one-line message).

Rows are never dropped. Lines are appended and flushed as soon as they are
in order, so an interrupted run keeps every finished line (they reach the disk,
``fsync``, at least every :data:`FSYNC_INTERVAL` seconds and at the end);
``resume=True`` skips rows whose index is already in the output (a torn last
line is discarded first). The rows run where an :class:`.executor.Executor`
puts them: in this process, in local worker processes, or on a Dask cluster,
with the same output.
"""

from __future__ import annotations

import csv
import json
import logging
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from ..errors import InputError, NoPlanError, SolverError
from ..io import check_writable, plan_to_dict, tagged, write_atomic
from ..planners.geometric import SOLVERS, default_planner, plan
from ..problem import DEFAULT_K
from ..progress import Progress
from .executor import Executor

__all__ = ["COLUMNS", "REQUIRED", "DEFAULTS", "FSYNC_INTERVAL", "BatchResult", "read_targets", "plan_row",
           "run_batch", "read_output"]

log = logging.getLogger(__name__)

#: Columns of a targets file, in order.
COLUMNS = ("u_a", "v_a", "psi", "steps", "k")
#: Columns a targets file must have.
REQUIRED = ("u_a", "v_a")
#: Values of the optional columns when a column is missing or a cell is empty.
DEFAULTS = {"psi": "0", "steps": "1", "k": repr(DEFAULT_K)}
#: Seconds between two fsyncs of the output (lines are flushed at once; fsync guards against a crash of
#: the machine, not of the process, and costs milliseconds per call).
FSYNC_INTERVAL = 2.0


@dataclass(frozen=True)
class BatchResult:
    """Summary of a batch run.

    Attributes
    ----------
    total : int
        Data rows in the targets file.
    skipped : int
        Rows already in the output (resume).
    planned : int
        Rows planned in this run (successes and failures).
    failed : int
        Rows of this run recorded as failures.
    time_s : float
        Wall time of this run [s].
    failed_total : int
        Failed rows in the whole output: this run's and those kept from before (resume).
    """

    total: int
    skipped: int
    planned: int
    failed: int
    time_s: float
    failed_total: int = 0


def _data_lines(fh):
    """The lines of a CSV file that hold data: not blank, not a ``#`` comment."""
    for line in fh:
        text = line.strip()
        if text and not text.startswith("#"):
            yield line


def read_targets(path) -> list:
    """Rows of a targets CSV as dicts of strings (header required; blank and ``#`` lines skipped).

    Raises InputError if the file cannot be read or lacks a column of :data:`REQUIRED`.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"targets file {str(p)!r} does not exist")
    try:
        with open(p, newline="") as fh:
            reader = csv.DictReader(_data_lines(fh))
            header = [h.strip() for h in (reader.fieldnames or [])]
            missing = [c for c in REQUIRED if c not in header]
            if missing:
                raise InputError(f"targets file {str(p)!r} lacks column(s) {', '.join(missing)}: "
                                 f"its header must name {', '.join(REQUIRED)} (and may name "
                                 f"{', '.join(c for c in COLUMNS if c not in REQUIRED)})")
            reader.fieldnames = header
            rows = [{(key if key is not None else "_extra"): (val.strip() if isinstance(val, str) else val)
                     for key, val in row.items()} for row in reader]
    except UnicodeDecodeError:
        raise InputError(f"targets file {str(p)!r} is not a text CSV file") from None
    return rows


def _parse(row: dict):
    """(target, steps, k) from a row (missing or empty optional cells take :data:`DEFAULTS`);
    InputError naming the bad value."""
    value = lambda name: row.get(name) or DEFAULTS.get(name)  # noqa: E731
    vals = {}
    for name in ("u_a", "v_a", "psi", "k"):
        text = value(name)
        try:
            vals[name] = float(text)
        except (TypeError, ValueError):
            raise InputError(f"{name} = {text!r} is not a number") from None
    text = value("steps")
    try:
        steps = int(text)
    except (TypeError, ValueError):
        raise InputError(f"steps = {text!r} is not allowed: it must be a whole number >= 1") from None
    return (vals["u_a"], vals["v_a"], vals["psi"]), steps, vals["k"]


def _failed(index: int, row: dict, exc: BaseException) -> dict:
    """The output line of a row that failed: the exception's class and its first line."""
    return tagged({"index": index, "input": row, "status": "failed", "error": type(exc).__name__,
                   "reason": (str(exc).splitlines() or [type(exc).__name__])[0]}, "R")


def plan_row(index: int, row: dict, method: str = "ipopt") -> dict:
    """Plan one row; the JSON object of its output line (never raises for a bad row)."""
    try:
        target, steps, k = _parse(row)
        p = plan(target, steps, k=k, method=method)
        out = tagged(plan_to_dict(p, None, include_alternatives=False), p.problem.unit)
        out.update({"index": index, "input": row, "status": "ok"})
        return out
    except (InputError, NoPlanError, SolverError) as exc:
        return _failed(index, row, exc)
    except Exception as exc:  # a bug or an unexpected solver crash: record it, never drop the row
        log.exception("row %d failed unexpectedly", index)
        return _failed(index, row, exc)


def _plan_job(job):
    index, row, method = job
    return plan_row(index, row, method)


def _lost_row(job, exc) -> dict:
    """The output line of a row whose task was lost on a cluster (e.g. its worker died)."""
    return _failed(job[0], job[1], exc)


class _Warm:
    """Build the planner of ``method`` once per process (picklable, for spawned workers)."""

    def __init__(self, method: str) -> None:
        self.method = method

    def __call__(self) -> None:
        default_planner(self.method)


def read_output(path) -> list:
    """Valid lines of an output file as dicts (a torn or malformed line is left out)."""
    out = []
    p = Path(path)
    if not p.exists():
        return out
    with open(p, "rb") as fh:
        for raw in fh:
            if not raw.endswith(b"\n"):
                continue  # torn last line of an interrupted write
            try:
                d = json.loads(raw)
            except ValueError:
                continue
            if isinstance(d, dict) and isinstance(d.get("index"), int):
                out.append(d)
    return out


def _dump(d: dict) -> str:
    return json.dumps(d, allow_nan=False, separators=(",", ":")) + "\n"


def run_batch(targets, out, jobs: int = 1, resume: bool = False, overwrite: bool = False,
              method: str = "ipopt", progress: Callable | bool | None = None,
              scheduler: str | None = None) -> BatchResult:
    """Plan every row of ``targets`` into the JSON Lines file ``out``, in input order.

    Parameters
    ----------
    targets : path
        CSV file (module docstring: columns, defaults, comments).
    out : path
        Output JSON Lines file.
    jobs : int
        Worker processes on this machine (each starts with a built planner); 1 plans in this process.
    resume : bool
        Keep the lines already in ``out`` and plan only the rows missing there.
    overwrite : bool
        Replace an existing ``out`` (otherwise an existing file needs ``resume``).
    method : str
        Root solver of :func:`rollplan.planners.geometric.plan`.
    progress : callable ``(done, total, failed)``, True or None
        Progress report after each row; True shows it on stderr (:class:`rollplan.progress.Progress`:
        a bar on a terminal, a line every few seconds otherwise).
    scheduler : str, optional
        Address of a Dask distributed scheduler: plan the rows on its workers instead (``jobs`` is
        then ignored); the output is the same.

    Returns
    -------
    BatchResult
    """
    if method not in SOLVERS:
        raise InputError(f"method = {method!r} is not allowed: choose one of {', '.join(SOLVERS)}")
    executor = Executor(jobs, scheduler, _Warm(method))   # checks jobs and scheduler before any file is touched
    rows = read_targets(targets)
    out = check_writable(out)
    if out.exists() and not (resume or overwrite):
        raise InputError(f"output file {str(out)!r} exists: pass resume=True to continue it or overwrite=True "
                         "to replace it")
    with executor:   # connects to a scheduler (and checks its workers) before the output is touched
        done_lines = read_output(out) if resume else []
        if resume and out.exists():
            # rewrite without torn/malformed lines and duplicates, sorted, before appending
            seen = {}
            for d in done_lines:
                if 0 <= d["index"] < len(rows):
                    seen.setdefault(d["index"], d)
            done_lines = [seen[i] for i in sorted(seen)]
            write_atomic(out, "".join(_dump(d) for d in done_lines).encode())
        else:
            write_atomic(out, b"")
        have = {d["index"] for d in done_lines}
        kept_failed = sum(d.get("status") != "ok" for d in done_lines)
        todo = [(i, row, method) for i, row in enumerate(rows) if i not in have]
        shown = Progress(unit="targets") if progress is True else None
        report = ((lambda done, total, failed: shown("batch", done, total, failed=failed)) if shown is not None
                  else (progress or None))
        start = time.perf_counter()
        failed = 0
        done = len(have)
        in_order = not have or max(have) < (todo[0][0] if todo else len(rows))
        try:
            with open(out, "a", encoding="utf-8") as fh:
                results = executor.map(_plan_job, todo, on_error=_lost_row)
                if report:
                    report(done, len(rows), failed)
                synced = time.monotonic()
                try:
                    for d in results:
                        fh.write(_dump(d))
                        fh.flush()
                        if time.monotonic() - synced >= FSYNC_INTERVAL:
                            os.fsync(fh.fileno())
                            synced = time.monotonic()
                        done += 1
                        failed += d["status"] != "ok"
                        if report:
                            report(done, len(rows), failed)
                finally:
                    fh.flush()
                    os.fsync(fh.fileno())
        finally:
            if shown is not None:
                shown.close()
    if not in_order:
        lines = read_output(out)
        lines.sort(key=lambda d: d["index"])
        write_atomic(out, "".join(_dump(d) for d in lines).encode())
    return BatchResult(len(rows), len(have), len(todo), failed, time.perf_counter() - start, kept_failed + failed)
