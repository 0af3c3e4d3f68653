"""Property-based tests (hypothesis) of what users give rollplan: command-line arguments, robot files, batch CSV
files, route waypoint files and plan JSON files, valid and not. Whatever the input:

* the exit code is 0, 2 or 3 (success, bad input, no plan) -- never 1 (a traceback) nor 4;
* nothing on stderr is a traceback or a CasADi "NaN detected" warning;
* a refusal (exit 2) or no plan (exit 3) is exactly one line on stderr;
* every plan reported with exit 0 is certified: its figure eight, integrated by DOP853 on the paper's printed
  equations (``references``, independent of rollplan), reaches the target within 1e-9 R and rad; a plan or
  route between any two states: its pieces (rolls, leaves, circles), integrated by DOP853 on the printed
  (15), (16), (20) from its start state, end at its goal within 1e-9.

The commands run in this process (fast); stdout and stderr are captured at the file-descriptor level, so the
messages of CasADi's C++ code and of SUNDIALS are seen too. Targets and robots are drawn where planning takes
seconds, not minutes: k <= 10 (high-k plans are the planner's own issue), steps <= 3. The number of examples
per test is 30, or ROLLPLAN_FUZZ_EXAMPLES.
"""

import contextlib
import csv
import functools
import io
import json
import math
import os
import sys
import tempfile
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, event, example, given, settings
from hypothesis import strategies as st

from rollplan.cli import main

import references

pytestmark = pytest.mark.slow

#: Examples per test; ROLLPLAN_FUZZ_EXAMPLES=500 for a longer hunt.
FUZZ = settings(max_examples=int(os.environ.get("ROLLPLAN_FUZZ_EXAMPLES", "30")), deadline=None,
                suppress_health_check=list(HealthCheck))

#: Texts that look like numbers to someone, and are not all numbers to rollplan.
TRICKY = ["\u0661", "\uff11", "1_0", "0x10", "inf", "-inf", "nan", "", " 1", "1e400", "-1e-400", "1e", ".", "--1",
          "1,5", "+", "0" * 120, "1" * 5000, "\u00bd", "1.5.2", "2e-1", "-1e-3", "+.5", "5.", "1E+0"]


@contextlib.contextmanager
def captured():
    """Capture stdout and stderr of Python and of C code (file descriptors 1 and 2)."""
    result = {}
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        py_out, py_err = io.StringIO(), io.StringIO()
        sys.stdout.flush()
        sys.stderr.flush()
        saved = os.dup(1), os.dup(2)
        os.dup2(out.fileno(), 1)
        os.dup2(err.fileno(), 2)
        try:
            with contextlib.redirect_stdout(py_out), contextlib.redirect_stderr(py_err):
                yield result
        finally:
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            os.close(saved[0])
            os.close(saved[1])
            out.seek(0)
            err.seek(0)
            result["out"] = py_out.getvalue() + out.read().decode(errors="replace")
            result["err"] = py_err.getvalue() + err.read().decode(errors="replace")


def run_cli(argv):
    with captured() as streams:
        try:
            code = main(list(argv))
        except SystemExit as exc:   # argparse's own checks
            code = exc.code
    return code, streams["out"], streams["err"]


def check_exit(code, err, allowed=(0, 2, 3)):
    event(f"exit {code}")
    assert code in allowed, err
    assert "Traceback" not in err and "NaN detected" not in err, err
    if code != 0:
        assert len(err.strip().splitlines()) == 1, err


def angle_gap(a: float, b: float) -> float:
    """|a - b| reduced modulo 2 pi exactly (Fraction arithmetic with 2 pi to 700 digits)."""
    two_pi = references.two_pi_fraction()
    d = (Fraction(a) - Fraction(b)) % two_pi
    return float(min(d, two_pi - d))


