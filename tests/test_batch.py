"""Batch planning (rollplan.studies.batch): input order kept, failures recorded, interruption and resume,
the plans checked by (36) and the printed (28)-(30) integrated by DOP853 (``references``)."""

import json

import pytest

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
    assert cli.main(["batch", str(csv_path), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "3/3" in err   # progress bar
    assert len(out.read_text().splitlines()) == 3
    assert cli.main(["batch", str(csv_path), "--out", str(out)]) == 2   # exists, no --resume
    assert cli.main(["batch", str(csv_path), "--out", str(out), "--overwrite", "--quiet"]) == 0
    bad = tmp_path / "bad.csv"
    bad.write_text("u_a,v_a,psi,k\n0,1,0,0\n")
    assert cli.main(["batch", str(bad), "--out", str(tmp_path / "q.jsonl")]) == 2
    assert "steps" in capsys.readouterr().err
    assert cli.main(["batch", str(tmp_path / "none.csv"), "--out", str(tmp_path / "q.jsonl")]) == 2
    assert cli.main(["batch", str(csv_path), "--out", str(tmp_path / "q.jsonl"), "--jobs", "0"]) == 2
