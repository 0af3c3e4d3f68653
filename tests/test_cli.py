"""The rollplan command: outputs, JSON keys, exit codes, one-line errors, output files; plan --duration,
simulate, animate; the rules for numbers and files on the command line (bad input exits 2 in one line
naming the value, no plan exits 3). The commands of the studies (compare, atlas, batch, reproduce,
codegen) are tested with their subjects."""

import json
import os
import re
import stat
import subprocess
import sys

import numpy as np
import pytest
from conftest import one_line, run

from rollplan import InputError, Robot, State
from rollplan.cli import main
from rollplan.io import load_rotor_plan

import references

# ----------------------------------------------------------------------------- plan and step

@pytest.mark.slow
def test_plan_paper_case_json_and_plot(tmp_path, capsys):
    js, png = tmp_path / "p.json", tmp_path / "p.png"
    code, out, _ = run(capsys, "plan", "--to", "0", "1", "--k", "2.5", "--all", "--json", str(js), "--plot", str(png))
    assert code == 0
    assert "a = 0.300429 R" in out   # 6 significant digits, unit named
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


def _without_times(doc):
    """The plan document without the solver's wall times (which differ from run to run)."""
    doc["solver"].pop("time_s")
    for alt in doc["alternatives"]:
        alt["solver"].pop("time_s")
    return doc


def test_plan_all_json_streams_the_same_document_to_a_file_and_to_stdout(tmp_path, capfd):
    """plan --all --json FILE and --json -: the streamed file is exactly json.dumps of its content (the
    non-streamed text), and stdout carries the same document (up to the solver's wall times)."""
    js = tmp_path / "all.json"
    argv = ["plan", "--to", "0.3", "-0.2", "--psi", "0.5", "--steps", "2", "--k", "1.5", "--all", "--json"]
    code_file, _, err_file = run(capfd, *argv, js)
    code_out, stdout, err_out = run(capfd, *argv, "-")
    assert code_file == code_out == 0, (err_file, err_out)
    text = js.read_text()
    doc = json.loads(text)
    assert text == json.dumps(doc, indent=1) + "\n" and len(doc["alternatives"]) >= 10
    assert stdout == json.dumps(json.loads(stdout), indent=1) + "\n"
    assert _without_times(json.loads(stdout)) == _without_times(doc)


@pytest.mark.parametrize("argv,ab,k,gamma", [
    (["--a", "0.3", "--b", "0.4", "--k", "2.5"], (0.3, 0.4), 2.5, 0.0),
    (["--a", "0.6", "--b", "0.2", "--k", "5", "--gamma", "0.3"], (0.6, 0.2), 5.0, 0.3),
    (["--a", "0.5", "--k", "1.3"], (0.5, 0.5), 1.3, 0.0),                 # b defaults to a
    (["--a", "0.1", "--b", "0.65", "--k", "0", "--gamma", "-1"], (0.1, 0.65), 0.0, -1.0),
])
def test_step_command_matches_printed_reference(tmp_path, capsys, argv, ab, k, gamma):
    """`rollplan step` h, eta, final (u_a, v_a, psi) and direction against an independent DOP853
    integration of the printed (28)-(30), (35) (tests/references.py)."""
    js = tmp_path / "s.json"
    code, out, _ = run(capsys, "step", *argv, "--json", str(js))
    assert code == 0
    d = json.loads(js.read_text())
    ref = references.trace(ab[0], ab[1], k, gamma)
    assert (d["a"], d["b"], d["k"], d["gamma"]) == (ab[0], ab[1], k, gamma)
    assert [d["final"]["u_a"], d["final"]["v_a"], d["final"]["psi"]] == pytest.approx(ref, abs=1e-10)
    assert d["h"] == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)
    assert d["eta"] == pytest.approx(ref[2], abs=1e-10)
    assert d["direction"] == pytest.approx(np.arctan2(ref[1], ref[0]), abs=1e-9)
    # stdout reports the same h and eta, to the 6 significant digits of a summary
    shown = dict(re.findall(r"\b(h|eta) = (\S+)", out))
    assert float(shown["h"]) == pytest.approx(np.hypot(ref[0], ref[1]), rel=5e-6, abs=1e-12)
    assert float(shown["eta"]) == pytest.approx(ref[2], rel=5e-6, abs=1e-12)


