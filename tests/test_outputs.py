"""The output layer (rollplan.outputs): atomic writes that keep a replaced file's mode, refuse read-only files
and folders, names too long and inputs, lock an output against a second writer, survive a full disk with one
line, clean up after a killed writer, and sync line output in batches."""

import errno
import json
import math
import os
import stat
import subprocess
import sys
import textwrap

import pytest
from conftest import fill, one_line, run
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan.errors import InputError, OutputError
from rollplan.outputs import (
    LineWriter,
    check_folder,
    check_writable,
    claim,
    json_chunks,
    make_folder,
    write_atomic,
    write_json,
)

STEP = ["step", "--a", "0.3", "--k", "2.5", "--json"]


def test_replaced_file_keeps_its_mode(tmp_path, capsys):
    out = tmp_path / "s.json"
    out.write_text("old")
    out.chmod(0o600)
    assert run(capsys, *STEP, str(out))[0] == 0
    assert stat.S_IMODE(out.stat().st_mode) == 0o600 and json.loads(out.read_text())["a"] == 0.3
    out.chmod(0o640)
    write_atomic(out, b"new")
    assert stat.S_IMODE(out.stat().st_mode) == 0o640 and out.read_bytes() == b"new"


def test_read_only_file_and_folder_are_refused(tmp_path, capsys):
    out = tmp_path / "ro.json"
    out.write_text("keep")
    out.chmod(0o444)
    code, _, err = run(capsys, *STEP, str(out))
    assert code == 2 and "read-only" in err and one_line(err)
    assert out.read_text() == "keep"
    folder = tmp_path / "ro"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        code, _, err = run(capsys, *STEP, str(folder / "x.json"))
        assert code == 2 and "no permission" in err and one_line(err)
        code, _, err = run(capsys, "codegen", "--out", str(folder / "c"))
        assert code == 2 and one_line(err)
        code, _, err = run(capsys, "codegen", "--out", str(folder))
        assert code == 2 and one_line(err)
    finally:
        folder.chmod(0o755)
    assert list(folder.iterdir()) == []


def test_long_names(tmp_path, capsys):
    """A legal 255-byte name is written (its temporary and lock names are shortened); a longer one is
    refused before any work, in one line."""
    name = "x" * 250 + ".json"
    code, _, err = run(capsys, *STEP, str(tmp_path / name))
    assert code == 0, err
    assert json.loads((tmp_path / name).read_text())["a"] == 0.3
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]
    code, _, err = run(capsys, *STEP, str(tmp_path / ("y" * 300 + ".json")))
    assert code == 2 and "name has 305 bytes" in err and one_line(err)


def test_file_and_folder_outputs_check_their_folder_alike(tmp_path):
    """An output file and an output folder (codegen's) are refused for the same reasons in their parent folder:
    missing, not a folder, not writable, a name too long for it; each in one line naming the output."""
    plain = tmp_path / "plain"
    plain.write_text("")
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    cases = [(tmp_path / "missing" / "x", "folder"), (plain / "x", "not a folder"), (ro / "x", "no permission"),
             (tmp_path / ("y" * 300), "name has 300 bytes")]
    try:
        for path, reason in cases:
            for check, verb in ((check_writable, "is not writable"), (check_folder, "cannot be created")):
                with pytest.raises(OutputError) as info:
                    check(str(path))
                message = str(info.value)
                assert reason in message and "\n" not in message, message
                assert verb in message or reason == "not a folder", message
    finally:
        ro.chmod(0o755)


def test_codegen_folder_name_too_long_is_one_line(tmp_path, capsys):
    code, _, err = run(capsys, "codegen", "--out", str(tmp_path / ("y" * 300)))
    assert code == 2 and "name has 300 bytes" in err and "standard output" not in err and one_line(err)


def test_empty_and_directory_outputs(tmp_path, capsys):
    code, _, err = run(capsys, *STEP, "")
    assert code == 2 and "name is empty" in err and one_line(err)
    code, _, err = run(capsys, *STEP, str(tmp_path))
    assert code == 2 and "is a directory" in err and one_line(err)


def test_inputs_are_never_overwritten(tmp_path, capsys):
    robot = tmp_path / "robot.toml"
    robot.write_text("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2e-4\n"
                     "rotor_inertia_transverse = 1.2e-4\n")
    before = robot.read_bytes()
    code, _, err = run(capsys, "plan", "--robot", str(robot), "--to", "0", "0.05", "--json", str(robot))
    assert code == 2 and "is the input file" in err and one_line(err)
    link = tmp_path / "link.toml"
    link.symlink_to(robot)
    code, _, err = run(capsys, "plan", "--robot", str(link), "--to", "0", "0.05", "--json", str(robot))
    assert code == 2 and "is the input file" in err
    assert robot.read_bytes() == before
    with pytest.raises(OutputError, match="input file"):
        check_writable(link, inputs=[robot])


