"""Contact paths made of pieces of curves, integrated piece by piece from any start state.

A composed motion (an approach roll, figure eights, a departure roll; a route of
such motions) is a sequence of :class:`CurvePiece`: one smooth piece of a named
curve of :data:`CURVES` with its parameters and its rotation gamma about OZ
(31). :class:`PathIntegrator` integrates the model's curve ODE (28)-(30) along
the pieces with CVODES (Adams, relative tolerance 3e-15), carrying
``(u_a, v_a, psi)`` across the joints; the contact coordinates ``(u_o, v_o)``
are those of the curve's point, (24)-(25). It uses neither the composition law
of :mod:`.plane` nor the closed forms nor the spectral quadrature the planners
rely on, so it certifies a composed plan independently of how it was found.

The state ``x = (u_a, v_a, psi)`` is in units of R and rad.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from .. import interrupts
from . import families, model
from .curves import Piece, arc, based_figure_eight, figure_eight, great_circle, rotated_point
from .integrate import CvodesIntegrator

__all__ = ["CURVES", "family_curve", "CurvePiece", "figure_eight_pieces", "allocate_samples", "PathIntegrator"]


def family_curve(family: str) -> str:
    """Name in :data:`CURVES` of the figure eight of leaf family ``family`` (:data:`.families.FAMILIES`)."""
    return "figure_eight" if family == "circles" else f"figure_eight_{family}"


#: The curves a path can be made of, by name: the figure eight of circles (35), that of each other leaf family
#: (:func:`family_curve`, :mod:`.families`) the great circle of a roll, the figure eight at a base point and an arc.
CURVES = {"figure_eight": figure_eight(), "great_circle": great_circle(), "based_figure_eight": based_figure_eight(),
          "arc": arc(),
          **{family_curve(name): families.figure_eight(name) for name in families.FAMILIES if name != "circles"}}


@dataclass(frozen=True)
class CurvePiece:
    """One smooth piece of a plan's contact path, named: piece ``index`` of the curve ``CURVES[curve]`` with its
    parameters, its rotation and its role (execution times it as an
    :class:`rollplan.execution.path.ArcLengthPiece`).

    Attributes
    ----------
    curve : str
        Name in :data:`CURVES`.
    index : int
        Which piece of that curve (for the figure eight: 0 the +y circle, 1 the -y circle).
    params : tuple of float
        The curve's parameters [units of R, rad] (figure eight: ``(a, b)``; great circle:
        ``(sigma_0, sigma_1)``).
    gamma : float
        Rotation of the curve about OZ of the body frame, eq. (31) [rad].
    kind : str
        What the piece does in its plan (``"approach"``, ``"leaf"``, ``"turn"``, ``"departure"``).
    """

    curve: str
    index: int
    params: tuple
    gamma: float = 0.0
    kind: str = "leaf"

    @property
    def piece(self) -> Piece:
        return CURVES[self.curve].pieces[self.index]

    @property
    def length(self) -> float:
        """Length of the contact path of the piece [units of R] (on the sphere and on the plane)."""
        return float(self.piece.length(self.params))

    def contact(self, phi) -> np.ndarray:
        """Contact coordinates ``(u_o, v_o)`` at the piece parameters ``phi`` (24)-(25): shape (N, 2)."""
        phi = np.atleast_1d(np.asarray(phi, float))
        out = _contact_function(self.curve, self.index).map(phi.size)(phi[None, :], ca.DM(self.params), self.gamma)
        return np.array(out).T

    def end_contact(self) -> tuple[float, float]:
        """``(u_o, v_o)`` at the end of the piece (the curve's point, not integrated)."""
        u, v = self.contact(2.0 * np.pi)[0]
        return float(u), float(v)

    def as_dict(self) -> dict:
        """The JSON form: curve, index, params, gamma, kind and length."""
        return {"kind": self.kind, "curve": self.curve, "index": self.index,
                "params": [float(v) for v in self.params], "gamma": float(self.gamma), "length": self.length}


def figure_eight_pieces(a: float, b: float, gamma: float, steps: int, kind: str = "leaf",
                        family: str = "circles") -> list:
    """The pieces of ``steps`` traces of the figure eight (a, b) of leaf family ``family`` rotated by gamma (units
    of R): ``2 steps`` leaves, a polygon's leaf one piece per edge."""
    params, name = (float(a), float(b)), family_curve(family)
    count = len(CURVES[name].pieces)
    return [CurvePiece(name, i, params, float(gamma), kind) for _ in range(steps) for i in range(count)]


def allocate_samples(lengths, samples: int) -> np.ndarray:
    """Samples per piece (the start is one more sample): ``samples - 1`` in all, at least 4 per piece
    when there are enough (else at least 1), the rest in proportion to the lengths (largest remainders)."""
    lengths = np.asarray(lengths, float)
    n = lengths.size
    total = samples - 1
    least = 4 if total >= 4 * n else 1
    extra = total - least * n
    share = extra * lengths / lengths.sum() if lengths.sum() > 0 else np.full(n, extra / n)
    counts = least + np.floor(share).astype(int)
    rest = total - int(counts.sum())
    counts[np.argsort(-(share - np.floor(share)), kind="stable")[:rest]] += 1
    return counts


@lru_cache(maxsize=32)
def _contact_function(curve: str, index: int) -> ca.Function:
    """``(phi, params, gamma) -> (u_o, v_o)`` of a curve's piece, (24)-(25)."""
    phi, gamma = ca.SX.sym("phi"), ca.SX.sym("gamma")
    c = CURVES[curve]
    params = ca.SX.sym("p", c.n_params)
    u, v = model.contact_coordinates(rotated_point(c.pieces[index], phi, params, gamma))
    return ca.Function("contact", [phi, params, gamma], [ca.vertcat(u, v)])


class PathIntegrator:
    """CVODES integration of (28)-(30) along a sequence of :class:`CurvePiece` (see the module docstring).

    Integrators are built once per curve piece and output grid and kept.
    """

    name = "cvodes"

    def __init__(self, reltol: float = 3e-15, abstol: float = 1e-16) -> None:
        self._cvodes = {name: CvodesIntegrator(c, reltol=reltol, abstol=abstol) for name, c in CURVES.items()}
        self._integrators: dict = {}

    def _integrator(self, curve: str, index: int, count: int):
        key = (curve, index, count)
        if key not in self._integrators:
            if len(self._integrators) >= 64:
                self._integrators.pop(next(iter(self._integrators)))
            grid = np.linspace(0.0, 2.0 * np.pi, count + 1)[1:]
            self._integrators[key] = self._cvodes[curve].piece_integrator(index, grid)
        return self._integrators[key]

    def run(self, piece: CurvePiece, x, k: float, count: int = 1) -> np.ndarray:
        """States (count, 3) at ``count`` uniform piece parameters in (0, 2 pi], from ``x`` (3,)."""
        p = [*piece.params, k, piece.gamma]
        integ = self._integrator(piece.curve, piece.index, count)
        return np.array(interrupts.call(integ, x0=np.asarray(x, float), p=p)["xf"]).T

    def ends(self, pieces, start, k: float) -> np.ndarray:
        """The state (5,) at the start and at the end of every piece: shape (P + 1, 5), units of R."""
        start = np.asarray(start, float)
        rows = [start]
        x = start[:3]
        for piece in pieces:
            x = self.run(piece, x, k)[-1]
            rows.append(np.concatenate([x, piece.end_contact()]))
        return np.array(rows)

    def sample(self, pieces, start, k: float, counts) -> tuple:
        """The motion sampled from ``start`` (5,): ``counts[j]`` samples on piece j after the start.

        Returns
        -------
        s : ndarray, shape (N,)
            Path parameter: piece j spans ``[pi j, pi (j + 1)]`` (its own ``phi / 2`` added), so a
            figure eight's two leaves span 2 pi as the curve parameter theta of a plan does.
        states : ndarray, shape (N, 5)
            (u_a, v_a, psi, u_o, v_o) in units of R.
        segment : ndarray, shape (N,), int
            Piece of each sample (the start belongs to piece 0, a joint to the piece that ends there).
        """
        start = np.asarray(start, float)
        s, rows, seg = [np.zeros(1)], [start[None, :]], [np.zeros(1, int)]
        x = start[:3]
        for j, (piece, count) in enumerate(zip(pieces, counts)):
            phi = np.linspace(0.0, 2.0 * np.pi, int(count) + 1)[1:]
            xs = self.run(piece, x, k, int(count))
            rows.append(np.column_stack([xs, piece.contact(phi)]))
            s.append(math.pi * j + phi / 2.0)
            seg.append(np.full(phi.size, j))
            x = xs[-1]
        return np.concatenate(s), np.vstack(rows), np.concatenate(seg)
