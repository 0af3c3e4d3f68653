"""Approach and departure: straight rolls along the great circle through the south pole.

To bring the contact point from ``(u_o, v_o)`` to the south pole (approach) or
from the pole to ``(u_o, v_o)`` (departure), the contact point follows the arc
of the great circle through both (:func:`rollplan.core.curves.great_circle`
rotated by ``beta`` about OZ, (31)): ``sigma`` is the angular distance of the
contact point (1) ``c = (x, y, z)`` from the pole and ``beta`` the direction in
which it lies, ``sigma = atan2(hypot(x, y), -z)``, ``beta = atan2(y, x)``.

Why this arc:

* **Shortest.** The contact path has the same length on the sphere and on the
  plane ((15)-(16) give ``|p'|^2 = cos^2(v_o) u_o'^2 + v_o'^2``, the metric of
  the sphere), and the arc is the geodesic between its ends: a maneuver costs
  exactly ``sigma`` (units of R).
* **Clear of the singular set.** Along the arc ``n3z = cos(u_o) cos(v_o) =
  cos(polar angle)`` is monotone, so the maneuver never comes closer to the
  singular set ``n3z = 0`` of (13), (20) than its off-pole end, which the
  problem keeps at ``n3z >= N3Z_MIN`` (:func:`rollplan.problem.check_contact`).
* **Realizable with zero spin, for every k.** Rolling about the fixed
  horizontal axis ``z x d`` (``d = (cos beta, sin beta)`` the rolling
  direction) keeps ``n3 . omega`` at its value at the pole, where n3 is
  vertical and ``omega`` horizontal: 0. So ``omega = (omega_x, omega_y, 0)``
  satisfies (13), and since (18), (19), (13) determine omega uniquely from the
  contact rates, this pure roll *is* the realizable motion along the arc: the
  curve ODE (28)-(30) of the model reproduces it (it is what certifies a plan).
  On the plane the contact point runs straight, a length ``sigma`` in the
  direction ``beta``, and the ball does not yaw.

Closed form of the departure from the zero plane state (its element of the
composition law, :mod:`rollplan.core.plane`; the approach is the reversed arc,
whose element is the inverse): the orientation after the roll is the rotation
by ``sigma`` about ``z x d`` (Rodrigues), and reading psi off (2) through its
second column ``n2 = (cos v_o sin psi, cos v_o cos psi, -sin v_o)``,

    p_B   = sigma (cos beta, sin beta),
    psi_B = atan2(-(1 - cos sigma) d_x d_y, cos sigma + (1 - cos sigma) d_x^2).

``psi_B`` is not zero off the axes ``beta = 0, pi/2 (mod pi)`` although the
ball does not yaw: off the pole psi is the chart's contact angle of (2), not a
yaw. It does not depend on k. ``tests/test_reconfigure.py`` checks it against a
direct integration of the printed (15), (16), (20).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.paths import PathPiece
from ...core.plane import inverse

__all__ = ["StraightRoll", "departure_element"]


@dataclass(frozen=True)
class StraightRoll:
    """A roll along the great circle through the pole between the pole and a contact point.

    Attributes
    ----------
    u_o, v_o : float
        The off-pole end of the arc [rad].
    kind : str
        ``"approach"`` (from ``(u_o, v_o)`` to the pole) or ``"departure"`` (from the pole to ``(u_o, v_o)``).
    sigma : float
        Angular distance of ``(u_o, v_o)`` from the pole = length of the contact path [units of R].
    beta : float
        Direction of the arc at the pole in the body x-y plane [rad].
    """

    u_o: float
    v_o: float
    kind: str
    sigma: float
    beta: float

    @classmethod
    def make(cls, u_o: float, v_o: float, kind: str) -> StraightRoll:
        """The roll between the pole and the contact point ``(u_o, v_o)`` (kind ``approach`` or ``departure``)."""
        if kind not in ("approach", "departure"):
            raise ValueError(f"kind = {kind!r}: approach or departure")
        x, y, z = -math.sin(u_o) * math.cos(v_o), math.sin(v_o), -math.cos(u_o) * math.cos(v_o)   # (1)
        rho = math.hypot(x, y)
        return cls(float(u_o), float(v_o), kind, math.atan2(rho, -z), math.atan2(y, x) if rho > 0 else 0.0)

    @property
    def empty(self) -> bool:
        """True when the contact point is the pole itself (no roll)."""
        return self.sigma == 0.0

    def element(self) -> np.ndarray:
        """End state ``(u_a, v_a, psi)`` of this roll from the zero plane state (closed form, module docstring)."""
        g = departure_element(self.sigma, self.beta)
        return g if self.kind == "departure" else inverse(g)

    def piece(self) -> PathPiece:
        """The roll as a piece of a contact path (the great-circle curve rotated by beta)."""
        ends = (0.0, self.sigma) if self.kind == "departure" else (self.sigma, 0.0)
        return PathPiece("great_circle", 0, ends, self.beta, self.kind)

    def as_dict(self) -> dict:
        return {"sigma": self.sigma, "beta": self.beta, "path_length": self.sigma}


def departure_element(sigma: float, beta: float) -> np.ndarray:
    """``(u_a, v_a, psi)`` after a departure roll of angle sigma in the direction beta from zero (module docstring)."""
    dx, dy = math.cos(beta), math.sin(beta)
    one_c = 2.0 * math.sin(0.5 * sigma) ** 2   # 1 - cos(sigma) without cancellation
    return np.array([sigma * dx, sigma * dy, math.atan2(-one_c * dx * dy, math.cos(sigma) + one_c * dx * dx)])
