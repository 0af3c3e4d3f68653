"""Running a command: parse, run, and turn every failure into one line and an exit code."""

from __future__ import annotations

import contextlib
import logging
import os
import re
import sys
from contextlib import ExitStack

from .. import interrupts
from ..errors import InputError, NoPlanError, SolverError
from ..outputs import WRITE_FAILURES
from ..problem import DEFAULT_K
from ..progress import Progress, reporting
from .common import EXIT_INPUT, EXIT_INTERRUPTED, EXIT_NOPLAN, EXIT_SOLVER, EXIT_TERMINATED, Claims
from .parser import build_parser

__all__ = ["main", "cli_syntax"]

#: ``name='value'`` or ``name=True`` in a message of the Python API: an option to name in command-line syntax.
_API_OPTION = re.compile(r"\b([a-z][a-z_]*)=(?:'([^']*)'|True\b)")


#: ``name = value`` at the start of a message of the API: the value of the option --name (``steps per leaf``
#: for --steps-per-leaf), when the command has that option and it was given: the message names the option.
_API_NAME = re.compile(r"^([a-z](?:[a-z_ ]*[a-z])?) = ")
_NOT_OPTIONS = ("command", "func", "stdout", "waypoints", "targets", "plan_file")


def cli_syntax(message: str, args) -> str:
    """A message of the API with its option hints in command-line syntax (``guess='warm'`` -> ``--guess warm``),
    for the options the command has."""
    def sub(m):
        if m.group(1) not in vars(args):
            return m.group(0)
        flag = "--" + m.group(1).replace("_", "-")
        return flag if m.group(2) is None else f"{flag} {m.group(2)}"

    def option(m):   # "k = 200.0 is not allowed" -> "argument --k: k = 200.0 is not allowed" (as argparse says it)
        dest = m.group(1).replace(" ", "_")
        if dest in _NOT_OPTIONS or getattr(args, dest, None) is None:
            return m.group(0)
        return f"argument --{dest.replace('_', '-')}: {m.group(0)}"

    return _API_OPTION.sub(sub, _API_NAME.sub(option, message, count=1))


def _drop_stdout(stream=None) -> None:
    """Point stdout (or ``stream``) at /dev/null, so that the text left in its buffer is not written again (and
    fails again, with an 'Exception ignored' message) when Python exits."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, (stream or sys.stdout).fileno())
        os.close(devnull)
    except (OSError, ValueError):   # stdout without a file descriptor (captured): nothing is flushed at exit
        pass


def main(argv=None) -> int:
    """Run the command in ``argv`` (default ``sys.argv[1:]``) and return its exit status (module docstring)."""
    with interrupts.terminate_as_interrupt():   # SIGTERM stops the command as Ctrl-C does (exit 143)
        status = _main(argv)
    interrupts.settle()   # decided: a late Ctrl-C (Python's shutdown) no longer turns it into death by SIGINT
    if status in (EXIT_INTERRUPTED, EXIT_TERMINATED):
        interrupts.forget_unhandled()
        if interrupts.abandoned() and interrupts.cli_follows():   # a solver still being built in a thread
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError):
                    stream.flush()
            os._exit(status)
    return status


def _main(argv) -> int:
    try:
        interrupts.end_start_up()   # from here Ctrl-C is KeyboardInterrupt: exit 130 below
        parser = build_parser()
        argv = sys.argv[1:] if argv is None else list(argv)
        if not argv:   # a bare `rollplan`: say what it can do
            parser.print_help(sys.stderr)
            return EXIT_INPUT
        args = parser.parse_args(argv)
    except KeyboardInterrupt as exc:
        terminated = isinstance(exc, interrupts.Terminated)
        print(f"rollplan: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED
    logging.basicConfig(level=logging.INFO if args.verbose else logging.ERROR, format="%(name)s: %(message)s")
    if (getattr(args, "command", None) in ("plan", "compare", "route") and args.k is None and args.robot is None
            and getattr(args, "duration", None) is None and getattr(args, "timing", None) is None):
        args.k = DEFAULT_K
    args.stdout = sys.stdout
    to_stdout = getattr(args, "json", None) == "-"
    try:
        with ExitStack() as stack:
            Claims.stack, Claims.files = stack, {}
            with contextlib.redirect_stdout(sys.stderr) if to_stdout else contextlib.nullcontext(), \
                    Progress(delay=5.0) as progress, reporting(progress):
                status = args.func(args)
            args.stdout.flush()   # a full disk or a closed pipe behind stdout shows here, inside the handlers
            return status
    except interrupts.Terminated:   # SIGTERM, also inside the solvers
        print("rollplan: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:  # Ctrl-C, also inside the solvers (rollplan.interrupts)
        print("\nrollplan: interrupted" if sys.stderr.isatty() else "rollplan: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        print("rollplan: error: not enough memory for this input", file=sys.stderr)
        return EXIT_INPUT
    except InputError as exc:
        print(f"rollplan: error: {cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_INPUT
    except NoPlanError as exc:
        print(f"rollplan: no plan: {cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_NOPLAN
    except SolverError as exc:
        print(f"rollplan: solver failed ({exc.status}): {cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_SOLVER
    except OSError as exc:   # stdout on a full disk (`> /dev/full`), into a closed pipe (`| head -c1`): one line
        if exc.errno not in WRITE_FAILURES:
            return _interrupted_or_raise(exc)
        _drop_stdout()
        try:
            print(f"rollplan: error: the standard output cannot be written: {WRITE_FAILURES[exc.errno]}",
                  file=sys.stderr)
        except OSError:   # stderr is gone too (`2>&1 | head`): the exit status says it
            _drop_stdout(sys.stderr)
        return EXIT_INPUT
    except Exception as exc:
        return _interrupted_or_raise(exc)
    finally:
        Claims.stack = None


def _interrupted_or_raise(exc: Exception) -> int:
    """For an unexpected error ``exc``: the exit status of a Ctrl-C (or SIGTERM) pending when it was raised
    (:func:`rollplan.interrupts.pending`: the interrupt turned into another error on its way), its one line
    printed; ``exc`` raised on if none is pending."""
    signal_type = interrupts.pending()
    if signal_type is None:
        raise exc
    terminated = issubclass(signal_type, interrupts.Terminated)
    print(f"rollplan: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
    return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED
