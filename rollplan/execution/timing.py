"""Timing laws: how a plan's fixed path is run in time, by name, within the motors' limits.

Contract of a timing law
------------------------
A law is a :class:`TimeLaw` registered in :data:`LAWS` (:func:`register`), looked up by
name with :func:`get_law` (``rollplan plan --timing NAME``).

Input
    a :class:`TimingPath`: the path parameter s in [0, L] (the contact arc length for
    a figure eight), the pieces' boundaries ``starts`` and which joints are corners
    (where every motion must be at rest), and the rotor coefficients: rates
    ``G(s) s'``, torques ``A(s) s'' + B(s) s'^2`` (one-sided values at the joints,
    where ``B`` jumps); :class:`~rollplan.execution.path.ContactPath` is one. Then
    :class:`~rollplan.execution.limits.Limits` (possibly none) and a duration T [s], or
    None for the law's shortest duration within the limits (which needs a limit).
Output
    a :class:`TimeProfile`: ``s(t)`` on [0, T] as a piecewise polynomial, evaluated by
    :meth:`TimeProfile.evaluate` to ``(s, s', s'')``, with the law's
    ``minimum_duration`` (None without limits). Guaranteed: ``s(0) = 0``,
    ``s(T) = L``, ``s'(0) = s'(T) = 0``, ``s' >= 0``, s and s' continuous, s''
    bounded and piecewise continuous, ``s' = 0`` at every corner; laws with
    ``stops_at_joints`` also have ``s' = s'' = 0`` at every joint. The rotor rates
    ``G s'`` and torques ``A s'' + B s'^2`` stay within the limits (``time-optimal``:
    exactly at its check points, and between them up to the discretisation error of
    the check, see below).
Limits
    :meth:`TimeLaw.minimum_duration` is the shortest T for which the law stays within
    the limits. A requested T below it raises :class:`rollplan.errors.InputError`
    naming the limit, the value the law would need, and the shortest feasible
    duration (rounded up, so that it is accepted when given back).
Sampling
    ``samples_per_piece``: the least number of uniform time samples per piece that
    the law's rotor rates need for a cubic spline through them (the rotor-only
    simulation of :mod:`rollplan.execution.plants`, the motion's certificate) to
    reach the target within a tenth of the certificate's tolerance (1e-7 of 1e-6),
    measured on the README's examples and random plans with and without active
    limits. The non-stop laws have kinks in the rates (the torque steps at the
    joints; the time-optimal law's switches and piecewise-constant s''), where the
    spline's error falls only as h^2, so they need many more than ``min-jerk``.

Laws
----
``min-jerk`` (the default with ``--duration``)
    Today's law: every piece takes ``T / P`` with the quintic rest-to-rest profile
    ``10 tau^3 - 15 tau^4 + 6 tau^5``; stops at every joint.
``nonstop-min-jerk``
    One quintic rest-to-rest profile in s over every stretch between corners (the
    whole path of a figure eight), each stretch in a time proportional to its length.
    Does not stop at the smooth joints (the torque steps there by ``Delta B s'^2``).
``smooth-cruise``
    Non-stop and smooth: over every stretch between corners the speed rises by the
    quintic smoothstep over a fraction ``ramp`` of the stretch's time, cruises, and
    falls the same way (s is C3 in t). With limits, ``ramp`` is the fraction with the
    shortest duration within them (golden section); without, 1/4. Close to
    time-optimal when the speed is capped by the path's curvature (the ``B s'^2``
    term of the torque).
``time-optimal``
    The minimum-time rest-to-rest profile under the limits
    (:func:`rollplan.execution.topp.solve_topp`, TOPP-RA's passes on a grid of
    :data:`TOPP_INTERVALS` intervals or more); needs ``max_rotor_torque``. The grid
    solution meets the limits at the nodes and may exceed them in between by
    O(Delta^2); the law checks :data:`CHECK_POINTS` points per grid interval (with the
    one-sided values at piece ends and joints) and stretches the profile in time by the
    factor that brings them within the limits. Given a longer T, the profile is
    stretched uniformly.

Time scaling: the first three laws are ``s(t) = F(t / T)``, so rates scale as
``1/T`` and torques as ``1/T^2`` (both terms of ``A s'' + B s'^2``), and
``T_min = max(rho_rate / max_rotor_rate, sqrt(rho_torque / max_rotor_torque))``
with the peaks ``rho`` of the unit-duration law (:func:`unit_peaks`).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, replace
from typing import Protocol, runtime_checkable

import numpy as np

from ..errors import InputError, check_range
from .limits import Limits
from .path import PathGrid
from .topp import GridProfile, maximum_velocity_curve, solve_topp

__all__ = ["MIN_JERK", "DURATION_RANGE", "NO_LIMITS", "TOPP_INTERVALS", "CHECK_POINTS", "TimingPath", "TimeProfile",
           "TimeLaw", "ScaledLaw", "MinJerk", "NonstopMinJerk", "SmoothCruise", "TimeOptimal", "LAWS", "register",
           "get_law", "unit_peaks", "peak_utilisation", "joint_times", "velocity_limit", "round_up", "resting_sides"]

log = logging.getLogger(__name__)

#: Coefficients of the minimum-jerk rest-to-rest profile ``10 tau^3 - 15 tau^4 + 6 tau^5``, ascending powers.
MIN_JERK = np.array([0.0, 0.0, 0.0, 10.0, -15.0, 6.0])
#: Accepted durations [s].
DURATION_RANGE = (1e-3, 1e6)
#: Least number of grid intervals of the time-optimal law (at least 16 per piece).
TOPP_INTERVALS = 2000
#: Points per grid interval at which the time-optimal law checks the limits.
CHECK_POINTS = 16
#: No limit at all.
NO_LIMITS = Limits()

_SMOOTHSTEP_INTEGRAL = np.polynomial.Polynomial([0.0, 0.0, 0.0, 0.0, 2.5, -3.0, 1.0])  # int_0^tau 10u^3-15u^4+6u^5


@runtime_checkable
class TimingPath(Protocol):
    """What a timing law needs of a path (:class:`~rollplan.execution.path.ContactPath` is one).

    Attributes
    ----------
    length : float
        L, the path parameter at the end [R].
    starts : ndarray, shape (P + 1,)
        s at the start of every piece, and L.
    corners : ndarray, shape (P - 1,), bool
        For every joint ``starts[1:-1]``: must every motion be at rest there.
    """

    length: float
    starts: np.ndarray
    corners: np.ndarray

    def coefficients(self, s, side: str = "left") -> tuple:
        """``(G, A, B)``, each (N, 2), at the values s; at a joint from the piece that ends (left) or starts there."""
        ...

    def grid(self, n: int) -> PathGrid:
        """The coefficients on a grid of about n intervals with every joint a node."""
        ...


@dataclass(frozen=True)
class TimeProfile:
    """``s(t)`` as a piecewise polynomial in time.

    Attributes
    ----------
    breaks : ndarray, shape (M + 1,)
        Piece boundaries [s]; ``breaks[0] = 0``, ``breaks[-1] = T``.
    coeffs : ndarray, shape (M, d + 1)
        Coefficients of piece k in ascending powers of ``t - breaks[k]``.
    law : str
        Name of the law that made it.
    length : float
        L [R].
    minimum_duration : float or None
        The law's shortest duration within the limits it was made with [s]; None without limits.
    grid : GridProfile or None
        The time-optimal law's solution on its grid (with the maximum velocity curve); None otherwise.
    """

    breaks: np.ndarray
    coeffs: np.ndarray
    law: str
    length: float
    minimum_duration: float | None = None
    grid: GridProfile | None = None

    @property
    def duration(self) -> float:
        return float(self.breaks[-1])

    def evaluate(self, t, piece=None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(s, s', s'')`` at times ``t`` (clipped to [0, T]); at a break the piece that starts there.

        ``piece`` (ints like ``t``) forces the polynomial piece used, e.g. the one that ends at a break.
        """
        c, pw = self._terms(t, piece)
        p = np.arange(c.shape[1])
        s = np.sum(c * pw, axis=1)
        sd = np.sum(c[:, 1:] * p[1:] * pw[:, :-1], axis=1)
        sdd = np.sum(c[:, 2:] * (p[2:] * (p[2:] - 1)) * pw[:, :-2], axis=1)
        return s, sd, sdd

    def position(self, t) -> np.ndarray:
        """``s`` at times ``t``: the first value of :meth:`evaluate`, computed alone."""
        c, pw = self._terms(t)
        return np.sum(c * pw, axis=1)

    def _terms(self, t, piece=None) -> tuple[np.ndarray, np.ndarray]:
        """The coefficients (M, degree + 1) of the pieces of times ``t`` (M,), clipped to [0, T], and the powers
        of the times from the pieces' starts (M, degree + 1)."""
        t = np.clip(np.atleast_1d(np.asarray(t, float)), 0.0, self.duration)
        if piece is None:
            k = np.clip(np.searchsorted(self.breaks, t, side="right") - 1, 0, self.coeffs.shape[0] - 1)
        else:
            k = np.asarray(piece, int)
        return self.coeffs[k], (t - self.breaks[k])[:, None] ** np.arange(self.coeffs.shape[1])

    def stretched(self, factor: float) -> TimeProfile:
        """The same path run ``factor`` times slower: ``s(t / factor)``."""
        p = np.arange(self.coeffs.shape[1])
        return replace(self, breaks=self.breaks * factor, coeffs=self.coeffs / factor**p)


