"""The one record of a motion in time: :class:`TimeSeries`, and :class:`Arrival`, how a run ends at a goal.

Every producer of a motion in time returns a :class:`TimeSeries` or a small result that holds one in
its ``series`` field with what is specific to it: a timing law's path parameter
(:class:`rollplan.execution.actuation.Actuation`), a rotor-driven simulation's arrival
(:class:`rollplan.execution.plants.RotorSimulation`), a plant's measurements and commands
(:class:`rollplan.execution.plants.PlantResponse`), a closed loop's estimates and corrections
(:class:`rollplan.execution.feedback.ExecutionResult`), a collocation's stats
(:class:`rollplan.planners.collocation.rest.RestResult`). :class:`rollplan.result.Trajectory` is
the other record: a plan sampled along its path, with no time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError
from .problem import STATE_NAMES, State, arrival_error
from .result import Trajectory

__all__ = ["TimeSeries", "Arrival"]

#: The optional per-sample fields of a :class:`TimeSeries` and their columns.
OPTIONAL_COLUMNS = {"velocity": 2, "omega": 3, "rotor_rates": 2, "rotor_angles": 2, "rotor_torques": 2,
                    "rotor_momenta": 2}


@dataclass(frozen=True)
class TimeSeries:
    """A motion sampled in time: one row per sample, a field None when its producer has none.

    Attributes
    ----------
    time : ndarray, shape (N,)
        Finite, non-decreasing times [s], N >= 2; a time given twice marks a step of the torques (the
        first row holds the value before, the second the value after; the other fields agree).
    state : ndarray, shape (N, 5)
        States in the one order of :data:`rollplan.problem.STATE_NAMES` (u_a, v_a, psi, u_o, v_o)
        [length unit, length unit, rad, rad, rad].
    segment : ndarray, shape (N,), int, or None
        Piece of the motion each sample lies on, counted from 0 (a leaf, a roll, a circle of a timed
        plan; a segment of a closed-loop run); a sample at a joint belongs to the piece that ends there.
    velocity : ndarray, shape (N, 2), or None
        Contact-point velocity on the plane (u_a_dot, v_a_dot) [length unit/s].
    omega : ndarray, shape (N, 3), or None
        Angular velocity of the sphere, plane frame, as in (6)-(11) [rad/s].
    rotor_rates : ndarray, shape (N, 2), or None
        phi_1_dot, phi_2_dot relative to the shell, (11) [rad/s].
    rotor_angles : ndarray, shape (N, 2), or None
        phi_1, phi_2 [rad].
    rotor_torques : ndarray, shape (N, 2), or None
        Motor torques about n_1, n_2 [N m].
    rotor_momenta : ndarray, shape (N, 2), or None
        The rotors' absolute axial momenta ``J_r (n_i . omega + phi_i_dot)`` [N m s].
    radius : float
        Sphere radius [length unit].
    """

    time: np.ndarray
    state: np.ndarray
    segment: np.ndarray | None = None
    velocity: np.ndarray | None = None
    omega: np.ndarray | None = None
    rotor_rates: np.ndarray | None = None
    rotor_angles: np.ndarray | None = None
    rotor_torques: np.ndarray | None = None
    rotor_momenta: np.ndarray | None = None
    radius: float = 1.0

    def __post_init__(self) -> None:
        t = np.asarray(self.time, float)
        n = t.size
        if t.ndim != 1 or n < 2 or not np.all(np.isfinite(t)) or np.any(np.diff(t) < 0):
            raise InputError("TimeSeries.time must hold at least 2 finite, non-decreasing times")
        object.__setattr__(self, "time", t)
        for name, cols in {"state": 5, **OPTIONAL_COLUMNS}.items():
            a = getattr(self, name)
            if a is None:
                continue
            a = np.asarray(a, float)
            if a.shape != (n, cols):
                raise InputError(f"TimeSeries.{name} of shape {a.shape} is not allowed: expected ({n}, {cols})")
            object.__setattr__(self, name, a)
        if self.segment is not None:
            seg = np.asarray(self.segment)
            if seg.shape != (n,):
                raise InputError(f"TimeSeries.segment of shape {seg.shape} is not allowed: expected ({n},)")
            object.__setattr__(self, "segment", seg.astype(int))

    def __len__(self) -> int:
        return self.time.size

    @property
    def duration(self) -> float:
        """``time[-1] - time[0]`` [s]."""
        return float(self.time[-1] - self.time[0])

    @property
    def final(self) -> State:
        """The last sample's state [length unit, rad]."""
        return State(*(float(v) for v in self.state[-1]))

    def distinct(self) -> np.ndarray:
        """Indices of the samples at distinct times (the first row of a time given twice)."""
        keep = np.ones(self.time.size, bool)
        keep[1:] = np.diff(self.time) > 0
        return np.nonzero(keep)[0]

    def repeated_times(self) -> np.ndarray:
        """The times given twice (the steps of the torques) [s]."""
        return self.time[1:][np.diff(self.time) == 0]

    def trajectory(self) -> Trajectory:
        """The samples as a :class:`~rollplan.result.Trajectory` in time (a time given twice once)."""
        i = self.distinct()
        segment = np.zeros(i.size, int) if self.segment is None else self.segment[i]
        return Trajectory(self.time[i], self.state[i], segment, self.radius, "t")

    def columns(self) -> dict:
        """``t`` and the state's columns as lists (a time given twice once): the JSON form."""
        i = self.distinct()
        d = {"t": [float(v) for v in self.time[i]]}
        d.update({name: [float(v) for v in self.state[i, j]] for j, name in enumerate(STATE_NAMES)})
        return d


class Arrival:
    """How a run ends at its goal: the base of results with a ``series`` (a :class:`TimeSeries`) and a ``goal``
    (a :class:`~rollplan.problem.State` [length unit, rad], or None)."""

    @property
    def final(self) -> State:
        """The run's final state: ``series.final``."""
        return self.series.final

    @property
    def error(self) -> np.ndarray | None:
        """:func:`rollplan.problem.arrival_error` of ``final`` to ``goal`` (u_a, v_a in units of R, psi wrapped
        to (-pi, pi], u_o, v_o in rad), shape (5,); None without a goal."""
        if self.goal is None:
            return None
        return arrival_error(self.final, State.of(self.goal, "goal"), self.series.radius)

    @property
    def arrival_error(self) -> float | None:
        """Euclidean norm of ``error`` (units of R and rad); None without a goal."""
        e = self.error
        return None if e is None else float(np.linalg.norm(e))

    @property
    def position_error(self) -> float | None:
        """Distance of the final contact point from the goal's [units of R]; None without a goal."""
        e = self.error
        return None if e is None else float(np.hypot(e[0], e[1]))