def test_animate_out_must_be_a_gif(tmp_path, capsys):
    code, _, err = run(capsys, "animate", str(tmp_path / "plan.json"), "--out", str(tmp_path / "x.png"))
    assert code == 2 and ".gif" in err and one_line(err)
    assert not (tmp_path / "x.png").exists()


# ----------------------------------------------------------------------------- disk full


@pytest.mark.slow
def test_disk_full_is_one_line_and_leaves_nothing(full_disk, tmp_path, capsys):
    """plan --json, step --json, atlas, batch and codegen onto a full disk: exit 2, one line, no temporary
    left; an existing output is left as it was."""
    old = full_disk / "old.json"
    targets = tmp_path / "t.csv"
    targets.write_text("u_a,v_a,psi,steps,k\n0,1,0,1,2.5\n")
    commands = [["plan", "--to", "0", "1", "--k", "2.5", "--json", str(full_disk / "p.json")],
                [*STEP, str(old)],
                ["atlas", "--k", "2.5", "--resolution", "5", "--out", str(full_disk / "a.png")],
                ["batch", str(targets), "--out", str(full_disk / "b.jsonl"), "--jobs", "1", "--quiet"],
                ["codegen", "--out", str(full_disk / "c")]]
    (full_disk / "filler").unlink()
    old.write_text("old")
    fill(full_disk / "filler")
    for argv in commands:
        code, _, err = run(capsys, *argv)
        assert code == 2 and "disk is full" in err and one_line(err), (argv, err)
    assert old.read_text() == "old"
    leftovers = [p.name for p in full_disk.rglob("*") if p.name.endswith((".tmp", ".lock"))]
    assert leftovers == []


TWO_TARGETS = "u_a,v_a,psi,steps,k\n0,1,0,1,2.5\n0.5,0.3,0.4,1,2.5\n"


@pytest.mark.slow
def test_batch_on_a_full_disk_leaves_no_output(full_disk, tmp_path, capsys):
    """`batch` onto a full disk left an empty output file (its start wrote the empty file, which needs no
    space). Now nothing is created; an existing output given with --overwrite is replaced by the first line
    with the old file's (atomic, as every output), so when even that does not fit it is left as it was."""
    targets = tmp_path / "t.csv"
    targets.write_text(TWO_TARGETS)
    old = full_disk / "old.jsonl"
    (full_disk / "filler").unlink()
    old.write_text("old\n")
    fill(full_disk / "filler")
    code, _, err = run(capsys, "batch", str(targets), "--out", str(full_disk / "b.jsonl"), "--jobs", "1", "--quiet")
    assert code == 2 and "disk is full" in err and one_line(err), err
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler", "old.jsonl"]
    code, _, err = run(capsys, "batch", str(targets), "--out", str(old), "--jobs", "1", "--quiet", "--overwrite")
    assert code == 2 and "disk is full" in err and one_line(err), err
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler", "old.jsonl"]
    assert old.read_text() == "old\n"


@pytest.mark.slow
def test_codegen_on_a_full_disk_leaves_nothing(full_disk, capsys):
    """`codegen` onto a full disk left a half-written folder. Now a new folder appears whole or not at all, and
    a folder written before is left as it was (and no temporary folder remains)."""
    from rollplan import codegen

    (full_disk / "filler").unlink()
    codegen.generate(full_disk / "old")   # 0.4 MB of the 1 MiB disk
    before = {p.name: p.read_bytes() for p in (full_disk / "old").iterdir()}
    fill(full_disk / "filler")
    code, _, err = run(capsys, "codegen", "--out", str(full_disk / "c"))
    assert code == 2 and "disk is full" in err and one_line(err), err
    code, _, err = run(capsys, "codegen", "--out", str(full_disk / "old"), "--real", "float")
    assert code == 2 and "disk is full" in err and one_line(err), err
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler", "old"]
    assert {p.name: p.read_bytes() for p in (full_disk / "old").iterdir()} == before