def _pieces(starts: np.ndarray, times: np.ndarray, unit: np.ndarray):
    """Piecewise polynomial of ``s = S_j + L_j F((t - t_j) / T_j)`` with ``F`` in ascending powers ``unit``."""
    lengths, durations = np.diff(starts), np.diff(times)
    coeffs = lengths[:, None] * unit[None, :] / durations[:, None] ** np.arange(unit.size)
    coeffs[:, 0] += starts[:-1]
    return coeffs


def _stretches(path: TimingPath) -> np.ndarray:
    """s at the ends of the stretches between corners: ``[0, corners..., L]``."""
    return np.concatenate([[0.0], np.asarray(path.starts)[1:-1][np.asarray(path.corners, bool)], [path.length]])


def joint_times(path: TimingPath, profile: TimeProfile, iterations: int = 100) -> np.ndarray:
    """Times at which a profile passes the joints ``starts[1:-1]``.

    Bisection on the nondecreasing s(t) (``iterations`` halvings, or fewer once no bracket changes: then
    none would); a break of the profile where s is the joint to rounding (``1e-12 L``) is taken instead, so
    that a law that rests at a joint is evaluated exactly there.
    """
    joints = np.asarray(path.starts, float)[1:-1]
    lo, hi = np.zeros(joints.size), np.full(joints.size, profile.duration)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        below = profile.position(mid) < joints
        lo_next, hi_next = np.where(below, mid, lo), np.where(below, hi, mid)
        if np.array_equal(lo_next, lo) and np.array_equal(hi_next, hi):
            break
        lo, hi = lo_next, hi_next
    b = profile.breaks
    near = b[np.clip(np.searchsorted(b, hi), 0, b.size - 1)]
    on_break = np.abs(profile.evaluate(near)[0] - joints) <= 1e-12 * path.length
    return np.where(on_break, near, hi)


