"""Hostile input (issue 29): every flag of every command, and every kind of input file (robot TOML, plan JSON,
batch CSV, waypoints CSV), given a bad value, is refused before any work: exit 2, exactly one line on stderr
naming the flag or the file, no traceback, no output written.

The flags are enumerated from the parser itself (:func:`rollplan.cli.build_parser`): a flag without a case in
:data:`FLAG_CASES` fails :func:`test_every_flag_of_every_command_has_a_case`. The refusals come before any
planning, so the cases and the regressions of the issue's findings run the command in this process.
"""

import argparse
import json
import math
import os

import pytest
from conftest import one_line, run

from rollplan.cli import build_parser
from rollplan.errors import SHOW_WIDTH

import references

ROBOT = ("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2e-4\n"
         "rotor_inertia_transverse = 1.2e-4\n")
WAYPOINTS = "u_a,v_a,psi,label\n0,0,0,home\n0.5,0.3,0.4,a\n"
TARGETS = "u_a,v_a,psi\n0,1,0\n"

#: Each command with valid arguments (outputs included); a case appends its bad flag (the last one given wins).
BASE = {
    "plan": ["plan", "--json", "out.json"],
    "route": ["route", "w.csv", "--json", "out.json"],
    "step": ["step", "--a", "0.3", "--json", "out.json"],
    "reproduce": ["reproduce", "--out", "outdir"],
    "simulate": ["simulate", "plan.json", "--json", "out.json"],
    "animate": ["animate", "plan.json", "--out", "out.gif"],
    "compare": ["compare", "--to", "0.5", "0.3", "--json", "out.json"],
    "codegen": ["codegen", "--out", "outdir"],
    "batch": ["batch", "t.csv", "--out", "out.jsonl"],
    "atlas": ["atlas", "--out", "out.png"],
    "mjcf": ["mjcf", "--out", "out.xml"],
    None: [],   # the options of rollplan itself
}

LONG = "9" * 99   # a number of 99 digits (at most 100 characters are read)
N = ["abc", "1_0", "\uff11", "nan"]   # no number: refused by the one number parser
W = ["1.5", " 1", "\u0661", "1e3"]    # no whole number

#: (command, flag) -> [(values after the flag, text the one line must contain)]; the flag itself is always
#: expected in the message too, unless the text names a file.
FLAG_CASES = {
    (None, "--help"): [(["=1"], "--help")],
    (None, "--version"): [(["=1"], "--version")],
    (None, "--verbose"): [(["=1"], "--verbose")],
}


def _cases(command, flag, *cases):
    FLAG_CASES[(command, flag)] = [(list(values), needle or flag) for values, needle in cases]


def _numbers(command, flag, nargs=1, *extra):
    _cases(command, flag, *[([v] * nargs, None) for v in N], *extra)


def _wholes(command, flag, *extra):
    _cases(command, flag, *[([v], None) for v in W], *extra)


for _c in ("plan", "route", "step", "reproduce", "simulate", "animate", "compare", "codegen", "batch", "atlas", "mjcf"):
    _cases(_c, "--help", (["=1"], "--help"))
for _c in ("plan", "route", "compare"):
    _numbers(_c, "--k", 1, (["200"], None), (["-1"], None))
    _cases(_c, "--robot", (["missing.toml"], "robot file"), (["bad.toml"], "robot file"))
    _numbers(_c, "--radius", 1, (["5e-324"], None), (["0"], None), (["2e3"], None), ([LONG], None))
    _cases(_c, "--json", (["notdir/x.json"], "notdir"), (["robot.toml", "--robot", "robot.toml"], "robot.toml"))
    _cases(_c, "--plot", (["out.txt"], "out.txt"), (["notdir/x.png"], "notdir"))
for _c in ("plan", "compare"):
    _numbers(_c, "--to", 2, (["1e200", "0"], None), (["1e6", "0"], None))
    _numbers(_c, "--psi")
    _wholes(_c, "--steps", (["0"], None), (["1001"], None), ([LONG], None))
