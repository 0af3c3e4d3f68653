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
it returns the shortest solution found among the starts (best of the starts, no completeness).
:func:`move_base` then moves the base point with the leaves to shorten the whole motion, rolls included (a
local solve from that solution: a local improvement). Every plan built on them is certified by the caller by an
independent integration of the whole motion.
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

__all__ = ["POLAR_MAX", "LEAF_MIN", "BasedLeg", "base_of", "polar_distance", "along", "beside", "arc_piece",
           "arc_element", "step_element", "leaf_bound", "solve_leg", "move_base"]

#: Farthest polar angle a leaf may reach [rad]: that of the largest admissible leaf at the pole, 2 asin(A_MAX)
#: (n3z >= 1 - 2 A_MAX^2 = 0.048 on the leaves, as for the pole figure eights).
POLAR_MAX = 2.0 * math.asin(A_MAX)
#: Smallest leaf radius of the local solve [units of R].
LEAF_MIN = 1e-3
#: Iteration cap of one IPOPT start.
ITERATIONS = 60
#: How far [rad] :func:`move_base` starts from a base point at a roll's end, along the other roll.
NUDGE = 0.02
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


def beside(p, q, t: float, offset: float) -> tuple[float, float]:
    """The base point ``offset`` [rad] off the great-circle arc from ``p`` to ``q`` at the fraction ``t`` of its
    way, along the great circle perpendicular to the arc (positive to the left of ``p x q``); the point of
    :func:`along` when ``offset`` is 0 or ``p`` and ``q`` coincide."""
    m = _unit(along(p, q, t))
    normal = np.cross(_unit(p), _unit(q))
    if offset == 0.0 or np.linalg.norm(normal) == 0.0:
        return along(p, q, t)
    normal -= (normal @ m) * m
    e = math.cos(offset) * m + math.sin(offset) * normal / np.linalg.norm(normal)
    rho = math.hypot(e[0], e[1])
    return math.atan2(rho, -e[2]), (math.atan2(e[1], e[0]) if rho > 0 else 0.0)


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

    The turn is matched on the wrapped branch, and from the first start on the next branch too.
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
    for i, (a0, b0, o0) in enumerate(guesses):
        z0 = [min(max(a0, 2 * LEAF_MIN), 0.95 * bound), min(max(b0, 2 * LEAF_MIN), 0.95 * bound), o0]
        for psi in branches[:2] if i == 0 else branches[:1]:
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


def _angle(s0, b0, s1, b1):
    e0 = ca.vertcat(ca.sin(s0) * ca.cos(b0), ca.sin(s0) * ca.sin(b0), -ca.cos(s0))
    e1 = ca.vertcat(ca.sin(s1) * ca.cos(b1), ca.sin(s1) * ca.sin(b1), -ca.cos(s1))
    return ca.atan2(ca.norm_2(ca.cross(e0, e1)), ca.dot(e0, e1))


@lru_cache(maxsize=16)
def _joint_solver(steps: int, nodes: int = DEFAULT_NODES):
    """IPOPT over the leaves, the orientation and the base point: minimise the whole contact path (roll, figure
    eights, roll) subject to reaching the goal from the start."""
    z = ca.MX.sym("z", 5)                 # a, b, orientation, sigma, beta of the base point
    par = ca.MX.sym("par", 11)            # start (3), goal (3, psi with its branch), start base (2), goal base (2), k
    arc_step, eight = _arc_step(nodes), _eight_step(nodes)
    k = par[10]
    x = arc_step(par[0:3], ca.vertcat(par[6], par[7], z[3], z[4]), k, 0.0)
    for _ in range(steps):
        x = eight(x, ca.vertcat(z[0], z[1], z[3], z[2]), k, z[4])
    x = arc_step(x, ca.vertcat(z[3], z[4], par[8], par[9]), k, 0.0)
    length = (_angle(par[6], par[7], z[3], z[4]) + _angle(z[3], z[4], par[8], par[9])
              + 2.0 * math.pi * steps * (z[0] + z[1]))
    g = ca.vertcat(x - par[3:6], z[3] + 2.0 * ca.asin(z[0]), z[3] + 2.0 * ca.asin(z[1]))
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-12,
            "ipopt.constr_viol_tol": 1e-13, "ipopt.max_iter": 3 * ITERATIONS, "expand": True,
            "ipopt.hessian_approximation": "limited-memory"}
    return ca.nlpsol(f"joint{steps}", "ipopt", {"x": z, "p": par, "f": length, "g": g}, opts), ca.Function(
        "end", [z, par], [x, length])


def move_base(start, goal, start_base, goal_base, k: float, leg: BasedLeg, tol: float = 1e-11):
    """The leg and its base point moved together to shorten the whole motion (roll from ``start_base``, the
    leg, roll to ``goal_base``), by a local solve from ``leg``: ``(leg, length)`` or None when it fails or the
    base point ends at a roll's end (where the arc is degenerate). A local improvement, no guarantee."""
    solver, end = _joint_solver(leg.steps)
    base = (leg.sigma, leg.beta)
    for p, q in ((start_base, goal_base), (goal_base, start_base)):   # the arc is degenerate at a roll's end:
        if polar_distance(p, base) < 1e-6:                            # start a little way along the other roll
            if polar_distance(p, q) < 1e-6:
                return None
            base = along(p, q, min(1.0, NUDGE / polar_distance(p, q)))
    z0 = [leg.a, leg.b, leg.orientation, *base]
    par = [*start[:3], *goal[:3], *start_base, *goal_base, k]
    x_end = np.array(end(z0, par)[0]).ravel()
    par[5] = goal[2] + 2.0 * math.pi * round((x_end[2] - goal[2]) / (2.0 * math.pi))
    sol = interrupts.call(solver, x0=z0, p=par, lbx=[LEAF_MIN, LEAF_MIN, -math.inf, 1e-3, -math.inf],
                          ubx=[A_MAX, A_MAX, math.inf, POLAR_MAX, math.inf], lbg=[0, 0, 0, -math.inf, -math.inf],
                          ubg=[0, 0, 0, POLAR_MAX, POLAR_MAX])
    g = np.abs(np.array(sol["g"]).ravel()[:3])
    if not np.all(np.isfinite(g)) or g.max() > tol:
        return None
    a, b, o, s, be = (float(v) for v in np.array(sol["x"]).ravel())
    for p in (start_base, goal_base):
        if polar_distance(p, (s, be)) < 1e-6:
            return None
    moved = BasedLeg(a, b, s, float(wrap(be)), float(wrap(o)), leg.steps, "local")
    return moved, float(sol["f"])