def _at_breaks(profile: TimeProfile, t: np.ndarray, side: str):
    """Times snapped to a break within rounding, and the piece that ends (left) or starts (right) there."""
    b = profile.breaks
    i = np.clip(np.searchsorted(b, t), 1, b.size - 1)
    for cand in (i - 1, i):
        t = np.where(np.abs(t - b[cand]) <= 1e-12 * profile.duration, b[cand], t)
    k = np.searchsorted(b, t, side=side) - 1
    return t, np.clip(k, 0, b.size - 2)


def resting_sides(path: TimingPath, s, s_ddot, side: str = "left") -> np.ndarray:
    """Which samples must take the path's other one-sided coefficients than ``side``: those at rest on a corner
    (s within ``1e-12 L``, where the path takes the joint's value) that leave it (``s'' > 0``: the piece after)
    while ``side`` is "left", or arrive (``s'' < 0``: the piece before) while it is "right".

    Near a corner a resting motion's s is flat, so samples a little after the rest have s at the corner to rounding
    and would pair the piece before's coefficients (``A`` jumps at a corner) with the s'' of the piece after."""
    corners = np.asarray(path.starts, float)[1:-1][np.asarray(path.corners, bool)]
    s = np.atleast_1d(np.asarray(s, float))
    if not corners.size:
        return np.zeros(s.size, bool)
    near = np.abs(s[:, None] - corners[None, :]).min(axis=1) <= 1e-12 * path.length
    return near & ((np.asarray(s_ddot) > 0) if side == "left" else (np.asarray(s_ddot) < 0))