_wholes("route", "--steps", (["0"], None), (["1001"], None))
_cases("plan", "--base", (["middle"], None), (["x" * 500], None))
_cases("plan", "--polish", (["slow"], None), (["x" * 500], None))
for _c in ("plan", "route"):
    _cases(_c, "--legs", (["three"], None), (["x" * 500], None))
    _cases(_c, "--method", (["IPOPT"], None))
    _numbers(_c, "--duration", 1, (["-1"], None), (["0"], None))
    _cases(_c, "--timing", (["fast"], None))
    _wholes(_c, "--samples", (["1"], None), (["10000000000"], None))
    _cases(_c, "--timing-plot", (["t.png"], None), (["t.txt"], "t.txt"))
_numbers("plan", "--from", 5, (["0", "0", "0", "2", "0"], None), (["1e300", "0", "0", "0", "0"], None))
_numbers("plan", "--contact", 2, (["1.6", "0"], None), (["1.5", "1.5"], None))
_cases("plan", "--all", (["=1"], None))
_cases("plan", "--refine", (["=1"], None), (["--all"], "--all"), (["--duration", "5"], "--duration"),
       (["--timing", "min-jerk"], "--timing"), (["--plot", "p.png"], "--plot"))
_wholes("plan", "--branch", (["1" * 101], None), (["1_0"], None))
_numbers("step", "--a", 1, (["0.9"], None), (["0"], None))
_numbers("step", "--b", 1, (["0.9"], None), (["-0.1"], None))
_numbers("step", "--k", 1, (["200"], None))
_numbers("step", "--gamma")
_cases("step", "--json", (["notdir/x.json"], "notdir"))
_cases("step", "--curve", (["hexagon"], None), (["Viviani"], None), (["x" * 500], None))
_cases("atlas", "--curve", (["hexagon"], None), (["Circles"], None))
_cases("plan", "--curve", (["hexagon"], None), (["Viviani"], None), (["x" * 500], None))
_cases("compare", "--curve", (["hexagon"], None), (["Viviani"], None))
_cases("codegen", "--curve", (["hexagon"], None), (["Triangle"], None))
_cases("reproduce", "--out", (["w.csv"], "w.csv"), (["w.csv/x"], "w.csv"))
_cases("simulate", "--robot", (["missing.toml"], "robot file"), (["bad.toml"], "robot file"))
_cases("simulate", "--json", (["notdir/x.json"], "notdir"), (["plan.json"], "plan.json"))
_cases("simulate", "--plot", (["out.txt"], "out.txt"))
_cases("simulate", "--closed-loop", (["=1"], None))
_cases("simulate", "--plant", (["voltage"], None))
_numbers("simulate", "--noise", 1, (["5"], None), (["-0.01"], None))
_wholes("simulate", "--seed", (["-1"], None), (["1" * 30], None))
_cases("simulate", "--engine", (["bullet"], None))
_wholes("simulate", "--average", (["0"], None), (["1" * 30], None))
_numbers("simulate", "--tolerance", 1, (["0"], None), (["2"], None), (["-1e-6"], None))
_wholes("simulate", "--corrections", (["-1"], None), (["101"], None))
_cases("simulate", "--mjcf", (["model.xml"], None))   # without --engine mujoco
_numbers("simulate", "--servo", 1, (["5"], None), (["-1", "--engine", "mujoco"], None),
         (["2e3", "--engine", "mujoco"], None))
