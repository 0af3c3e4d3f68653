"""Approach and departure: straight rolls along the great circle through the south pole.

The contact point runs along the arc of the great circle between the pole and ``(u_o, v_o)``, at angular
distance ``sigma = atan2(hypot(x, y), -z)`` in the direction ``beta = atan2(y, x)``: the shortest contact
path, monotone in ``n3z`` (clear of the singular set of (13)), and realizable with zero spin for every k. Its
element of the composition law, from zero, is ``p_B = sigma (cos beta, sin beta)``,
``psi_B = atan2(-(1 - cos sigma) d_x d_y, cos sigma + (1 - cos sigma) d_x^2)`` (:func:`departure_element`);
the approach is the reversed arc, with the inverse element.

Derivation: docs/design/composition.md (approach and departure rolls).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...core.paths import CurvePiece
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
        """End state ``(u_a, v_a, psi)`` of this roll from the zero plane state (closed form,
        docs/design/composition.md)."""
        g = departure_element(self.sigma, self.beta)
        return g if self.kind == "departure" else inverse(g)

    def piece(self) -> CurvePiece:
        """The roll as a piece of a contact path (the great-circle curve rotated by beta)."""
        ends = (0.0, self.sigma) if self.kind == "departure" else (self.sigma, 0.0)
        return CurvePiece("great_circle", 0, ends, self.beta, self.kind)

    def as_dict(self) -> dict:
        return {"sigma": self.sigma, "beta": self.beta, "path_length": self.sigma}


def departure_element(sigma: float, beta: float) -> np.ndarray:
    """``(u_a, v_a, psi)`` after a departure roll of angle sigma in the direction beta from zero
    (docs/design/composition.md)."""
    dx, dy = math.cos(beta), math.sin(beta)
    one_c = 2.0 * math.sin(0.5 * sigma) ** 2   # 1 - cos(sigma) without cancellation
    return np.array([sigma * dx, sigma * dy, math.atan2(-one_c * dx * dy, math.cos(sigma) + one_c * dx * dx)])
