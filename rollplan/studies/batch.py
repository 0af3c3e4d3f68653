"""Batch planning: many targets from a CSV file, in parallel, one JSON line each.

Every row of the targets file is planned with :func:`rollplan.planners.geometric.plan`,
which solves (32)-(33) for the figure eight (31) and verifies the plan by an
independent CVODES integration of (28)-(30). The targets file is read by
:func:`rollplan.inputs.read_csv` and its numbers by
:func:`rollplan.inputs.parse_number` (the rules of the command line). It is CSV
with a header; columns ``u_a, v_a`` are required, ``psi`` (default 0), ``steps``
(default 1), ``k`` (default :data:`~rollplan.problem.DEFAULT_K`, the paper's
case) and ``curve`` (the leaf family of the row's figure eight, one of
:data:`~rollplan.planners.geometric.CURVE_CHOICES`; default ``circles``) are
optional, and an empty cell takes the default too; more columns are
carried along. Blank lines and lines starting with ``#`` are skipped (they are
not data rows). The output is JSON Lines, one object per row, in input order:

* a plan: :func:`rollplan.io.plan_to_dict` (no trajectory, no alternatives)
  plus ``"curve"`` (the plan's family; for ``best`` the one chosen), ``"index"`` (0-based data row),
  ``"key"``, ``"input"`` (the row as read), ``"status": "ok"``, and ``"version"`` and ``"units"``
  (:func:`rollplan.io.tagged`);
* a failure: ``"index"``, ``"key"``, ``"input"``, ``"status": "failed"``,
  ``"error"`` (the exception's class name) and ``"reason"`` (its one-line message).

Rows are never dropped, and a row is never recorded as failed because the run
was interrupted: Ctrl-C stops the run (also inside the solvers, see
:mod:`rollplan.interrupts`) and the row in flight is planned again next time.
The rows run where an :class:`.executor.Executor` puts them: in this process,
in local worker processes, or on a Dask cluster, with the same output.

Resume. ``key`` is a SHA-256 of the row's content (its columns and fields as
read, in a canonical order) and of the root solver: ``resume=True`` keeps a
finished line whose key is some row's key (renumbered to that row's index)
and plans every other row. A row edited, inserted or moved is planned again or
kept by what it holds, never by its position; lines of rows no longer in the
file are dropped. Lines are appended as soon as they are in order, each
reaching the file at once (:class:`rollplan.outputs.LineWriter`, fsync in
batches), so a run stopped at any moment (Ctrl-C, SIGKILL) and resumed writes
the same lines as a run never stopped (up to the solvers' wall-clock times,
``solver.time_s``).

Safety (:mod:`rollplan.outputs`): the output is locked for the whole run (a
second batch on the same output is refused), it may not be the targets file,
an existing output needs ``resume`` or ``overwrite`` (not both), and
``resume`` refuses a file that is not a batch output. The output is made
(atomically) with its first new line, so a run that cannot write that (disk
full) leaves no file and an existing output as it was; a later line that
cannot be written whole is cut off again, leaving the finished lines.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .. import interrupts
from ..errors import InputError, NoPlanError, OutputError, SolverError, check_choice, check_flag, check_whole
from ..inputs import parse_number, parse_whole, read_csv, show_path
from ..io import plan_to_dict, tagged
from ..outputs import LineWriter, check_writable, claim, write_atomic
from ..planners import solve
from ..planners.geometric import CURVE_CHOICES, DEFAULT_ROOT_SOLVER, SOLVERS, default_planner, plan_many
from ..planners.method import renamed_option
from ..problem import DEFAULT_K, Problem
from ..progress import Progress, reporting
from .executor import MAX_JOBS, Executor

__all__ = ["COLUMNS", "REQUIRED", "DEFAULTS", "FSYNC_INTERVAL", "MAX_TARGETS_BYTES", "BatchResult", "read_targets",
           "row_key",
           "plan_row", "run_batch", "read_output"]

log = logging.getLogger(__name__)

#: Columns of a targets file, in order.
COLUMNS = ("u_a", "v_a", "psi", "steps", "k", "curve")
#: Columns a targets file must have.
REQUIRED = ("u_a", "v_a")
#: Values of the optional columns when a column is missing or a cell is empty.
DEFAULTS = {"psi": "0", "steps": "1", "k": repr(DEFAULT_K), "curve": "circles"}
#: Largest targets file read.
MAX_TARGETS_BYTES = 1 << 28
#: Seconds between two fsyncs of the output (each line reaches the file at once; fsync guards against a crash
#: of the machine, not of the process, and costs milliseconds per call).
FSYNC_INTERVAL = 2.0
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
    failed_total : int
        Rows recorded as failures in the whole output (kept ones included).
    """

    total: int
    skipped: int
    planned: int
    failed: int
    time_s: float
    failed_total: int = 0


