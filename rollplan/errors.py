"""Exceptions of rollplan: bad input, no plan, and solver failure."""

from __future__ import annotations

import math
from decimal import Decimal
from numbers import Integral, Real

import numpy as np

__all__ = ["InputError", "OutputError", "UnsafeCacheError", "NoPlanError", "SolverError", "SHOW_WIDTH", "show",
           "show_limit", "check_finite", "check_range", "check_whole", "check_choice", "check_flag"]


class InputError(ValueError):
    """A user-supplied value is not allowed. The message is one line."""


class OutputError(InputError):
    """An output cannot be written (read-only, locked by another writer, disk full, name too long...).

    A kind of :class:`InputError` (the command exits 2 with one line): the
    user chose where to write. The message is one line.
    """


class UnsafeCacheError(InputError):
    """The cache directory, or a compiled library in it, is owned by another user or writable by group or
    others: rollplan refuses to load code from it. A kind of :class:`InputError` (the command exits 2 with
    one line): the user chose the directory (``ROLLPLAN_CACHE_DIR``)."""


class NoPlanError(RuntimeError):
    """No plan reaches the target with the given number of steps."""


class SolverError(RuntimeError):
    """A numerical solver failed; carries the solver's status."""

    def __init__(self, message: str, status: str = "") -> None:
        super().__init__(message)
        self.status = status


#: Longest value shown in a message (:func:`show`): longer ones are cut, with an ellipsis.
SHOW_WIDTH = 24


def show(value, width: int = SHOW_WIDTH) -> str:
    """``repr(value)``, shortened to ``width`` characters (an ellipsis at the cut) for a one-line message:
    every message shows a user's value through it."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def show_limit(x) -> str:
    """A limit of an allowed range, printed exactly: ``100``, ``0.69``, ``1.5707963267948966``.

    Whole numbers print without a fraction; every other float prints as its
    shortest round-trip ``repr``, so a refused value is never shown beside a
    limit rounded to look like it.
    """
    if isinstance(x, Integral) and not isinstance(x, bool):
        return str(int(x))
    x = float(x)
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    if x.is_integer() and abs(x) < 1e16:
        return str(int(x))
    return repr(x)


def check_finite(name: str, value) -> float:
    """Return ``value`` as a float, or raise InputError unless it is a finite real number.

    Real numbers of any type (int, float, numpy scalars, Fraction, Decimal) are
    accepted; booleans, strings and everything else are refused.
    """
    scalar_array = isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf"
    if isinstance(value, (bool, str, bytes)) or not (isinstance(value, (Real, Decimal)) or scalar_array):
        raise InputError(f"{name} = {show(value)} is not allowed: it must be a finite real number")
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InputError(f"{name} = {show(value)} is not allowed: it must be a finite real number") from None
    if not math.isfinite(x):
        raise InputError(f"{name} = {show(value)} is not allowed: it must be a finite number")
    return x


def check_range(name: str, value, low=None, high=None, low_open=False, high_open=False) -> float:
    """Finite ``value`` within [low, high] (or open ends); InputError naming the bound otherwise."""
    x = check_finite(name, value)
    bad_low = low is not None and (x <= low if low_open else x < low)
    bad_high = high is not None and (x >= high if high_open else x > high)
    if bad_low or bad_high:
        lo = "-inf" if low is None else show_limit(low)
        hi = "inf" if high is None else show_limit(high)
        span = ("(" if low_open or low is None else "[") + f"{lo}, {hi}" + (")" if high_open or high is None else "]")
        raise InputError(f"{name} = {show(x)} is not allowed: it must lie in {span}")
    return x


def check_whole(name: str, value, low=None, high=None) -> int:
    """Return ``value`` as an int, or raise InputError unless it is a whole number in [low, high].

    Booleans are refused; so are floats, even whole-valued ones.
    """
    if isinstance(value, bool) or not isinstance(value, Integral):
        raise InputError(f"{name} = {show(value)} is not allowed: it must be a whole number")
    if (low is not None and value < low) or (high is not None and value > high):
        span = f">= {low}" if high is None else (f"<= {high}" if low is None else f"in [{low}, {high}]")
        raise InputError(f"{name} = {show(value)} is not allowed: it must be a whole number {span}")
    return int(value)


def check_choice(name: str, value, choices) -> str:
    """Return ``value`` if it is one of the names ``choices`` (strings); InputError listing them otherwise."""
    if not isinstance(value, str) or value not in choices:
        raise InputError(f"{name} = {show(value)} is not allowed: choose one of {', '.join(choices)}")
    return value


def check_flag(name: str, value) -> bool:
    """Return ``value`` if it is a bool (True or False); InputError otherwise (no truthy strings or numbers)."""
    if not isinstance(value, (bool, np.bool_)):
        raise InputError(f"{name} = {show(value)} is not allowed: it must be True or False")
    return bool(value)
