"""The motors' limits and what they allow on a path: the maximum velocity curve.

Along a path with parameter s (:mod:`rollplan.execution.path`), with ``x = s'^2``
and ``u = s''``, the limits of the robot file read

    |G_i(s)| sqrt(x) <= max_rotor_rate,                 (first order: x <= x_rate(s))
    |A_i(s) u + B_i(s) x| <= max_rotor_torque,          (second order, linear in (u, x))

for both rotors i. The largest ``x`` for which some ``u`` satisfies all of them at
a point s is the maximum velocity curve (MVC) of time-optimal path
parameterisation: the smaller of its rate part :func:`rate_bound` and its torque
part :func:`torque_bound`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import check_range
from ..robot import Robot

__all__ = ["Limits", "rate_bound", "torque_bound"]


@dataclass(frozen=True)
class Limits:
    """Symmetric bounds ``|phi_i_dot| <= max_rotor_rate`` and ``|tau_i| <= max_rotor_torque`` for both rotors.

    Attributes
    ----------
    max_rotor_rate : float or None
        Largest rotor rate [rad/s]; None means unlimited.
    max_rotor_torque : float or None
        Largest motor torque [N m]; None means unlimited.
    """

    max_rotor_rate: float | None = None
    max_rotor_torque: float | None = None

    def __post_init__(self):
        for name in ("max_rotor_rate", "max_rotor_torque"):
            v = getattr(self, name)
            if v is not None:
                object.__setattr__(self, name, check_range(name, v, 0.0, None, low_open=True))

    @classmethod
    def of(cls, robot: Robot) -> Limits:
        """The limits in a robot's file (absent keys: unlimited)."""
        return cls(robot.max_rotor_rate, robot.max_rotor_torque)

    @property
    def any(self) -> bool:
        """True if at least one limit is set."""
        return self.max_rotor_rate is not None or self.max_rotor_torque is not None

    def describe(self) -> str:
        """The set limits as text, e.g. ``max_rotor_rate = 300 rad/s, max_rotor_torque = 0.05 N m``."""
        parts = []
        if self.max_rotor_rate is not None:
            parts.append(f"max_rotor_rate = {self.max_rotor_rate:g} rad/s")
        if self.max_rotor_torque is not None:
            parts.append(f"max_rotor_torque = {self.max_rotor_torque:g} N m")
        return ", ".join(parts) or "no limits"

    def utilisation(self, rates, torques) -> np.ndarray:
        """Largest ratio ``|value| / limit`` over both rotors and both limits, per sample (0 where unlimited).

        Parameters
        ----------
        rates, torques : array, shape (N, 2)
            Rotor rates [rad/s] and torques [N m].
        """
        u = np.zeros(np.shape(rates)[0])
        if self.max_rotor_rate is not None:
            u = np.maximum(u, np.abs(rates).max(axis=1) / self.max_rotor_rate)
        if self.max_rotor_torque is not None:
            u = np.maximum(u, np.abs(torques).max(axis=1) / self.max_rotor_torque)
        return u


def rate_bound(G: np.ndarray, limits: Limits) -> np.ndarray:
    """Largest ``x = s'^2`` the rate limit allows where the rates per unit s' are ``G``: ``min_i (max / |G_i|)^2``.

    ``G`` has shape (N, m); the result (N,) is inf without a rate limit or where ``G = 0``.
    """
    n = G.shape[0]
    if limits.max_rotor_rate is None:
        return np.full(n, np.inf)
    g = np.abs(G).max(axis=1)
    safe = np.where(g > 0, g, 1.0)
    return np.where(g > 0, (limits.max_rotor_rate / safe) ** 2, np.inf)


def torque_bound(A: np.ndarray, B: np.ndarray, limits: Limits) -> np.ndarray:
    """Largest ``x = s'^2`` for which some ``s''`` satisfies every torque row ``|A_i s'' + B_i x| <= tau``.

    Row i with ``A_i != 0`` allows ``s''`` in an interval of half-width ``tau / |A_i|``
    centred at ``-B_i x / A_i``; two such rows have a common point iff
    ``x |B_i A_j - B_j A_i| <= tau (|A_i| + |A_j|)``. A row with ``A_i = 0`` allows
    ``|B_i| x <= tau`` whatever ``s''``. Intervals on a line have a common point iff
    every two of them have one (Helly's theorem in one dimension), so the minimum over
    rows and pairs is exact.

    Parameters
    ----------
    A, B : ndarray, shape (N, m)
        Torque coefficients of ``m`` rows at N points.

    Returns
    -------
    ndarray, shape (N,)
        The torque part of the MVC (inf where unbounded or without a torque limit).
    """
    n, m = A.shape
    if limits.max_rotor_torque is None:
        return np.full(n, np.inf)
    tau = limits.max_rotor_torque
    best = np.full(n, np.inf)
    for i in range(m):
        single = np.where(A[:, i] == 0, np.abs(B[:, i]), 0.0)
        best = np.minimum(best, np.where(single > 0, tau / np.where(single > 0, single, 1.0), np.inf))
        for j in range(i + 1, m):
            num = tau * (np.abs(A[:, i]) + np.abs(A[:, j]))
            den = np.abs(B[:, i] * A[:, j] - B[:, j] * A[:, i])
            best = np.minimum(best, np.where(den > 0, num / np.where(den > 0, den, 1.0), np.inf))
    return best