@pytest.mark.parametrize("curve,ab,k,gamma", [
    ("viviani", (0.5, 0.3), 2.5, 0.0),
    pytest.param("triangle", (0.69, 0.2), 20.0, 0.4, marks=pytest.mark.slow),   # the reference: ~0.9 s
    ("square", (0.1, 0.6), 0.0, -1.0),
    ("circles", (0.3, 0.4), 2.5, 0.0),
])
def test_step_curve_matches_printed_reference(tmp_path, capsys, curve, ab, k, gamma):
    """`rollplan step --curve NAME`: the family's figure eight (docs/design/curve-families.md) against DOP853 on
    the printed (28)-(30) along the leaves as typed in tests/references.py; the JSON names the curve."""
    js = tmp_path / "s.json"
    code, out, _ = run(capsys, "step", "--curve", curve, "--a", str(ab[0]), "--b", str(ab[1]), "--k", str(k),
                       "--gamma", str(gamma), "--json", str(js))
    assert code == 0
    d = json.loads(js.read_text())
    ref = references.family_trace(curve, ab[0], ab[1], k, gamma)
    assert d["curve"] == curve and (d["a"], d["b"], d["k"], d["gamma"]) == (ab[0], ab[1], k, gamma)
    scale = 1e-9 * (1 + abs(ref[2]))
    assert [d["final"]["u_a"], d["final"]["v_a"], d["final"]["psi"]] == pytest.approx(ref, abs=scale)
    assert d["h"] == pytest.approx(np.hypot(ref[0], ref[1]), abs=scale)
    assert d["eta"] == pytest.approx(ref[2], abs=scale)
    shown = dict(re.findall(r"\b(h|eta) = (\S+)", out))
    assert float(shown["eta"]) == pytest.approx(ref[2], rel=5e-6, abs=1e-12)


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
    (["step", "--k", "2.5"], "--a"),
    (["step", "--a", "0.3", "--curve", "hexagon"], "hexagon"),
    (["step", "--a", "0.7", "--curve", "viviani"], "a = 0.7"),
    (["step", "--a", "0.3", "--curve", "square", "--k", "101"], "k = 101"),
    (["frobnicate"], "invalid choice"),
])
def test_bad_input_exits_2_with_one_line(capsys, argv, needle):
    code, _, err = run(capsys, *argv)
    assert code == 2
    assert needle in err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_no_plan_exits_3(capsys):
    code, _, err = run(capsys, "plan", "--to", "30", "0", "--k", "2.5")
    assert code == 3 and "more steps" in err and len(err.strip().splitlines()) == 1


def test_console_script_no_traceback():
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--k", "-3"], check=False, capture_output=True,
                       text=True)
    assert r.returncode == 2 and "Traceback" not in r.stderr and "k = -3" in r.stderr


def test_outputs_are_atomic(tmp_path, capsys):
    js = tmp_path / "p.json"
    js.write_text("old")
    code, _, _ = run(capsys, "plan", "--to", "30", "0", "--k", "2.5", "--json", str(js))
    assert code == 3 and js.read_text() == "old"  # a failed run leaves the old file intact
    assert not list(tmp_path.glob(".*.tmp"))


def test_output_files_get_the_usual_mode(tmp_path, capsys):
    js = tmp_path / "s.json"
    run(capsys, "step", "--a", "0.3", "--k", "2.5", "--json", str(js))
    umask = os.umask(0)
    os.umask(umask)
    assert stat.S_IMODE(js.stat().st_mode) == 0o666 & ~umask


# ----------------------------------------------------------------------------- numbers and files


@pytest.mark.parametrize("psi", ["1e20", "-1e300"])
def test_huge_psi_returns_quickly(psi):
    """psi = 1e20 must not hang (nor exhaust memory): a plan (exit 0) or no plan (exit 3), in a
    separate process with a time limit."""
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0.5", "0.3", f"--psi={psi}",
                        "--k", "2.5"], check=False, capture_output=True, text=True, timeout=120)
    assert r.returncode in (0, 3), r.stderr
    assert "Traceback" not in r.stderr
    if r.returncode == 3:
        assert one_line(r.stderr)


@pytest.mark.parametrize("argv,needle", [
    (["plan", "--steps", "1001"], "steps = 1001"),
    (["plan", "--steps", "2.5"], "2.5"),
    (["plan", "--k", "100.5"], "k = 100.5"),
    (["plan", "--k", "1e9"], "k = 1000000000.0"),
])
def test_cli_rejects_steps_and_k_outside_the_rules(capsys, argv, needle):
    code, _, err = run(capsys, *argv)
    assert code == 2 and needle in err and one_line(err)