def _rates_torques(path: TimingPath, profile: TimeProfile, t, side: str = "left", piece=None):
    s, sd, sdd = profile.evaluate(t, piece)
    s = np.clip(s, 0.0, path.length)
    G, A, B = path.coefficients(s, side)
    flip = resting_sides(path, s, sdd, side)
    if flip.any():
        G[flip], A[flip], B[flip] = path.coefficients(s[flip], "right" if side == "left" else "left")
    return G * sd[:, None], A * sdd[:, None] + B * sd[:, None] ** 2


def _joint_sets(path: TimingPath, profile: TimeProfile):
    """``(times, pieces, side)`` of the joint passages, from both sides (a joint at a break: both pieces)."""
    tj = joint_times(path, profile)
    return [(*_at_breaks(profile, tj, side), side) for side in ("left", "right")] if tj.size else []


def unit_peaks(path: TimingPath, profile: TimeProfile, samples: int = 4000, refine: int = 400) -> tuple[float, float]:
    """Peak ``|rotor rate|`` and ``|torque|`` of a profile, by dense sampling refined around the largest values.

    ``samples`` uniform times, then ``refine`` points within one spacing of the three
    largest samples of each quantity, and the joint passages with both one-sided
    torques. For a smooth peak the relative error is ``O((1 / (samples refine))^2)``.
    """
    t = np.linspace(0.0, profile.duration, samples + 1)
    r, q = _rates_torques(path, profile, t)
    best = [float(np.abs(r).max()), float(np.abs(q).max())]
    h = t[1] - t[0]
    for which, vals in enumerate((np.abs(r).max(axis=1), np.abs(q).max(axis=1))):
        for i in np.argsort(vals)[-3:]:
            tt = np.linspace(max(t[i] - h, 0.0), min(t[i] + h, profile.duration), refine + 1)
            best[which] = max(best[which], float(np.abs(_rates_torques(path, profile, tt)[which]).max()))
    for tt, kk, side in _joint_sets(path, profile):
        rr, qq = _rates_torques(path, profile, tt, side, kk)
        best = [max(best[0], float(np.abs(rr).max())), max(best[1], float(np.abs(qq).max()))]
    return best[0], best[1]


