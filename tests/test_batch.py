"""Batch planning (rollplan.studies.batch): input order kept, failures recorded, interruption and resume,
the plans checked by (36) and the printed (28)-(30) integrated by DOP853 (``references``)."""

import contextlib
import json
import os
import random
import re
import signal
import subprocess
import sys
import time

import pytest
from conftest import run_program

from rollplan import cli
from rollplan.errors import InputError
from rollplan.studies.batch import read_output, run_batch

import references

ROWS = [
    # u_a, v_a, psi, steps, k, note
    ("0", "1", "0", "1", "0", "paper"),        # k = 0, psi = 0: a = b solves (36)
    ("0.3", "-0.4", "0.2", "2", "0", "ok"),
    ("0.2", "0.1", "0.1", "0", "0", "bad steps"),
    ("abc", "0.1", "0.1", "1", "0", "bad number"),
    ("0", "40", "0", "1", "0", "too far"),      # far beyond any one-step shift at k = 0
    ("0.5", "0.2", "-0.3", "1", "0", "ok"),
]


def write_csv(path, rows=ROWS):
    path.write_text("u_a,v_a,psi,steps,k,note\n" + "".join(",".join(r) + "\n" for r in rows))
    return path


def check_lines(lines, rows=ROWS):
    assert [d["index"] for d in lines] == list(range(len(rows)))
    for d, row in zip(lines, rows):
        assert d["input"]["note"] == row[5]
    status = [d["status"] for d in lines]
    assert status == ["ok", "ok", "failed", "failed", "failed", "ok"]
    assert lines[2]["error"] == "InputError" and "steps = 0" in lines[2]["reason"]
    assert lines[3]["error"] == "InputError" and "'abc'" in lines[3]["reason"]
    assert lines[4]["error"] == "NoPlanError" and lines[4]["reason"]
    for d in lines:
        if d["status"] == "ok":
            assert "trajectory" not in d
            u, v, psi = (float(d["input"][c]) for c in ("u_a", "v_a", "psi"))
            f = d["final"]
            assert abs(f["u_a"] - u) < 1e-9 and abs(f["v_a"] - v) < 1e-9 and abs(f["psi"] - psi) < 1e-9


@pytest.mark.slow
def test_order_kept_and_failures_recorded_in_parallel(tmp_path):
    out = tmp_path / "plans.jsonl"
    r = run_batch(write_csv(tmp_path / "t.csv"), out, jobs=2)
    assert (r.total, r.skipped, r.planned, r.failed) == (6, 0, 6, 3)
    lines = [json.loads(x) for x in out.read_text().splitlines()]
    check_lines(lines)
    # independent checks of a plan: (36) for k = 0 and psi = 0, and scipy on the printed (28)-(30)
    a = lines[0]["figure_eight"]["a"]
    assert lines[0]["figure_eight"]["b"] == pytest.approx(a, abs=1e-9)
    assert references.shift_36(a) == pytest.approx(1.0, abs=1e-9)
    fe = lines[1]["figure_eight"]
    x = references.trace(fe["a"], fe["b"], 0.0, fe["gamma"], steps=2)
    assert x == pytest.approx([0.3, -0.4, 0.2], abs=1e-9)


@pytest.mark.slow
def test_interrupted_run_keeps_lines_and_resumes(tmp_path):
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "plans.jsonl"

    def stop_after_three(done, total, failed):
        if done == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(csv_path, out, jobs=1, progress=stop_after_three)
    kept = out.read_bytes()
    assert [d["index"] for d in read_output(out)] == [0, 1, 2]
    with open(out, "ab") as fh:   # a line torn by the interruption
        fh.write(b'{"index": 3, "inp')
    with pytest.raises(InputError, match="exists"):
        run_batch(csv_path, out)
    r = run_batch(csv_path, out, jobs=1, resume=True)
    assert (r.skipped, r.planned) == (3, 3)
    assert out.read_bytes().startswith(kept)   # finished lines untouched
    check_lines([json.loads(x) for x in out.read_text().splitlines()])
    r = run_batch(csv_path, out, resume=True)   # nothing left to do
    assert (r.skipped, r.planned) == (6, 0)


def test_resume_with_a_gap_restores_input_order(tmp_path):
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "plans.jsonl"
    run_batch(csv_path, out)
    lines = out.read_text().splitlines()
    out.write_text("\n".join(lines[:1] + lines[3:]) + "\n")   # rows 1 and 2 lost
    r = run_batch(csv_path, out, resume=True)
    assert (r.skipped, r.planned) == (4, 2)
    check_lines([json.loads(x) for x in out.read_text().splitlines()])