def test_cli_turn_in_place_is_planned(capsys):
    """``--to 0 0 --psi 1`` (once refused): a turn in place by a pair of circles, certified."""
    code, out, _ = run(capsys, "plan", "--to", "0", "0", "--psi", "1", "--k", "2.5")
    assert code == 0 and "mode          turn" in out and "residual" in out


@pytest.mark.parametrize("name,ext", [("x.unknownext", "unknownext"), ("x.json", "json")])
def test_plot_with_unsupported_extension_exits_2_before_computing(tmp_path, capsys, name, ext):
    """The target is unreachable (exit 3 if anything were computed): exit 2 shows the
    extension is checked first."""
    out = tmp_path / name
    code, _, err = run(capsys, "plan", "--to", "30", "0", "--k", "2.5", "--plot", str(out))
    assert code == 2 and ext in err and one_line(err)
    assert not out.exists() and not list(tmp_path.iterdir())


@pytest.mark.parametrize("argv", [["step", "--a", "0.3", "--k", "2.5", "--json"],
                                  ["plan", "--to", "0", "1", "--k", "2.5", "--json"]])
def test_output_path_that_is_a_fifo_exits_2(tmp_path, capsys, argv):
    fifo = tmp_path / "out.json"
    os.mkfifo(fifo)
    code, _, err = run(capsys, *argv, str(fifo))
    assert code == 2 and "out.json" in err and one_line(err)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)  # left alone


def test_plot_path_that_is_a_fifo_exits_2(tmp_path, capsys):
    fifo = tmp_path / "out.png"
    os.mkfifo(fifo)
    code, _, err = run(capsys, "plan", "--to", "0", "1", "--k", "2.5", "--plot", str(fifo))
    assert code == 2 and "out.png" in err and one_line(err)
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)


def test_symlink_output_is_written_through_to_its_target(tmp_path, capsys):
    (tmp_path / "links").mkdir()
    (tmp_path / "data").mkdir()
    real = tmp_path / "data" / "real.json"
    real.write_text("old")
    link = tmp_path / "links" / "link.json"
    link.symlink_to(real)
    code, _, _ = run(capsys, "step", "--a", "0.3", "--b", "0.4", "--k", "2.5", "--json", str(link))
    assert code == 0
    assert link.is_symlink() and os.readlink(link) == str(real)
    d = json.loads(real.read_text())
    ref = references.trace(0.3, 0.4, 2.5)
    assert d["eta"] == pytest.approx(ref[2], abs=1e-10)
    assert sorted(p.name for p in (tmp_path / "links").iterdir()) == ["link.json"]  # no temporary left
    assert sorted(p.name for p in (tmp_path / "data").iterdir()) == ["real.json"]


def test_relative_symlink_output_is_written_through(tmp_path, capsys, monkeypatch):
    real = tmp_path / "real.json"
    (tmp_path / "rel.json").symlink_to("real.json")
    monkeypatch.chdir(tmp_path)
    code, _, _ = run(capsys, "step", "--a", "0.3", "--k", "2.5", "--json", "rel.json")
    assert code == 0 and (tmp_path / "rel.json").is_symlink()
    assert json.loads(real.read_text())["a"] == 0.3


def test_unreadable_and_invalid_files(tmp_path, capsys):
    assert main(["plan", "--robot", str(tmp_path / "none.toml")]) == 2
    assert "cannot be read" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("radius = = 1\n")
    assert main(["plan", "--robot", str(bad)]) == 2
    assert "not valid TOML" in capsys.readouterr().err


# ----------------------------------------------------------------------------- plan --duration, simulate, animate

ROBOT_TOML = """radius = 0.15
mass_total = 2.0
mass_shell = 0.6
rotor_inertia_axial = 4.0e-4
rotor_inertia_transverse = 2.5e-4
"""


@pytest.fixture(scope="module")
def planned(tmp_path_factory):
    d = tmp_path_factory.mktemp("plan")
    robot = d / "robot.toml"
    robot.write_text(ROBOT_TOML)
    out = d / "plan.json"
    code = main(["plan", "--robot", str(robot), "--to", "0.06", "0.1", "--psi", "0.4", "--steps", "2",
                 "--duration", "12", "--json", str(out), "--plot", str(d / "motion.png")])
    assert code == 0
    return d, robot, out, json.loads(out.read_text())