def peak_utilisation(path: TimingPath, profile: TimeProfile, limits: Limits, per_piece: int = CHECK_POINTS):
    """Largest rate and torque utilisation (``|value| / limit``) of a profile at check points.

    Points: ``per_piece - 1`` inside every polynomial piece; both ends of every piece, each
    with that piece's s'' and the path's one-sided values on its side; and the joint passages
    from both sides. Returns ``(rate, torque)`` (0 for an absent limit).
    """
    b = profile.breaks
    m = b.size - 1
    frac = np.arange(1, per_piece) / per_piece
    inner = (b[:-1, None] + np.diff(b)[:, None] * frac[None, :]).ravel()
    pieces = np.arange(m)
    sets = [(b[:-1], pieces, "right"), (b[1:], pieces, "left"), (inner, np.repeat(pieces, frac.size), "left"),
            *_joint_sets(path, profile)]
    ur = uq = 0.0
    for t, piece, side in sets:
        if t.size == 0:
            continue
        r, q = _rates_torques(path, profile, t, side, piece)
        if limits.max_rotor_rate is not None:
            ur = max(ur, float(np.abs(r).max() / limits.max_rotor_rate))
        if limits.max_rotor_torque is not None:
            uq = max(uq, float(np.abs(q).max() / limits.max_rotor_torque))
    return ur, uq


def round_up(x: float, digits: int = 6) -> float:
    """``x`` > 0 rounded up to ``digits`` significant digits (a shortest duration that is accepted when given back)."""
    exponent = math.floor(math.log10(x)) - digits + 1
    return float(f"{math.ceil(x / 10.0**exponent * (1 - 1e-15))}e{exponent}")


def _duration_for(rho_rate: float, rho_torque: float, limits: Limits) -> float:
    """Shortest duration of a scaled law with unit-duration peaks ``rho_rate``, ``rho_torque``."""
    out = 0.0
    if limits.max_rotor_rate is not None:
        out = max(out, rho_rate / limits.max_rotor_rate)
    if limits.max_rotor_torque is not None:
        out = max(out, math.sqrt(rho_torque / limits.max_rotor_torque))
    return out


class TimeLaw:
    """A named timing law (see the module docstring for the contract).

    Attributes
    ----------
    name : str
    summary : str
        One line for ``--help``.
    stops_at_joints : bool
        ``s' = s'' = 0`` at every joint between pieces (every law stops at corners).
    needs_torque_limit : bool
        Defined only with ``max_rotor_torque`` (time-optimal).
    samples_per_piece : int
        Least number of uniform time samples per piece (module docstring, "Sampling").
    """

    name: str = ""
    summary: str = ""
    stops_at_joints: bool = False
    needs_torque_limit: bool = False
    samples_per_piece: int = 3000

    def make(self, path: TimingPath, limits: Limits, duration: float | None) -> TimeProfile:
        """The profile for a checked duration (None: the shortest); subclasses implement it."""
        raise NotImplementedError

    def profile(self, path: TimingPath, limits: Limits = NO_LIMITS, duration: float | None = None) -> TimeProfile:
        """``s(t)`` of this law over ``duration`` (None: the shortest within the limits).

        Raises
        ------
        InputError
            A bad duration; no limit where one is needed; a duration shorter than the
            law's minimum (naming the limit and that minimum).
        """
        if not isinstance(path, TimingPath):
            raise InputError(f"path = {path!r:.60} is not allowed: give a ContactPath (or another TimingPath)")
        prof = self.make(path, limits, self.check(limits, duration))
        low, high = DURATION_RANGE
        if duration is None and not low <= prof.duration <= high:
            hint = "give a duration" if prof.duration < low else "the limits are too small for this motion"
            raise InputError(f"timing '{self.name}': the shortest feasible duration within {limits.describe()} is "
                             f"{prof.duration:.6g} s, outside the accepted [{low:g}, {high:g}] s: {hint}")
        return prof

    def check(self, limits: Limits, duration: float | None = None) -> float | None:
        """The checks of :meth:`profile` that need no path (cheap: call them before planning); the duration.

        Raises
        ------
        InputError
            ``limits`` not a Limits, a duration outside :data:`DURATION_RANGE`, no torque limit for a law that
            needs one, or neither a duration nor a limit.
        """
        if not isinstance(limits, Limits):
            raise InputError(f"limits = {limits!r:.60} is not allowed: give a rollplan.execution.limits.Limits")
        if self.needs_torque_limit and limits.max_rotor_torque is None:
            raise InputError(f"timing '{self.name}' needs max_rotor_torque (in the robot file): with a rate limit "
                             "alone, or none, the fastest motion needs an infinite torque")
        if duration is None and not limits.any:
            raise InputError(f"timing '{self.name}' needs a duration, or limits in the robot file "
                             "(max_rotor_rate, max_rotor_torque) to find the shortest one")
        return None if duration is None else check_range("duration", duration, *DURATION_RANGE)

    def minimum_duration(self, path: TimingPath, limits: Limits) -> float:
        """Shortest duration [s] for which this law stays within ``limits`` (which must not be empty)."""
        return self.profile(path, limits, None).duration

    def _refuse(self, duration, needed: str, limit: str, shortest: float):
        raise InputError(f"duration = {duration!r} s is not allowed with timing '{self.name}': it needs {needed} > "
                         f"{limit}; the shortest feasible duration is {round_up(shortest):.6g} s")


