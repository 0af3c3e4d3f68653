"""Exceptions of rollplan: bad input, no plan, and solver failure."""

from __future__ import annotations

import math
from decimal import Decimal
from numbers import Integral, Real

import numpy as np

__all__ = ["InputError", "NoPlanError", "SolverError", "show", "check_finite", "check_range", "check_whole"]


class InputError(ValueError):
    """A user-supplied value is not allowed. The message is one line."""


class NoPlanError(RuntimeError):
    """No plan reaches the target with the given number of steps."""


class SolverError(RuntimeError):
    """A numerical solver failed; carries the solver's status."""

    def __init__(self, message: str, status: str = "") -> None:
        super().__init__(message)
        self.status = status


def show(value, width: int = 40) -> str:
    """``repr(value)``, shortened to ``width`` characters for a one-line message."""
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


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
        lo = "-inf" if low is None else f"{low:g}"
        hi = "inf" if high is None else f"{high:g}"
        span = ("(" if low_open or low is None else "[") + f"{lo}, {hi}" + (")" if high_open or high is None else "]")
        raise InputError(f"{name} = {x!r} is not allowed: it must lie in {span}")
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
