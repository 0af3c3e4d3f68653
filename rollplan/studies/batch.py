"""Batch planning: many targets from a CSV file, in parallel, one JSON line each.

Every row of the targets file (columns ``u_a, v_a, psi, steps, k``; more
columns are carried along) is planned with :func:`rollplan.planners.geometric.plan`,
which solves (32)-(33) for the figure eight (31) and verifies the plan by an
independent CVODES integration of (28)-(30). The output is JSON Lines, one
object per row, in input order:

* a plan: :func:`rollplan.io.plan_to_dict` (no trajectory, no alternatives)
  plus ``"index"`` (0-based data row), ``"input"`` (the row as read) and
  ``"status": "ok"``;
* a failure: ``"index"``, ``"input"``, ``"status": "failed"``, ``"error"``
  (the exception's class name) and ``"reason"`` (its one-line message).

Rows are never dropped. Lines are appended and flushed as soon as they are
in order, so an interrupted run keeps every finished line; ``resume=True``
skips rows whose index is already in the output (a torn last line is
discarded first).
"""

from __future__ import annotations

import csv
import json
import logging
import multiprocessing
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from ..errors import InputError, NoPlanError, SolverError, check_whole
from ..io import check_writable, plan_to_dict, write_atomic
from ..planners.geometric import SOLVERS, plan

__all__ = ["COLUMNS", "BatchResult", "read_targets", "plan_row", "run_batch", "read_output"]

log = logging.getLogger(__name__)

#: Columns a targets file must have.
COLUMNS = ("u_a", "v_a", "psi", "steps", "k")


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
    """

    total: int
    skipped: int
    planned: int
    failed: int
    time_s: float


def read_targets(path) -> list:
    """Rows of a targets CSV as dicts of strings (header required, blank lines skipped).

    Raises InputError if the file cannot be read or lacks a column of :data:`COLUMNS`.
    """
    p = Path(path)
    if not p.is_file():
        raise InputError(f"targets file {str(p)!r} does not exist")
    try:
        with open(p, newline="") as fh:
            reader = csv.DictReader(fh)
            header = [h.strip() for h in (reader.fieldnames or [])]
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise InputError(f"targets file {str(p)!r} lacks column(s) {', '.join(missing)}: "
                                 f"its header must name {', '.join(COLUMNS)}")
            reader.fieldnames = header
            rows = [{(key if key is not None else "_extra"): (val.strip() if isinstance(val, str) else val)
                     for key, val in row.items()} for row in reader]
    except UnicodeDecodeError:
        raise InputError(f"targets file {str(p)!r} is not a text CSV file") from None
    return rows


def _parse(row: dict):
    """(target, steps, k) from a row; InputError naming the bad value."""
    vals = {}
    for name in ("u_a", "v_a", "psi", "k"):
        text = row.get(name)
        try:
            vals[name] = float(text)
        except (TypeError, ValueError):
            raise InputError(f"{name} = {text!r} is not a number") from None
    text = row.get("steps")
    try:
        steps = int(text)
    except (TypeError, ValueError):
        raise InputError(f"steps = {text!r} is not allowed: it must be a whole number >= 1") from None
    return (vals["u_a"], vals["v_a"], vals["psi"]), steps, vals["k"]


def plan_row(index: int, row: dict, method: str = "ipopt") -> dict:
    """Plan one row; the JSON object of its output line (never raises for a bad row)."""
    try:
        target, steps, k = _parse(row)
        p = plan(target, steps, k=k, method=method)
        out = plan_to_dict(p, None, include_alternatives=False)
        out.update({"index": index, "input": row, "status": "ok"})
        return out
    except (InputError, NoPlanError, SolverError) as exc:
        return {"index": index, "input": row, "status": "failed", "error": type(exc).__name__,
                "reason": str(exc).splitlines()[0] if str(exc) else type(exc).__name__}
    except Exception as exc:  # a bug or an unexpected solver crash: record it, never drop the row
        log.exception("row %d failed unexpectedly", index)
        return {"index": index, "input": row, "status": "failed", "error": type(exc).__name__,
                "reason": (str(exc).splitlines() or [type(exc).__name__])[0]}


def _ignore_sigint():
    """Worker initializer: Ctrl-C is handled by the parent, which stops the pool."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _plan_job(job):
    index, row, method = job
    return plan_row(index, row, method)


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


def _tick(bar, done: int, failed: int) -> None:
    bar.n = done
    bar.set_postfix(failed=failed, refresh=False)
    bar.refresh()


def run_batch(targets, out, jobs: int = 1, resume: bool = False, overwrite: bool = False,
              method: str = "ipopt", progress: Callable | bool | None = None) -> BatchResult:
    """Plan every row of ``targets`` into the JSON Lines file ``out``, in input order.

    Parameters
    ----------
    targets : path
        CSV file with columns :data:`COLUMNS`.
    out : path
        Output JSON Lines file.
    jobs : int
        Worker processes (each builds its own planner); 1 plans in this process.
    resume : bool
        Keep the lines already in ``out`` and plan only the rows missing there.
    overwrite : bool
        Replace an existing ``out`` (otherwise an existing file needs ``resume``).
    method : str
        Root solver of :func:`rollplan.planners.geometric.plan`.
    progress : callable ``(done, total, failed)``, True or None
        Progress report after each row; True draws a tqdm bar on stderr.

    Returns
    -------
    BatchResult
    """
    jobs = check_whole("jobs", jobs, 1)
    if method not in SOLVERS:
        raise InputError(f"method = {method!r} is not allowed: choose one of {', '.join(SOLVERS)}")
    rows = read_targets(targets)
    out = check_writable(out)
    if out.exists() and not (resume or overwrite):
        raise InputError(f"output file {str(out)!r} exists: pass resume to continue it or overwrite to replace it")
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
    todo = [(i, row, method) for i, row in enumerate(rows) if i not in have]
    bar = tqdm(total=len(rows), initial=len(have), unit="target", file=sys.stderr) if progress is True else None
    report = (lambda done, total, failed: _tick(bar, done, failed)) if bar is not None else (progress or None)
    start = time.perf_counter()
    failed = 0
    done = len(have)
    in_order = not have or max(have) < (todo[0][0] if todo else len(rows))
    pool = None
    try:
        with open(out, "a", encoding="utf-8") as fh:
            if jobs == 1 or len(todo) <= 1:
                results = map(_plan_job, todo)
            else:
                ctx = multiprocessing.get_context("spawn")
                pool = ctx.Pool(min(jobs, len(todo)), initializer=_ignore_sigint)
                results = pool.imap(_plan_job, todo, chunksize=1)   # yields in input order
            if report:
                report(done, len(rows), failed)
            for d in results:
                fh.write(_dump(d))
                fh.flush()
                os.fsync(fh.fileno())
                done += 1
                failed += d["status"] != "ok"
                if report:
                    report(done, len(rows), failed)
        if pool is not None:
            pool.close()
            pool.join()
            pool = None
    finally:
        if bar is not None:
            bar.close()
        if pool is not None:
            pool.terminate()
            pool.join()
    if not in_order:
        lines = read_output(out)
        lines.sort(key=lambda d: d["index"])
        write_atomic(out, "".join(_dump(d) for d in lines).encode())
    return BatchResult(len(rows), len(have), len(todo), failed, time.perf_counter() - start)
