"""Costs of a timed motion, by name: one function for the motions of every method.

A :class:`TimedMotion` is a motion sampled in time with what the costs need: the
state, the angular velocity, the rotor rates and the motor torques. Both planners'
motions become one (the geometric-phase path timed by a law,
:mod:`rollplan.execution.optimal_timing`; the rest-to-rest collocation,
:mod:`rollplan.planners.collocation.rest`), and :func:`measure` computes every
cost of :data:`COSTS` from the samples alone, the same way for both.

Jumps. A motion whose torques jump (piecewise-constant accelerations) is sampled
with the jump's time twice, the value before and the value after; the quadrature
then integrates each smooth block between repeated times on its own (Simpson's
rule on an odd number of uniform samples, else the trapezoid), so a jump costs no
accuracy.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .errors import InputError, check_choice
from .problem import STATE_NAMES
from .result import Trajectory

__all__ = ["COSTS", "RENAMED_COSTS", "cost_key", "TimedMotion", "measure", "integrate_samples"]

#: Old names of the planners' running costs, ``{old: new}``: ``"path_length"`` named the energy form
#: ``int |v|^2 dt`` (now ``"path_energy"``) in :data:`rollplan.planners.collocation.COSTS`,
#: :data:`~rollplan.planners.collocation.rest.REST_COSTS` and
#: :data:`~rollplan.execution.optimal_timing.TIMING_COSTS`, while here it is the length ``int |v| dt``.
RENAMED_COSTS = {"path_length": "path_energy"}


def cost_key(name, choices, option: str = "cost") -> str:
    """``name`` if it is one of ``choices``; the new name of a renamed cost (:data:`RENAMED_COSTS`) with a
    DeprecationWarning; else InputError naming ``option`` and the choices."""
    if isinstance(name, str) and name not in choices and RENAMED_COSTS.get(name) in choices:
        warnings.warn(f"{option} = {name!r} is deprecated: use {RENAMED_COSTS[name]!r} (the same integral "
                      "int |v|^2 dt)", DeprecationWarning, stacklevel=3)
        name = RENAMED_COSTS[name]
    return check_choice(option, name, choices)


#: Cost names and what they are (units with lengths in the motion's length unit).
COSTS = {
    "path_length": "contact path length int |v| dt [length unit]",
    "angular_velocity": "angular-velocity energy int |omega|^2 dt [rad^2/s]",
    "rotor_energy": "motor torque energy int |tau|^2 dt [N^2 m^2 s]",
    "peak_rotor_rate": "largest |phi_i_dot| [rad/s]",
    "peak_rotor_torque": "largest |tau_i| [N m]",
    "duration": "T [s]",
}


@dataclass(frozen=True)
class TimedMotion:
    """A motion sampled in time (see the module docstring on jumps).

    Attributes
    ----------
    t : ndarray, shape (N,)
        Non-decreasing times [s]; a time given twice marks a jump (value before, then after).
    state : ndarray, shape (N, 5)
        (u_a, v_a, psi, u_o, v_o) [length unit, rad].
    velocity : ndarray, shape (N, 2)
        (u_a_dot, v_a_dot) [length unit / s].
    omega : ndarray, shape (N, 3)
        Angular velocity of the sphere, plane frame [rad/s].
    rotor_rates, rotor_torques : ndarray, shape (N, 2)
        phi_i_dot from (11) [rad/s] and the motor torques [N m].
    radius : float
        Sphere radius [length unit].
    """

    t: np.ndarray
    state: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    rotor_rates: np.ndarray
    rotor_torques: np.ndarray
    radius: float = 1.0

    def __post_init__(self) -> None:
        n = np.asarray(self.t).size
        shapes = {"state": 5, "velocity": 2, "omega": 3, "rotor_rates": 2, "rotor_torques": 2}
        for name, cols in shapes.items():
            if np.asarray(getattr(self, name)).shape != (n, cols):
                raise InputError(f"TimedMotion.{name} of shape {np.asarray(getattr(self, name)).shape} is not "
                                 f"allowed: expected ({n}, {cols})")
        if n < 2 or np.any(np.diff(self.t) < 0) or not np.all(np.isfinite(self.t)):
            raise InputError("TimedMotion.t must hold at least 2 finite, non-decreasing times")

    def trajectory(self) -> Trajectory:
        """The samples as a :class:`~rollplan.result.Trajectory` in time (jumps' repeated samples dropped)."""
        keep = np.r_[True, np.diff(self.t) > 0]
        return Trajectory(self.t[keep], self.state[keep], np.zeros(int(keep.sum()), int), self.radius, "t")

    def columns(self) -> dict:
        """``t`` and the state's columns (jumps' repeated samples dropped), as lists: the JSON form."""
        tr = self.trajectory()
        d = {"t": [float(v) for v in tr.s]}
        d.update({n: [float(v) for v in tr.state[:, i]] for i, n in enumerate(STATE_NAMES)})
        return d


def integrate_samples(t, y) -> float:
    """``int y dt`` over samples ``y`` (N,) at times ``t`` (N,), block by block between repeated times.

    Each block of an odd number (>= 3) of uniform samples is integrated by Simpson's rule, any other
    block by the trapezoid rule.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    cuts = np.flatnonzero(np.diff(t) == 0) + 1
    total = 0.0
    for tb, yb in zip(np.split(t, cuts), np.split(y, cuts)):
        if tb.size < 2:
            continue
        h = np.diff(tb)
        if tb.size % 2 == 1 and np.allclose(h, h[0], rtol=1e-9, atol=0.0):
            total += h[0] / 3.0 * (yb[0] + yb[-1] + 4.0 * yb[1:-1:2].sum() + 2.0 * yb[2:-1:2].sum())
        else:
            total += float(np.sum(0.5 * (yb[1:] + yb[:-1]) * h))
    return float(total)


def measure(m: TimedMotion) -> dict:
    """Every cost of :data:`COSTS` of a timed motion, from its samples alone: ``{name: value}``."""
    if not isinstance(m, TimedMotion):
        raise InputError(f"motion = {m!r:.60} is not allowed: give a rollplan.measures.TimedMotion")
    speed = np.hypot(m.velocity[:, 0], m.velocity[:, 1])
    return {
        "path_length": integrate_samples(m.t, speed),
        "angular_velocity": integrate_samples(m.t, (m.omega ** 2).sum(axis=1)),
        "rotor_energy": integrate_samples(m.t, (m.rotor_torques ** 2).sum(axis=1)),
        "peak_rotor_rate": float(np.abs(m.rotor_rates).max()),
        "peak_rotor_torque": float(np.abs(m.rotor_torques).max()),
        "duration": float(m.t[-1] - m.t[0]),
    }
