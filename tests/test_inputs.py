"""The input layer (rollplan.inputs): numbers written as text, and input files (regular files only, never
blocking, size cap, UTF-8 and byte-order marks, nesting and integer caps, CSV headers). Every refusal is one
line naming the value or the file."""

import json
import math
import os
import threading

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan.errors import InputError, check_range, show_limit
from rollplan.inputs import (
    MAX_DEPTH,
    MAX_INT_DIGITS,
    MAX_NUMBER_CHARS,
    load_json,
    load_toml,
    parse_number,
    parse_whole,
    read_csv,
    read_text,
)


def one_line(exc_info):
    return "\n" not in str(exc_info.value)


# ----------------------------------------------------------------------------- numbers


@pytest.mark.parametrize("text, value", [("2.5", 2.5), ("-1e-3", -1e-3), ("-2e-1", -0.2), (".5", 0.5), ("5.", 5.0),
                                         ("+3", 3.0), ("1E+3", 1000.0), ("-0", -0.0), ("1e-400", 0.0),
                                         ("0.1000000000000000055511151231257827", 0.1)])
def test_decimal_numbers_are_read_exactly_as_float_reads_them(text, value):
    assert parse_number(text) == value and parse_number(text) == float(text)


@pytest.mark.parametrize("text", ["\u0661", "\uff11", "1_0", "0x10", "inf", "-inf", "nan", "NaN", "Infinity", " 1",
                                  "1 ", "", "e3", ".", "1e", "1e+", "--1", "1,5", "\u0661.5", "1\u00a0", "١٢",
                                  "1" * (MAX_NUMBER_CHARS + 1)])
def test_anything_else_is_refused_in_one_line_naming_the_text(text):
    with pytest.raises(InputError) as err:
        parse_number(text, "k")
    assert one_line(err) and str(err.value).startswith("k = ")


def test_overflow_is_refused_not_inf():
    with pytest.raises(InputError, match="too large"):
        parse_number("1e400", "k")


def test_wrong_type_is_refused():
    for value in (None, 2.5, b"2.5", ["2"]):
        with pytest.raises(InputError, match="as text"):
            parse_number(value, "k")


@pytest.mark.parametrize("text, value", [("2", 2), ("-3", -3), ("+7", 7), ("007", 7)])
def test_whole_numbers(text, value):
    assert parse_whole(text) == value


@pytest.mark.parametrize("text", ["2.5", "1e3", "\uff12", "2_0", "0x2", "", " 2", "1" * 5000])
def test_whole_numbers_refuse_the_rest(text):
    with pytest.raises(InputError) as err:
        parse_whole(text, "steps")
    assert one_line(err)


def test_ranges_print_their_limits_exactly():
    """A value just outside a limit is never shown next to a limit rounded to look like it (%g)."""
    with pytest.raises(InputError) as err:
        parse_number("100.00000000000001", "k", 0, 100)
    assert str(err.value) == "k = 100.00000000000001 is not allowed: it must lie in [0, 100]"
    with pytest.raises(InputError) as err:
        check_range("bound", 1.5708, 0.0, math.pi / 2, True, True)
    assert "(0, 1.5707963267948966)" in str(err.value)
    assert [show_limit(x) for x in (100.0, 0.69, 1e-6, 1e9, 3, -math.inf)] == ["100", "0.69", "1e-06", "1000000000",
                                                                               "3", "-inf"]


def test_property_tests_have_no_wall_clock_deadline():
    """The two property tests below ran with Hypothesis's default deadline (200 ms of wall time per example): on a
    shared machine an example that waited for a CPU failed the run ("Unreliable test timings"). The suite's
    profile (conftest.py) has no deadline, and these tests use it."""
    assert settings.default.deadline is None
    for test in (test_every_double_round_trips_through_its_repr, test_random_text_is_a_number_or_one_line):
        assert getattr(test, "_hypothesis_internal_use_settings", settings.default).deadline is None


@given(st.floats(allow_nan=False, allow_infinity=False))
def test_every_double_round_trips_through_its_repr(x):
    assert parse_number(repr(x)) == x


@given(st.text(max_size=30))
def test_random_text_is_a_number_or_one_line(text):
    try:
        x = parse_number(text, "value")
    except InputError as exc:
        assert "\n" not in str(exc)
    else:
        assert math.isfinite(x) and text.isascii() and x == float(text)


# ----------------------------------------------------------------------------- files


def test_fifo_is_refused_without_blocking(tmp_path):
    """A FIFO with no writer would block open() for ever: refused after a stat, in a thread with a deadline."""
    fifo = tmp_path / "robot.toml"
    os.mkfifo(fifo)
    result = {}

    def read():
        try:
            read_text(fifo, "robot file")
        except InputError as exc:
            result["error"] = str(exc)

    worker = threading.Thread(target=read, daemon=True)
    worker.start()
    worker.join(5.0)
    assert not worker.is_alive(), "reading a FIFO blocked"
    assert "FIFO" in result["error"] and "robot.toml" in result["error"]


def test_devices_and_directories_are_refused(tmp_path):
    with pytest.raises(InputError, match="character device"):
        read_text("/dev/zero", "robot file")
    with pytest.raises(InputError, match="is a directory"):
        read_text(tmp_path, "targets file")
    with pytest.raises(InputError, match="does not exist"):
        read_text(tmp_path / "none.csv", "targets file")
    with pytest.raises(InputError, match="name is empty"):
        read_text("", "robot file")


