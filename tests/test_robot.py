"""Robot parameters (rollplan.robot): the shipped default file, the inertia ratio (14), refusal of bad
files (InputError and CLI exit 2, naming the key), and plans in metres with a robot."""

import math
import re

import pytest

import rollplan
from rollplan import InputError, Robot, load_robot
from rollplan.cli import main
from rollplan.robot import default_robot

import references

GOOD = {"radius": 0.12, "mass_total": 2.0, "mass_shell": 0.5, "rotor_inertia_axial": 3e-4,
        "rotor_inertia_transverse": 2e-4}


def write(tmp_path, entries, name="robot.toml"):
    path = tmp_path / name
    path.write_text("".join(f"{k} = {v}\n" for k, v in entries.items()))
    return path


def test_default_file_is_documented_and_equals_defaults():
    from importlib.resources import files

    text = files("rollplan").joinpath("data/default_robot.toml").read_text()
    assert default_robot() == Robot()
    for name in GOOD:
        line = next(row for row in text.splitlines() if row.startswith(name))
        assert re.search(r"#.*\[(m|kg|kg m\^2)\]", line), line  # each value documented with its unit


def test_inertia_ratio_14():
    rob = Robot(**GOOD)
    jzz = 2 / 3 * 0.5 * 0.12**2 + 2 * 2e-4 + 3e-4
    assert rob.k == pytest.approx(references.inertia_ratio(**GOOD), rel=1e-15)  # (14) as printed
    assert rob.j_xx == pytest.approx(jzz + 2.0 * 0.12**2, rel=1e-15)
    assert rob.as_dict()["k"] == rob.k


def test_good_file(tmp_path):
    assert load_robot(write(tmp_path, GOOD)) == Robot(**GOOD)


def test_motor_limits_are_optional(tmp_path):
    """max_rotor_rate and max_rotor_torque: absent means unlimited (None); given, they are kept."""
    rob = load_robot(write(tmp_path, GOOD))
    assert rob.max_rotor_rate is None and rob.max_rotor_torque is None
    assert "max_rotor_rate" not in rob.as_dict()
    limited = load_robot(write(tmp_path, {**GOOD, "max_rotor_rate": 250, "max_rotor_torque": 0.04}))
    assert limited == Robot(**GOOD, max_rotor_rate=250, max_rotor_torque=0.04)
    assert limited.k == rob.k and limited.as_dict()["max_rotor_torque"] == 0.04
    only_rate = load_robot(write(tmp_path, {**GOOD, "max_rotor_rate": 250.0}))
    assert only_rate.max_rotor_torque is None


@pytest.mark.parametrize("change, key", [
    ({"radius": None}, "radius"),                       # missing
    ({"colour": "'red'"}, "colour"),                    # unknown
    ({"mass_shell": -0.5}, "mass_shell"),               # negative
    ({"rotor_inertia_axial": 0}, "rotor_inertia_axial"),  # zero
    ({"mass_total": "nan"}, "mass_total"),              # non-finite
    ({"rotor_inertia_transverse": "inf"}, "rotor_inertia_transverse"),
    ({"radius": "true"}, "radius"),                     # not a number
    ({"radius": "'0.1'"}, "radius"),
    ({"mass_shell": 3.0}, "mass_shell"),                # heavier than the whole robot
    ({"max_rotor_rate": 0}, "max_rotor_rate"),          # the optional limits: finite numbers > 0
    ({"max_rotor_torque": -0.05}, "max_rotor_torque"),
    ({"max_rotor_torque": "nan"}, "max_rotor_torque"),
    ({"max_rotor_rate": "inf"}, "max_rotor_rate"),
    ({"max_rotor_rate": "'fast'"}, "max_rotor_rate"),
    ({"max_rotor_torque": "false"}, "max_rotor_torque"),
    ({"max_torque": 0.05}, "max_torque"),               # unknown (the key is max_rotor_torque)
])
def test_bad_file_names_the_key(tmp_path, capsys, change, key):
    entries = {**GOOD, **change}
    entries = {k: v for k, v in entries.items() if v is not None}
    path = write(tmp_path, entries)
    with pytest.raises(InputError, match=key):
        load_robot(path)
    code = main(["plan", "--robot", str(path), "--to", "0", "0.1"])
    err = capsys.readouterr().err
    assert code == 2 and key in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_robot_file_not_utf8_exits_2_naming_the_file(tmp_path, capsys):
    robot = tmp_path / "latin1-robot.toml"
    robot.write_bytes("radius = 0.1  # Kreisel \u00e4\u00f6\n".encode("latin-1") + b"mass_total = 1.2\n")
    code = main(["plan", "--to", "0.05", "0", "--robot", str(robot)])
    err = capsys.readouterr().err
    assert code == 2 and "latin1-robot.toml" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    with pytest.raises(InputError, match="latin1-robot.toml"):
        load_robot(robot)


def test_to_is_in_metres_with_a_robot(tmp_path):
    p = rollplan.plan((0.0, 0.12, 0.0), 1, robot=Robot(**GOOD))
    assert p.radius == 0.12 and p.final.v_a == pytest.approx(0.12, abs=1e-10) and p.problem.unit == "m"
    # the same motion in units of R with the same k
    q = rollplan.plan((0.0, 1.0, 0.0), 1, k=Robot(**GOOD).k)
    assert p.a == pytest.approx(0.12 * q.a, rel=1e-9) and math.isclose(p.gamma, q.gamma, abs_tol=1e-9)