def test_plan_json_has_the_motion(planned):
    d, _, _, data = planned
    n = len(data["time"])
    assert n >= 2000
    for key, cols in (("omega", 3), ("rotor_rates", 2), ("rotor_angles", 2), ("rotor_torques", 2)):
        assert np.asarray(data[key]).shape == (n, cols)
    rob = Robot(0.15, 2.0, 0.6, 4.0e-4, 2.5e-4)
    assert data["robot"] == {**{k: getattr(rob, k) for k in ("radius", "mass_total", "mass_shell",
                                                             "rotor_inertia_axial", "rotor_inertia_transverse")},
                             "k": rob.k}
    assert data["k"] == rob.k and data["time"][-1] == 12.0
    # --to in metres
    assert data["final"]["u_a"] == pytest.approx(0.06, abs=1e-10)
    assert data["final"]["v_a"] == pytest.approx(0.1, abs=1e-10)
    assert data["rotor_simulation"]["arrival_error"] < 1e-6
    assert (d / "motion.png").stat().st_size > 10000
    # the motion's states in State order (u_a, v_a, psi, u_o, v_o), at rest at the goal at the end
    state = np.asarray(data["state"])
    assert state.shape == (n, 5)
    assert state[-1] == pytest.approx([0.06, 0.1, 0.4, 0.0, 0.0], abs=1e-10)
    assert np.array_equal(state[0], np.zeros(5))


def test_plan_json_is_the_text_json_dumps_writes(planned):
    """The plan file of a motion (tables of thousands of samples, written by json's C encoder and indented by
    the writer) is byte for byte ``json.dumps(indent=1)`` of its value and a newline."""
    _, _, out, data = planned
    assert out.read_bytes() == (json.dumps(data, indent=1) + "\n").encode()


def test_plan_timing_without_json_builds_no_json_lists(tmp_path, capsys, monkeypatch):
    """plan --duration without --json: the summary and the figure, and none of the JSON's lists of samples
    (building them took as long as the plan)."""
    import rollplan.io

    def refuse(motion):
        raise AssertionError("motion_to_dict called without --json")

    monkeypatch.setattr(rollplan.io, "motion_to_dict", refuse)
    robot = tmp_path / "robot.toml"
    robot.write_text(ROBOT_TOML)
    code, out, err = run(capsys, "plan", "--robot", robot, "--to", "0.06", "0.1", "--duration", "12")
    assert code == 0, err
    assert "rotor-only    arrival error" in out


def test_load_rotor_plan_reads_what_plan_duration_wrote(planned):
    _, _, out, data = planned
    rp = load_rotor_plan(out)
    assert rp.goal == State(0.06, 0.1, 0.4)
    assert rp.robot == Robot(0.15, 2.0, 0.6, 4.0e-4, 2.5e-4)
    assert np.array_equal(rp.time, data["time"]) and np.array_equal(rp.rotor_rates, data["rotor_rates"])
    assert rp.data == data


@pytest.mark.parametrize("text, match", [(None, "cannot be read"), ("{", "not valid JSON"), ("[1, 2]", "JSON object"),
                                         ('{"time": [0, 1]}', "no key 'rotor_rates'")])
def test_load_rotor_plan_refuses_other_files(tmp_path, text, match):
    path = tmp_path / "plan.json"
    if text is not None:
        path.write_text(text)
    with pytest.raises(InputError, match=match) as err:
        load_rotor_plan(path)
    assert "\n" not in str(err.value)


def test_simulate_reports_arrival_error(planned, capsys):
    d, _, out, _ = planned
    capsys.readouterr()
    assert main(["simulate", str(out), "--json", str(d / "sim.json")]) == 0
    text = capsys.readouterr().out
    err = float(re.search(r"arrival error (\S+)", text).group(1))
    assert err < 1e-6
    assert json.loads((d / "sim.json").read_text())["arrival_error"] == pytest.approx(err, rel=1e-3)


def test_simulate_other_robot(planned, tmp_path, capsys):
    _, _, out, _ = planned
    other = tmp_path / "other.toml"
    other.write_text(ROBOT_TOML.replace("mass_total = 2.0", "mass_total = 2.2"))
    capsys.readouterr()
    assert main(["simulate", str(out), "--robot", str(other)]) == 0
    err = float(re.search(r"arrival error (\S+)", capsys.readouterr().out).group(1))
    assert err > 1e-3