@pytest.mark.slow
def test_cli_batch(tmp_path, capsys):
    csv_path, out = write_csv(tmp_path / "t.csv", ROWS[:3]), tmp_path / "p.jsonl"
    assert cli.main(["batch", str(csv_path), "--out", str(out)]) == 1   # row 2 fails
    err = capsys.readouterr().err
    assert "3/3" in err   # progress
    assert len(out.read_text().splitlines()) == 3
    assert cli.main(["batch", str(csv_path), "--out", str(out)]) == 2   # exists, no --resume
    assert cli.main(["batch", str(csv_path), "--out", str(out), "--overwrite", "--quiet"]) == 1
    bad = tmp_path / "bad.csv"
    bad.write_text("u_a,psi,k\n0,1,0,0\n")
    assert cli.main(["batch", str(bad), "--out", str(tmp_path / "q.jsonl")]) == 2
    assert "v_a" in capsys.readouterr().err
    assert cli.main(["batch", str(tmp_path / "none.csv"), "--out", str(tmp_path / "q.jsonl")]) == 2
    assert cli.main(["batch", str(csv_path), "--out", str(tmp_path / "q.jsonl"), "--jobs", "0"]) == 2


# ----------------------------------------------------------------------------- resume by content, locks, inputs


def without_times(lines):
    """The lines with the solvers' wall-clock times removed (the only field that differs between runs)."""
    out = []
    for d in lines:
        d = json.loads(json.dumps(d))
        if "solver" in d:
            d["solver"].pop("time_s")
        out.append(d)
    return out


# ----------------------------------------------------------------------------- conventions of issue 18

def strip_times(lines):
    """Output lines without the solver's wall time (the only field that differs between two runs)."""
    out = []
    for d in lines:
        d = json.loads(json.dumps(d))
        d.get("solver", {}).pop("time_s", None)
        out.append(d)
    return out


def read_lines(path):
    return [json.loads(x) for x in path.read_text().splitlines()]


def test_resume_matches_rows_by_content_not_position(tmp_path):
    """Insert a row at the top, edit one, delete one: resume plans exactly the new and the edited rows, keeps
    the others (renumbered), and the output equals a fresh run of the new file."""
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "plans.jsonl"
    run_batch(csv_path, out)
    old = {d["input"]["note"]: d for d in read_lines(out)}
    new_rows = [("0.1", "0.2", "0.3", "1", "0", "inserted")] + [r for r in ROWS if r[5] != "bad steps"]
    new_rows[2] = ("0.3", "-0.4", "0.25", "2", "0", "ok")          # psi edited: planned again
    write_csv(csv_path, new_rows)
    r = run_batch(csv_path, out, resume=True)
    assert (r.total, r.skipped, r.planned) == (6, 4, 2)
    lines = read_lines(out)
    assert [d["index"] for d in lines] == list(range(6))
    assert lines[0]["input"]["note"] == "inserted" and lines[0]["status"] == "ok"
    assert lines[2]["final"]["psi"] == pytest.approx(0.25, abs=1e-9)           # the edited row's own plan
    assert lines[1]["figure_eight"] == old["paper"]["figure_eight"]            # kept, renumbered
    fresh = tmp_path / "fresh.jsonl"
    run_batch(csv_path, fresh)
    assert without_times(lines) == without_times(read_lines(fresh))
    # the kept lines are the very same bytes apart from their index
    assert lines[1]["solver"]["time_s"] == old["paper"]["solver"]["time_s"]


def test_same_row_twice_is_planned_once_and_written_twice(tmp_path):
    csv_path, out = write_csv(tmp_path / "t.csv", [ROWS[0], ROWS[1], ROWS[0]]), tmp_path / "p.jsonl"
    run_batch(csv_path, out)
    r = run_batch(csv_path, out, resume=True)
    assert (r.skipped, r.planned) == (3, 0)
    lines = read_lines(out)
    assert lines[0]["key"] == lines[2]["key"] and lines[0]["figure_eight"] == lines[2]["figure_eight"]


def test_output_is_never_the_targets_file(tmp_path, capsys):
    csv_path = write_csv(tmp_path / "t.csv")
    before = csv_path.read_bytes()
    for flags in ([], ["--resume"], ["--overwrite"]):
        assert cli.main(["batch", str(csv_path), "--out", str(csv_path), *flags, "--quiet"]) == 2
        err = capsys.readouterr().err
        assert "is the input file" in err and len(err.strip().splitlines()) == 1
    assert csv_path.read_bytes() == before