def test_size_cap(tmp_path):
    big = tmp_path / "big.toml"
    big.write_bytes(b"#" * 2000 + b"\n")
    assert read_text(big, max_bytes=2001)
    with pytest.raises(InputError, match="too large: 2001 bytes, at most 2000"):
        read_text(big, max_bytes=2000)


def test_utf8_bom_is_skipped_utf16_and_binary_are_refused(tmp_path):
    f = tmp_path / "r.toml"
    f.write_bytes(b"\xef\xbb\xbfradius = 0.1\n")
    assert read_text(f) == "radius = 0.1\n"
    assert load_toml(f) == {"radius": 0.1}
    f.write_bytes("radius = 0.1\n".encode("utf-16"))
    with pytest.raises(InputError, match="UTF-16"):
        read_text(f)
    f.write_bytes(b"radius = \xe4\n")
    with pytest.raises(InputError, match="not UTF-8 text: byte 0xe4 at offset 9"):
        read_text(f)
    f.write_bytes(b"radius = 0.1\x00\n")
    with pytest.raises(InputError, match="NUL"):
        read_text(f)


def test_deep_nesting_is_refused_in_toml_and_json(tmp_path):
    for depth in (MAX_DEPTH + 1, 100_000):
        toml = tmp_path / "deep.toml"
        toml.write_text("a = " + "[" * depth + "]" * depth + "\n")
        with pytest.raises(InputError, match="nested too deeply") as err:
            load_toml(toml, "robot file")
        assert one_line(err)
        js = tmp_path / "deep.json"
        js.write_text("[" * depth + "]" * depth)
        with pytest.raises(InputError, match="nested too deeply"):
            load_json(js, "plan file")
    ok = tmp_path / "ok.json"
    ok.write_text("[" * MAX_DEPTH + "]" * MAX_DEPTH)
    assert load_json(ok) is not None


def test_json_numbers_must_be_finite_and_integers_short(tmp_path):
    js = tmp_path / "p.json"
    for text, needle in (('{"a": NaN}', "NaN"), ('{"a": -Infinity}', "-Infinity"), ('{"a": 1e400}', "too large"),
                         ('{"a": ' + "9" * 5000 + "}", "5000 digits")):
        js.write_text(text)
        with pytest.raises(InputError, match=needle) as err:
            load_json(js, "plan file")
        assert one_line(err) and "p.json" in str(err.value)
    js.write_text('{"a": ' + "9" * MAX_INT_DIGITS + "}")
    assert load_json(js)["a"] == int("9" * MAX_INT_DIGITS)
    js.write_text(json.dumps({"a": [1.5, -2e-300]}))
    assert load_json(js) == {"a": [1.5, -2e-300]}


def test_csv_header_rules(tmp_path):
    f = tmp_path / "t.csv"
    f.write_bytes(b"\xef\xbb\xbfu_a,v_a,psi,steps,k\n0,1,0,1,2.5\n\n")   # BOM, blank line
    table = read_csv(f, "targets file", ("u_a", "v_a", "psi", "steps", "k"))
    assert table.header == ("u_a", "v_a", "psi", "steps", "k") and table.rows == [
        {"u_a": "0", "v_a": "1", "psi": "0", "steps": "1", "k": "2.5"}] and table.lines == [2]
    f.write_text("u_a,v_a,psi,steps,k,k\n0,1,0,1,2.5,3\n")
    with pytest.raises(InputError, match="column 'k' appears twice"):
        read_csv(f, "targets file", ("k",))
    f.write_text("u_a,,psi\n")
    with pytest.raises(InputError, match="column 2 of the header has no name"):
        read_csv(f, "targets file")
    f.write_text("")
    with pytest.raises(InputError, match="is empty"):
        read_csv(f, "targets file", ("u_a",))
    f.write_text("u_a,v_a\n1,2,3\n1\n")
    table = read_csv(f, "targets file", ("u_a",))
    assert table.problems == ["line 2 has 3 field(s), the header 2", "line 3 has 1 field(s), the header 2"]


def test_csv_field_over_the_limit_is_one_line(tmp_path):
    f = tmp_path / "t.csv"
    f.write_text("u_a,note\n1," + "x" * 131073 + "\n")
    with pytest.raises(InputError, match="longer than 131072 characters") as err:
        read_csv(f, "targets file")
    assert one_line(err) and "line 2" in str(err.value)


@pytest.mark.parametrize("text, value, refused", [
    ('{"a": 1e999, "a": 1}', None, "1e999"),           # the overflowing value is replaced by a later one
    ('[{"b": [-1e400], "b": 2}]', None, "-1e400"),
    ('{"a": 1, "a": 2.5}', {"a": 2.5}, None),          # as json reads it: the last value of a key
])
def test_a_key_given_twice_does_not_hide_a_number_too_large(tmp_path, text, value, refused):
    """Every number token of a JSON file is checked, also one whose key is given again later in the object."""
    from rollplan.inputs import load_json

    path = tmp_path / "p.json"
    path.write_text(text)
    if refused:
        with pytest.raises(InputError, match=f"the number '{refused}' is too large for a double"):
            load_json(path, "plan file")
    else:
        assert load_json(path, "plan file") == value == json.loads(text)