class ScaledLaw(TimeLaw):
    """A law ``s(t) = F(t / T)``: :meth:`unit` gives F over a unit duration; the peaks scale with 1/T and 1/T^2."""

    def unit(self, path: TimingPath, limits: Limits) -> TimeProfile:
        """The profile over T = 1 s."""
        raise NotImplementedError

    def make(self, path, limits, duration):
        unit = self.unit(path, limits)
        if not limits.any:
            return unit.stretched(duration)
        rho_rate, rho_torque = unit_peaks(path, unit)
        shortest = _duration_for(rho_rate, rho_torque, limits)
        if duration is None:
            duration = shortest
        elif duration < shortest * (1 - 1e-9):
            worst = []
            if limits.max_rotor_rate is not None:
                need = rho_rate / duration
                worst.append((need / limits.max_rotor_rate, f"{need:.4g} rad/s",
                              f"max_rotor_rate = {limits.max_rotor_rate!r} rad/s"))
            if limits.max_rotor_torque is not None:
                need = rho_torque / duration**2
                worst.append((need / limits.max_rotor_torque, f"{need:.4g} N m",
                              f"max_rotor_torque = {limits.max_rotor_torque!r} N m"))
            _, needed, limit = max(worst)
            self._refuse(duration, needed, limit, shortest)
        return replace(unit.stretched(duration), minimum_duration=shortest)


class MinJerk(ScaledLaw):
    """Every piece in ``T / P`` with the minimum-jerk rest-to-rest profile: stops at every joint."""

    name = "min-jerk"
    summary = "every piece (half-step) in T/P with the quintic rest-to-rest profile: stops at every pole"
    stops_at_joints = True
    samples_per_piece = 400

    def unit(self, path, limits):
        starts = np.asarray(path.starts, float)
        times = np.linspace(0.0, 1.0, starts.size)
        return TimeProfile(times, _pieces(starts, times, MIN_JERK), self.name, path.length)


class NonstopMinJerk(ScaledLaw):
    """One minimum-jerk profile in s over every stretch between corners, in a time proportional to its length."""

    name = "nonstop-min-jerk"
    summary = "one quintic rest-to-rest profile in the arc length: smooth, no stop at the poles"
    samples_per_piece = 20000

    def unit(self, path, limits):
        ends = _stretches(path)
        times = ends / path.length
        return TimeProfile(times, _pieces(ends, times, MIN_JERK), self.name, path.length)