_cases("mjcf", "--robot", (["missing.toml"], "robot file"), (["bad.toml"], "robot file"))
_cases("mjcf", "--out", (["notdir/x.xml"], "notdir"), (["robot.toml", "--robot", "robot.toml"], "robot.toml"))
_numbers("mjcf", "--com-offset", 3, (["1", "0", "0"], None))
_numbers("mjcf", "--floor-solref", 2, (["0", "1"], None), (["1e-3", "0"], None))
_numbers("mjcf", "--rolling-resistance", 1, (["-1"], None), (["2"], None))
_numbers("mjcf", "--friction", 1, (["0"], None), (["1e9"], None))
_numbers("mjcf", "--timestep", 1, (["1"], None), (["0"], None))
_cases("animate", "--out", (["out.png"], None), (["notdir/a.gif"], "notdir"), (["plan.json"], "plan.json"))
_wholes("animate", "--frames", (["1"], None), (["2001"], None))
_wholes("animate", "--fps", (["0"], None), (["101"], None))
_cases("compare", "--cost", (["time"], None))
_numbers("compare", "--horizon", 1, (["0"], None), (["-1"], None))
_wholes("compare", "--intervals", (["1"], None), (["1000001"], None))
_wholes("compare", "--degree", (["0"], None), (["10"], None))
_cases("compare", "--scheme", (["gauss"], None))
_wholes("compare", "--branches", (["0"], None))
_numbers("compare", "--contact-bound", 1, (["0"], None), (["3"], None))
_cases("codegen", "--out", (["w.csv"], "w.csv"))
_wholes("codegen", "--steps-per-leaf", (["7"], None), (["0"], None))
_cases("codegen", "--prefix", (["1a"], None), (["a-b"], None), (["x" * 500], None))
_numbers("codegen", "--k-max", 1, (["1000"], None), (["0.1"], None))
_cases("codegen", "--real", (["half"], None))
_cases("codegen", "--overwrite", (["=1"], None))
_cases("batch", "--out", (["-"], None), (["t.csv"], "t.csv"), (["notdir/o.jsonl"], "notdir"))
_wholes("batch", "--jobs", (["0"], None), (["100000"], None))
_cases("batch", "--scheduler", (["foo"], None))
_cases("batch", "--resume", (["=1"], None))
_cases("batch", "--overwrite", (["=1"], None))
_cases("batch", "--method", (["IPOPT"], None))
_cases("batch", "--quiet", (["=yes"], None))
_numbers("atlas", "--k", 1, (["200"], None), (["-1"], None))
_wholes("atlas", "--steps", (["0"], None))
_wholes("atlas", "--resolution", (["1"], None), (["100000"], None))
_cases("atlas", "--out", (["a.txt"], "a.txt"), (["notdir/a.png"], "notdir"))
_cases("atlas", "--json", (["notdir/a.json"], "notdir"))
_cases("atlas", "--scheduler", (["foo"], None))

