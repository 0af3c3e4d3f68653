"""Waypoints of a route from a CSV file (``rollplan route WAYPOINTS.csv``).

Format::

    # lines starting with '#' and blank lines are ignored
    u_a,v_a,psi,u_o,v_o,steps,label
    0,0,0,,,,home
    1.0,0.5,0.3,,,1,a
    1.2,0.4,1.5,0.3,-0.2,2,inspect

* A header row names the columns, in any order: ``u_a``, ``v_a``, ``psi``
  (required), ``u_o``, ``v_o`` (the contact point on the sphere; empty or
  missing means the south pole), ``steps`` (figure eights per leg of the leg
  arriving at this row; empty: the command's ``--steps``) and ``label`` (free
  text). Unknown columns are refused.
* One waypoint per row; the first is the start (its ``steps`` cell must be
  empty); at least two rows. Lengths in the unit of the plan (R, or metres with
  a robot), angles in rad. A row with ``u_a, v_a, psi`` only is a position with
  a heading (contact at the pole), one with ``u_o, v_o`` a full state.
* Every error names the file and the line, on one line.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass

from .errors import InputError, check_finite
from .problem import STATE_NAMES, State, check_contact, check_steps

__all__ = ["COLUMNS", "Waypoint", "read_waypoints"]

#: Columns a waypoints file may have.
COLUMNS = (*STATE_NAMES, "steps", "label")
_REQUIRED = ("u_a", "v_a", "psi")


@dataclass(frozen=True)
class Waypoint:
    """A waypoint of a route.

    Attributes
    ----------
    state : State
        [length unit, rad].
    steps : int or None
        Figure eights per leg of the leg arriving here (None: the route's default).
    label : str
        Free text.
    """

    state: State
    steps: int | None = None
    label: str = ""


def _row(cells: dict, first: bool) -> Waypoint:
    values = []
    for name in STATE_NAMES:
        cell = cells.get(name, "")
        if cell == "" and name in _REQUIRED:
            raise InputError(f"{name} is empty")
        try:
            value = float(cell) if cell != "" else 0.0
        except ValueError:
            raise InputError(f"{name} = {cell!r} is not a number") from None
        values.append(check_finite(name, value))
    state = State(*values)
    check_contact(state.u_o, state.v_o, "waypoint")
    steps = None
    if cells.get("steps", "") != "":
        if first:
            raise InputError("the first row is the start: its steps cell must be empty")
        try:
            steps = int(cells["steps"])
        except ValueError:
            raise InputError(f"steps = {cells['steps']!r} is not a whole number") from None
        steps = check_steps(steps)
    return Waypoint(state, steps, cells.get("label", ""))


def read_waypoints(path) -> list:
    """The waypoints of a CSV file (module docstring); InputError naming the file and the line otherwise."""
    name = str(path)
    try:
        with open(path, encoding="utf-8", newline="") as fh:
            lines = fh.read().splitlines()
    except OSError as exc:
        raise InputError(f"waypoints file {name!r} cannot be read: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise InputError(f"waypoints file {name!r} is not a text file (UTF-8)") from None
    rows = [(i + 1, line) for i, line in enumerate(lines) if line.strip() and not line.lstrip().startswith("#")]
    if not rows:
        raise InputError(f"waypoints file {name!r} has no header row (columns {', '.join(COLUMNS)})")
    parsed = list(csv.reader([line for _, line in rows]))
    head_no, header = rows[0][0], [c.strip() for c in parsed[0]]
    where = f"{name} line {head_no}"
    unknown = [c for c in header if c not in COLUMNS]
    if unknown:
        raise InputError(f"{where}: unknown column {unknown[0]!r}; allowed: {', '.join(COLUMNS)}")
    missing = [c for c in _REQUIRED if c not in header]
    if missing:
        raise InputError(f"{where}: missing column {missing[0]!r}")
    if len(set(header)) != len(header):
        raise InputError(f"{where}: a column is named twice")
    out = []
    for (line_no, _), cells in zip(rows[1:], parsed[1:]):
        cells = [c.strip() for c in cells]
        try:
            if len(cells) != len(header):
                raise InputError(f"{len(cells)} cells, the header has {len(header)}")
            out.append(_row(dict(zip(header, cells)), not out))
        except InputError as exc:
            raise InputError(f"{name} line {line_no}: {exc}") from None
    if len(out) < 2:
        raise InputError(f"waypoints file {name!r}: a route needs at least two waypoints (the first is the start)")
    return out