def certify_pieces(d, goal, start=None):
    """The pieces of a plan or route JSON (``segments``: curve, index, params in units of R, gamma), integrated
    from ``start`` (default the file's ``start``) by DOP853 on the printed (15), (16), (20), reach ``goal``
    (u_a, v_a, psi, u_o, v_o) [plan unit, rad] within 1e-9 (units of R, rad)."""
    from types import SimpleNamespace

    R = d["radius"]
    scale = np.array([R, R, 1.0, 1.0, 1.0])
    x0 = np.array([d["start"][n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")] if start is None else start) / scale
    pieces = [SimpleNamespace(**seg) for seg in d["segments"]]
    final = references.composed_final(pieces, x0, d["k"]) if pieces else x0
    gap = np.asarray(final) - np.asarray(goal, float) / scale
    gap[2] = angle_gap(final[2], goal[2])
    assert np.linalg.norm(gap) < 1.05e-9, (gap, d["segments"][:4], goal)


def certify(fe, k, steps, radius, target):
    """The figure eight (a, b, gamma) in the plan's length unit, traced ``steps`` times by DOP853 on the
    printed equations, reaches ``target`` (u_a, v_a, psi) within 1e-9 (units of R, rad)."""
    x = references.trace(fe["a"] / radius, fe["b"] / radius, k, fe["gamma"], steps)
    u, v, psi = target
    gap = math.hypot(math.hypot(x[0] - u / radius, x[1] - v / radius), angle_gap(x[2], psi))
    assert gap < 1.05e-9, (gap, fe, k, steps, radius, target)


# ----------------------------------------------------------------------------- command-line arguments


@st.composite
def number_text(draw, low, high):
    """Mostly a number in [low, high] as repr or in exponent form, one time in eight a tricky text."""
    if draw(st.integers(0, 7)) == 0:
        return draw(st.sampled_from(TRICKY))
    x = draw(st.floats(low, high))
    return draw(st.sampled_from([repr(x), f"{x:.3e}", f"{x:.6f}"]))


@FUZZ
@given(u=number_text(-2.5, 2.5), v=number_text(-2.5, 2.5), psi=st.one_of(number_text(-8, 8), st.just("1e8")),
       steps=st.one_of(*[st.integers(1, 3).map(str)] * 4,
                       st.sampled_from(["0", "1001", "2.5", "1e0", "x", "\uff12"])),
       k=st.one_of(st.none(), number_text(0, 10), number_text(0, 10), st.sampled_from(["-1", "100.5", "1e9"])),
       radius=st.one_of(st.none(), st.none(), number_text(1e-3, 1e3), st.sampled_from(["0", "-1"])),
       method=st.sampled_from(["ipopt", "newton"]),
       start=st.one_of(st.none(), st.none(), st.tuples(number_text(-1, 1), number_text(-1, 1), number_text(-3, 3),
                                                       number_text(-0.6, 0.6), number_text(-0.6, 0.6))),
       contact=st.one_of(st.none(), st.none(), st.tuples(number_text(-0.6, 0.6), number_text(-1.6, 1.6))),
       legs=st.sampled_from([None, None, "one", "fallback", "two"]))
def test_plan_arguments(tmp_path_factory, u, v, psi, steps, k, radius, method, start, contact, legs):
    out = tmp_path_factory.mktemp("plan") / "p.json"
    argv = ["plan", "--to", u, v, f"--psi={psi}", "--steps", steps, "--method", method, "--json", str(out),
            "--polish", "off"]
    if start is not None:
        argv += ["--from", *start]
    if contact is not None:
        argv += ["--contact", *contact]
    if legs is not None:
        argv += ["--legs", legs]
    if k is not None:
        argv += [f"--k={k}"]
    if radius is not None:
        argv += [f"--radius={radius}"]
    code, _, err = run_cli(argv)
    check_exit(code, err)
    if code == 0:
        d = json.loads(out.read_text())
        tg = d["target"]
        assert (tg["u_a"], tg["v_a"], tg["psi"]) == (float(u), float(v), float(psi))
        goal = (float(u), float(v), float(psi), *(map(float, contact) if contact is not None else (0.0, 0.0)))
        certify_pieces(d, goal, [float(x) for x in start] if start is not None else [0.0] * 5)
        if "figure_eight" in d and start is None and contact is None and d["mode"] == "one":
            certify(d["figure_eight"], d["k"], d["steps"], d["radius"], (tg["u_a"], tg["v_a"], tg["psi"]))
    else:
        assert not out.exists()


@FUZZ
@given(a=number_text(0, 0.69), b=st.one_of(st.none(), number_text(0, 0.69)), k=number_text(0, 10),
       gamma=st.one_of(st.none(), number_text(-1e3, 1e3)))
def test_step_arguments(a, b, k, gamma):
    argv = ["step", f"--a={a}", f"--k={k}", "--json", "-"] + ([f"--b={b}"] if b is not None else []) + \
        ([f"--gamma={gamma}"] if gamma is not None else [])
    code, out, err = run_cli(argv)
    check_exit(code, err)
    if code == 0:   # full precision from the JSON on stdout (summaries have 6 digits)
        eta = json.loads(out)["eta"]
        ref = references.trace(float(a), float(b if b is not None else a), float(k), float(gamma or 0.0))
        assert abs(eta - ref[2]) < 1e-9


# ----------------------------------------------------------------------------- robot files

ROBOT_KEYS = ("radius", "mass_total", "mass_shell", "rotor_inertia_axial", "rotor_inertia_transverse")
LIMIT_KEYS = ("max_rotor_rate", "max_rotor_torque")


def toml_value():
    floats = st.floats(allow_nan=True, allow_infinity=True).map(
        lambda x: "nan" if math.isnan(x) else ("inf" if x == math.inf else ("-inf" if x == -math.inf else repr(x))))
    return st.one_of(floats, st.integers(-10**30, 10**30).map(str), st.just("1" * 500),
                     st.text(max_size=8).map(json.dumps), st.booleans().map(lambda b: "true" if b else "false"),
                     st.just("[1, 2]"), st.just("{x = 1}"), st.just("1979-05-27"), st.just("[" * 200 + "]" * 200))


@st.composite
def plausible_robot(draw):
    """A robot that exists: J_r <= 2 J_p, rotor inertias within what the non-shell mass can have."""
    radius = draw(st.floats(0.04, 0.3))
    shell = draw(st.floats(0.1, 2.0))
    total = shell + draw(st.floats(0.05, 2.0))
    jp = draw(st.floats(0.01, 0.4)) * (total - shell) * radius**2
    jr = draw(st.floats(0.05, 2.0)) * jp
    return {"radius": radius, "mass_total": total, "mass_shell": shell, "rotor_inertia_axial": jr,
            "rotor_inertia_transverse": jp}


@st.composite
def robot_text(draw):
    kind = draw(st.sampled_from(["plausible", "plausible", "changed", "garbage"]))
    robot = draw(plausible_robot())
    entries = {key: repr(value) for key, value in robot.items()}
    if draw(st.booleans()):
        entries["max_rotor_rate"] = repr(draw(st.floats(50.0, 1000.0)))
        entries["max_rotor_torque"] = repr(draw(st.floats(0.01, 1.0)))
    if kind == "changed":
        for key in draw(st.lists(st.sampled_from(ROBOT_KEYS + LIMIT_KEYS + ("colour",)), min_size=1, max_size=3)):
            if draw(st.booleans()) and key in entries:
                del entries[key]
            else:
                entries[key] = draw(toml_value())
    text = "".join(f"{key} = {value}\n" for key, value in entries.items())
    if kind == "garbage":
        text = draw(st.sampled_from([text[: draw(st.integers(0, len(text)))], draw(st.text(max_size=60)),
                                     text.replace("=", "==", 1)]))
    data = text.encode()
    if draw(st.booleans()):
        data = b"\xef\xbb\xbf" + data
    return data, robot if kind == "plausible" else None


#: A robot (k = 4.7) for which the target has no one-leg plan: plan answers with a composed plan of two legs.
TWO_LEGS = (b"radius = 0.28125\nmass_total = 2.0\nmass_shell = 1.0\nrotor_inertia_axial = 0.03955078125\n"
            b"rotor_inertia_transverse = 0.019775390625\n",
            {"radius": 0.28125, "mass_total": 2.0, "mass_shell": 1.0, "rotor_inertia_axial": 0.03955078125,
             "rotor_inertia_transverse": 0.019775390625})


@FUZZ
@given(robot=robot_text(), to=st.floats(0.01, 0.08), psi=st.floats(-1, 1))
@example(robot=TWO_LEGS, to=0.015625, psi=0.75)
def test_robot_files(tmp_path_factory, robot, to, psi):
    data, plausible = robot
    if plausible is not None:
        assume(references.inertia_ratio(**plausible) <= 10)
    folder = tmp_path_factory.mktemp("robot")
    (folder / "robot.toml").write_bytes(data)
    out = folder / "p.json"
    code, _, err = run_cli(["plan", "--robot", str(folder / "robot.toml"), "--to", "0", repr(to),
                            f"--psi={psi!r}", "--json", str(out)])
    check_exit(code, err)
    if plausible is not None:
        assert code in (0, 3), err   # a robot that exists is never refused
    if code == 0:
        d = json.loads(out.read_text())
        if plausible is not None:
            assert d["radius"] == plausible["radius"]
        if "segments" in d:   # a composed plan: two legs (issue 12)
            certify_pieces(d, (0.0, to, psi, 0.0, 0.0))
        else:
            certify(d["figure_eight"], d["k"], 1, d["radius"], (0.0, to, psi))


# ----------------------------------------------------------------------------- batch CSV files

COLUMNS = ["u_a", "v_a", "psi", "steps", "k"]


@st.composite
def csv_header(draw, columns, extras):
    """The header ``columns``, or with a column added, missing, twice, or the columns shuffled."""
    header = list(columns)
    change = draw(st.sampled_from(["none", "none", "none", "extra", "shuffle", "drop", "duplicate"]))
    if change == "extra":
        header.append(draw(st.sampled_from(extras)))
    elif change == "shuffle":
        header = draw(st.permutations(header))
    elif change == "drop":
        header.remove(draw(st.sampled_from(columns)))
    elif change == "duplicate":
        header.append(draw(st.sampled_from(columns)))
    return header


@st.composite
def targets_csv(draw):
    header = draw(csv_header(COLUMNS, ["note", "id", ""]))
    values = {"u_a": number_text(-2, 2), "v_a": number_text(-2, 2), "psi": number_text(-4, 4),
              "steps": st.one_of(st.integers(1, 3).map(str), st.sampled_from(["0", "x", "2.0"])),
              "k": number_text(0, 6)}
    rows = []
    for _ in range(draw(st.integers(0, 3))):
        row = [draw(values.get(h, st.text(alphabet="abc ,\"", max_size=5))) for h in header]
        if draw(st.integers(0, 9)) == 0:
            row = row[:-1] if draw(st.booleans()) else row + ["9"]
        rows.append(row)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(header)
    writer.writerows(rows)
    data = buf.getvalue().encode()
    if draw(st.booleans()):
        data = b"\xef\xbb\xbf" + data
    return data, len(rows)


@FUZZ
@given(csv_file=targets_csv())
def test_batch_files(tmp_path_factory, csv_file):
    data, count = csv_file
    folder = tmp_path_factory.mktemp("batch")
    (folder / "t.csv").write_bytes(data)
    out = folder / "o.jsonl"
    code, _, err = run_cli(["batch", str(folder / "t.csv"), "--out", str(out), "--jobs", "1", "--quiet"])
    check_exit(code, err, (0, 1, 2, 3))   # batch: 1 some rows failed, 3 every row failed (issue 18)
    if code == 2:
        return
    lines = [json.loads(x) for x in out.read_text().splitlines()]
    failed = sum(d["status"] != "ok" for d in lines)
    assert code == (0 if failed == 0 else 3 if failed == len(lines) else 1)
    assert [d["index"] for d in lines] == list(range(count))
    for d in lines:
        assert d["status"] in ("ok", "failed")
        assert d["status"] == "ok" or d["error"] in ("InputError", "NoPlanError"), d
        if d["status"] == "ok":
            # a missing column or an empty cell takes the documented default (docs/batches.md)
            row = {**{"psi": "0", "steps": "1", "k": "2.5"}, **{c: v for c, v in d["input"].items() if v != ""}}
            target = (float(row["u_a"]), float(row["v_a"]), float(row["psi"]))
            assert "figure_eight" in d or "segments" in d, d
            if "segments" in d:   # a composed plan: a turn in place or two legs (issue 12)
                certify_pieces(d, (*target, 0.0, 0.0))
            if "figure_eight" in d:
                certify(d["figure_eight"], float(row["k"]), int(row["steps"]), 1.0, target)


# ----------------------------------------------------------------------------- plan JSON files


#: Samples per piece of the smooth-cruise plan file (the law's own: 16000): 3000 give a file with the same keys,
#: pieces and repeated time (the step of the torques between the stretches) under a fifth the size, and its
#: rotor-only replay still arrives within 1e-7 (and within 1e-9 of the reference's replay, references.rotor_drive).
FUZZ_SAMPLES_PER_PIECE = 3000


@pytest.fixture(scope="module", params=["pole", "composed"])
def plan_json(tmp_path_factory, request):
    """A plan with its motion, as written by plan --duration: pole to pole (default robot), or from a start off
    the pole timed by the smooth-cruise law within a robot's motor limits (sampled
    :data:`FUZZ_SAMPLES_PER_PIECE` times per piece: each example writes, reads and replays the whole file)."""
    from rollplan.execution.timing import SmoothCruise

    folder = tmp_path_factory.mktemp("planjson")
    out = folder / "plan.json"
    if request.param == "pole":
        argv = ["plan", "--to", "0.03", "0.05", "--psi", "0.3", "--duration", "4", "--samples", "800"]
    else:
        (folder / "r.toml").write_text("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2e-4\n"
                                       "rotor_inertia_transverse = 1.2e-4\nmax_rotor_rate = 300.0\n"
                                       "max_rotor_torque = 0.05\n")
        argv = ["plan", "--robot", str(folder / "r.toml"), "--from", "0", "0", "0", "0.2", "0", "--to", "0.03",
                "0.05", "--psi", "0.3", "--timing", "smooth-cruise", "--samples", "800"]
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(SmoothCruise, "samples_per_piece", FUZZ_SAMPLES_PER_PIECE)
        code, _, err = run_cli([*argv, "--json", str(out)])
    assert code == 0, err
    if request.param == "composed":   # what the file stands for: pieces and a time given twice
        d = json.loads(out.read_text())
        assert d["timing"] == "smooth-cruise" and len(d["segments"]) == 3 and len(d["torque_breaks"]) == 1
        assert len(d["time"]) <= 3 * FUZZ_SAMPLES_PER_PIECE + 3
    return out


def json_value():
    return st.one_of(st.none(), st.booleans(), st.floats(allow_nan=False, allow_infinity=False),
                     st.integers(-10**20, 10**20), st.text(max_size=5), st.just([]), st.just({}),
                     st.just([[1.0, 2.0]]), st.just({"u_a": "0"}))


class Mutated:
    """A plan file's bytes after one mutation (its repr names the mutation only)."""

    def __init__(self, raw: bytes, kind: str, detail: str = "") -> None:
        self.raw, self.kind, self.detail = raw, kind, detail

    def __repr__(self) -> str:
        return f"Mutated({self.kind} {self.detail}, {len(self.raw)} bytes)"


@functools.lru_cache(maxsize=2)
def plan_data(path):
    """The plan file's value, read once, and each of its top-level values as ``json.dumps`` writes it."""
    data = json.loads(path.read_text())
    return data, {key: json.dumps(value) for key, value in data.items()}


@functools.lru_cache(maxsize=2)
def rotor_reference(path) -> np.ndarray:
    """The final state (u_a, v_a, psi, u_o, v_o) of the plan file's rotor rates alone, by
    ``references.rotor_drive`` (DOP853 on the printed equations), integrated once for every unchanged copy of the
    file that a test simulates."""
    d = plan_data(path)[0]
    x0 = [d["start"][n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")]
    t = np.asarray(d["time"])
    keep = np.r_[True, np.diff(t) > 0]   # a time given twice is a step of the torques: the rates once
    return references.rotor_drive(d["robot"], t[keep], np.asarray(d["rotor_rates"])[keep], x0)[-1]


def dumps_plan(data, path) -> str:
    """``json.dumps(data)`` for a shallow copy of the plan file's value: the values it shares are not written
    again."""
    base, texts = plan_data(path)
    return "{" + ", ".join(f"{json.dumps(key)}: {texts[key] if base.get(key) is value else json.dumps(value)}"
                           for key, value in data.items()) + "}"


@st.composite
def plan_file(draw, path):
    data = dict(plan_data(path)[0])   # the values changed below are replaced, never changed in place
    kind = draw(st.sampled_from(["same", "drop", "replace", "robot", "scale", "text", "text"]))
    if kind == "drop":
        del data[draw(st.sampled_from(["time", "rotor_rates", "robot", "target", "start", "goal"]))]
    elif kind == "replace":
        data[draw(st.sampled_from(["time", "rotor_rates", "robot", "target", "start", "goal"]))] = draw(json_value())
    elif kind == "robot":
        key = draw(st.sampled_from([*ROBOT_KEYS, *LIMIT_KEYS, "k", "colour"]))
        data["robot"] = {**data["robot"], key: draw(json_value())}
    elif kind == "scale":
        factor = 10.0 ** draw(st.integers(-300, 300))
        data["rotor_rates"] = [[r * factor for r in row] for row in data["rotor_rates"]]
        # which times are scaled too: one draw for the whole column (a draw per sample would overrun the
        # choices Hypothesis allows an example on a long file); all, none or each at random
        share = draw(st.sampled_from([0.0, 0.5, 1.0]))
        scaled = np.random.default_rng(draw(st.integers(0, 2**32 - 1))).random(len(data["time"])) < share
        data["time"] = [t * factor if s else t for t, s in zip(data["time"], scaled)]
    raw = dumps_plan(data, path)
    if kind == "text":
        edit = draw(st.sampled_from(["truncate", "nan", "huge", "int", "deep", "bom", "latin1"]))
        if edit == "truncate":
            raw = raw[: draw(st.integers(0, len(raw)))]
        elif edit == "nan":
            raw = raw.replace('"psi": ', '"psi": NaN, "x": ', 1)
        elif edit == "huge":
            raw = raw.replace('"time": [0.0', '"time": [1e400', 1)
        elif edit == "int":
            raw = raw.replace('"time": [0.0', '"time": [' + "9" * 5000, 1)
        elif edit == "deep":
            raw = raw.replace('"robot": {', '"deep": ' + "[" * 100000 + "]" * 100000 + ', "robot": {', 1)
        elif edit == "bom":
            raw = "\ufeff" + raw
        else:
            return Mutated(raw.encode("utf-8").replace(b'"k"', b'"\xe4"', 1), kind, edit)
        return Mutated(raw.encode(), kind, edit)
    return Mutated(raw.encode(), kind)


@FUZZ
@given(data=st.data(), command=st.sampled_from(["simulate", "simulate", "simulate", "animate"]))
def test_plan_files(tmp_path_factory, plan_json, data, command):
    mutated = data.draw(plan_file(plan_json))
    raw, kind = mutated.raw, mutated.kind
    folder = tmp_path_factory.mktemp("planfile")
    (folder / "plan.json").write_bytes(raw)
    extra = ["--json", str(folder / "sim.json")] if command == "simulate" else ["--out", str(folder / "a.gif"),
                                                                              "--frames", "2"]
    code, out, err = run_cli([command, str(folder / "plan.json"), *extra])
    check_exit(code, err)
    if code == 0 and command == "simulate":
        sim = json.loads((folder / "sim.json").read_text())
        assert all(math.isfinite(v) for v in sim["final"].values())
        if kind == "same":
            assert sim["arrival_error"] < 1e-6
            # two cubic splines through the same samples, two integrators: agree far below the 1e-6 tolerance
            assert np.allclose([sim["final"][n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")],
                               rotor_reference(plan_json), atol=1e-8)


@pytest.mark.parametrize("plan_json", ["composed"], indirect=True)
def test_every_mutation_of_the_largest_plan_file_is_drawn(plan_json):
    """Each kind of mutation is drawn whole for the longest file too (a draw per sample overran the choices
    Hypothesis allows an example: the example was dropped, and scaled files of composed plans never ran)."""
    kinds = set()

    @settings(max_examples=40, deadline=None, database=None, derandomize=True,
              suppress_health_check=list(HealthCheck))
    @given(data=st.data())
    def draw(data):
        kinds.add(data.draw(plan_file(plan_json)).kind)

    draw()
    assert kinds == {"same", "drop", "replace", "robot", "scale", "text"}


def json_text_value():
    """JSON values as text: nested lists (tables of rows among them) and objects of numbers (some too large for a
    double), strings, booleans and null."""
    number = st.one_of(st.floats(allow_nan=False, allow_infinity=False).map(repr), st.integers(-10**6, 10**6).map(str),
                       st.sampled_from(["1e400", "-2.5e308", "1e-400", "2e308", "0.5"]))
    scalar = st.one_of(number, number, st.sampled_from(['"x"', "true", "null"]))
    row = st.lists(number, max_size=4).map(lambda xs: "[" + ", ".join(xs) + "]")
    return st.recursive(st.one_of(scalar, row), lambda inner: st.one_of(
        st.lists(inner, max_size=4).map(lambda xs: "[" + ", ".join(xs) + "]"),
        st.lists(row, max_size=4).map(lambda xs: "[" + ", ".join(xs) + "]"),
        st.dictionaries(st.sampled_from("abc"), inner, max_size=3).map(
            lambda d: "{" + ", ".join(f'"{k}": {v}' for k, v in d.items()) + "}")), max_leaves=40)


def text_depth(text: str) -> int:
    """Deepest nesting of brackets and braces in a JSON text without strings holding them."""
    deepest = level = 0
    for ch in text:
        level += ch in "[{"
        level -= ch in "]}"
        deepest = max(deepest, level)
    return deepest


@FUZZ
@given(text=json_text_value(), wrap=st.integers(0, 34))
def test_plan_json_numbers_and_depth(tmp_path_factory, text, wrap):
    """The JSON reader of plan files takes a value if and only if every number is finite as a double and it is
    nested at most MAX_DEPTH deep; the value is what Python's json module reads; a refusal names the first
    number too large."""
    from rollplan.errors import InputError
    from rollplan.inputs import MAX_DEPTH, load_json

    text = "[" * wrap + text + "]" * wrap
    path = tmp_path_factory.mktemp("json") / "p.json"
    path.write_text(text)
    numbers = []
    json.loads(text, parse_float=numbers.append, parse_int=lambda s: 0)
    large = [x for x in numbers if math.isinf(float(x))]
    if large:
        with pytest.raises(InputError, match=f"the number '{large[0]}' is too large for a double"):
            load_json(path, "plan file")
    elif text_depth(text) > MAX_DEPTH:
        with pytest.raises(InputError, match="nested too deeply"):
            load_json(path, "plan file")
    else:
        assert load_json(path, "plan file") == json.loads(text)


# ----------------------------------------------------------------------------- route waypoint files

WAYPOINT_COLUMNS = ["u_a", "v_a", "psi", "u_o", "v_o", "steps", "label"]


@st.composite
def waypoints_csv(draw):
    """A waypoints file: plausible rows near the pole (a move, a turn, a state off the pole) or mutated ones."""
    header = draw(csv_header(WAYPOINT_COLUMNS, ["note", ""]))
    values = {"u_a": number_text(-0.5, 0.5), "v_a": number_text(-0.5, 0.5), "psi": number_text(-2, 2),
              "u_o": st.one_of(st.just(""), number_text(-0.4, 0.4), st.just("1.56")),
              "v_o": st.one_of(st.just(""), number_text(-0.4, 0.4)),
              "steps": st.one_of(st.just(""), st.just(""), st.integers(1, 2).map(str), st.sampled_from(["0", "x"])),
              "label": st.text(alphabet="ab ,\"#", max_size=5)}
    rows = []
    for i in range(draw(st.integers(0, 3))):
        row = [draw(values.get(h, st.text(alphabet="abc ,", max_size=5))) for h in header]
        if i == 0 and "steps" in header and draw(st.integers(0, 3)) != 0:
            row[header.index("steps")] = ""
        if draw(st.integers(0, 9)) == 0:
            row = row[:-1] if draw(st.booleans()) else row + ["9"]
        rows.append(row)
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    if draw(st.booleans()):
        buf.write("# waypoints\n")
    writer.writerow(header)
    writer.writerows(rows)
    data = buf.getvalue().encode()
    if draw(st.booleans()):
        data = b"\xef\xbb\xbf" + data
    return data


@FUZZ
@given(data=waypoints_csv(), k=st.sampled_from(["2.5", "5"]))
def test_route_files(tmp_path_factory, data, k):
    folder = tmp_path_factory.mktemp("route")
    (folder / "w.csv").write_bytes(data)
    out = folder / "r.json"
    code, _, err = run_cli(["route", str(folder / "w.csv"), "--k", k, "--legs", "one", "--json", str(out)])
    check_exit(code, err)
    if code == 0:
        d = json.loads(out.read_text())
        goal = [d["goal"][n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")]
        certify_pieces(d, goal)
        first = d["waypoints"][0]
        assert [d["start"][n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")] == \
            [first[n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")]
    else:
        assert not out.exists()