@pytest.mark.slow
def test_batch_that_fills_the_disk_keeps_whole_lines(tmp_path):
    """A batch whose output reaches the limit after its first line (a file size limit: EFBIG, as a full disk):
    exit 2, one line that says the finished lines are kept, and the output holds whole lines only, which
    --resume continues."""
    targets = tmp_path / "t.csv"
    targets.write_text(TWO_TARGETS)
    out = tmp_path / "p.jsonl"
    code = ("import resource, sys\nresource.setrlimit(resource.RLIMIT_FSIZE, (int(sys.argv[1]),) * 2)\n"
            "from rollplan.cli import main\nsys.exit(main(sys.argv[2:]))\n")
    argv = ["batch", str(targets), "--out", str(out), "--jobs", "1", "--quiet"]
    whole = subprocess.run([sys.executable, "-c", code, str(1 << 30), *argv], capture_output=True, text=True,
                           timeout=600, check=False)
    assert whole.returncode == 0, whole.stderr
    first = out.read_text().splitlines(keepends=True)[0]   # the size of one line (times differ between runs)
    out.unlink()
    r = subprocess.run([sys.executable, "-c", code, str(len(first) + 100), *argv], capture_output=True, text=True,
                       timeout=600, check=False)
    assert r.returncode == 2 and one_line(r.stderr), r.stderr
    assert "file size limit" in r.stderr and "1 finished lines are kept" in r.stderr and "--resume" in r.stderr
    text = out.read_text()
    assert text.count("\n") == 1 and text.endswith("\n") and json.loads(text)["index"] == 0   # no torn line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.jsonl", "t.csv"]


@pytest.mark.slow
def test_file_size_limit_is_one_line(tmp_path):
    """The same in a process with a file size limit (EFBIG; works without root)."""
    out = tmp_path / "p.json"
    code = ("import resource, sys\nresource.setrlimit(resource.RLIMIT_FSIZE, (200, 200))\n"
            "from rollplan.cli import main\nsys.exit(main(sys.argv[1:]))\n")
    r = subprocess.run([sys.executable, "-c", code, *STEP, str(out)], capture_output=True, text=True, timeout=300,
                       check=False)
    assert r.returncode == 2 and "file size limit" in r.stderr and one_line(r.stderr), r.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_os_errors_become_output_errors(tmp_path, monkeypatch):
    def full(fd, data):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "write", full)
    with pytest.raises(OutputError, match="disk is full") as err:
        write_atomic(tmp_path / "x.json", b"data")
    assert isinstance(err.value, InputError) and "\n" not in str(err.value)
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------- locks


HOLD = textwrap.dedent("""
    import sys, time
    from rollplan.outputs import claim
    with claim(sys.argv[1]):
        print("held", flush=True)
        time.sleep(60)
""")


