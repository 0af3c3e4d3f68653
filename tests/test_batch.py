"""Batch planning (rollplan.studies.batch): input order kept, failures recorded, interruption and resume,
the plans checked by (36) and the printed (28)-(30) integrated by DOP853 (``references``)."""

import json
import re

import pytest

from rollplan import cli
from rollplan.errors import InputError
from rollplan.planners.geometric import default_planner
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


# ----------------------------------------------------------------------------- conventions of issue 18

def _strip_times(lines):
    """Output lines without the solver's wall time (the only field that differs between two runs)."""
    out = []
    for d in lines:
        d = json.loads(json.dumps(d))
        d.get("solver", {}).pop("time_s", None)
        out.append(d)
    return out


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
    """Every line is flushed at once, but fsync (milliseconds each) runs at most every FSYNC_INTERVAL and at the end."""
    import os

    from rollplan.studies import batch

    calls = []
    real = os.fsync
    monkeypatch.setattr(batch.os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    sizes = []

    def watch(done, total, failed):
        sizes.append((tmp_path / "p.jsonl").stat().st_size)

    r = run_batch(write_csv(tmp_path / "t.csv"), tmp_path / "p.jsonl", progress=watch)
    assert len(calls) <= 1 + r.time_s / batch.FSYNC_INTERVAL
    assert all(b > a for a, b in zip(sizes[1:], sizes[2:]))   # each line on disk (flushed) as it is done


def test_progress_is_plain_lines_in_a_log(tmp_path, capsys):
    run_batch(write_csv(tmp_path / "t.csv", ROWS[:3]), tmp_path / "p.jsonl", progress=True)
    err = capsys.readouterr().err
    assert "\r" not in err
    assert re.search(r"^batch: 3/3 targets \(100%\), 1 failed, .* elapsed$", err, re.MULTILINE)


def test_forked_workers_start_with_the_planner_built():
    """With --jobs 2 the workers are forked after the parent built the planner: they construct nothing."""
    from rollplan.studies.executor import Executor, start_method

    if start_method() != "fork":
        pytest.skip("no fork here (or this process runs other threads): the workers are spawned")
    ex = Executor(2, warm=_warm)
    with ex:
        seen = list(ex.map(_planner_misses, range(6)))
    parent = default_planner.cache_info().misses
    assert {m for _, m in seen} == {parent}   # no worker missed the cache, i.e. built a planner
    assert len({pid for pid, _ in seen}) >= 1


def _warm():
    default_planner("ipopt")


def _planner_misses(_):
    import os

    default_planner("ipopt")
    return os.getpid(), default_planner.cache_info().misses


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
    """examples/targets.csv (shown in the README): four plans and two recorded failures, exit 1."""
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
