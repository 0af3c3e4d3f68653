"""CLI: plan --duration, simulate, animate."""

import json
import re

import numpy as np
import pytest

from rollplan import Robot
from rollplan.cli import main

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


def test_animate_writes_a_gif(planned, tmp_path):
    _, _, out, _ = planned
    gif = tmp_path / "roll.gif"
    assert main(["animate", str(out), "--out", str(gif), "--frames", "3"]) == 0
    from PIL import Image

    assert gif.read_bytes()[:6] in (b"GIF89a", b"GIF87a")
    assert Image.open(gif).n_frames == 3
