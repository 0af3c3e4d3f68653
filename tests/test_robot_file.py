"""Robot files: the shipped default, the inertia ratio (14), and refusal of bad files (exit 2, naming the key)."""

import math
import re

import pytest

import rollplan
from rollplan import InputError, Robot, load_robot
from rollplan.cli import main
from rollplan.robot import default_robot

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
        line = next(l for l in text.splitlines() if l.startswith(name))
        assert re.search(r"#.*\[(m|kg|kg m\^2)\]", line), line  # each value documented with its unit


def test_inertia_ratio_14():
    rob = Robot(**GOOD)
    jzz = 2 / 3 * 0.5 * 0.12**2 + 2 * 2e-4 + 3e-4
    assert rob.k == pytest.approx(1 + 2.0 * 0.12**2 / jzz, rel=1e-15)  # (14) as printed
    assert rob.j_xx == pytest.approx(jzz + 2.0 * 0.12**2, rel=1e-15)
    assert rob.as_dict()["k"] == rob.k


def test_good_file(tmp_path):
    assert load_robot(write(tmp_path, GOOD)) == Robot(**GOOD)


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


def test_unreadable_and_invalid_files(tmp_path, capsys):
    assert main(["plan", "--robot", str(tmp_path / "none.toml")]) == 2
    assert "cannot be read" in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text("radius = = 1\n")
    assert main(["plan", "--robot", str(bad)]) == 2
    assert "not valid TOML" in capsys.readouterr().err


def test_to_is_in_metres_with_a_robot(tmp_path):
    p = rollplan.plan((0.0, 0.12, 0.0), 1, robot=Robot(**GOOD))
    assert p.radius == 0.12 and p.final[1] == pytest.approx(0.12, abs=1e-10)
    # the same motion in units of R with the same k
    q = rollplan.plan((0.0, 1.0, 0.0), 1, k=Robot(**GOOD).k)
    assert p.a == pytest.approx(0.12 * q.a, rel=1e-9) and math.isclose(p.gamma, q.gamma, abs_tol=1e-9)