def _targets(path):
    return read_csv(path, "targets file", REQUIRED, MAX_TARGETS_BYTES, comments=True)


def read_targets(path) -> list:
    """Rows of a targets CSV as dicts of stripped strings (header required; blank and ``#`` lines skipped).

    Raises InputError if the file cannot be read (see :func:`rollplan.inputs.read_csv`)
    or lacks a column of :data:`REQUIRED`.
    """
    return _targets(path).rows


def row_key(row: dict, root_solver: str = DEFAULT_ROOT_SOLVER, problem: str | None = None) -> str:
    """The content key of a row: SHA-256 of its columns and fields (sorted by column), the root solver,
    and what is wrong with its shape (``problem``), as hex."""
    content = json.dumps({"format": _KEY_FORMAT, "method": root_solver, "row": row, "problem": problem},
                         sort_keys=True, ensure_ascii=True)
    return hashlib.sha256(content.encode()).hexdigest()


def _parse(row: dict):
    """(target, steps, k, curve) from a row (missing or empty optional cells take :data:`DEFAULTS`);
    InputError naming the bad value."""
    value = lambda name: row.get(name) or DEFAULTS.get(name)  # noqa: E731
    vals = {}
    for name in ("u_a", "v_a", "psi", "k"):
        if value(name) is None:
            raise InputError(f"{name} is missing")
        vals[name] = parse_number(value(name), name)
    steps = parse_whole(value("steps"), "steps")
    curve = check_choice("curve", value("curve"), CURVE_CHOICES)
    return (vals["u_a"], vals["v_a"], vals["psi"]), steps, vals["k"], curve


def plan_row(index: int, row: dict, root_solver: str = DEFAULT_ROOT_SOLVER, problem: str | None = None) -> dict:
    """Plan one row by the method ``"geometric"`` (:func:`rollplan.planners.solve`) with ``root_solver``;
    the JSON object of its output line (never raises for a bad row).

    ``problem`` says what is wrong with the row's shape (it is then recorded as
    failed). KeyboardInterrupt is never caught: an interrupted row is not a result.
    """
    head = {"index": index, "key": row_key(row, root_solver, problem)}
    try:
        if problem:
            raise InputError(problem)
        target, steps, k, curve = _parse(row)
        options = {"curve": curve} if curve != "circles" else {}
        p = solve(Problem(target, k=k, steps=steps), "geometric", root_solver=root_solver, **options)
        out = plan_to_dict(p, None, include_alternatives=False)
        out = {"curve": getattr(p, "curve", "circles"), **out}
        return tagged({**head, **out, "input": row, "status": "ok"}, p.problem.unit)
    except (InputError, NoPlanError, SolverError) as exc:
        return _failed(head, row, exc)
    except Exception as exc:  # a bug or an unexpected solver crash: record it, never drop the row
        log.exception("row %d failed unexpectedly", index)
        return _failed(head, row, exc)


def _failed(head: dict, row: dict, exc: BaseException) -> dict:
    """The output line of a row that failed: the exception's class and its first line."""
    return tagged({**head, "input": row, "status": "failed", "error": type(exc).__name__,
                   "reason": (str(exc).splitlines() or [type(exc).__name__])[0]}, "R")


