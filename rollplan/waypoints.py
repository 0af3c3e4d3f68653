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
* The file is read by :func:`rollplan.inputs.read_csv` (a regular UTF-8 file,
  a column named once) and numbers are read as on the command line
  (:func:`rollplan.inputs.parse_number`). Every error names the file and the
  line, on one line.
"""

from __future__ import annotations

from dataclasses import dataclass

from .errors import InputError, show
from .inputs import parse_number, parse_whole, read_csv, show_path
from .problem import STATE_NAMES, State, check_contact, check_steps

__all__ = ["COLUMNS", "MAX_WAYPOINTS", "Waypoint", "read_waypoints"]

#: Columns a waypoints file may have.
COLUMNS = (*STATE_NAMES, "steps", "label")
_REQUIRED = ("u_a", "v_a", "psi")
#: Most waypoints of a file (a route plans and certifies them one leg after the other).
MAX_WAYPOINTS = 10_000
#: Largest waypoints file read.
MAX_WAYPOINTS_BYTES = 1 << 24


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
        values.append(parse_number(cell, name) if cell != "" else 0.0)
    state = State(*values)
    check_contact(state.u_o, state.v_o, "waypoint")
    steps = None
    if cells.get("steps", "") != "":
        if first:
            raise InputError("the first row is the start: its steps cell must be empty")
        steps = check_steps(parse_whole(cells["steps"], "steps"))
    return Waypoint(state, steps, cells.get("label", ""))


def read_waypoints(path) -> list:
    """The waypoints of a CSV file (module docstring; read by :func:`rollplan.inputs.read_csv`: a regular
    UTF-8 file, numbers as on the command line); InputError naming the file and the line otherwise."""
    where = f"waypoints file {show_path(path)}"
    table = read_csv(path, "waypoints file", _REQUIRED, MAX_WAYPOINTS_BYTES, comments=True)
    unknown = [c for c in table.header if c not in COLUMNS]
    if unknown:
        raise InputError(f"{where}, line {table.header_line}: unknown column {show(unknown[0])}; allowed: "
                         f"{', '.join(COLUMNS)}")
    if len(table.rows) > MAX_WAYPOINTS:
        raise InputError(f"{where} has {len(table.rows)} waypoints: at most {MAX_WAYPOINTS} are allowed")
    out = []
    for cells, line, problem in zip(table.rows, table.lines, table.problems):
        try:
            if problem is not None:   # "line N has m field(s), the header n"
                raise InputError(problem.removeprefix(f"line {line} "))
            out.append(_row(cells, not out))
        except InputError as exc:
            raise InputError(f"{where}, line {line}: {exc}") from None
    if len(out) < 2:
        raise InputError(f"{where}: a route needs at least two waypoints (the first is the start)")
    return out