def test_resume_and_overwrite_exclude_each_other(tmp_path, capsys):
    csv_path = write_csv(tmp_path / "t.csv")
    assert cli.main(["batch", str(csv_path), "--out", str(tmp_path / "o.jsonl"), "--resume", "--overwrite"]) == 2
    assert "exclude each other" in capsys.readouterr().err
    with pytest.raises(InputError, match="exclude each other"):
        run_batch(csv_path, tmp_path / "o.jsonl", resume=True, overwrite=True)


def test_resume_refuses_a_file_that_is_not_a_batch_output(tmp_path):
    csv_path, out = write_csv(tmp_path / "t.csv"), tmp_path / "notes.txt"
    out.write_text("my notes\nmore notes\n")
    with pytest.raises(InputError, match="not a rollplan batch output"):
        run_batch(csv_path, out, resume=True)
    assert out.read_text() == "my notes\nmore notes\n"


def test_targets_file_rules(tmp_path, capsys):
    """Directory, duplicated column, BOM, rows of the wrong length, an over-long field: one line or a failed
    row, never a traceback."""
    out = tmp_path / "o.jsonl"
    assert cli.main(["batch", str(tmp_path), "--out", str(out)]) == 2
    assert "is a directory" in capsys.readouterr().err
    dup = tmp_path / "dup.csv"
    dup.write_text("u_a,v_a,psi,steps,k,k\n0,1,0,1,0,5\n")
    assert cli.main(["batch", str(dup), "--out", str(out)]) == 2
    assert "column 'k' appears twice" in capsys.readouterr().err
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbfu_a,v_a,psi,steps,k\n0,1,0,1,0\n0,1,0\n0,1,0,1,0,9\n")
    r = run_batch(bom, out)
    lines = read_lines(out)
    assert (r.total, r.failed) == (3, 2) and lines[0]["status"] == "ok"
    assert "has 3 field(s), the header 5" in lines[1]["reason"] and "has 6 field(s)" in lines[2]["reason"]
    huge = tmp_path / "huge.csv"
    huge.write_text("u_a,v_a,psi,steps,k,note\n0,1,0,1,0," + "x" * 200000 + "\n")
    assert cli.main(["batch", str(huge), "--out", str(tmp_path / "h.jsonl")]) == 2
    err = capsys.readouterr().err
    assert "longer than 131072" in err and len(err.strip().splitlines()) == 1


def test_numbers_in_rows_follow_the_command_line_rules(tmp_path):
    rows = [("-1e-3", "1", "0", "1", "0", "exponent"), ("\uff10", "1", "0", "1", "0", "full width"),
            ("0", "1_0", "0", "1", "0", "underscore"), ("0", "1", "nan", "1", "0", "nan"),
            ("0", "1", "0", "1e0", "0", "steps exponent")]
    csv_path, out = write_csv(tmp_path / "t.csv", rows), tmp_path / "o.jsonl"
    run_batch(csv_path, out)
    status = [(d["status"], d.get("reason", "")) for d in read_lines(out)]
    assert status[0][0] == "ok"
    assert all(s == "failed" and "decimal number" in reason for s, reason in status[1:4])
    assert status[4][0] == "failed" and "whole number" in status[4][1]


SLOW_ROWS = [  # a new k per row (the leaf tables are built per k): a second or more each; failures of every kind
    ("0", "1", "0", "1", "2.5", "a"), ("0.4", "0.3", "0.5", "2", "1.3", "b"), ("x", "1", "0", "1", "2", "bad"),
    ("0.2", "-0.5", "-1", "2", "4.1", "c"), ("0", "40", "0", "1", "0", "far"), ("-0.6", "0.1", "2", "3", "3.7", "d"),
    ("0.5", "0.5", "1", "5", "8.2", "e"), ("0.1", "0.9", "-0.3", "2", "3.1", "f"), ("1", "0", "0.7", "3", "5.3", "g"),
    ("0.3", "0.8", "2.5", "4", "9.6", "h"), ("1.5", "1", "-2", "6", "6.4", "i"),
    ("-0.2", "0.7", "1.2", "3", "7.1", "j"),
]
#: Exit status of a finished batch of SLOW_ROWS: 1, some rows failed ("bad", "far"), the others planned.
SLOW_EXIT = 1