def test_plan_json_metadata(planned):
    import rollplan

    data = planned[3]
    assert data["version"] == rollplan.__version__ and data["units"]["length"] == "m"
    assert data["units"]["torque"] == "N m"


@pytest.mark.slow
def test_simulate_plot_and_json_metadata(planned, tmp_path, capsys):
    import rollplan

    _, _, out, data = planned
    assert data["version"] == rollplan.__version__ and data["units"]["length"] == "m"
    assert data["units"]["torque"] == "N m"
    png, js = tmp_path / "sim.png", tmp_path / "sim.json"
    capsys.readouterr()
    assert main(["simulate", str(out), "--plot", str(png), "--json", str(js)]) == 0
    text = capsys.readouterr().out
    assert png.read_bytes()[:4] == b"\x89PNG" and png.stat().st_size > 20000
    d = json.loads(js.read_text())
    assert d["version"] == rollplan.__version__ and d["units"]["length"] == "m"
    assert d["position_error_m"] == pytest.approx(d["position_error"] * 0.15)
    assert "Euclidean norm" in text and re.search(r"position \S+ m", text)


def test_plan_duration_prints_torques_in_n_m_and_position_error_in_m(tmp_path, capsys):
    code, out, _ = run(capsys, "plan", "--to", "0", "0.1", "--duration", "5")
    assert code == 0
    assert re.search(r"max \|torque\| = \S+ N m", out)
    assert re.search(r"position error \S+ m ", out) and " R;" not in out


def test_default_robot_when_no_file(tmp_path, capsys):
    out = tmp_path / "p.json"
    assert main(["plan", "--to", "0", "0.1", "--duration", "5", "--json", str(out)]) == 0
    assert "default robot" in capsys.readouterr().out
    assert json.loads(out.read_text())["robot"]["radius"] == Robot().radius


def test_duration_errors(capsys, tmp_path):
    assert main(["plan", "--k", "2.5", "--duration", "5"]) == 2
    assert "--robot" in capsys.readouterr().err
    assert main(["plan", "--to", "0", "0.1", "--duration", "-1"]) == 2
    assert "duration" in capsys.readouterr().err
    plain = tmp_path / "plain.json"
    assert main(["plan", "--k", "2.5", "--json", str(plain)]) == 0
    capsys.readouterr()
    assert main(["simulate", str(plain)]) == 2
    err = capsys.readouterr().err
    assert "'time'" in err and "--duration" in err
    assert main(["simulate", str(tmp_path / "missing.json")]) == 2
    assert main(["animate", str(plain), "--out", str(tmp_path / "a.gif")]) == 2


@pytest.mark.slow
def test_animate_writes_a_gif(planned, tmp_path):
    _, _, out, _ = planned
    gif = tmp_path / "roll.gif"
    assert main(["animate", str(out), "--out", str(gif), "--frames", "3"]) == 0
    from PIL import Image

    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    assert Image.open(gif).n_frames == 3


# ----------------------------------------------------------------------------- Unix conventions (issue 18)

def test_json_dash_pipes_into_a_json_parser():
    """`--json -` writes only the JSON document to stdout (the summary goes to stderr): piped into a parser."""
    reader = "import json, sys; d = json.load(sys.stdin); print(d['h'], d['eta'], d['version'], d['units']['length'])"
    cmd = f"{sys.executable} -m rollplan.cli step --a 0.3 --b 0.4 --json - | {sys.executable} -c \"{reader}\""
    r = subprocess.run(cmd, shell=True, check=True, capture_output=True, text=True, timeout=300)
    h, eta, version, unit = r.stdout.split()
    ref = references.trace(0.3, 0.4, 2.5)   # k defaults to 2.5
    assert float(h) == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)
    assert float(eta) == pytest.approx(ref[2], abs=1e-10)
    assert unit == "R"
    import rollplan

    assert version == rollplan.__version__


def test_json_dash_in_process_keeps_stdout_pure(capsys):
    code, out, err = run(capsys, "plan", "--to", "0.5", "0.3", "--psi", "0.4", "--json", "-")
    assert code == 0
    d = json.loads(out)   # nothing but the document on stdout
    assert d["final"]["u_a"] == pytest.approx(0.5, abs=1e-9) and len(d["trajectory"]["theta"]) > 100
    assert "figure eight" in err and "residual" in err and "wrote" not in err
    assert not os.path.exists("-")


