"""Batch planning: many targets from a CSV file, in parallel, one JSON line each.

Every row of the targets file (columns ``u_a, v_a, psi, steps, k``; more
columns are carried along) is planned with :func:`rollplan.planners.geometric.plan`,
which solves (32)-(33) for the figure eight (31) and verifies the plan by an
independent CVODES integration of (28)-(30). The targets file is read by
:func:`rollplan.inputs.read_csv` and its numbers by
:func:`rollplan.inputs.parse_number` (the rules of the command line). The
output is JSON Lines, one object per row, in input order:

* a plan: :func:`rollplan.io.plan_to_dict` (no trajectory, no alternatives)
  plus ``"index"`` (0-based data row), ``"key"``, ``"input"`` (the row as
  read) and ``"status": "ok"``;
* a failure: ``"index"``, ``"key"``, ``"input"``, ``"status": "failed"``,
  ``"error"`` (the exception's class name) and ``"reason"`` (its one-line message).

Rows are never dropped, and a row is never recorded as failed because the run
was interrupted: Ctrl-C stops the run (also inside the solvers, see
:mod:`rollplan.interrupts`) and the row in flight is planned again next time.

Resume. ``key`` is a SHA-256 of the row's content (its columns and fields as
read, in a canonical order) and of the root solver: ``resume=True`` keeps a
finished line whose key is some row's key (renumbered to that row's index)
and plans every other row. A row edited, inserted or moved is planned again or
kept by what it holds, never by its position; lines of rows no longer in the
file are dropped. Lines are appended as soon as they are in order, each
reaching the file at once (:class:`rollplan.outputs.LineWriter`), so a run
stopped at any moment (Ctrl-C, SIGKILL) and resumed writes the same lines as a
run never stopped (up to the solvers' wall-clock times, ``solver.time_s``).

Safety (:mod:`rollplan.outputs`): the output is locked for the whole run (a
second batch on the same output is refused), it may not be the targets file,
an existing output needs ``resume`` or ``overwrite`` (not both), and
``resume`` refuses a file that is not a batch output.
"""

from __future__ import annotations

import hashlib
import json
import logging
import multiprocessing
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from tqdm import tqdm

from ..errors import InputError, NoPlanError, SolverError, check_choice, check_flag, check_whole
from ..inputs import parse_number, parse_whole, read_csv, show_path
from ..io import plan_to_dict
from ..outputs import LineWriter, check_writable, claim, write_atomic
from ..planners.geometric import SOLVERS, plan

__all__ = ["COLUMNS", "MAX_TARGETS_BYTES", "BatchResult", "read_targets", "row_key", "plan_row", "run_batch",
           "read_output"]

log = logging.getLogger(__name__)

#: Columns a targets file must have.
COLUMNS = ("u_a", "v_a", "psi", "steps", "k")
#: Largest targets file read.
MAX_TARGETS_BYTES = 1 << 28
#: Version of what ``key`` hashes; a line of another version is planned again on resume.
_KEY_FORMAT = 1


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


def _targets(path):
    return read_csv(path, "targets file", COLUMNS, MAX_TARGETS_BYTES)


def read_targets(path) -> list:
    """Rows of a targets CSV as dicts of stripped strings (header required, blank lines skipped).

    Raises InputError if the file cannot be read (see :func:`rollplan.inputs.read_csv`)
    or lacks a column of :data:`COLUMNS`.
    """
    return _targets(path).rows


def row_key(row: dict, method: str = "ipopt", problem: str | None = None) -> str:
    """The content key of a row: SHA-256 of its columns and fields (sorted by column), the root solver,
    and what is wrong with its shape (``problem``), as hex."""
    content = json.dumps({"format": _KEY_FORMAT, "method": method, "row": row, "problem": problem},
                         sort_keys=True, ensure_ascii=True)
    return hashlib.sha256(content.encode()).hexdigest()


def _parse(row: dict):
    """(target, steps, k) from a row; InputError naming the bad value."""
    vals = {}
    for name in ("u_a", "v_a", "psi", "k"):
        if name not in row:
            raise InputError(f"{name} is missing")
        vals[name] = parse_number(row[name], name)
    if "steps" not in row:
        raise InputError("steps is missing")
    steps = parse_whole(row["steps"], "steps")
    return (vals["u_a"], vals["v_a"], vals["psi"]), steps, vals["k"]


def plan_row(index: int, row: dict, method: str = "ipopt", problem: str | None = None) -> dict:
    """Plan one row; the JSON object of its output line (never raises for a bad row).

    ``problem`` says what is wrong with the row's shape (it is then recorded as
    failed). KeyboardInterrupt is never caught: an interrupted row is not a result.
    """
    head = {"index": index, "key": row_key(row, method, problem)}
    try:
        if problem:
            raise InputError(problem)
        target, steps, k = _parse(row)
        p = plan(target, steps, k=k, method=method)
        out = plan_to_dict(p, None, include_alternatives=False)
        return {**head, **out, "input": row, "status": "ok"}
    except (InputError, NoPlanError, SolverError) as exc:
        return {**head, "input": row, "status": "failed", "error": type(exc).__name__,
                "reason": str(exc).splitlines()[0] if str(exc) else type(exc).__name__}
    except Exception as exc:  # a bug or an unexpected solver crash: record it, never drop the row
        log.exception("row %d failed unexpectedly", index)
        return {**head, "input": row, "status": "failed", "error": type(exc).__name__,
                "reason": (str(exc).splitlines() or [type(exc).__name__])[0]}


