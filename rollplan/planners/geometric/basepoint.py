"""Figure eights at any base point: one leg of ``n`` figure eights traced around a contact point off the pole.

A base point ``(sigma, beta)`` (angular distance from the south pole and direction, as the rolls of
:mod:`.maneuvers`) carries the figure eight (a, b) turned by an ``orientation`` about its base
(:func:`rollplan.core.curves.based_figure_eight`). The n-step law and the composition law (C) hold there as at
the pole, but the rotation about the base is no longer a symmetry: the step's turn and the length of its shift
depend on the orientation too, so a leg has three unknowns ``(a, b, orientation)`` for the three coordinates of
its target, with no closed form for any of them (docs/design/basepoint.md).

Guarantees. At the pole (``sigma = 0``) the leg is the complete search of :class:`.planner.GeometricPhasePlanner`.
Off the pole :func:`solve_leg` is a local solve (IPOPT through CasADi on the spectral step map, minimum
``a + b``) from a few starts: the pole solution for the same target carried over, and a grid of orientations;
it returns the shortest solution found among the starts (best of the starts, no completeness). Every plan built
on it is certified by the caller by an independent integration of the whole motion.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ... import interrupts
from ...core.curves import A_MAX
from ...core.integrate import DEFAULT_NODES, spectral_step
from ...core.paths import CURVES, CurvePiece
from ...core.plane import wrap

__all__ = ["POLAR_MAX", "LEAF_MIN", "BasedLeg", "base_of", "polar_distance", "along", "arc_piece", "arc_element",
           "step_element", "leaf_bound", "solve_leg"]

#: Farthest polar angle a leaf may reach [rad]: that of the largest admissible leaf at the pole, 2 asin(A_MAX)
#: (n3z >= 1 - 2 A_MAX^2 = 0.048 on the leaves, as for the pole figure eights).
POLAR_MAX = 2.0 * math.asin(A_MAX)
#: Smallest leaf radius of the local solve [units of R].
LEAF_MIN = 1e-3
#: Iteration cap of one IPOPT start.
ITERATIONS = 60
#: Orientations of the grid of starts [rad].
ORIENTATIONS = tuple(np.linspace(-math.pi, math.pi, 4, endpoint=False))


def base_of(u_o: float, v_o: float) -> tuple[float, float]:
    """``(sigma, beta)`` of the contact point ``(u_o, v_o)``: angular distance from the pole and direction (1)."""
    x, y, z = -math.sin(u_o) * math.cos(v_o), math.sin(v_o), -math.cos(u_o) * math.cos(v_o)
    rho = math.hypot(x, y)
    return math.atan2(rho, -z), (math.atan2(y, x) if rho > 0 else 0.0)


def _unit(base) -> np.ndarray:
    s, b = base
    return np.array([math.sin(s) * math.cos(b), math.sin(s) * math.sin(b), -math.cos(s)])


def polar_distance(p, q) -> float:
    """Angle between two base points ``(sigma, beta)`` = length of the great-circle arc between them [R]."""
    e0, e1 = _unit(p), _unit(q)
    return float(math.atan2(np.linalg.norm(np.cross(e0, e1)), float(e0 @ e1)))


def along(p, q, t: float) -> tuple[float, float]:
    """The base point a fraction ``t`` of the way along the great-circle arc from ``p`` to ``q``."""
    e0, e1 = _unit(p), _unit(q)
    angle = polar_distance(p, q)
    if angle == 0.0:
        return p
    e = (math.sin((1.0 - t) * angle) * e0 + math.sin(t * angle) * e1) / math.sin(angle)
    return math.atan2(math.hypot(e[0], e[1]), -e[2]), (math.atan2(e[1], e[0]) if math.hypot(e[0], e[1]) > 0 else 0.0)


def arc_piece(p, q, kind: str) -> CurvePiece | None:
    """The roll along the great-circle arc from base point ``p`` to ``q`` (None when they coincide)."""
    if polar_distance(p, q) <= 1e-14:
        return None
    return CurvePiece("arc", 0, (float(p[0]), float(p[1]), float(q[0]), float(q[1])), 0.0, kind)


@lru_cache(maxsize=4)
def _arc_step(nodes: int = DEFAULT_NODES) -> ca.Function:
    return spectral_step(CURVES["arc"], nodes)


@lru_cache(maxsize=4)
def _eight_step(nodes: int = DEFAULT_NODES) -> ca.Function:
    return spectral_step(CURVES["based_figure_eight"], nodes)


def arc_element(piece: CurvePiece | None, k: float) -> np.ndarray:
    """``(u_a, v_a, psi)`` after the roll ``piece`` from the zero plane state (spectral quadrature)."""
    if piece is None:
        return np.zeros(3)
    return np.array(_arc_step()(ca.DM.zeros(3), piece.params, k, 0.0)).ravel()


def step_element(a: float, b: float, base, orientation: float, k: float) -> np.ndarray:
    """``(u_a, v_a, psi)`` after one figure eight at ``base`` from the zero plane state (spectral quadrature)."""
    return np.array(_eight_step()(ca.DM.zeros(3), [a, b, base[0], orientation], k, base[1])).ravel()


def leaf_bound(sigma: float) -> float:
    """Largest leaf radius at a base point ``sigma`` from the pole: no point of a leaf is farther than
    :data:`POLAR_MAX` from the pole (a leaf of radius a reaches ``2 asin(a)`` from its base)."""
    return min(A_MAX, math.sin(max(0.0, 0.5 * (POLAR_MAX - sigma))))


@dataclass(frozen=True)
class BasedLeg:
    """One leg of ``steps`` figure eights (a, b) at a base point, turned by ``orientation`` [units of R, rad].

    ``guarantee`` is ``"complete"`` (the pole search) or ``"best of starts"`` (the local solve).
    """

    a: float
    b: float
    sigma: float
    beta: float
    orientation: float
    steps: int
    guarantee: str

    @property
    def length(self) -> float:
        return 2.0 * math.pi * self.steps * (self.a + self.b)

    def pieces(self, kind: str = "leaf") -> list:
        params = (float(self.a), float(self.b), float(self.sigma), float(self.orientation))
        return [CurvePiece("based_figure_eight", i, params, float(self.beta), kind)
                for _ in range(self.steps) for i in (0, 1)]

    def as_dict(self, R: float = 1.0) -> dict:
        return {"a": self.a * R, "b": self.b * R, "sigma": self.sigma, "beta": self.beta,
                "orientation": self.orientation, "steps": self.steps, "guarantee": self.guarantee,
                "path_length": self.length * R}


@lru_cache(maxsize=16)
def _solver(steps: int, nodes: int = DEFAULT_NODES):
    """IPOPT: minimise a + b subject to n figure eights at the base taking zero to the target."""
    z = ca.MX.sym("z", 3)                 # a, b, orientation
    par = ca.MX.sym("par", 6)             # target (3, psi with its branch), sigma, beta, k
    step = _eight_step(nodes)
    x = ca.MX.zeros(3)
    for _ in range(steps):
        x = step(x, ca.vertcat(z[0], z[1], par[3], z[2]), par[5], par[4])
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-12,
            "ipopt.constr_viol_tol": 1e-13, "ipopt.max_iter": ITERATIONS, "expand": True,
            "ipopt.hessian_approximation": "limited-memory"}
    return ca.nlpsol(f"based{steps}", "ipopt", {"x": z, "p": par, "f": z[0] + z[1], "g": x - par[:3]}, opts)


def solve_leg(target, base, k: float, steps: int, guesses, tol: float = 1e-11) -> BasedLeg | None:
    """The shortest leg of ``steps`` figure eights at ``base`` reaching ``target`` from zero, among local
    solves from ``guesses`` (``(a, b, orientation)`` starts); None when no start converges.

    The turn is matched on the branch nearest each start's own turn and on the wrapped branch.
    A local solve: the best of the starts, not a complete search (module docstring).
    """
    target = np.asarray(target, float)
    sigma, beta = float(base[0]), float(base[1])
    bound = leaf_bound(sigma)
    if bound <= LEAF_MIN:
        return None
    solver = _solver(int(steps))
    best = None
    psi_w = float(wrap(target[2]))
    branches = [psi_w] + [psi_w + 2.0 * math.pi * m for m in (-1, 1) if abs(psi_w + 2.0 * math.pi * m) < 1.5 * math.pi]
    tried = set()
    for a0, b0, o0 in guesses:
        z0 = [min(max(a0, 2 * LEAF_MIN), 0.95 * bound), min(max(b0, 2 * LEAF_MIN), 0.95 * bound), o0]
        for psi in branches[:2]:
            key = (round(z0[0], 6), round(z0[1], 6), round(o0, 6), round(psi, 9))
            if key in tried:
                continue
            tried.add(key)
            sol = interrupts.call(solver, x0=z0, p=[target[0], target[1], psi, sigma, beta, k],
                                  lbx=[LEAF_MIN, LEAF_MIN, -math.inf], ubx=[bound, bound, math.inf], lbg=0, ubg=0)
            g = np.abs(np.array(sol["g"]).ravel())
            if not solver.stats()["success"] and not (g.max() <= tol):
                continue
            if g.max() > tol:
                continue
            a, b, o = (float(v) for v in np.array(sol["x"]).ravel())
            if best is None or a + b < best.a + best.b:
                best = BasedLeg(a, b, sigma, beta, float(wrap(o)), int(steps), "best of starts")
    return best