def test_json_dash_is_not_a_file_named_dash(capsys, tmp_path, monkeypatch):
    """`--json -` once took a lock on a file named '-' in the current folder: a second `--json -` run there was
    refused as 'being written by another process'. With another process holding that name, stdout still works."""
    monkeypatch.chdir(tmp_path)
    holder = subprocess.Popen([sys.executable, "-c", "import sys, time\nfrom rollplan.outputs import claim\n"
                               "with claim('-'):\n    print('held', flush=True)\n    time.sleep(60)\n"],
                              stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        code, out, err = run(capsys, "step", "--a", "0.3", "--b", "0.4", "--json", "-")
    finally:
        holder.kill()
        holder.wait()
    assert code == 0, err
    assert json.loads(out)["version"]


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="needs /dev/full (Linux)")
@pytest.mark.parametrize("argv", [["step", "--a", "0.3"], ["step", "--a", "0.3", "--json", "-"]])
def test_stdout_on_a_full_disk_is_one_line_and_exit_2(argv):
    """`rollplan plan ... > /dev/full` ended in an OSError traceback with exit 1."""
    with open("/dev/full", "w") as full:
        r = subprocess.run([sys.executable, "-m", "rollplan.cli", *argv], stdout=full, stderr=subprocess.PIPE,
                           text=True, timeout=120, check=False)
    assert r.returncode == 2, r.stderr
    last = r.stderr.strip().splitlines()[-1]
    assert last == "rollplan: error: the standard output cannot be written: the disk is full"
    assert "Traceback" not in r.stderr and "Exception ignored" not in r.stderr


CLOSED_PIPE = "rollplan: error: the standard output cannot be written: the reader closed the pipe"


@pytest.mark.parametrize("argv", [["plan", "--to", "0.5", "0.3", "--json", "-"], ["step", "--a", "0.3"]])
def test_stdout_into_a_closed_pipe_is_a_failure(argv):
    """`plan --to 0.5 0.3 --json - | head -c1` exited 0 although the JSON was not delivered: stdout is a pipe whose
    reader has gone (closed before the command writes), and the command exits 2 with one line."""
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        r = subprocess.run([sys.executable, "-m", "rollplan.cli", *argv], stdout=write_end, stderr=subprocess.PIPE,
                           text=True, timeout=300, check=False)
    finally:
        os.close(write_end)
    assert r.returncode == 2, r.stderr
    assert r.stderr.strip().splitlines()[-1] == CLOSED_PIPE
    assert "Traceback" not in r.stderr and "Exception ignored" not in r.stderr


def test_json_dash_into_head_is_a_failure(tmp_path):
    """The reported pipeline itself: the JSON (300 kB, more than a pipe holds) into `head -c1`; the shell's
    pipefail reports the command's status."""
    cmd = f"set -o pipefail; {sys.executable} -m rollplan.cli plan --to 0.5 0.3 --json - 2>err.txt | head -c1"
    r = subprocess.run(["bash", "-c", cmd], cwd=tmp_path, capture_output=True, text=True, timeout=300, check=False)
    err = (tmp_path / "err.txt").read_text()
    assert r.stdout == "{" and r.returncode == 2, err
    assert err.strip().splitlines()[-1] == CLOSED_PIPE and "Traceback" not in err


@pytest.mark.parametrize("command, option, low", [("batch", "--jobs", 1), ("plan", "--samples", 2),
                                                  ("compare", "--intervals", 4)])
