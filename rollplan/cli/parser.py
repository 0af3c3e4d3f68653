"""The ``rollplan`` command line: the top-level parser and its commands, in the order of ``--help``."""

from __future__ import annotations

import argparse

from ..version import __version__
from .arguments import Parser
from .commands import (
    animate,
    atlas,
    batch,
    codegen,
    compare,
    mjcf,
    plan,
    reproduce,
    route,
    simulate,
    step,
)

__all__ = ["DESCRIPTION", "build_parser"]

#: What ``rollplan --help`` says first.
DESCRIPTION = """The rollplan command: exact motion planning for a spherical robot driven by two internal rotors.

Exit codes: 0 success, 2 bad input, 3 no plan, 4 solver failure, 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM, stopped as for Ctrl-C); batch: 1 when some rows failed, 3 when every row failed. `--json -` writes
the JSON document to stdout and the summary to stderr.
Lengths are printed in the unit in use (R, or m with --robot or --radius), summaries with 6
significant digits (JSON files in full precision); long work shows its progress on stderr.
"""

#: The commands, in the order ``rollplan --help`` lists them.
COMMANDS = (plan, route, step, reproduce, simulate, mjcf, animate, compare, codegen, batch, atlas)


def build_parser() -> argparse.ArgumentParser:
    """The parser of ``rollplan`` and all its commands."""
    parser = Parser(prog="rollplan", description=DESCRIPTION, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"rollplan {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the planner's progress")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=Parser, metavar="COMMAND")
    for command in COMMANDS:
        command.register(sub)
    return parser
