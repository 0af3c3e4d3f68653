"""What every command shares: exit codes, the outputs it holds, JSON output, the robot and target checks."""

from __future__ import annotations

import logging
import os
from contextlib import ExitStack

from ..errors import InputError
from ..inputs import show_path
from ..io import check_figure_path, check_writable, tagged, write_json
from ..outputs import claim, json_chunks, write_all
from ..problem import State, check_contact, check_reach
from ..robot import load_robot

__all__ = ["EXIT_OK", "EXIT_SOME_FAILED", "EXIT_INPUT", "EXIT_NOPLAN", "EXIT_SOLVER", "EXIT_INTERRUPTED",
           "EXIT_TERMINATED", "NORM", "Claims", "check_outputs", "emit_json", "k_or_robot", "radius_in_use",
           "check_target", "quiet_dask"]

EXIT_OK, EXIT_SOME_FAILED, EXIT_INPUT, EXIT_NOPLAN, EXIT_SOLVER, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
EXIT_TERMINATED = 143   # SIGTERM: stopped as for Ctrl-C (128 + 15, the shell's status of a terminated command)

#: What a residual is (printed next to every residual and arrival error).
NORM = "Euclidean norm; lengths in R, angles in rad"


class Claims:
    """The outputs the running command holds (:func:`rollplan.outputs.claim`), released when it ends."""

    stack: ExitStack | None = None
    files: dict = {}   # real path of each output of the running command -> the name given


def check_outputs(json=None, figure=None, inputs=()) -> None:
    """Refuse unwritable output paths, unknown figure formats, outputs that are inputs and two outputs that are
    one file before any computation, and hold the outputs (a second process writing one of them is refused)."""
    if json == "-":   # stdout: no file to check, compare or hold
        json = None
    if json is not None:
        check_writable(json, inputs=inputs)
    if figure is not None:
        check_figure_path(figure)
        check_writable(figure, "figure", inputs=inputs)
    for name in (json, figure):
        if name is None:
            continue
        real = os.path.realpath(name)
        if real in Claims.files:
            raise InputError(f"output {show_path(name)} is the same file as output "
                             f"{show_path(Claims.files[real])}: give each output its own name")
        Claims.files[real] = name
    if Claims.stack is not None:
        Claims.stack.enter_context(claim(json, figure))


def emit_json(args, obj, unit: str) -> None:
    """Write ``obj`` (with ``version`` and ``units``) to ``--json FILE``, or to stdout for ``--json -``."""
    doc = tagged(obj, unit)
    if args.json == "-":   # streamed, piece by piece as it is encoded
        args.stdout.flush()
        try:
            fd = args.stdout.fileno()
        except (AttributeError, OSError, ValueError):   # a stream without a file descriptor (captured)
            for piece in json_chunks(doc):
                args.stdout.write(piece.decode())
            args.stdout.flush()
        else:   # not through the stream: Python's buffered writer drops the rest of a short write into a pipe
            for piece in json_chunks(doc):
                write_all(fd, piece)
    else:
        write_json(args.json, doc)
        print(f"wrote {args.json}")


def k_or_robot(args):
    """(k, robot) from --k / --robot."""
    if args.robot is not None:
        return None, load_robot(args.robot)
    return args.k, None


def radius_in_use(args, robot) -> float:
    """The sphere's radius in the length unit of the command: --radius, else the robot's, else 1 (R)."""
    return args.radius if args.radius is not None else (robot.radius if robot is not None else 1.0)


def check_target(args, robot, start=(0.0,) * 5, contact=(0.0, 0.0)) -> None:
    """--to (within reach of the start), --from and --contact before any work, each named in its message."""
    check_contact(start[3], start[4], "argument --from: start")
    check_contact(contact[0], contact[1], "argument --contact: goal")
    radius = radius_in_use(args, robot)
    check_reach(State(*start), State(*args.to), radius, "argument --to: goal",
                "the start (--from)" if any(start) else "the start")


def quiet_dask(args) -> None:
    """Without --verbose, Dask's own log (tracebacks of lost connections, on stderr) is silenced: the command
    says in one line what failed."""
    if getattr(args, "scheduler", None) is not None and not args.verbose:
        import distributed  # noqa: F401  (sets its loggers' levels on import: set ours after it)

        logging.getLogger("distributed").setLevel(logging.CRITICAL)