#: (command, the positional) -> [(file name, content or None for absent, text the one line must contain)]: the
#: input files, bad. Plan files: only what is refused today (their contents are checked in test_simulate_file).
FILE_CASES = {
    ("route", "waypoints"): [
        ("w1.csv", "u_a,v_a,psi,label\n0,0,0,home\n1,0,0,\"a\n0,0,0,back\n", "line 3"),
        ("w2.csv", "u_a,v_a,psi\n0,0,0\n1_0,0,0\n", "line 3"),
        ("w3.csv", "u_a,v_a,psi,speed\n0,0,0,1\n1,0,0,1\n", "speed"),
        ("w4.csv", "u_a,v_a,psi\n0,0,0\n", "two waypoints"),
        ("w5.csv", "u_a,v_a,psi,steps\n0,0,0,2\n1,0,0,\n", "line 2"),
        ("w6.csv", "u_a,v_a,psi\n0,0,0\nnan,0,0\n", "line 3"),
        ("w7.csv", "u_a,v_a,psi\n0,0,0\n1e9,0,0\n", "17345"),
        ("w8.csv", "u_a,u_a,psi\n0,0,0\n", "twice"),
        ("w9.csv", "", "empty"),
        ("w10.csv", "u_a,v_a,psi\n0,0,0\n1,0,0,\"x\"y\n", "line 3"),
        ("w11.csv", f"u_a,v_a,psi,{'c' * 300}\n0,0,0,1\n1,0,0,1\n", "'" + "c" * (SHOW_WIDTH - 4) + "..."),
        ("missing.csv", None, "does not exist"),
    ],
    ("batch", "targets"): [
        ("t1.csv", "u_a,v_a,psi,note\n0,1,0,\"open\n0.5,0.3,0.4,x\n", "line 2"),
        ("t2.csv", "u_a,psi\n0,1\n", "lacks"),
        ("t3.csv", "u_a,v_a,v_a\n0,1,2\n", "twice"),
        ("t4.csv", "", "empty"),
        ("t5.csv", b"u_a,v_a\n0,\xff\n", "UTF-8"),
        ("t6.csv", f"u_a,v_a,{'c' * 300},{'c' * 300}\n0,1,2,3\n", "'" + "c" * (SHOW_WIDTH - 4) + "..."),
        ("missing.csv", None, "does not exist"),
    ],
    ("plan", "--robot"): [
        ("r1.toml", "radius = = 1\n", "not valid TOML"),
        ("r2.toml", ROBOT.replace("radius = 0.1", "radius = -0.1"), "radius"),
        ("r3.toml", ROBOT.replace("radius = 0.1\n", ""), "radius"),
        ("r4.toml", ROBOT + "colour = 1\n", "colour"),
        ("r5.toml", ROBOT.replace("radius = 0.1", 'radius = "0.1"'), "radius"),
        ("r6.toml", ROBOT.replace("radius = 0.1", "radius = 1e-320"), "radius"),
        ("r7.toml", ROBOT.replace("mass_shell = 0.4", "mass_shell = 2.0"), "mass_shell"),
        ("r8.toml", ROBOT + "max_rotor_rate = nan\n", "max_rotor_rate"),
        ("r9.toml", ROBOT + f"{'c' * 300} = 1\n", "'" + "c" * (SHOW_WIDTH - 4) + "..."),
    ],
    ("simulate", "plan_file"): [
        ("p1.json", "{", "not valid JSON"),
        ("p2.json", "[]", "p2.json"),
        ("p3.json", "{}", "time"),
        ("p4.json", '{"time": NaN}', "p4.json"),
        ("missing.json", None, "does not exist"),
    ],
    ("animate", "plan_file"): [
        ("p1.json", "{", "not valid JSON"),
        ("p3.json", "{}", "time"),
        ("missing.json", None, "does not exist"),
    ],
}


def _commands():
    """{command or None: [its options]}: every flag of every command, from the parser."""
    parser = build_parser()
    flags = {None: [a.option_strings[-1] for a in parser._actions if a.option_strings]}
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    for name, p in sub.choices.items():
        p.format_help()   # builds the options of a command that adds them on first use
        flags[name] = [a.option_strings[-1] for a in p._actions if a.option_strings]
    return flags, sub


def _positionals():
    _, sub = _commands()
    return {(name, a.dest) for name, p in sub.choices.items() for a in p._actions if not a.option_strings}


def _write_inputs(path):
    """Valid input files (and a plan.json that is read only after the options) in the folder ``path``."""
    (path / "robot.toml").write_text(ROBOT)
    (path / "bad.toml").write_text("radius = = 1\n")
    (path / "w.csv").write_text(WAYPOINTS)
    (path / "t.csv").write_text(TARGETS)
    (path / "plan.json").write_text("{}")
    (path / "notdir").write_text("a file, not a folder\n")


@pytest.fixture
def folder(tmp_path, monkeypatch):
    """A working folder of its own with valid input files, for a test that writes input files there."""
    monkeypatch.chdir(tmp_path)
    _write_inputs(tmp_path)
    return tmp_path


@pytest.fixture(scope="module")
def _shared_inputs(tmp_path_factory):
    path = tmp_path_factory.mktemp("inputs")
    _write_inputs(path)
    return path


@pytest.fixture
def inputs(_shared_inputs, monkeypatch):
    """The working folder with valid input files that the tests of a bad flag share (made once per module: a
    folder per test cost more than most of these tests); each such test checks that nothing was written there."""
    monkeypatch.chdir(_shared_inputs)
    return _shared_inputs