class SmoothCruise(ScaledLaw):
    """Smoothstep ramp up, cruise, ramp down over every stretch between corners (s is C3 in t).

    Parameters
    ----------
    ramp : float or None
        Fraction of each stretch's time spent in each ramp, in [0.01, 0.5]; None: the fraction with
        the shortest duration within the limits (golden section), or 1/4 without limits.
    """

    name = "smooth-cruise"
    summary = ("smoothstep ramp up, cruise, ramp down in the arc length (C3): no stop at the poles; the ramp "
               "minimises the duration within the limits")
    samples_per_piece = 16000

    def __init__(self, ramp: float | None = None):
        self.ramp = None if ramp is None else check_range("ramp", ramp, 0.01, 0.5)

    def shape(self, path: TimingPath, ramp: float) -> TimeProfile:
        """The unit-duration profile with ramp fraction ``ramp``."""
        ends = _stretches(path)
        times = ends / path.length
        breaks, coeffs = [], []
        for s0, s1, t0, t1 in zip(ends[:-1], ends[1:], times[:-1], times[1:]):
            length, dur = s1 - s0, t1 - t0
            tr = ramp * dur
            v = length / (dur - tr)
            up = s0 + v * tr * _SMOOTHSTEP_INTEGRAL(np.polynomial.Polynomial([0.0, 1.0 / tr]))
            down = s1 - v * tr * _SMOOTHSTEP_INTEGRAL(np.polynomial.Polynomial([1.0, -1.0 / tr]))
            parts = [(t0, up.coef), (t0 + tr, np.array([s0 + 0.5 * v * tr, v])), (t1 - tr, down.coef)]
            if dur - 2 * tr <= 1e-12 * dur:  # ramp = 1/2: no cruise
                parts.pop(1)
            for b, c in parts:
                breaks.append(b)
                coeffs.append(np.pad(c, (0, 7 - c.size)))
        breaks.append(1.0)
        return TimeProfile(np.array(breaks), np.array(coeffs), self.name, path.length)

    def unit(self, path, limits):
        ramp = self.ramp
        if ramp is None:
            ramp = self.best_ramp(path, limits) if limits.any else 0.25
        return self.shape(path, ramp)

    def best_ramp(self, path: TimingPath, limits: Limits, lo: float = 0.01, hi: float = 0.5, tol: float = 1e-3,
                  table: int = 8000) -> float:
        """Ramp fraction with the shortest duration within the limits (golden section on [lo, hi]).

        The search evaluates the path's coefficients tabulated once on a grid of ``table`` intervals,
        linearly interpolated (both one-sided values at the joints), at 2000 times per trial; the
        chosen ramp's duration is then computed by :func:`unit_peaks`. Should ``T_min(ramp)`` not be
        unimodal, this finds a local minimum: still a feasible law, perhaps not the fastest ramp.
        """
        grid = path.grid(table)

        def interp(s, C):
            return np.column_stack([np.interp(s, grid.s, C[:, i]) for i in range(C.shape[1])])

        def shortest(r):
            prof = self.shape(path, r)
            s, sd, sdd = prof.evaluate(np.linspace(0.0, 1.0, 2001))
            rate = np.abs(interp(s, grid.G_left) * sd[:, None]).max()
            torque = np.abs(interp(s, grid.A_left) * sdd[:, None] + interp(s, grid.B_left) * sd[:, None] ** 2).max()
            if grid.joints.size:
                _, psd, psdd = prof.evaluate(joint_times(path, prof))
                j = grid.joints
                for A, B in ((grid.A_left, grid.B_left), (grid.A_right, grid.B_right)):
                    torque = max(torque, np.abs(A[j] * psdd[:, None] + B[j] * psd[:, None] ** 2).max())
            return _duration_for(rate, torque, limits)

        g = (math.sqrt(5) - 1) / 2
        a, b = lo, hi
        c, d = b - g * (b - a), a + g * (b - a)
        fc, fd = shortest(c), shortest(d)
        while b - a > tol:
            if fc < fd:
                b, d, fd = d, c, fc
                c = b - g * (b - a)
                fc = shortest(c)
            else:
                a, c, fc = c, d, fd
                d = a + g * (b - a)
                fd = shortest(d)
        return 0.5 * (a + b)