def test_a_second_writer_is_refused_while_the_first_holds_the_output(tmp_path, capsys):
    out = tmp_path / "s.json"
    holder = subprocess.Popen([sys.executable, "-c", HOLD, str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        code, _, err = run(capsys, *STEP, str(out))
        assert code == 2 and "being written by another process" in err and f"pid {holder.pid}" in err
        assert one_line(err) and not out.exists()
        with pytest.raises(OutputError, match="another process"):
            write_atomic(out, b"x")
    finally:
        holder.kill()
        holder.wait()
    # a killed holder leaves its lock file, but not its lock
    assert run(capsys, *STEP, str(out))[0] == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.json"]


def test_claims_are_reentrant_and_removed(tmp_path):
    out = tmp_path / "x.jsonl"
    with claim(out), claim(out):
        write_atomic(out, b"a\n")
        assert (tmp_path / ".x.jsonl.lock").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["x.jsonl"]


def test_temporaries_of_a_killed_writer_are_removed_by_the_next(tmp_path):
    out = tmp_path / "x.json"
    stale = tmp_path / ".x.json.k3j_9a0z.tmp"
    other = tmp_path / ".x.json.b.k3j_9a0z.tmp"       # another output's (x.json.b) temporary: kept
    stale.write_text("half")
    other.write_text("half")
    write_atomic(out, b"{}")
    assert sorted(p.name for p in tmp_path.iterdir()) == [other.name, "x.json"]


def test_line_writer_syncs_in_batches(tmp_path, monkeypatch):
    out = tmp_path / "x.jsonl"
    out.write_text("")
    calls = []
    real = os.fsync
    monkeypatch.setattr(os, "fsync", lambda fd: (calls.append(fd), real(fd)))
    with LineWriter(out, sync_every=10, sync_seconds=3600) as w:
        for i in range(25):
            w.write(f"{i}\n")
            assert out.read_text().count("\n") == i + 1   # each line reaches the file at once
    assert len(calls) == 3   # after 10, 20, and at close
    assert out.read_text() == "".join(f"{i}\n" for i in range(25))


def test_make_folder(tmp_path):
    assert make_folder(tmp_path / "a").is_dir()
    with pytest.raises(OutputError, match="does not exist"):
        make_folder(tmp_path / "b" / "c")
    assert make_folder(tmp_path / "b" / "c", parents=True).is_dir()
    (tmp_path / "f").write_text("x")
    with pytest.raises(OutputError, match="is a file"):
        make_folder(tmp_path / "f")


def test_json_chunks_are_the_text_of_json_dumps_in_pieces():
    """json_chunks: pieces of about the size asked for, which together are json.dumps(obj, indent=1) and a newline
    (the non-streamed text, byte for byte)."""
    obj = {"a": 1.5, "list": [{"x": i / 7, "s": "é\u2192", "n": None, "t": [True, False]} for i in range(500)],
           "empty": [], "nested": {"k": {}}}
    pieces = list(json_chunks(obj, size=1000))
    assert len(pieces) > 10 and all(len(p) < 1200 for p in pieces)
    assert b"".join(pieces) == (json.dumps(obj, indent=1) + "\n").encode()


NUMBER = st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.integers(-10**30, 10**30),
                   st.integers(10**308, 10**400))
JSON_VALUES = st.recursive(
    st.one_of(NUMBER, st.booleans(), st.none(), st.text(max_size=5)),
    lambda inner: st.one_of(st.lists(inner, max_size=4), st.lists(NUMBER, min_size=1, max_size=6),
                            st.lists(st.lists(NUMBER, min_size=1, max_size=3), min_size=1, max_size=3),
                            st.tuples(inner, NUMBER),
                            st.dictionaries(st.one_of(st.text(max_size=4), st.integers(),
                                                      st.floats(allow_nan=False, allow_infinity=False),
                                                      st.booleans(), st.none()), inner, max_size=3)),
    max_leaves=30)


@settings(max_examples=120, deadline=None)
@given(obj=JSON_VALUES, size=st.integers(1, 200))
def test_json_chunks_are_json_dumps_for_any_value(obj, size):
    """Byte for byte json.dumps(obj, indent=1) and a newline, for any JSON value: numbers (-0.0, huge ints,
    subnormals), lists of numbers and rows of them (the fast path), bools among numbers, tuples, keys of every
    type json converts."""
    assert b"".join(json_chunks(obj, size=size)) == (json.dumps(obj, indent=1) + "\n").encode()


@pytest.mark.parametrize("bad", [[1.0, math.nan], [[1.0], [2.0, math.inf]], {"a": [-math.inf]}, {math.nan: 1},
                                 {math.inf: []}])
def test_json_chunks_refuse_non_finite_numbers_like_json(bad):
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        b"".join(json_chunks(bad))
    with pytest.raises(ValueError, match="Out of range float values are not JSON compliant"):
        json.dumps(bad, indent=1, allow_nan=False)


def test_write_json_streams_into_a_temporary_file_then_renames(tmp_path):
    """write_atomic writes the pieces of an iterable as they come (the temporary file grows while the output keeps
    its old content); an error while the pieces are produced (a NaN in the JSON) leaves the old file and no
    temporary file."""
    out = tmp_path / "list.json"
    out.write_text("old\n")
    seen = []

    def pieces():
        yield b"x" * 100
        temporaries = [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]
        seen.append((out.read_text(), [p.stat().st_size for p in temporaries]))
        yield b"y\n"

    write_atomic(out, pieces())
    assert seen == [("old\n", [100])] and out.read_text() == "x" * 100 + "y\n"
    obj = {"plans": [{"a": i / 3} for i in range(20000)]}
    write_json(out, obj)
    assert out.read_bytes() == (json.dumps(obj, indent=1) + "\n").encode()
    with pytest.raises(ValueError):
        write_json(out, {"plans": [{"a": i / 3} for i in range(20000)] + [{"a": math.nan}]})
    assert out.read_bytes() == (json.dumps(obj, indent=1) + "\n").encode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["list.json"]


def test_json_chunks_raise_the_error_of_json_for_what_it_cannot_write():
    """A circular list and an int of more digits than Python writes: json's own errors."""
    circular = [1.0]
    circular.append(circular)
    for bad in (circular, {"a": [1.0, 10**5000]}):
        with pytest.raises(ValueError) as ours:
            b"".join(json_chunks(bad))
        with pytest.raises(ValueError) as theirs:
            json.dumps(bad, indent=1, allow_nan=False)
        assert str(ours.value) == str(theirs.value)
