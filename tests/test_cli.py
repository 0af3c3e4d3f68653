"""The rollplan command: outputs, JSON keys, exit codes, one-line errors."""

import json
import re
import subprocess
import sys

import numpy as np
import pytest

import printed_rhs
from rollplan.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_plan_paper_case_json_and_plot(tmp_path, capsys):
    js, png = tmp_path / "p.json", tmp_path / "p.png"
    code, out, _ = run(capsys, "plan", "--to", "0", "1", "--k", "2.5", "--all", "--json", str(js), "--plot", str(png))
    assert code == 0
    assert "0.300428" in out
    d = json.loads(js.read_text())
    for key in ("k", "radius", "steps", "target", "figure_eight", "step", "final", "residual", "path_length",
                "trajectory", "alternatives"):
        assert key in d
    assert set(d["target"]) == {"u_a", "v_a", "psi"}
    assert set(d["figure_eight"]) == {"a", "b", "gamma"}
    assert set(d["step"]) == {"h", "eta"}
    assert set(d["final"]) == {"u_a", "v_a", "psi", "u_o", "v_o"}
    assert set(d["trajectory"]) >= {"theta", "u_o", "v_o", "u_a", "v_a", "psi"}
    assert d["figure_eight"]["a"] == pytest.approx(0.300429, abs=5e-7)
    assert any(abs(alt["figure_eight"]["a"] - 0.491471) < 5e-7 for alt in d["alternatives"])
    assert d["residual"] < 1e-9
    tr = d["trajectory"]
    assert tr["v_a"][-1] == pytest.approx(1.0, abs=1e-9) and len(tr["theta"]) > 100
    assert png.stat().st_size > 10000 and png.read_bytes()[:4] == b"\x89PNG"


@pytest.mark.parametrize("argv,ab,k,gamma", [
    (["--a", "0.3", "--b", "0.4", "--k", "2.5"], (0.3, 0.4), 2.5, 0.0),
    (["--a", "0.6", "--b", "0.2", "--k", "5", "--gamma", "0.3"], (0.6, 0.2), 5.0, 0.3),
    (["--a", "0.5", "--k", "1.3"], (0.5, 0.5), 1.3, 0.0),                 # b defaults to a
    (["--a", "0.1", "--b", "0.65", "--k", "0", "--gamma", "-1"], (0.1, 0.65), 0.0, -1.0),
])
def test_step_command_matches_printed_reference(tmp_path, capsys, argv, ab, k, gamma):
    """`rollplan step` h, eta, final (u_a, v_a, psi) and direction against an independent DOP853
    integration of the printed (28)-(30), (35) (tests/printed_rhs.py)."""
    js = tmp_path / "s.json"
    code, out, _ = run(capsys, "step", *argv, "--json", str(js))
    assert code == 0
    d = json.loads(js.read_text())
    ref = printed_rhs.trace(ab[0], ab[1], k, gamma)
    assert (d["a"], d["b"], d["k"], d["gamma"]) == (ab[0], ab[1], k, gamma)
    assert [d["final"]["u_a"], d["final"]["v_a"], d["final"]["psi"]] == pytest.approx(ref, abs=1e-10)
    assert d["h"] == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)
    assert d["eta"] == pytest.approx(ref[2], abs=1e-10)
    assert d["direction"] == pytest.approx(np.arctan2(ref[1], ref[0]), abs=1e-9)
    # stdout reports the same h and eta
    shown = dict(re.findall(r"\b(h|eta) = (\S+)", out))
    assert float(shown["h"]) == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)
    assert float(shown["eta"]) == pytest.approx(ref[2], abs=1e-10)


@pytest.mark.parametrize("argv,needle", [
    (["plan", "--to", "nan", "1"], "nan"),
    (["plan", "--to", "0", "inf"], "inf"),
    (["plan", "--k", "-1"], "k = -1"),
    (["plan", "--steps", "0"], "steps = 0"),
    (["plan", "--steps", "two"], "two"),
    (["plan", "--radius", "0"], "radius = 0"),
    (["plan", "--json", "/nonexistent-dir/x.json"], "not writable"),
    (["plan", "--robot", "/nonexistent.toml"], "cannot be read"),
    (["plan", "--k", "2", "--robot", "r.toml"], "not allowed with"),
    (["step", "--a", "0.8", "--k", "2.5"], "a = 0.8"),
    (["step", "--a", "0.3", "--b", "0", "--k", "2.5"], "b = 0"),
    (["step", "--a", "0.3"], "--k"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, needle):
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse's own checks
        code = exc.code
    _, err = capsys.readouterr()
    assert code == 2
    assert needle in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_no_plan_exits_3(capsys):
    code, _, err = run(capsys, "plan", "--to", "30", "0", "--k", "2.5")
    assert code == 3 and "more steps" in err and len(err.strip().splitlines()) == 1


def test_console_script_no_traceback():
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--k", "-3"], capture_output=True, text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "k = -3" in r.stderr


def test_outputs_are_atomic(tmp_path, capsys):
    js = tmp_path / "p.json"
    js.write_text("old")
    code, _, _ = run(capsys, "plan", "--to", "30", "0", "--k", "2.5", "--json", str(js))
    assert code == 3 and js.read_text() == "old"  # a failed run leaves the old file intact
    assert not list(tmp_path.glob(".*.tmp"))


def test_output_files_get_the_usual_mode(tmp_path, capsys):
    import os
    import stat

    js = tmp_path / "s.json"
    run(capsys, "step", "--a", "0.3", "--k", "2.5", "--json", str(js))
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(js.stat().st_mode) == 0o666 & ~umask