def _files(path):
    return sorted(os.path.relpath(os.path.join(d, f), path) for d, _, fs in os.walk(path) for f in fs) + \
        sorted(os.path.relpath(os.path.join(d, s), path) for d, ss, _ in os.walk(path) for s in ss)


def _refused(capsys, folder, argv, needles):
    before = _files(folder)
    code, out, err = run(capsys, *argv)
    assert code == 2, (argv, code, out, err)
    assert one_line(err), (argv, err)
    for needle in needles:
        assert needle in err, (argv, needle, err)
    assert _files(folder) == before, (argv, "wrote", set(_files(folder)) - set(before))
    return err


def test_every_flag_of_every_command_has_a_case():
    flags, _ = _commands()
    missing = [(c, f) for c, fs in flags.items() for f in fs if (c, f) not in FLAG_CASES]
    assert not missing, f"flags without a hostile-input case: {missing}"
    assert set(BASE) == set(flags)


def test_every_input_file_has_cases():
    assert _positionals() <= set(FILE_CASES), _positionals() - set(FILE_CASES)


def test_every_number_option_uses_the_one_parser():
    """No option parses with int() or float(): each typed option refuses what the one number parser refuses
    (other scripts' digits, underscores, spaces, newlines, 101-digit numbers, hex)."""
    _, sub = _commands()
    typed = [(name, a) for name, p in sub.choices.items() for a in p._actions if a.type is not None]
    assert typed
    for name, action in typed:
        assert action.type not in (int, float), (name, action.option_strings)
        for text in ("\u0661", "\uff11", "1_0", " 1", "1\n", "1" * 101, "0x10"):
            with pytest.raises(argparse.ArgumentTypeError):
                action.type(text)


@pytest.mark.parametrize("command, flag, values, needle",
                         [(c, f, v, n) for (c, f), cases in FLAG_CASES.items() for v, n in cases],
                         ids=lambda x: repr(x)[:30])
def test_a_bad_flag_is_refused_in_one_line(capsys, inputs, command, flag, values, needle):
    if values and values[0].startswith("="):
        bad = [flag + values[0]]
    else:
        bad = [flag, *values]
    argv = [*bad, *BASE[command]] if command is None else [*BASE[command], *bad]
    _refused(capsys, inputs, argv, {needle})


@pytest.mark.parametrize("command, dest, name, content, needle",
                         [(c, d, *case) for (c, d), cases in FILE_CASES.items() for case in cases],
                         ids=lambda x: repr(x)[:30])
def test_a_bad_input_file_is_refused_in_one_line(capsys, folder, command, dest, name, content, needle):
    if content is not None:
        (folder / name).write_bytes(content if isinstance(content, bytes) else content.encode())
    argv = list(BASE[command])
    if dest.startswith("--"):
        argv += [dest, name]
    else:
        argv[1] = name
    err = _refused(capsys, folder, argv, {needle, name})
    assert "c" * SHOW_WIDTH not in err


def test_long_values_are_shortened_in_every_message(capsys, folder):
    """A long value is shown with at most SHOW_WIDTH characters and an ellipsis, by argparse's own messages
    too (an invalid choice, an unknown argument)."""
    for argv in (["plan", "--steps", LONG], ["plan", "--legs", "x" * 500], ["plan", "y" * 500],
                 ["codegen", "--out", "outdir", "--prefix", "z" * 500]):
        err = _refused(capsys, folder, argv, {"..."})
        assert max(len(word) for word in err.replace("'", " ").split()) <= SHOW_WIDTH, err


# ----------------------------------------------------------------------------- the findings, run as the command


