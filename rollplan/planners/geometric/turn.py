"""Turning in place: pairs of equal circles through the pole whose shifts cancel.

n identical figure eights cannot turn in place (three equations for two unknowns). A circle (35) of radius
``b`` rotated by ``gamma_1``, then by ``gamma_2 = gamma_1 + eta + pi``, cancels its own shift exactly and turns
by ``2 eta_s(b)``; a turn by psi with ``n`` pairs solves ``eta_s(b) = (psi + 2 pi m) / (2 n)``, one equation in
one unknown, and the smallest root ``b`` gives the shortest turn (contact path ``4 pi n b``). The search
tabulates ``eta_1`` (refined to :data:`ETA_STEP`) and refines the first crossing by Brent's method.

Construction and search: docs/design/composition.md (turning in place).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ...core.curves import A_MAX, figure_eight
from ...core.integrate import DEFAULT_NODES, spectral_step
from ...core.paths import CurvePiece
from ...core.roots import brent
from ...errors import NoPlanError

__all__ = ["ETA_STEP", "CircleTurn", "leaf_maps", "circle_steps", "turn_in_place"]

TWO_PI = 2.0 * math.pi
#: Grid refinement of the search: neighbouring eta_1 values differ by less than this [rad].
ETA_STEP = 0.05
#: Smallest circle radius of the search [R].
B_MIN = 1e-4
_TABLES: dict = {}


@lru_cache(maxsize=1)
def leaf_maps() -> tuple:
    """The spectral maps of the two leaves of the figure eight, ``F_s(x0, (a, b), k, gamma) -> x_end``."""
    curve = figure_eight()
    return tuple(spectral_step(curve, DEFAULT_NODES, pieces=(i,)) for i in range(2))


def circle_steps(side: int, b, k: float) -> np.ndarray:
    """``(u_a, v_a, psi)`` after one circle of radius ``b`` (array) on ``side``, from zero: shape (3, N)."""
    b = np.atleast_1d(np.asarray(b, float))
    return np.array(leaf_maps()[side].map(b.size)(ca.DM.zeros(3), np.vstack([b, b]), k, 0))


def _table(k: float, b_max: float):
    """``(b, eta_1(b))`` on the grid of ``k``, refined below ``b_max`` (kept per k; docs/design/composition.md)."""
    if k not in _TABLES:
        b = np.linspace(B_MIN, A_MAX, 400)
        eta = circle_steps(1, b, k)[2]
        probe = b[::57]
        if not np.allclose(circle_steps(0, probe, k)[2], -circle_steps(1, probe, k)[2], rtol=1e-10, atol=1e-13):
            raise ValueError("the two circles are not mirror images: the turn construction does not apply")
        _TABLES[k] = (b, eta)
        while len(_TABLES) > 8:
            _TABLES.pop(next(iter(_TABLES)))
    b, eta = _TABLES[k]
    for _ in range(60):
        gap = (np.abs(np.diff(eta)) > ETA_STEP) & (b[:-1] < b_max)
        if not gap.any() or b.size > 400000:
            break
        mid = 0.5 * (b[:-1] + b[1:])[gap]
        b = np.concatenate([b, mid])
        eta = np.concatenate([eta, circle_steps(1, mid, k)[2]])
        order = np.argsort(b)
        b, eta = b[order], eta[order]
    _TABLES[k] = (b, eta)
    return b, eta


def _crossings(eta, psi: float, steps: int) -> list:
    """``(i, level, sign)`` for every grid cell ``[i, i + 1]`` where eta_1 crosses a level
    ``sign (psi + 2 pi m) / (2 n)`` (sign +1: the -y circle turns by it; -1: the +y circle)."""
    n2 = 2 * steps
    lo, hi = float(eta.min()), float(eta.max())
    out = []
    for sign in (1.0, -1.0):
        first, last = sorted((sign * n2 * lo - psi, sign * n2 * hi - psi))
        for m in range(math.ceil(first / TWO_PI), math.floor(last / TWO_PI) + 1):
            level = sign * (psi + TWO_PI * m) / n2
            if abs(level) > 1e-15:
                d = eta - level
                out += [(int(i), level, sign) for i in np.flatnonzero(np.sign(d[:-1]) * np.sign(d[1:]) <= 0)]
    return out


@dataclass(frozen=True)
class CircleTurn:
    """A turn in place by ``steps`` pairs of equal circles (units of R).

    Attributes
    ----------
    side : int
        0 (the +y circle) or 1 (the -y circle).
    b : float
        Circle radius [R].
    eta : float
        Holonomy of one circle [rad]; the turn is ``2 n eta = psi + 2 pi m``.
    gammas : tuple of float
        Rotation of each of the ``2 n`` circles about OZ (31) [rad].
    steps : int
        Pairs n.
    path_length : float
        ``4 pi n b`` [R].
    """

    side: int
    b: float
    eta: float
    gammas: tuple
    steps: int
    path_length: float

    def pieces(self) -> list:
        """The circles as pieces of a contact path."""
        return [CurvePiece("figure_eight", self.side, (self.b, self.b), g, "turn") for g in self.gammas]

    def as_dict(self, radius: float = 1.0) -> dict:
        return {"kind": "circle_pairs", "side": self.side, "b": self.b * radius, "eta": self.eta,
                "gammas": list(self.gammas), "pairs": self.steps, "path_length": self.path_length * radius}


def turn_in_place(psi: float, k: float, steps: int = 1) -> CircleTurn:
    """The shortest turn in place by ``psi`` [rad] with ``steps`` pairs of equal circles (docs/design/composition.md).

    Raises
    ------
    NoPlanError
        No circle of radius ``<= A_MAX`` turns by ``(psi + 2 pi m) / (2 n)``.
    """
    b, eta = _table(k, 0.0)
    cross = []
    for _ in range(60):   # refine only below the first crossing: a smaller root can lie only there
        cross = _crossings(eta, psi, steps)
        bound = b[min(c[0] for c in cross) + 1] if cross else A_MAX
        size = b.size
        b, eta = _table(k, bound)
        if b.size == size:
            break
    if not cross:
        raise NoPlanError(f"no turn in place by psi = {psi:g} rad with {steps} pair(s) of circles of radius "
                          f"<= {A_MAX} R at k = {k:g}")
    first = min(c[0] for c in cross)
    roots = []
    for i, level, sign in cross:
        if i == first:
            f = lambda x, level=level: float(circle_steps(1, x, k)[2, 0]) - level  # noqa: E731
            roots.append((brent(f, b[i], b[i + 1], xtol=1e-15, rtol=1e-15) if f(b[i]) != 0 else
                          float(b[i]), sign))
    r, sign = min(roots)
    side = 1 if sign > 0 else 0
    eta1 = float(circle_steps(side, r, k)[2, 0])
    gammas = (0.0, eta1 + math.pi) * steps
    return CircleTurn(side, float(r), eta1, gammas, steps, 2 * TWO_PI * steps * float(r))