def _batch_process(csv_path, out, jobs):
    return subprocess.Popen([sys.executable, "-m", "rollplan.cli", "batch", str(csv_path), "--out", str(out),
                             "--resume", "--quiet", "--jobs", str(jobs)], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


#: (signal, --jobs) of the interrupted attempts, in turn: each signal in a run in this process and in a run with
#: forked workers. A SIGKILL falls at a random moment of the i-th of as many equal parts of a whole run (attempt
#: i: start-up, planner construction, planning and writing are all hit); a SIGINT at a random moment of the
#: 0.3 s after a row of this attempt is written (the next rows are in flight: none may be recorded as failed).
INTERRUPTIONS = [(signal.SIGINT, 1), (signal.SIGKILL, 2), (signal.SIGINT, 2), (signal.SIGKILL, 1)]


@pytest.mark.slow
def test_interrupted_at_random_moments_and_resumed_equals_an_uninterrupted_run(tmp_path):
    """Run the batch, stop it by SIGINT (Ctrl-C) or SIGKILL at random moments from its start (imports,
    planner construction, planning, writing), resume, again and again: the final output equals an
    uninterrupted run line for line (up to the solvers' wall-clock times). A SIGINT exits 130 with one line
    and no traceback (within a second in the solvers; CasADi's construction of a solver, a few seconds on a
    loaded machine, is not interruptible) and never records the row in flight as failed. (One sequence of
    attempts alternates the two signals, so both share the reference run and the final resume.)"""
    rows = SLOW_ROWS
    csv_path = write_csv(tmp_path / "t.csv", rows)
    reference = tmp_path / "reference.jsonl"
    t0 = time.perf_counter()
    proc = _batch_process(csv_path, reference, jobs=1)
    assert proc.wait(timeout=600) == SLOW_EXIT
    whole = time.perf_counter() - t0          # the moments are drawn over a whole run, start-up included
    failing = {d["input"]["note"] for d in read_output(reference) if d["status"] != "ok"}   # "bad" and "far"
    out = tmp_path / "out.jsonl"
    rng = random.Random(18)
    history = []
    for i, (sig, jobs) in enumerate(INTERRUPTIONS):
        done = len(read_output(out)) if out.exists() else 0
        t_start = time.perf_counter()
        proc = _batch_process(csv_path, out, jobs=jobs)
        if sig == signal.SIGKILL:
            time.sleep(0.3 + (whole - 0.3) * (i + rng.random()) / len(INTERRUPTIONS))
        else:   # a row of this attempt written: the next ones are being planned
            while proc.poll() is None and (len(read_output(out)) if out.exists() else 0) <= done:
                time.sleep(0.01)
            time.sleep(0.3 * rng.random())
        delay = time.perf_counter() - t_start
        if sig == signal.SIGKILL:
            os.killpg(proc.pid, signal.SIGKILL)
        else:
            proc.send_signal(signal.SIGINT)
        t_sig = time.perf_counter()
        _, err = proc.communicate(timeout=120)
        history.append((sig.name, jobs, delay, proc.returncode, len(read_output(out))))
        if sig == signal.SIGINT:
            assert proc.returncode in (SLOW_EXIT, 130), (history, err)
            assert time.perf_counter() - t_sig < 10.0, history
            assert "Traceback" not in err and \
                (proc.returncode == SLOW_EXIT or "interrupted" in err.strip().splitlines()[-1])
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)   # pool workers of a killed run
        assert {d["input"]["note"] for d in read_output(out) if d["status"] != "ok"} <= failing, history
    proc = _batch_process(csv_path, out, jobs=2)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == SLOW_EXIT, err
    print("interrupted runs (signal, jobs, delay [s], exit code, finished lines):", history)
    assert out.read_text().count("\n") == len(rows)
    assert without_times(read_lines(out)) == without_times(read_lines(reference)), history
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.jsonl", "reference.jsonl", "t.csv"]


@pytest.mark.slow
def test_second_batch_on_the_same_output_is_refused(tmp_path, capsys):
    csv_path, out = write_csv(tmp_path / "t.csv", SLOW_ROWS), tmp_path / "out.jsonl"
    first = _batch_process(csv_path, out, jobs=1)
    try:
        t0 = time.perf_counter()
        while not out.exists() and time.perf_counter() - t0 < 120:
            time.sleep(0.05)
        assert cli.main(["batch", str(csv_path), "--out", str(out), "--resume", "--quiet"]) == 2
        err = capsys.readouterr().err
        assert f"being written by another process (pid {first.pid})" in err and len(err.strip().splitlines()) == 1
        assert cli.main(["batch", str(csv_path), "--out", str(out), "--overwrite", "--quiet"]) == 2
    finally:
        _, err = first.communicate(timeout=600)
    assert first.returncode == SLOW_EXIT, err
    assert [d["index"] for d in read_lines(out)] == list(range(len(SLOW_ROWS)))