def test_an_unclosed_quote_in_a_targets_file_is_refused(tmp_path, capfd):
    """An unclosed quote swallowed every later row: batch planned one target of two and exited 0."""
    (tmp_path / "t.csv").write_text('u_a,v_a,psi,note\n0,1,0,"open\n0.5,0.3,0.4,x\n')
    code, _, err = run(capfd, "batch", "t.csv", "--out", "o.jsonl", "--jobs", "1", cwd=tmp_path)
    assert code == 2 and one_line(err) and "'t.csv', line 2" in err and "quote" in err, err
    assert not (tmp_path / "o.jsonl").exists()


def test_an_unclosed_quote_in_a_waypoints_file_is_refused(tmp_path, capfd):
    """`1,0,0,"a` on row 3 took the way home into its label: a 1-leg route, exit 0."""
    (tmp_path / "w.csv").write_text('u_a,v_a,psi,label\n0,0,0,home\n1,0,0,"a\n0,0,0,back\n')
    code, out, err = run(capfd, "route", "w.csv", "--json", "r.json", cwd=tmp_path)
    assert code == 2 and one_line(err) and "'w.csv', line 3" in err and "quote" in err, err
    assert not (tmp_path / "r.json").exists()


@pytest.mark.parametrize("branch", [" 1", "1\n", "\u0661", "\uff11", "1_0", "1" * 101])
def test_branch_is_read_by_the_number_parser(tmp_path, capfd, branch):
    """`plan --branch` read int(): spaces, a newline, Arabic-Indic and full-width digits, 1_0 and a 101-digit
    number were taken."""
    code, _, err = run(capfd, "plan", "--branch", branch, cwd=tmp_path)
    assert code == 2 and one_line(err) and "--branch" in err, err


def test_a_target_beyond_reach_is_refused_before_planning(tmp_path, capfd):
    """`plan --to 1e200 0` searched on inf/NaN (six numpy warnings) before exit 3."""
    code, out, err = run(capfd, "plan", "--to", "1e200", "0", cwd=tmp_path)
    assert code == 2 and one_line(err) and "--to" in err and "17345 R" in err, err
    assert "Warning" not in err and out == ""


def test_radius_has_the_limits_of_a_robot_file(tmp_path, capfd):
    """`--radius 5e-324` exited 3, "overflows"; a robot file's radius is held to [1e-6, 1000] m."""
    for radius in ("5e-324", "2000"):
        code, _, err = run(capfd, "plan", "--radius", radius, cwd=tmp_path)
        assert code == 2 and one_line(err) and "--radius" in err and "[1e-06, 1000] m" in err, err


def test_samples_are_checked_before_planning(tmp_path, capfd):
    """`plan --steps 1000 --json f.json` planned, printed the summary, then refused "samples = 2000" without
    naming --samples. Now a --samples too small for the plan is refused first, naming --samples."""
    code, out, err = run(capfd, "plan", "--steps", "1000", "--samples", "2000", "--json", "f.json", cwd=tmp_path)
    assert code == 2 and one_line(err) and "--samples 2000" in err and ">= 4003" in err, err
    assert out == "" and not (tmp_path / "f.json").exists()


def test_samples_cover_the_pieces_of_base_any(tmp_path, capfd):
    """With --base any a plan of one leg may have n + 1 figure eights between two rolls: 2 (n + 1) + 2 pieces,
    more than --legs one allows at the pole; a --samples too small for it is refused before planning."""
    code, out, err = run(capfd, "plan", "--from", "0", "0", "0", "0.5", "-0.3", "--to", "0.8", "0.2", "--contact",
                         "-0.4", "0.4", "--legs", "one", "--base", "any", "--samples", "6", "--json", "f.json",
                         cwd=tmp_path)
    assert code == 2 and one_line(err) and "--samples 6" in err and ">= 7" in err, err
    assert out == "" and not (tmp_path / "f.json").exists()


