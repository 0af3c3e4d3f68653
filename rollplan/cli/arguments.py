"""The command line's parser class, number types and the options several commands share."""

from __future__ import annotations

import argparse
import re

from ..errors import SHOW_WIDTH, InputError, show, show_limit
from ..inputs import parse_number, parse_whole
from ..problem import DEFAULT_K, K_MAX, MAX_STEPS
from ..robot import ROBOT_KEYS
from .common import EXIT_INPUT

__all__ = ["Parser", "number", "radius", "whole", "K_HELP", "STEPS_HELP", "JSON_HELP", "add_target_options",
           "add_robot_options"]

#: The limits of ``--radius``: those of a robot file's radius.
_RADIUS = next(key for key in ROBOT_KEYS if key.name == "radius")
#: Numbers as argparse should see them: also in exponent form (-1e-3) and -inf/-nan (refused later by the
#: number check, with a clear message, instead of being taken for an option).
_NEGATIVE_NUMBER = re.compile(r"^-([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


#: A value argparse echoes in a message, quoted or not, longer than a message shows (:func:`rollplan.errors.show`).
_QUOTED_LONG = re.compile(r"'([^'\s]{%d,})'" % SHOW_WIDTH)
_BARE_LONG = re.compile(r"(?<![\S])[^\s']{%d,}" % (SHOW_WIDTH + 1))


class Parser(argparse.ArgumentParser):
    """argparse that takes negative numbers in any form and reports bad input in one line with exit code 2.

    ``builder(parser)``, if given, adds the arguments when the parser is first used (a command whose options
    need heavy modules loads them only when it runs or shows its help).
    """

    def __init__(self, *args, builder=None, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER
        self._builder = builder

    def _build(self) -> None:
        if self._builder is not None:
            build, self._builder = self._builder, None
            build(self)

    def parse_known_args(self, args=None, namespace=None):
        self._build()
        return super().parse_known_args(args, namespace)

    def format_help(self):
        self._build()
        return super().format_help()

    def format_usage(self):
        self._build()
        return super().format_usage()

    def error(self, message):
        message = _QUOTED_LONG.sub(lambda m: show(m.group(1)), message)   # argparse echoes values in full
        message = _BARE_LONG.sub(lambda m: m.group(0)[:SHOW_WIDTH - 3] + "...", message)
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


def number(text: str) -> float:
    try:
        return parse_number(text, "value")
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value = ")) from None


def radius(text: str) -> float:
    """``--radius``: a number within the limits of a robot file's ``radius`` (:data:`rollplan.robot.ROBOT_KEYS`)."""
    try:
        return parse_number(text, "radius", _RADIUS.low, _RADIUS.high)
    except InputError as exc:
        raise argparse.ArgumentTypeError(f"{exc} {_RADIUS.unit}") from None


def whole(text: str) -> int:
    try:
        return parse_whole(text, "value")
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value = ")) from None


K_HELP = "inertia ratio k in [0, %g] (default %g, the paper's case)" % (K_MAX, DEFAULT_K)
STEPS_HELP = "in [1, %d]" % MAX_STEPS
JSON_HELP = "write {} as JSON to FILE (- for stdout; the summary then goes to stderr)"


def add_target_options(parser, to_default, steps_help, k_help=K_HELP) -> None:
    """--to, --psi, --steps, --k | --robot, --radius: the target and the robot, as in ``plan``."""
    if to_default is None:
        parser.add_argument("--to", nargs=2, type=number, metavar=("U", "V"), required=True,
                            help="target contact point (u_a, v_a) on the plane")
    else:
        parser.add_argument("--to", nargs=2, type=number, metavar=("U", "V"), default=to_default,
                            help="target contact point (u_a, v_a) on the plane (default %g %g)" % tuple(to_default))
    parser.add_argument("--psi", type=number, default=0.0, help="target contact angle [rad] (default 0)")
    parser.add_argument("--steps", type=whole, default=1, help=steps_help)
    add_robot_options(parser, k_help)


def add_robot_options(parser, k_help=K_HELP) -> None:
    """--k | --robot, --radius: the robot, as in ``plan``."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--k", type=number, default=None, help=k_help)
    g.add_argument("--robot", metavar="FILE.toml", help="robot parameters (k from eq. 14; lengths in metres)")
    parser.add_argument("--radius", type=radius, default=None,
                        help=f"sphere radius R [m] in [{show_limit(_RADIUS.low)}, {show_limit(_RADIUS.high)}] (as "
                             "in a robot file); lengths are then in metres (default: lengths in units of R, or the "
                             "robot's radius)")