def _lost_row(job, exc) -> dict:
    """The output line of a row whose task was lost on a cluster (e.g. its worker died)."""
    index, row, root_solver, problem = job
    return _failed({"index": index, "key": row_key(row, root_solver, problem)}, row, exc)


class _Warm:
    """Build the planner of ``root_solver`` once per process (picklable, for spawned workers)."""

    def __init__(self, root_solver: str) -> None:
        self.root_solver = root_solver

    def __call__(self) -> None:
        default_planner(self.root_solver)


#: Most rows per task of the planning phase (:func:`_task_size`): with the default root solver, the rows of a task
#: that share k and steps are planned by one call of :func:`rollplan.planners.geometric.plan_many`.
ROWS_PER_TASK = 64


def _task_size(rows: int, jobs: int) -> int:
    """Rows per task: :data:`ROWS_PER_TASK`, at most an eighth of each worker's share (a short batch: row by row)."""
    return max(1, min(ROWS_PER_TASK, rows // (8 * jobs)))


def _plan_task(jobs) -> list:
    """The output lines of the rows ``jobs`` (a task), in order: with the default root solver, the rows of one k
    and one number of steps by :func:`~rollplan.planners.geometric.plan_many` (a certified one-leg plan, the
    plan :func:`plan_row` gives it); every other row (and one without such a plan, which may need two legs, or
    fails with its own reason) by :func:`plan_row`."""
    lines = [None] * len(jobs)
    with reporting(None):   # the batch shows its own progress, not the planner's of each row
        if jobs and jobs[0][2] == DEFAULT_ROOT_SOLVER:
            groups = {}
            for j, (_, row, _, problem) in enumerate(jobs):
                if not problem:
                    try:
                        target, steps, k, curve = _parse(row)
                    except InputError:
                        continue
                    if curve != "circles":
                        continue   # another leaf family: row by row
                    groups.setdefault((k, steps), []).append((j, target))
            for (k, steps), members in groups.items():
                try:
                    found = plan_many([t for _, t in members], k=k, steps=steps)
                except (InputError, SolverError):
                    continue   # planned row by row below, each line with its own reason
                for i in np.flatnonzero(found.ok):
                    j = members[i][0]
                    index, row, root_solver, problem = jobs[j]
                    p = found.plan(int(i))
                    head = {"index": index, "key": row_key(row, root_solver, problem)}
                    lines[j] = tagged({**head, "curve": "circles", **plan_to_dict(p, None, include_alternatives=False),
                                       "input": row, "status": "ok"}, p.problem.unit)
        return [d if d is not None else plan_row(*job) for d, job in zip(lines, jobs)]


def _lost_task(jobs, exc) -> list:
    """The output lines of a task lost on a cluster."""
    return [_lost_row(job, exc) for job in jobs]


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


def run_batch(targets, out, jobs: int = 1, resume: bool = False, overwrite: bool = False,
              method: str | None = None, progress: Callable | bool | None = None,
              scheduler: str | None = None, *, root_solver: str | None = None) -> BatchResult:
    """Plan every row of ``targets`` into the JSON Lines file ``out``, in input order.

    Parameters
    ----------
    targets : path
        CSV file (module docstring: columns, defaults, comments).
    out : path
        Output JSON Lines file (not the targets file); locked while the run lasts.
    jobs : int
        Worker processes on this machine; 1 plans in this process. Where processes fork (Linux), the first
        row is planned here and the workers forked after it, so they start with the planner and the
        tables of its k built (:class:`.executor.Executor`, ``first_here``).
    resume : bool
        Keep the finished lines of ``out`` whose rows are still in ``targets`` (by content, see the
        module docstring) and plan the other rows.
    overwrite : bool
        Replace an existing ``out`` (otherwise an existing file needs ``resume``; not both).
    method : str
        Deprecated name of ``root_solver``.
    progress : callable ``(done, total, failed)``, True or None
        Progress report after each row; True shows it on stderr (:class:`rollplan.progress.Progress`:
        a bar on a terminal, a line every few seconds otherwise).
    scheduler : str, optional
        Address of a Dask distributed scheduler: plan the rows on its workers instead (``jobs`` is
        then ignored); the output is the same.
    root_solver : str
        Root solver of the method ``"geometric"`` (:data:`rollplan.planners.geometric.SOLVERS`; default
        ``"c"``: the C planner's search, polish and certificate).

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
    jobs = check_whole("jobs", jobs, 1, MAX_JOBS)
    root_solver, name = renamed_option("method", method, "root_solver", root_solver, DEFAULT_ROOT_SOLVER)
    root_solver = check_choice(name, root_solver, SOLVERS)
    resume, overwrite = check_flag("resume", resume), check_flag("overwrite", overwrite)
    if resume and overwrite:
        raise InputError("resume and overwrite exclude each other: resume keeps the finished lines of the output, "
                         "overwrite replaces it")
    # Checks jobs and scheduler before any file is touched. Local workers are forked after the first row was
    # planned here: they start with what it built (the planner, the tables of its k), built once.
    executor = Executor(jobs, scheduler, _Warm(root_solver), first_here=True)
    table = _targets(targets)
    out = check_writable(out, "output file", inputs=[targets])
    with claim(out, what="output file"):
        return _run(table, out, executor, resume, overwrite, root_solver, progress)


def _run(table, out: Path, executor, resume, overwrite, root_solver, progress) -> BatchResult:
    if out.exists() and not (resume or overwrite):
        raise InputError(f"output file {show_path(out)} exists: pass --resume to continue it or --overwrite to "
                         "replace it")
    done = _finished(out) if resume and out.exists() else {}
    rows, problems = table.rows, table.problems
    lines, todo = {}, []
    for i, (row, problem) in enumerate(zip(rows, problems)):
        key = row_key(row, root_solver, problem)
        if key in done:
            lines[i] = {**done[key], "index": i}
        else:
            todo.append((i, row, root_solver, problem))
    kept = sorted(lines)
    kept_failed = sum(lines[i].get("status") != "ok" for i in kept)
    shown = Progress(unit="targets") if progress is True else None
    report = ((lambda d, total, f: shown("batch", d, total, failed=f)) if shown is not None else (progress or None))
    start = time.perf_counter()
    failed, count = 0, len(kept)
    head = "".join(_dump(lines[i]) for i in kept)
    writer = None
    try:
        with executor:   # connects to a scheduler (and checks its workers) before the output is touched
            size = _task_size(len(todo), executor.jobs)
            tasks = [todo[i:i + size] for i in range(0, len(todo), size)]
            results = executor.map(_plan_task, tasks, on_error=_lost_task)   # yields in input order
            if report:
                report(count, len(rows), failed)
            for d in (d for lines_ in results for d in lines_):
                if writer is None:   # the output is replaced when its first new line is ready, not before
                    write_atomic(out, (head + _dump(d)).encode(), "output file")
                    writer = LineWriter(out, "output file", sync_every=1 << 30, sync_seconds=FSYNC_INTERVAL)
                else:
                    try:
                        writer.write(_dump(d))
                    except OutputError as exc:
                        raise OutputError(f"{exc}; its {count} finished lines are kept: make room and rerun "
                                          "with resume=True") from None
                lines[d["index"]] = d
                count += 1
                failed += d["status"] != "ok"
                interrupts.check()   # a Ctrl-C swallowed while the row was planned stops the run here
                if report:
                    report(count, len(rows), failed)
            if writer is None:
                write_atomic(out, head.encode(), "output file")
            else:
                writer.close()
    finally:
        if writer is not None:
            with contextlib.suppress(OSError, InputError):
                writer.close()
        if shown is not None:
            shown.close()
    if kept and todo and kept[-1] > todo[0][0]:   # kept lines came first, out of input order: sort
        write_atomic(out, "".join(_dump(lines[i]) for i in sorted(lines)).encode(), "output file")
    return BatchResult(len(rows), len(kept), len(todo), failed, time.perf_counter() - start, kept_failed + failed)
