"""Input rules of plan/step and of the CLI's files: bad input is one InputError line
(CLI exit 2) naming the value; no target at the start point (exit 3); huge psi returns."""

import json
import os
import stat
import subprocess
import sys

import numpy as np
import pytest

import printed_rhs
import rollplan
from rollplan import InputError, NoPlanError
from rollplan.cli import main


def run(capsys, *argv):
    try:
        code = main(list(argv))
    except SystemExit as exc:  # argparse's own checks
        code = exc.code
    out, err = capsys.readouterr()
    return code, out, err


def one_line(err):
    return len(err.strip().splitlines()) == 1 and "Traceback" not in err


def wrap(angle):
    return np.angle(np.exp(1j * np.asarray(angle, float)))


# ----------------------------------------------------------------------------- plan(): steps, k, psi

@pytest.mark.parametrize("kwargs,match", [
    (dict(steps=1001), "steps = 1001"),
    (dict(steps=10**6), "steps = 1000000"),
    (dict(steps=0), "steps = 0"),
    (dict(steps=-3), "steps = -3"),
    (dict(steps=2.5), "steps = 2.5"),
    (dict(steps="2"), "steps = '2'"),
    (dict(steps=True), "steps = True"),
    (dict(k=100.5), "k = 100.5"),
    (dict(k=1e6), "k = 1e\\+06"),
    (dict(k=-0.1), "k = -0.1"),
    (dict(psi=np.nan), "psi"),
    (dict(psi=-np.inf), "psi"),
])
def test_plan_rejects_steps_k_psi_outside_the_rules(kwargs, match):
    k = kwargs.get("k", 2.5)
    psi = kwargs.get("psi", 0.0)
    with pytest.raises(InputError, match=match) as err:
        rollplan.plan((0.0, 1.0, psi), steps=kwargs.get("steps", 1), k=k)
    assert "\n" not in str(err.value)


@pytest.mark.parametrize("steps", [pytest.param(1000, marks=pytest.mark.slow), np.int64(1)])
def test_plan_accepts_steps_up_to_1000(steps):
    """steps = 1000 is allowed: the answer is a plan or NoPlanError, never InputError."""
    try:
        p = rollplan.plan((0.0, 1.0, 0.0), steps=steps, k=2.5)
    except NoPlanError:
        return
    assert p.steps == int(steps)


@pytest.mark.parametrize("k", [0.0, pytest.param(100.0, marks=pytest.mark.slow)])
def test_plan_accepts_k_at_the_ends_of_0_100(k):
    try:
        p = rollplan.plan((0.5, 0.3, 0.0), steps=2, k=k)
    except NoPlanError:
        return
    x = printed_rhs.trace(p.a, p.b, k, p.gamma, p.steps)
    assert np.abs([x[0] - 0.5, x[1] - 0.3, wrap(x[2])]).max() < 1e-9


@pytest.mark.parametrize("psi", [1000.5, -1000.5, 0.8 + 2 * np.pi * 50])
def test_large_psi_is_reduced_modulo_2pi(psi):
    """Any finite psi is a heading: the plan for psi equals the plan for psi reduced to (-pi, pi]
    and reaches the target per the independent reference (psi modulo 2 pi)."""
    small = wrap(psi)
    try:
        p = rollplan.plan((0.5, 0.7, psi), steps=3, k=2.5)
    except NoPlanError:
        with pytest.raises(NoPlanError):
            rollplan.plan((0.5, 0.7, small), steps=3, k=2.5)
        return
    x = printed_rhs.trace(p.a, p.b, p.k, p.gamma, p.steps)
    assert np.abs([x[0] - 0.5, x[1] - 0.7, wrap(x[2] - psi)]).max() < 1e-9
    q = rollplan.plan((0.5, 0.7, small), steps=3, k=2.5)
    assert p.path_length == pytest.approx(q.path_length, abs=1e-7)


@pytest.mark.parametrize("psi", ["1e20", "-1e300"])
def test_huge_psi_returns_quickly(psi):
    """psi = 1e20 must not hang (nor exhaust memory): a plan (exit 0) or no plan (exit 3), in a
    separate process with a time limit."""
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0.5", "0.3", f"--psi={psi}",
                        "--k", "2.5"], capture_output=True, text=True, timeout=120)
    assert r.returncode in (0, 3), r.stderr
    assert "Traceback" not in r.stderr
    if r.returncode == 3:
        assert one_line(r.stderr)


@pytest.mark.parametrize("argv,needle", [
    (["plan", "--steps", "1001"], "steps = 1001"),
    (["plan", "--steps", "2.5"], "2.5"),
    (["plan", "--k", "100.5"], "k = 100.5"),
    (["plan", "--k", "1e9"], "k = 1e+09"),
])
def test_cli_rejects_steps_and_k_outside_the_rules(capsys, argv, needle):
    code, _, err = run(capsys, *argv)
    assert code == 2 and needle in err and one_line(err)


# ----------------------------------------------------------------------------- target at the start point

@pytest.mark.parametrize("psi", [0.0, 1.0, -np.pi])
def test_target_at_the_start_point_has_no_plan(psi):
    with pytest.raises(NoPlanError) as err:
        rollplan.plan((0.0, 0.0, psi), k=2.5)
    assert "\n" not in str(err.value)


def test_cli_target_at_the_start_point_exits_3(capsys):
    code, _, err = run(capsys, "plan", "--to", "0", "0", "--psi", "1", "--k", "2.5")
    assert code == 3 and one_line(err)


# ----------------------------------------------------------------------------- step(): k is keyword-only

def test_step_needs_k_as_a_keyword():
    with pytest.raises(TypeError):
        rollplan.step(0.3, 0.4)           # k missing
    with pytest.raises(TypeError):
        rollplan.step(0.3, 0.4, 2.5)      # k given by position
    s = rollplan.step(0.3, 0.4, k=2.5)
    ref = printed_rhs.trace(0.3, 0.4, 2.5)
    assert np.abs(np.r_[s.shift, s.eta] - ref).max() < 1e-10
    assert s.h == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)


# ----------------------------------------------------------------------------- files

@pytest.mark.parametrize("name,ext", [("x.unknownext", "unknownext"), ("x.json", "json")])
def test_plot_with_unsupported_extension_exits_2_before_computing(tmp_path, capsys, name, ext):
    """The target is unreachable (exit 3 if anything were computed): exit 2 shows the
    extension is checked first."""
    out = tmp_path / name
    code, _, err = run(capsys, "plan", "--to", "30", "0", "--k", "2.5", "--plot", str(out))
    assert code == 2 and ext in err and one_line(err)
    assert not out.exists() and not list(tmp_path.iterdir())


def test_robot_file_not_utf8_exits_2_naming_the_file(tmp_path, capsys):
    robot = tmp_path / "latin1-robot.toml"
    robot.write_bytes("radius = 0.1  # Kreisel \u00e4\u00f6\n".encode("latin-1") + b"mass_total = 1.2\n")
    code, _, err = run(capsys, "plan", "--to", "0.05", "0", "--robot", str(robot))
    assert code == 2 and "latin1-robot.toml" in err and one_line(err)
    with pytest.raises(InputError, match="latin1-robot.toml"):
        rollplan.load_robot(robot)


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
    ref = printed_rhs.trace(0.3, 0.4, 2.5)
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