def _ignore_sigint():
    """Worker initializer: Ctrl-C is handled by the parent, which stops the pool."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _start_pool(processes: int):
    """Worker processes that ignore Ctrl-C from the start (the parent stops them): SIGINT is ignored while
    they are spawned, and an ignored signal stays ignored through exec, also while they import rollplan."""
    ctx = multiprocessing.get_context("spawn")
    if threading.current_thread() is not threading.main_thread():
        return ctx.Pool(processes, initializer=_ignore_sigint)
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return ctx.Pool(processes, initializer=_ignore_sigint)
    finally:
        signal.signal(signal.SIGINT, previous)


def _plan_job(job):
    index, row, method, problem = job
    return plan_row(index, row, method, problem)


def _batch_line(raw: bytes):
    """The object of one complete output line, or None if it is not a batch line."""
    try:
        d = json.loads(raw)
    except (ValueError, RecursionError):
        return None
    if isinstance(d, dict) and isinstance(d.get("index"), int) and d.get("status") in ("ok", "failed"):
        return d
    return None


def read_output(path) -> list:
    """Valid lines of an output file as dicts (a torn or malformed line is left out)."""
    p = Path(path)
    if not p.is_file():
        return []
    with open(p, "rb") as fh:
        return [d for d in (_batch_line(raw) for raw in fh if raw.endswith(b"\n")) if d is not None]


def _finished(out: Path) -> dict:
    """``key -> line`` of the finished lines of an existing output; InputError if it is not a batch output."""
    done = {}
    with open(out, "rb") as fh:
        for number, raw in enumerate(fh, 1):
            if not raw.endswith(b"\n"):
                break   # the torn last line of an interrupted write
            d = _batch_line(raw)
            if d is None and raw.strip():
                raise InputError(f"output file {show_path(out)} is not a rollplan batch output (line {number} is "
                                 "not a batch line): resume refuses to rewrite it; give another --out")
            if d is not None and isinstance(d.get("key"), str):
                done.setdefault(d["key"], d)
    return done


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
        Output JSON Lines file (not the targets file); locked while the run lasts.
    jobs : int
        Worker processes (each builds its own planner); 1 plans in this process.
    resume : bool
        Keep the finished lines of ``out`` whose rows are still in ``targets`` (by content, see the
        module docstring) and plan the other rows.
    overwrite : bool
        Replace an existing ``out`` (otherwise an existing file needs ``resume``; not both).
    method : str
        Root solver of :func:`rollplan.planners.geometric.plan`.
    progress : callable ``(done, total, failed)``, True or None
        Progress report after each row; True draws a tqdm bar on stderr.

    Returns
    -------
    BatchResult

    Raises
    ------
    InputError
        Bad arguments, an unreadable targets file, an output that cannot be
        written (:class:`~rollplan.errors.OutputError`: read-only, locked by
        another run, disk full...).
    KeyboardInterrupt
        Ctrl-C; the finished lines stay in ``out``.
    """
    jobs = check_whole("jobs", jobs, 1, 1024)
    method = check_choice("method", method, SOLVERS)
    resume, overwrite = check_flag("resume", resume), check_flag("overwrite", overwrite)
    if resume and overwrite:
        raise InputError("resume and overwrite exclude each other: resume keeps the finished lines of the output, "
                         "overwrite replaces it")
    table = _targets(targets)
    out = check_writable(out, "output file", inputs=[targets])
    with claim(out, what="output file"):
        return _run(table, out, jobs, resume, overwrite, method, progress)


def _run(table, out: Path, jobs, resume, overwrite, method, progress) -> BatchResult:
    if out.exists() and not (resume or overwrite):
        raise InputError(f"output file {show_path(out)} exists: pass --resume to continue it or --overwrite to "
                         "replace it")
    done = _finished(out) if resume and out.exists() else {}
    rows, problems = table.rows, table.problems
    lines, todo = {}, []
    for i, (row, problem) in enumerate(zip(rows, problems)):
        key = row_key(row, method, problem)
        if key in done:
            lines[i] = {**done[key], "index": i}
        else:
            todo.append((i, row, method, problem))
    kept = sorted(lines)
    write_atomic(out, "".join(_dump(lines[i]) for i in kept).encode(), "output file")
    bar = tqdm(total=len(rows), initial=len(kept), unit="target", file=sys.stderr) if progress is True else None
    report = (lambda d, total, f: _tick(bar, d, f)) if bar is not None else (progress or None)
    start = time.perf_counter()
    failed, count = 0, len(kept)
    pool = None
    try:
        with LineWriter(out, "output file") as writer:
            if jobs == 1 or len(todo) <= 1:
                results = map(_plan_job, todo)
            else:
                pool = _start_pool(min(jobs, len(todo)))
                results = pool.imap(_plan_job, todo, chunksize=1)   # yields in input order
            if report:
                report(count, len(rows), failed)
            for d in results:
                writer.write(_dump(d))
                lines[d["index"]] = d
                count += 1
                failed += d["status"] != "ok"
                if report:
                    report(count, len(rows), failed)
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
    if kept and todo and kept[-1] > todo[0][0]:   # kept lines came first, out of input order: sort
        write_atomic(out, "".join(_dump(lines[i]) for i in sorted(lines)).encode(), "output file")
    return BatchResult(len(rows), len(kept), len(todo), failed, time.perf_counter() - start)