def test_help_states_the_limit_the_command_enforces(capsys, tmp_path, command, option, low):
    """The help said [2, 10^7] for --samples and '>= 1' for --jobs while the commands refused above 10^6 and 1024:
    the range in --help is the one in the refusal of a value just above it."""
    import re

    from rollplan import cli

    with pytest.raises(SystemExit):
        cli.main([command, "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    high = int(re.search(rf"{option} \S+ .*?in \[{low}, (\d+)\]", help_text).group(1))
    csv_path = tmp_path / "t.csv"
    csv_path.write_text("u_a,v_a\n0.1,0.2\n")
    argv = {"batch": ["batch", str(csv_path), "--out", str(tmp_path / "o.jsonl")], "plan": ["plan"],
            "compare": ["compare", "--to", "0.5", "0.3"]}[command]
    code, _, err = run(capsys, *argv, option, str(high + 1))
    assert code == 2 and f"[{low}, {high}]" in err


def test_batch_out_dash_is_refused_not_a_file_named_dash(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "t.csv").write_text("u_a,v_a\n0.1,0.2\n")
    code, _, err = run(capsys, "batch", "t.csv", "--out", "-")
    assert code == 2 and "--out FILE.jsonl" in err
    assert not (tmp_path / "-").exists()


def test_version(capsys):
    from importlib.metadata import version

    import rollplan

    code, out, _ = run(capsys, "--version")
    assert code == 0 and out.strip() == f"rollplan {rollplan.__version__}" == f"rollplan {version('rollplan')}"


def test_bare_command_prints_usage(capsys):
    code, out, err = run(capsys)
    assert code == 2 and out == ""
    assert err.startswith("usage: rollplan")
    for command in ("plan", "step", "reproduce", "simulate", "animate", "compare", "codegen", "batch", "atlas"):
        assert f"\n    {command} " in err


@pytest.mark.parametrize("argv, target", [
    (["--to", "-1e-3", "1", "--psi", "-2e-1"], (-1e-3, 1.0, -0.2)),
    (["--to", "-.5", "-3E-1", "--psi", "-1E+0"], (-0.5, -0.3, -1.0)),
])
def test_negative_numbers_in_exponent_form(tmp_path, capsys, argv, target):
    js = tmp_path / "p.json"
    code, _, err = run(capsys, "plan", *argv, "--json", str(js))
    assert code == 0, err
    d = json.loads(js.read_text())
    assert (d["target"]["u_a"], d["target"]["v_a"], d["target"]["psi"]) == target
    fe = d["figure_eight"]
    x = references.trace(fe["a"], fe["b"], 2.5, fe["gamma"], steps=d["steps"])
    assert x[:2] == pytest.approx(target[:2], abs=1e-9)
    assert np.cos(x[2] - target[2]) == pytest.approx(1.0, abs=1e-12)


@pytest.mark.parametrize("value", ["-inf", "-nan", "-Infinity"])
def test_negative_non_numbers_are_refused_as_numbers(capsys, value):
    code, _, err = run(capsys, "plan", "--to", value, "1")
    assert code == 2 and value in err and "no spaces, underscores, hex, inf or nan" in err and one_line(err)


def test_errors_point_to_help(capsys):
    code, _, err = run(capsys, "step", "--a")
    assert code == 2 and "(see: rollplan step --help)" in err and one_line(err)


def test_k_defaults_to_the_papers_case(tmp_path, capsys):
    js = tmp_path / "s.json"
    assert run(capsys, "step", "--a", "0.3", "--json", str(js))[0] == 0
    d = json.loads(js.read_text())
    assert d["k"] == 2.5
    assert d["eta"] == pytest.approx(references.trace(0.3, 0.3, 2.5)[2], abs=1e-10)


@pytest.mark.slow
def test_atlas_k_defaults_to_the_papers_case(tmp_path, capsys):
    assert run(capsys, "atlas", "--resolution", "3", "--out", str(tmp_path / "a.png"), "--json",
               str(tmp_path / "a.json"))[0] == 0
    assert json.loads((tmp_path / "a.json").read_text())["k"] == 2.5


@pytest.mark.parametrize("command, needles", [
    ("plan", ["[0, 100]", "[1, 1000]", "default 2.5", "- for stdout"]),
    ("step", ["0 < a <= 0.69", "0 < b <= 0.69", "[0, 100]"]),
    ("atlas", ["[0, 100]", "[2, 1000]", "[1, 1000]", "--scheduler"]),
    ("animate", ["[2, 2000]", "[1, 100]"]),
    ("compare", ["[4, 2000]", "[1, 9]", "(0, pi/2)", "k in (1, 100]", "[1e-06, 1e+06]"]),
    ("batch", ["--scheduler", "in [1, ", "exit status"]),
])
def test_limits_are_in_the_help(capsys, command, needles):
    with pytest.raises(SystemExit):
        main([command, "--help"])
    text = " ".join(capsys.readouterr().out.split())
    for needle in needles:
        assert needle in text, needle


def test_lengths_are_printed_in_the_unit_in_use(capsys):
    code, out, _ = run(capsys, "plan", "--to", "0", "0.1", "--radius", "0.1")
    assert code == 0
    assert "R = 0.1 m" in out and "a = 0.0300429 m" in out and "units" not in out
    assert re.search(r"final +u_a = \S+ m +v_a = 0.1 m +psi = \S+ rad", out)
    assert "Euclidean norm; lengths in R, angles in rad" in out


def test_summaries_have_six_significant_digits(capsys):
    _, out, _ = run(capsys, "plan")
    for number in re.findall(r"= (-?[0-9.]+(?:e[-+][0-9]+)?) (?:R|rad)\b", out):
        assert len(number.split("e")[0].replace("-", "").replace(".", "").lstrip("0")) <= 6, number


@pytest.mark.slow
def test_route_and_composed_plan_follow_the_conventions(tmp_path, capsys):
    """The commands of composed plans (plan --from/--contact, route) keep the conventions: --json - on stdout
    with version and units, the summary on stderr with every length in the unit in use (named), 6 digits and
    the norm of the residual named."""
    path = tmp_path / "w.csv"
    path.write_text("u_a,v_a,psi,u_o,v_o\n0,0,0,0.1,0\n0.6,0.2,0.5,,\n")
    code, out, err = run(capsys, "route", str(path), "--k", "2.5", "--json", "-")
    assert code == 0
    d = json.loads(out)
    import rollplan

    assert d["version"] == rollplan.__version__ and d["units"]["length"] == "R" and len(d["legs"]) == 1
    assert "path length" in err and "Euclidean norm" in err and "wrote" not in err
    assert re.search(r"path length   \S+ R in \d+ pieces", err)
    code, out, err = run(capsys, "plan", "--from", "0.01", "-0.02", "0.4", "-0.5", "0.6", "--to", "0.05", "0.07",
                         "--radius", "0.1", "--json", "-")
    assert code == 0 and json.loads(out)["units"]["length"] == "m"
    start = re.search(r"from \(u_a, v_a, psi, u_o, v_o\) = \((.*?)\) to", err).group(1).split(", ")
    assert start == ["0.01 m", "-0.02 m", "0.4 rad", "-0.5 rad", "0.6 rad"]
    numbers = re.findall(r"= (-?\d[\d.e+-]*) m", err)
    assert numbers and all(len(n.lstrip("-").replace(".", "").split("e")[0].lstrip("0")) <= 6 for n in numbers)


def test_composed_figure_colours_follow_the_convention():
    """In a composed plan's figure the first leaf after an approach roll is the 1st half-step (red), the rolls
    have their own colours and every colour is named in a legend."""
    from rollplan.planners.geometric import plan
    from rollplan.plots.colors import LEAF, LEAF_LABELS, PIECE
    from rollplan.plots.common import segments
    from rollplan.plots.composed import piece_runs, plot_composed

    p = plan((0.05, 0.07, 0.8, 0.0, 0.0), 1, k=2.5, start=(0.0, 0.0, 0.0, 0.3, -0.2), polish="off")
    traj = p.sample(800)
    runs = piece_runs(p, traj)
    kinds = [p.pieces[j].kind for _, _, j in segments(traj)]
    assert kinds[0] == "approach" and runs[0][2] == PIECE["approach"]
    first_leaf = kinds.index("leaf")
    assert runs[first_leaf][2:] == (LEAF[0], LEAF_LABELS[0]) and runs[first_leaf + 1][2:] == (LEAF[1], LEAF_LABELS[1])
    fig = plot_composed(p, traj)
    legend = {t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()}
    assert {LEAF_LABELS[0], LEAF_LABELS[1], "approach roll (to the pole)", "start", "target"} <= legend


@pytest.mark.parametrize("given, expected", [(None, "1"), ("3", "3")])
def test_command_uses_one_blas_thread_unless_told(given, expected):
    """rollplan.cli sets OPENBLAS/OMP/MKL_NUM_THREADS to 1 before numpy loads, and keeps a value the user set."""
    import subprocess

    from rollplan.threads import THREAD_VARIABLES

    env = {k: v for k, v in os.environ.items() if k not in THREAD_VARIABLES}
    if given is not None:
        env.update({k: given for k in THREAD_VARIABLES})
    code = ("import sys; import rollplan.cli, os; "
            "print(' '.join(os.environ[k] for k in ('OPENBLAS_NUM_THREADS', 'OMP_NUM_THREADS', 'MKL_NUM_THREADS')))")
    done = subprocess.run([sys.executable, "-c", code], check=False, capture_output=True, text=True, env=env,
                          timeout=120)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.split() == [expected] * 3