def _stat(pid):
    """(state, parent pid, process group) of the process ``pid``, or None if it is gone (Linux /proc)."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            stat = fh.read()
    except OSError:
        return None
    state, ppid, pgrp = stat[stat.rfind(")") + 2:].split()[:3]
    return state, int(ppid), int(pgrp)


def _live(field, value):
    """Pids of the live processes (not zombies) whose parent pid (``field`` 1) or process group (2) is ``value``."""
    stats = ((int(name), _stat(name)) for name in os.listdir("/proc") if name.isdigit())
    return [pid for pid, stat in stats if stat is not None and stat[field] == value and stat[0] != "Z"]


def _live_children(pid):
    return _live(1, pid)


def _live_group(pgid):
    return _live(2, pgid)


def _alive(pid):
    stat = _stat(pid)
    return stat is not None and stat[0] != "Z"


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir("/proc/self"), reason="needs /proc (Linux)")
@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM])
def test_workers_die_with_the_parent(tmp_path, sig):
    """SIGKILL or SIGTERM of `batch --jobs 2` (the parent only) left its forked workers alive, later printing
    BrokenPipeError tracebacks. Now no worker outlives the parent by more than a few seconds and none prints;
    SIGTERM stops the run as Ctrl-C does: exit 143, one line, the finished lines kept (whole lines only)."""
    # rows of many steps at high k, polished and certified in Python (--method ipopt): a second or more each; the
    # first row, planned in the parent before it forks the workers, a quick one (the workers start sooner)
    rows = [("0", "1", "0", "1", "2.5", "r0")] + \
        [(f"{0.05 * i:.2f}", "0.8", "2.5", "20", f"{40 + 4 * i}", f"r{i}") for i in range(1, 16)]
    csv_path, out = write_csv(tmp_path / "t.csv", rows), tmp_path / "out.jsonl"
    err_path = tmp_path / "err.txt"
    # the run's cache: this test run's, so the compiled functions of --method ipopt are built once a run, not once
    # a case (the rows stay slow: they keep no tables on disk)
    with open(err_path, "w") as err_file:
        proc = subprocess.Popen([sys.executable, "-m", "rollplan.cli", "batch", str(csv_path), "--out", str(out),
                                 "--quiet", "--jobs", "2", "--method", "ipopt"], stdout=subprocess.DEVNULL,
                                stderr=err_file, start_new_session=True)
    try:
        t0 = time.perf_counter()
        while len(_live_children(proc.pid)) < 2 and time.perf_counter() - t0 < 300:
            time.sleep(0.05)
        time.sleep(random.Random(sig).uniform(0.2, 1.0))   # the workers busy with their rows
        workers = _live_children(proc.pid)
        assert len(workers) == 2, err_path.read_text()
        os.kill(proc.pid, sig)
        code = proc.wait(timeout=60)
        t0 = time.perf_counter()
        while any(map(_alive, workers)) and time.perf_counter() - t0 < 5.0:
            time.sleep(0.05)
        assert not any(map(_alive, workers)), f"workers {workers} outlived their parent (exit {code})"
        # nor any other process of the run (a worker started after the count above): once none is left,
        # nothing can print any more
        while _live_group(proc.pid) and time.perf_counter() - t0 < 5.0:
            time.sleep(0.05)
        assert _live_group(proc.pid) == [], f"processes of the run outlived their parent (exit {code})"
    finally:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    err = err_path.read_text()
    assert "Traceback" not in err and "Error" not in err, err
    if sig == signal.SIGKILL:
        assert code == -signal.SIGKILL and err == ""
    else:
        assert code == 143, err
        assert err.strip().splitlines() == [f"rollplan: terminated; finished lines are kept in {out}: rerun with "
                                            "--resume"]
    if out.exists():
        assert out.read_bytes().count(b"\n") == len(read_output(out))   # no torn or foreign line


def test_comments_blank_lines_and_defaults(tmp_path, scipy_trace):
    """# lines and blank lines are not rows; missing psi/steps/k columns and empty cells take 0, 1 and 2.5.
    The defaulted plan equals the explicit one and is checked by DOP853 on the printed (28)-(30)."""
    short = tmp_path / "short.csv"
    short.write_text("# targets\n\nu_a,v_a\n# a comment between rows\n0.5,0.3\n\n   \n0.2,-0.4\n")
    empty = tmp_path / "empty.csv"
    empty.write_text("u_a,v_a,psi,steps,k\n0.5,0.3,,,\n0.2,-0.4,0,1,2.5\n")
    r1 = run_batch(short, tmp_path / "a.jsonl")
    r2 = run_batch(empty, tmp_path / "b.jsonl")
    assert (r1.total, r1.failed, r2.total, r2.failed) == (2, 0, 2, 0)
    a, b = read_output(tmp_path / "a.jsonl"), read_output(tmp_path / "b.jsonl")
    assert [d["index"] for d in a] == [0, 1]
    for d in a + b:
        assert (d["k"], d["steps"], d["target"]["psi"]) == (2.5, 1, 0.0)
    assert [d["figure_eight"] for d in a] == [d["figure_eight"] for d in b]
    fe = a[0]["figure_eight"]
    assert scipy_trace(fe["a"], fe["b"], 2.5, fe["gamma"]) == pytest.approx([0.5, 0.3, 0.0], abs=1e-9)


def test_a_quoted_hash_is_a_field_not_a_comment(tmp_path):
    """A row whose first field is quoted "#1" was dropped as a comment (a row lost with exit 0): only lines that
    start with # are comments; a quoted field's later line that starts with # belongs to its field."""
    from rollplan.inputs import read_csv

    path = tmp_path / "q.csv"
    path.write_text('u_a,v_a\n  # a comment\n"#1",0.1\n0.2,"x\n# still the field"\n#,0.3\n0.4,0.5\n')
    table = read_csv(path, required=("u_a", "v_a"), comments=True)
    assert [row["u_a"] for row in table.rows] == ["#1", "0.2", "0.4"]
    assert table.rows[1]["v_a"] == "x\n# still the field"
    assert table.lines == [3, 5, 7]


