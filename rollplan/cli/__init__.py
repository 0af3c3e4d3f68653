"""The rollplan command (``rollplan --help``): a parser, and one module per command (``commands/``).

:func:`main` runs a command and returns its exit status; the exit codes and output conventions are in
:data:`.parser.DESCRIPTION`. Design: the commands only orchestrate (parse, call the API, print, write).
"""

from __future__ import annotations

from .. import threads  # noqa: F401  (before anything that loads numpy: one BLAS thread per process)
from .parser import build_parser
from .run import main

__all__ = ["main", "build_parser"]