class TimeOptimal(TimeLaw):
    """The minimum-time rest-to-rest profile within the limits (TOPP); longer durations stretch it.

    Parameters
    ----------
    intervals : int
        Least number of grid intervals (at least 16 per piece are used).
    backend : str
        Solver of :func:`rollplan.execution.topp.solve_topp`.
    """

    name = "time-optimal"
    samples_per_piece = 12000
    summary = ("shortest rest-to-rest motion within max_rotor_rate and max_rotor_torque (TOPP-RA); with a longer "
               "duration, the same profile stretched")
    needs_torque_limit = True

    def __init__(self, intervals: int = TOPP_INTERVALS, backend: str = "numpy"):
        self.intervals = int(check_range("intervals", intervals, 16, 10**6))
        self.backend = backend

    def make(self, path, limits, duration):
        pieces = np.asarray(path.starts).size - 1
        gp = solve_topp(path.grid(max(self.intervals, 16 * pieces)), limits, self.backend)
        coeffs = np.column_stack([gp.s[:-1], np.sqrt(gp.x[:-1]), 0.5 * gp.u])
        prof = TimeProfile(gp.t.copy(), coeffs, self.name, path.length, grid=gp)
        # between the grid nodes the limits may be exceeded by O(Delta^2): stretch by the factor that brings
        # the check points within them (rates scale as 1/c, torques as 1/c^2)
        ur, uq = peak_utilisation(path, prof, limits, CHECK_POINTS)
        c = max(1.0, ur, math.sqrt(uq))
        if c > 1.0:
            log.info("time-optimal: stretched by %.3e to stay within the limits between grid nodes", c - 1)
            prof = prof.stretched(c)
        shortest = prof.duration
        prof = replace(prof, minimum_duration=shortest)
        if duration is None:
            return prof
        if duration < shortest * (1 - 1e-9):
            raise InputError(f"duration = {duration!r} s is not allowed with timing '{self.name}': within "
                             f"{limits.describe()} the shortest feasible duration is {round_up(shortest):.6g} s")
        return prof.stretched(duration / shortest)


LAWS: dict[str, TimeLaw] = {}


def register(law: TimeLaw) -> TimeLaw:
    """Add a law to :data:`LAWS` under its name (a name may be registered once)."""
    if not isinstance(law, TimeLaw) or not law.name:
        raise ValueError(f"{law!r} is not a named TimeLaw")
    if law.name in LAWS:
        raise ValueError(f"timing law {law.name!r} is already registered")
    LAWS[law.name] = law
    return law


def get_law(name) -> TimeLaw:
    """The law called ``name``; InputError listing the names otherwise."""
    if isinstance(name, TimeLaw):
        return name
    if not isinstance(name, str) or name not in LAWS:
        raise InputError(f"timing = {name!r:.40} is not allowed: choose one of {', '.join(LAWS)}")
    return LAWS[name]


for _law in (MinJerk(), NonstopMinJerk(), SmoothCruise(), TimeOptimal()):
    register(_law)


def velocity_limit(path: TimingPath, limits: Limits, profile: TimeProfile | None = None,
                   intervals: int = TOPP_INTERVALS) -> tuple[np.ndarray, np.ndarray]:
    """The maximum velocity curve as ``(s, s'_max)``: the fastest the limits allow at each s [R, R/s].

    Taken from a time-optimal ``profile``'s grid when given, else computed on a grid of
    ``intervals`` intervals (:func:`rollplan.execution.topp.maximum_velocity_curve`); inf where
    no limit binds, 0 at the corners.
    """
    if profile is not None and profile.grid is not None:
        return profile.grid.s, np.sqrt(profile.grid.mvc)
    grid = path.grid(intervals)
    return grid.s, np.sqrt(maximum_velocity_curve(grid, limits))