@pytest.mark.slow
def test_default_samples_serve_the_largest_steps(tmp_path, capfd):
    """The default --samples serves --steps 1000 (2000 did not: a plan of 1000 figure eights has 2000 pieces,
    2001 piece ends): the JSON has a sample at every piece end, and the last is the target asked for."""
    code, out, err = run(capfd, "plan", "--to", "0", "1", "--steps", "1000", "--json", "f.json", cwd=tmp_path)
    assert code == 0, err
    d = json.loads((tmp_path / "f.json").read_text())
    t = d["trajectory"]
    assert len(t["u_a"]) >= 2 * 1000 + 1 and len(set(t["segment"])) == len(d["segments"])
    assert abs(t["u_a"][-1] - 0.0) < 1e-9 and abs(t["v_a"][-1] - 1.0) < 1e-9   # the target asked for


def test_long_values_are_shortened(tmp_path, capfd):
    """"steps = 1000000000000..." was printed in full."""
    code, _, err = run(capfd, "plan", "--steps", "1" + "0" * 90, cwd=tmp_path)
    assert code == 2 and one_line(err) and "--steps" in err and "..." in err, err
    assert "0" * SHOW_WIDTH not in err


@pytest.mark.slow
def test_a_plan_file_duration_is_named_as_the_file_says(tmp_path, capsys):
    """simulate --closed-loop on a plan file of duration -10 said "piece_duration = -5.0 is not allowed": the
    message names the file, its key duration and the value it holds."""
    code, _, err = run(capsys, "plan", "--to", "0.03", "0.05", "--psi", "0.3", "--duration", "4", "--samples",
                       "800", "--json", str(tmp_path / "plan.json"))
    assert code == 0, err
    d = json.loads((tmp_path / "plan.json").read_text())
    d["duration"] = -10.0
    (tmp_path / "bad.json").write_text(json.dumps(d))
    code, _, err = run(capsys, "simulate", "bad.json", "--closed-loop", cwd=tmp_path)
    assert code == 2 and one_line(err) and "'bad.json'" in err and "'duration' = -10.0" in err, err
    assert "piece_duration" not in err


def test_the_reach_limit_is_refused_in_the_api_before_any_leg():
    """rollplan.plan and plan_route refuse a goal beyond MAX_DISTANCE with InputError naming it; a route's far
    leg is refused before its first leg is planned."""
    import rollplan
    from rollplan.planners.geometric import plan_route
    from rollplan.problem import MAX_DISTANCE

    with pytest.raises(rollplan.InputError, match=f"at most {MAX_DISTANCE} R"):
        rollplan.plan((1e200, 0.0, 0.0), k=2.5)
    with pytest.raises(rollplan.InputError, match=f"at most {MAX_DISTANCE} R"):
        rollplan.plan((0.0, 1.0, 0.0), k=2.5, radius=5e-324)
    calls = []
    with pytest.raises(rollplan.InputError, match="waypoint 3"):
        plan_route([(0, 0, 0), (0.5, 0.3, 0.4), (0.5 + MAX_DISTANCE * 1.01, 0.3, 0.4)], k=2.5,
                   progress=lambda done, total: calls.append(done))
    assert calls == []


@pytest.mark.parametrize("k", [0.0, 2.5, pytest.param(10.0, marks=pytest.mark.slow)])
def test_the_reach_limit_bounds_what_a_figure_eight_does(k):
    """MAX_DISTANCE rests on: one figure eight moves the contact point on the plane by at most its length
    4 pi A_MAX (two circles of radius <= A_MAX). Checked on the largest leaves by DOP853 on the printed
    equations (references.trace); and the limit is 2 MAX_STEPS 4 pi A_MAX + pi, rounded up."""
    from rollplan.core.curves import A_MAX
    from rollplan.problem import MAX_DISTANCE, MAX_STEPS

    for a, b in ((A_MAX, A_MAX), (A_MAX, 0.05), (0.3, A_MAX)):
        x = references.trace(a, b, k)   # gamma turns the shift, not its length
        assert math.hypot(x[0], x[1]) <= 2 * math.pi * (a + b)
    assert math.ceil(2 * MAX_STEPS * 4 * math.pi * A_MAX + math.pi) == MAX_DISTANCE
