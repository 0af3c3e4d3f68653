"""What users give, read one way everywhere: numbers written as text, and input files.

Numbers (the command line, CSV fields)
--------------------------------------
:func:`parse_number` accepts an ASCII decimal number and nothing else: an
optional sign, digits with an optional fraction, an optional exponent
(``2.5``, ``-1e-3``, ``.5``, ``1E+3``). Refused, with one line naming the
value: digits of other scripts (``١``, full-width ``１``), underscores
(``1_0``), hexadecimal (``0x10``), ``inf`` and ``nan``, spaces, more than
:data:`MAX_NUMBER_CHARS` characters, and a value that is not a finite double
(``1e400``). Ranges are checked by :func:`rollplan.errors.check_range`, which
prints its limits exactly. :func:`parse_whole` is the same for whole numbers
(ASCII digits with an optional sign).

Files
-----
:func:`read_text` reads a regular file only: it is looked at (``os.stat``)
before it is opened, and opened with ``O_NONBLOCK`` and looked at again, so a
FIFO, a device or a directory is refused at once and never blocks. It reads at
most a size cap, decodes UTF-8 (a UTF-8 byte-order mark is skipped; UTF-16 and
UTF-32 text and NUL bytes are refused with a message that says so).
:func:`load_toml` and :func:`load_json` parse such text with a nesting cap
(:data:`MAX_DEPTH`) and refuse what cannot be a finite number (JSON ``NaN``,
``Infinity``, ``1e400``, integers of more than :data:`MAX_INT_DIGITS` digits).
:func:`read_csv` reads a CSV file with a header: duplicated or unnamed columns
are refused, fields are capped, a quote left open is refused with the line
it opens on (never read on to the end of the file, swallowing the rows after
it), and every row keeps its line number.

Every refusal is an :class:`~rollplan.errors.InputError` with one line that
names the file (or the value) and what is allowed.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import re
import stat
from dataclasses import dataclass
from itertools import chain

from .errors import InputError, check_range, check_whole, show

__all__ = ["MAX_NUMBER_CHARS", "MAX_DEPTH", "MAX_INT_DIGITS", "parse_number", "parse_whole",
           "show_path", "check_path", "read_text", "load_toml", "load_json", "CsvTable", "read_csv", "depth"]

#: Longest text accepted as one number.
MAX_NUMBER_CHARS = 100
#: Deepest nesting of arrays and tables accepted in a TOML or JSON input (ours nest at most 3 deep).
MAX_DEPTH = 32
#: Most digits of an integer in a JSON input (any double's integer part has at most 309).
MAX_INT_DIGITS = 400

_DECIMAL = re.compile(r"[+-]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
_WHOLE = re.compile(r"[+-]?[0-9]+")
_EXAMPLES = "such as 2.5, -0.3 or -1e-3"


def _text_of(text, name: str, kind: str) -> str:
    if not isinstance(text, str):
        raise InputError(f"{name} = {show(text)} is not allowed: give {kind} as text")
    if len(text) > MAX_NUMBER_CHARS:
        raise InputError(f"{name} = {show(text)} is not allowed: a number has at most {MAX_NUMBER_CHARS} characters")
    return text


def parse_number(text, name: str = "value", low=None, high=None, low_open: bool = False,
                 high_open: bool = False) -> float:
    """The finite double written as the ASCII decimal ``text``, within ``[low, high]`` (or open ends).

    Raises
    ------
    InputError
        One line naming ``name``, the text, and what is allowed.
    """
    text = _text_of(text, name, "a number")
    if not _DECIMAL.fullmatch(text):
        raise InputError(f"{name} = {show(text)} is not allowed: it must be a decimal number {_EXAMPLES} "
                         "(ASCII digits; no spaces, underscores, hex, inf or nan)")
    x = float(text)
    if not math.isfinite(x):
        raise InputError(f"{name} = {show(text)} is not allowed: it is too large for a double (at most ~1.8e308)")
    return check_range(name, x, low, high, low_open, high_open)


def parse_whole(text, name: str = "value", low=None, high=None) -> int:
    """The whole number written in ASCII digits as ``text`` (optional sign), within ``[low, high]``."""
    text = _text_of(text, name, "a whole number")
    if not _WHOLE.fullmatch(text):
        raise InputError(f"{name} = {show(text)} is not allowed: it must be a whole number written in "
                         "ASCII digits, such as 2 or 2000")
    return check_whole(name, int(text), low, high)


# ----------------------------------------------------------------------------- paths and files


def show_path(path, width: int = 80) -> str:
    """``repr`` of a path for a message, its middle elided beyond ``width`` characters (the name stays)."""
    text = repr(os.fspath(path)) if isinstance(path, (str, os.PathLike)) else show(path)
    if len(text) <= width:
        return text
    keep = (width - 3) // 2
    return text[:keep] + "..." + text[-keep:]


def check_path(path, what: str = "file") -> str:
    """``path`` as a string if it can name a file (a str or os.PathLike, not empty, no NUL); InputError otherwise."""
    if isinstance(path, bytes) or not isinstance(path, (str, os.PathLike)):
        raise InputError(f"{what} = {show(path)} is not allowed: give a file name (str or pathlib.Path)")
    text = os.fspath(path)
    if not isinstance(text, str):
        raise InputError(f"{what} = {show(path)} is not allowed: give a file name (str or pathlib.Path)")
    if text == "":
        raise InputError(f"{what} name is empty: give a file name")
    if "\x00" in text:
        raise InputError(f"{what} name {show_path(text)} is not allowed: it contains a NUL character")
    return text


def _kind(mode: int) -> str:
    for test, name in ((stat.S_ISFIFO, "a FIFO"), (stat.S_ISCHR, "a character device"),
                       (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a directory")):
        if test(mode):
            return name
    return "not a regular file"


def _unreadable(what: str, path: str, exc: OSError) -> InputError:
    if isinstance(exc, (FileNotFoundError, NotADirectoryError)):
        return InputError(f"{what} {show_path(path)} cannot be read: it does not exist")
    return InputError(f"{what} {show_path(path)} cannot be read: {exc.strerror or exc}")


def _read_bytes(path, what: str, max_bytes: int) -> bytes:
    text = check_path(path, what)
    try:
        st = os.stat(text)
    except OSError as exc:
        raise _unreadable(what, text, exc) from None
    if stat.S_ISDIR(st.st_mode):
        raise InputError(f"{what} {show_path(text)} is a directory: give a file")
    if not stat.S_ISREG(st.st_mode):
        raise InputError(f"{what} {show_path(text)} is not allowed: it is {_kind(st.st_mode)}, not a regular file")
    if st.st_size > max_bytes:
        raise InputError(f"{what} {show_path(text)} is too large: {st.st_size} bytes, at most {max_bytes}")
    try:
        # O_NONBLOCK: should the name now be a FIFO (swapped since the stat), opening it does not block
        fd = os.open(text, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        raise _unreadable(what, text, exc) from None
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise InputError(f"{what} {show_path(text)} is not allowed: it is {_kind(st.st_mode)}, "
                             "not a regular file")
        chunks, size = [], 0
        while size <= max_bytes:
            chunk = os.read(fd, min(1 << 20, max_bytes + 1 - size))
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise _unreadable(what, text, exc) from None
    finally:
        os.close(fd)
    if size > max_bytes:
        raise InputError(f"{what} {show_path(text)} is too large: more than {max_bytes} bytes")
    return b"".join(chunks)


def read_text(path, what: str = "file", max_bytes: int = 1 << 20) -> str:
    """The text of the regular file ``path`` (UTF-8, a byte-order mark skipped), at most ``max_bytes`` long.

    ``what`` names the file in messages (``"robot file"``). See the module docstring.
    """
    data = _read_bytes(path, what, max_bytes)
    where = f"{what} {show_path(path)}"
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    elif data.startswith((b"\xff\xfe", b"\xfe\xff")):
        raise InputError(f"{where} is UTF-16 or UTF-32 text (it starts with a byte-order mark): save it as UTF-8")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise InputError(f"{where} is not UTF-8 text: byte 0x{data[exc.start]:02x} at offset {exc.start} "
                         "(save it as UTF-8)") from None
    if "\x00" in text:
        raise InputError(f"{where} is not a text file: it contains a NUL character at offset {text.index(chr(0))}")
    return text


def _scan(value) -> tuple[int, bool]:
    """Nesting depth of lists and dicts in ``value`` (a scalar has depth 0) and whether every float in it is
    finite, without recursion; lists of numbers (and lists of rows of numbers) are checked at C speed."""
    deepest, finite, stack = 0, True, [(value, 0)]
    while stack:
        item, level = stack.pop()
        if isinstance(item, dict):
            item = list(item.values())
        if not isinstance(item, list):
            finite = finite and not (type(item) is float and not math.isfinite(item))
            continue
        level += 1
        kinds = set(map(type, item))
        if kinds == {list}:    # a table: its rows as one list when they hold numbers only
            flat = list(chain.from_iterable(item))
            if set(map(type, flat)) <= {float, int}:
                level, item, kinds = level + 1, flat, set(map(type, flat))
        deepest = max(deepest, level)
        floats = item if kinds == {float} else [v for v in item if type(v) is float] if float in kinds else ()
        finite = finite and all(map(math.isfinite, floats))
        if any(issubclass(t, (list, dict)) for t in kinds):
            stack.extend((v, level) for v in item if isinstance(v, (list, dict)))
    return deepest, finite


def depth(value) -> int:
    """Nesting depth of lists and dicts in ``value`` (a scalar has depth 0), without recursion."""
    return _scan(value)[0]


def _check_depth(value, where: str):
    if depth(value) > MAX_DEPTH:
        raise InputError(f"{where} is nested too deeply: arrays and tables at most {MAX_DEPTH} levels deep")
    return value


def load_toml(path, what: str = "TOML file", max_bytes: int = 1 << 20) -> dict:
    """The table of the TOML file ``path`` (see :func:`read_text`), nested at most :data:`MAX_DEPTH` deep."""
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib
    text = read_text(path, what, max_bytes)
    where = f"{what} {show_path(path)}"
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{where} is not valid TOML: {str(exc).splitlines()[0]}") from None
    except RecursionError:
        raise InputError(f"{where} is nested too deeply: arrays and tables at most {MAX_DEPTH} levels deep") from None
    except ValueError as exc:  # e.g. an integer longer than Python converts
        raise InputError(f"{where} is not valid TOML: {str(exc).splitlines()[0][:120]}") from None
    return _check_depth(data, where)


def _json_int(text: str) -> int:
    if len(text.lstrip("-")) > MAX_INT_DIGITS:
        raise InputError(f"an integer of {len(text.lstrip('-'))} digits (at most {MAX_INT_DIGITS})")
    return int(text)


def _json_float(text: str) -> float:
    x = float(text)
    if not math.isfinite(x):
        raise InputError(f"the number {show(text)} is too large for a double")
    return x


def _json_constant(text: str):
    raise InputError(f"{text} is not allowed: numbers must be finite")


def _unique_keys(pairs) -> dict:
    """The object of ``pairs``; ValueError if a key is given twice (see :func:`load_json`)."""
    data = dict(pairs)
    if len(data) != len(pairs):
        raise ValueError("a key is given twice")
    return data


def load_json(path, what: str = "JSON file", max_bytes: int = 1 << 29):
    """The value of the JSON file ``path`` (see :func:`read_text`): finite numbers only, nested at most
    :data:`MAX_DEPTH` deep, integers of at most :data:`MAX_INT_DIGITS` digits."""
    text = read_text(path, what, max_bytes)
    where = f"{what} {show_path(path)}"
    try:
        # floats parsed by json's C scanner, then checked finite in one pass with the depth; any problem is
        # reported by the exact parse below (it names the number that is too large, the first error in the text).
        # A key given twice goes to the exact parse too: the value it replaces is not seen by the scan.
        data = json.loads(text, parse_int=_json_int, parse_constant=_json_constant, object_pairs_hook=_unique_keys)
    except (InputError, ValueError, RecursionError, MemoryError):
        pass
    else:
        deepest, finite = _scan(data)
        if finite and deepest <= MAX_DEPTH:
            return data
    try:
        data = json.loads(text, parse_int=_json_int, parse_float=_json_float, parse_constant=_json_constant)
    except InputError as exc:
        raise InputError(f"{where} is not allowed: {exc}") from None
    except json.JSONDecodeError as exc:
        raise InputError(f"{where} is not valid JSON: {exc}") from None
    except RecursionError:
        raise InputError(f"{where} is nested too deeply: arrays and objects at most {MAX_DEPTH} levels deep") from None
    except MemoryError:
        raise InputError(f"{where} is too large to read into memory") from None
    return _check_depth(data, where)


@dataclass(frozen=True)
class CsvTable:
    """A CSV file read by :func:`read_csv`.

    Attributes
    ----------
    header : tuple of str
        Column names, stripped, in file order (unique, none empty).
    rows : list of dict
        One dict per data row, column name -> stripped field (missing fields absent).
    lines : list of int
        Line number (from 1) of each row in the file.
    problems : list of str or None
        For each row, what is wrong with its shape (more or fewer fields than the header), else None.
    header_line : int
        Line number (from 1) of the header.
    """

    header: tuple
    rows: list
    lines: list
    problems: list
    header_line: int = 1


def read_csv(path, what: str = "CSV file", required=(), max_bytes: int = 1 << 28, comments: bool = False) -> CsvTable:
    """Read a CSV file with a header row (see :func:`read_text`); blank lines are skipped, and with
    ``comments`` also lines that start with ``#`` (after blanks; a quoted ``"#1"`` is a field, not a comment).

    The header must name every column of ``required``, and no column twice or
    not at all. The reading is strict: a quote left open to the end of the file, or
    text after a closing quote, is refused with the line of the record. A row
    with more or fewer fields than the header is kept, with its problem noted (a
    batch records it as a failed row, never drops it).
    """
    text = read_text(path, what, max_bytes)
    where = f"{what} {show_path(path)}"
    raw_lines = []   # the lines the reader has taken, to see how a record's first line starts

    def taken(source):
        for line in source:
            raw_lines.append(line)
            yield line

    reader = csv.reader(taken(io.StringIO(text, newline="")), strict=True)
    try:
        header, header_line = None, 1
        rows, lines, problems = [], [], []
        first = 0
        for fields in reader:
            record_start, first = raw_lines[first], len(raw_lines)
            if not fields or (len(fields) == 1 and not fields[0].strip()):
                continue
            fields = [f.strip() for f in fields]
            if comments and record_start.lstrip().startswith("#"):
                continue
            if header is None:
                header, header_line = _check_header(fields, where, required), reader.line_num
                continue
            problem = None
            if len(fields) != len(header):
                problem = (f"line {reader.line_num} has {len(fields)} field(s), the header {len(header)}")
            rows.append(dict(zip(header, fields)))
            lines.append(reader.line_num)
            problems.append(problem)
    except csv.Error as exc:
        if "field limit" in str(exc):  # the csv module caps fields (131072 characters by default)
            raise InputError(f"{where}, line {reader.line_num}: a field is longer than {csv.field_size_limit()} "
                             "characters") from None
        if "end of data" in str(exc):   # the file ends inside a quoted field: name the line the record starts on
            raise InputError(f"{where}, line {first + 1}: a quote is opened and never closed (the file ends "
                             "inside the quoted field)") from None
        raise InputError(f"{where}, line {reader.line_num}: not valid CSV: {exc}") from None
    if header is None:
        raise InputError(f"{where} is empty: it needs a header naming the columns {', '.join(required)}")
    return CsvTable(tuple(header), rows, lines, problems, header_line)


def _check_header(fields, where: str, required) -> list:
    for i, name in enumerate(fields):
        if not name:
            raise InputError(f"{where}: column {i + 1} of the header has no name")
        if name in fields[:i]:
            raise InputError(f"{where}: column {show(name)} appears twice in the header "
                             f"(columns {fields.index(name) + 1} and {i + 1})")
    missing = [c for c in required if c not in fields]
    if missing:
        raise InputError(f"{where} lacks column(s) {', '.join(missing)}: its header must name {', '.join(required)}")
    return fields