def test_lines_carry_version_and_units(tmp_path):
    import rollplan

    run_batch(write_csv(tmp_path / "t.csv", ROWS[:3]), tmp_path / "p.jsonl")
    for d in read_output(tmp_path / "p.jsonl"):
        assert d["version"] == rollplan.__version__
        assert d["units"]["length"] == "R" and d["units"]["angle"] == "rad"


def test_missing_required_column_names_the_required_ones(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("u_a,psi\n0,1\n")
    with pytest.raises(InputError, match="v_a"):
        run_batch(bad, tmp_path / "q.jsonl")


def test_fsync_is_batched(tmp_path, monkeypatch):
    """Every line reaches the file at once, but fsync (milliseconds each) runs at most every FSYNC_INTERVAL and at
    the end (plus the atomic creation of the output: file and folder)."""
    import os

    from rollplan import outputs
    from rollplan.studies import batch

    calls = []
    real = os.fsync
    monkeypatch.setattr(outputs.os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    sizes = []

    def watch(done, total, failed):   # the output is made with its first line (0 bytes before)
        out = tmp_path / "p.jsonl"
        sizes.append(out.stat().st_size if out.exists() else 0)

    r = run_batch(write_csv(tmp_path / "t.csv"), tmp_path / "p.jsonl", progress=watch)
    assert len(calls) <= 3 + r.time_s / batch.FSYNC_INTERVAL
    assert all(b > a for a, b in zip(sizes[1:], sizes[2:]))   # each line on disk (flushed) as it is done


def test_progress_is_plain_lines_in_a_log(tmp_path, capsys):
    run_batch(write_csv(tmp_path / "t.csv", ROWS[:3]), tmp_path / "p.jsonl", progress=True)
    err = capsys.readouterr().err
    assert "\r" not in err
    assert re.search(r"^batch: 3/3 targets \(100%\), 1 failed, .* elapsed$", err, re.MULTILINE)


def test_rows_do_not_show_the_planners_own_progress(tmp_path):
    """A batch shows its own progress (or none with --quiet): the search progress of each row's planner would
    be one stale label over the whole run."""
    from rollplan.progress import reporting

    labels = []
    with reporting(lambda label, *a, **kw: labels.append(label)):
        run_batch(write_csv(tmp_path / "t.csv", ROWS[:2]), tmp_path / "p.jsonl", jobs=1)
    assert labels == []


_FORKED = """
import os
from rollplan.planners.geometric import default_planner
from rollplan.studies.executor import Executor, start_method

def warm():
    default_planner("ipopt")

def planner_misses(_):
    default_planner("ipopt")
    return os.getpid(), default_planner.cache_info().misses

if __name__ == "__main__":
    assert start_method() == "fork", start_method()
    with Executor(2, warm=warm) as ex:
        seen = list(ex.map(planner_misses, range(6)))
    parent = default_planner.cache_info().misses
    assert {m for _, m in seen} == {parent}, (seen, parent)   # no worker missed the cache, i.e. built a planner
    assert any(pid != os.getpid() for pid, _ in seen), seen
    print("ok")
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="fork start method: Linux only")
def test_forked_workers_start_with_the_planner_built(tmp_path):
    """With --jobs 2 the workers are forked after the parent built the planner: they construct nothing. Run in a
    fresh interpreter: the test process may run other threads (a Dask test leaves one), and then the executor
    rightly spawns instead of forking."""
    done = run_program(tmp_path, "forked.py", _FORKED)
    assert done.returncode == 0 and done.stdout.strip() == "ok", done.stderr[-2000:]


@pytest.mark.parametrize("rows, code", [(ROWS[:2], 0), (ROWS[:3], 1), (ROWS[2:5], 3)])
def test_cli_exit_codes(tmp_path, capsys, rows, code):
    """0 when every row is planned, 1 when some failed, 3 when all failed (documented in --help)."""
    out = tmp_path / "p.jsonl"
    assert cli.main(["batch", str(write_csv(tmp_path / "t.csv", rows)), "--out", str(out), "--jobs", "1",
                     "--quiet"]) == code
    err = capsys.readouterr().err
    assert len(out.read_text().splitlines()) == len(rows)
    if code:
        assert "failed" in err and "Traceback" not in err


def test_a_ctrl_c_inside_a_rows_planning_is_not_recorded(tmp_path, monkeypatch):
    """A KeyboardInterrupt raised while a row is planned (in this process) stops the run: the rows before it are
    kept, the row in flight is not written (as failed or otherwise), so that a resumed run plans it."""
    from rollplan.studies import batch

    csv_path, out = write_csv(tmp_path / "t.csv", ROWS), tmp_path / "p.jsonl"
    real, calls = batch.solve, []

    def solve(*args, **kwargs):
        calls.append(args)
        if len(calls) == 3:
            raise KeyboardInterrupt
        return real(*args, **kwargs)

    monkeypatch.setattr(batch, "solve", solve)
    with pytest.raises(KeyboardInterrupt):
        run_batch(csv_path, out, jobs=1, root_solver="newton")   # row by row through plan_row
    assert [d["index"] for d in read_output(out)] == [0, 1, 2, 3] and len(calls) == 3   # rows 2, 3: bad input


def test_cli_exit_code_counts_rows_kept_by_resume(tmp_path, capsys):
    csv_path, out = write_csv(tmp_path / "t.csv", ROWS[2:5]), tmp_path / "p.jsonl"

    def stop_after_two(done, total, failed):
        if done == 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_batch(csv_path, out, progress=stop_after_two)
    assert cli.main(["batch", str(csv_path), "--out", str(out), "--resume", "--quiet"]) == 3   # as uninterrupted


def test_cli_exists_message_names_the_flags(tmp_path, capsys):
    csv_path, out = write_csv(tmp_path / "t.csv", ROWS[:1]), tmp_path / "p.jsonl"
    out.write_text("")
    assert cli.main(["batch", str(csv_path), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "--resume" in err and "--overwrite" in err and "resume=True" not in err


def test_cli_help_documents_exit_codes_and_columns(capsys):
    with pytest.raises(SystemExit):
        cli.main(["batch", "--help"])
    text = capsys.readouterr().out
    assert "1 some rows failed" in text and "3 every row failed" in text and "#" in text and "default 2.5" in text


@pytest.mark.slow
def test_the_shipped_example_runs(tmp_path, capsys):
    """examples/targets.csv (shown in docs/batches.md): four plans and two recorded failures, exit 1."""
    from pathlib import Path

    example = Path(__file__).resolve().parent.parent / "examples" / "targets.csv"
    out = tmp_path / "plans.jsonl"
    assert cli.main(["batch", str(example), "--out", str(out), "--quiet"]) == 1
    lines = read_output(out)
    assert [d["status"] for d in lines] == ["ok"] * 4 + ["failed"] * 2
    assert lines[0]["figure_eight"]["a"] == pytest.approx(0.300429, abs=5e-7)   # the paper's a1
    for d in lines[:4]:
        u, v, psi = d["target"]["u_a"], d["target"]["v_a"], d["target"]["psi"]
        assert [d["final"]["u_a"], d["final"]["v_a"], d["final"]["psi"]] == pytest.approx([u, v, psi], abs=1e-9)


@pytest.mark.slow
def test_rows_are_planned_many_per_call_as_one_by_one(tmp_path, monkeypatch):
    """The planning phase gives the rows of one k and one number of steps to plan_many together (not one call each),
    and writes the lines plan_row writes for each row alone (solver times aside), failures and a target that needs
    two legs included."""
    from rollplan.studies import batch
    from rollplan.studies.batch import plan_row, read_targets

    rows = ROWS + [("0.1", "0.2", "0.3", "2", "0", "ok"), ("0", "0.0001", "3", "1", "2.5", "two legs")]
    csv = write_csv(tmp_path / "t.csv", rows)
    calls = []
    real = batch.plan_many

    def counting(targets, *args, **kwargs):
        calls.append(len(targets))
        return real(targets, *args, **kwargs)

    monkeypatch.setattr(batch, "plan_many", counting)
    monkeypatch.setattr(batch, "_task_size", lambda rows, jobs: batch.ROWS_PER_TASK)   # one task
    out = tmp_path / "plans.jsonl"
    run_batch(csv, out)
    lines = read_lines(out)
    # (k 0, n 1): rows 0, 4, 5; (k 0, n 2): rows 1, 6; (k 2.5, n 1): row 7; (k 0, n 0): row 2, refused
    assert sorted(calls) == [1, 1, 2, 3]
    alone = [plan_row(i, row) for i, row in enumerate(read_targets(csv))]
    for d in lines + alone:   # the two-leg search's wall time
        d.get("solver", {}).get("two_legs", {}).pop("search_s", None)
    assert strip_times(lines) == strip_times(alone)
    check_lines(lines[:6])
    assert lines[7]["status"] == "ok"


def test_a_short_batch_is_shared_row_by_row():
    """Tasks hold at most an eighth of each worker's share, so a short batch still runs on every worker and its lines
    are written as they are planned."""
    from rollplan.studies.batch import ROWS_PER_TASK, _task_size

    assert _task_size(12, 2) == 1 and _task_size(200, 2) == 12 and _task_size(100000, 2) == ROWS_PER_TASK
    assert _task_size(0, 1) == 1


def test_curve_column_chooses_the_family_per_row_and_is_echoed(tmp_path, capsys):
    """A column ``curve`` picks the leaf family of each row (empty: circles); the output says which family planned
    it (for ``best``, the family chosen); the Viviani plan, integrated by DOP853 along the typed lobes (printed
    (28)-(30)), lands on its target; a bad family fails its row with a line naming the value and the choices.

    Each leaf family builds its C tables for each k it meets, so the rows share one k, and the ``best`` row has a k
    below 1/2, where only the circles plan (the other families refuse that k): the family ``best`` chose is then
    known without building the tables of all four families."""
    path = tmp_path / "t.csv"
    path.write_text("u_a,v_a,psi,k,curve\n0,1,0,1,viviani\n0,1,0,1,\n0,1,0,1,hexagon\n0.2,0.5,0.3,0.2,best\n")
    out = tmp_path / "o.jsonl"
    assert cli.main(["batch", str(path), "--out", str(out)]) == 1
    lines = read_output(out)
    assert [d["status"] for d in lines] == ["ok", "ok", "failed", "ok"]
    assert [d.get("curve") for d in lines] == ["viviani", "circles", None, "circles"]
    assert lines[3]["solver"]["method"] == "c" and "curve" not in lines[3]["solver"]
    # the Viviani leaves are the shorter ones here, as at k = 2.5 in results/curve_families.md
    assert lines[0]["path_length"] < lines[1]["path_length"]
    assert "curve = 'hexagon' is not allowed: choose one of circles" in lines[2]["reason"]
    fe = lines[0]["figure_eight"]
    assert lines[0]["k"] == 1.0 and lines[3]["k"] == 0.2
    end = references.family_trace("viviani", fe["a"], fe["b"], 1.0, fe["gamma"])
    assert end == pytest.approx([0.0, 1.0, 0.0], abs=1e-9)
