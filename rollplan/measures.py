"""Costs of a timed motion, by name: one function for the motions of every method.

A :class:`~rollplan.timeseries.TimeSeries` with what the costs need (the state, the
contact velocity, the angular velocity, the rotor rates and the motor torques) is the
input. Both planners' motions become one (the geometric-phase path timed by a law,
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

import numpy as np

from .errors import InputError, check_choice
from .timeseries import TimeSeries

__all__ = ["COSTS", "RENAMED_COSTS", "cost_key", "measure", "integrate_samples"]

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


def measure(m: TimeSeries) -> dict:
    """Every cost of :data:`COSTS` of a motion in time, from its samples alone: ``{name: value}``.

    ``m`` needs ``velocity``, ``omega``, ``rotor_rates`` and ``rotor_torques``.
    """
    if not isinstance(m, TimeSeries):
        raise InputError(f"motion = {m!r:.60} is not allowed: give a rollplan.timeseries.TimeSeries")
    missing = [name for name in ("velocity", "omega", "rotor_rates", "rotor_torques") if getattr(m, name) is None]
    if missing:
        raise InputError(f"motion without {', '.join(missing)} is not allowed: the costs need them")
    speed = np.hypot(m.velocity[:, 0], m.velocity[:, 1])
    return {
        "path_length": integrate_samples(m.time, speed),
        "angular_velocity": integrate_samples(m.time, (m.omega ** 2).sum(axis=1)),
        "rotor_energy": integrate_samples(m.time, (m.rotor_torques ** 2).sum(axis=1)),
        "peak_rotor_rate": float(np.abs(m.rotor_rates).max()),
        "peak_rotor_torque": float(np.abs(m.rotor_torques).max()),
        "duration": m.duration,
    }
