"""Leaf families of the figure eight: circles, Viviani lobes, geodesic triangles and squares.

A leaf is a closed curve through the south pole on the +y side, mirror-symmetric in the plane x = 0, traced
counterclockwise seen from inside (leaving the pole to the +x side); its size ``a`` is half the chord from the
pole to the leaf's farthest point, so every family reaches the same polar cap and the same admissible range
``0 < a <= A_MAX`` as the circles (35). The figure eight (31) is leaf ``a`` on +y, then leaf ``b`` mirrored to
-y, rotated about OZ by gamma. :func:`figure_eight` gives it as a :class:`~.curves.Curve` for the integrators
(a polygon leaf is one piece per great-circle edge); :func:`turn` is the closed-form turn E of a leaf.

Parametrisations, structure (split of eta, mirror symmetry, ``d = rho exp(-i E/2)``, monotonicity) and the
closed forms: docs/design/curve-families.md.
"""

from __future__ import annotations

import math
from functools import lru_cache

import casadi as ca
import numpy as np

from ..errors import check_choice, check_finite, check_range
from .curves import A_MAX, Curve, Piece, circle_point
from .curves import figure_eight as circle_figure_eight

__all__ = ["FAMILIES", "TRIANGLE_APEX", "SQUARE_APEX", "viviani_point", "polygon_vertices", "geodesic_point",
           "leaf_pieces", "figure_eight", "pieces_per_leaf", "circle_turn", "turn", "area", "leaf_length", "step"]

#: The leaf families by name (``circles`` is the paper's (35)).
FAMILIES = ("circles", "viviani", "triangle", "square")
#: Angle of the triangle at the pole [rad]: the isosceles geodesic triangle with legs of equal length.
TRIANGLE_APEX = math.pi / 3
#: Angle of the square (a geodesic rhombus: four equal sides) at the pole [rad].
SQUARE_APEX = math.pi / 2

_VIVIANI_BREAKS = tuple(np.pi * np.array([0.0, 0.4, 0.65, 0.82, 0.93, 1.0, 1.07, 1.18, 1.35, 1.6, 2.0]))
# Edges are graded towards their far ends, where the edge comes nearest the equator.
_TO_END = tuple(2.0 * np.pi * np.array([0.0, 0.3, 0.55, 0.72, 0.84, 0.92, 0.97, 1.0]))
_TO_START = tuple(2.0 * np.pi - np.array(_TO_END[::-1]))
_BOTH = tuple(np.pi * np.array([0.0, 0.03, 0.08, 0.16, 0.28, 0.45, 0.7, 1.0, 1.3, 1.55, 1.72, 1.84, 1.92, 1.97,
                                2.0]))


def viviani_point(a, phi, side=1.0):
    """Viviani lobe of size ``a`` (cylinder radius ``a^2``, units of R) through the south pole, phi in [0, 2 pi].

    ``(a^2 sin phi, side 2 a c sin(phi/2), -(1 - 2 a^2 sin^2(phi/2)))``, ``c = sqrt(1 - a^2)``: the sphere cut by
    the cylinder of radius a^2 touching it from inside at the pole, axis along y. It leaves the pole in the
    direction ``(a, side c)`` (angle ``asin a`` from its axis) and returns along ``(a, -side c)``; ``side = -1``
    mirrors it to -y, and the two lobes of equal size make one smooth closed curve.
    """
    c = ca.sqrt(1 - a * a)
    half = ca.sin(phi / 2)
    return ca.vertcat(a * a * ca.sin(phi), side * 2 * a * c * half, -(1 - 2 * a * a * half * half))


def _polar(sigma, beta, side, lib=ca):
    """Point at polar distance sigma from the pole, in the direction beta from +y towards +x (y mirrored by side)."""
    s = lib.sin(sigma)
    return (s * lib.sin(beta), side * s * lib.cos(beta), -lib.cos(sigma))


def polygon_vertices(name, a, side=1.0, lib=ca):
    """Vertices after the pole of the polygon leaf ``name`` of size ``a``, in tracing order, as (x, y, z) tuples.

    ``triangle``: two vertices at polar distance ``D = 2 asin a``, ``TRIANGLE_APEX / 2`` either side of the axis.
    ``square``: the geodesic rhombus with angle ``SQUARE_APEX`` at the pole and four equal sides: vertices at
    ``l = atan(sqrt(2) tan(D/2))`` at 45 degrees either side of the axis and the far vertex at ``D`` on the axis.
    ``lib`` is ``casadi`` (symbols) or ``numpy`` (arrays).
    """
    d = 2 * lib.arcsin(a) if lib is np else 2 * lib.asin(a)
    if name == "triangle":
        half = TRIANGLE_APEX / 2
        return [_polar(d, half, side, lib), _polar(d, -half, side, lib)]
    leg = lib.arctan(math.sqrt(2) * a / lib.sqrt(1 - a * a)) if lib is np else \
        lib.atan(math.sqrt(2) * a / lib.sqrt(1 - a * a))
    half = SQUARE_APEX / 2
    return [_polar(leg, half, side, lib), _polar(d, 0.0, side, lib), _polar(leg, -half, side, lib)]


def geodesic_point(start, end, phi):
    """Great-circle arc from unit vector ``start`` to ``end`` (CasADi (3,)), at constant speed over phi in
    [0, 2 pi]: ``cos(t) start + sin(t) u`` with ``t = phi theta / (2 pi)``, theta the arc's angle."""
    start, end = ca.vertcat(*start), ca.vertcat(*end)
    theta = 2 * ca.asin(ca.norm_2(end - start) / 2)
    u = (end - ca.cos(theta) * start) / ca.sin(theta)
    t = phi * theta / (2 * np.pi)
    return ca.cos(t) * start + ca.sin(t) * u


_POLE = (0.0, 0.0, -1.0)


def _edge_angle(start, end):
    return 2.0 * math.asin(min(1.0, float(np.linalg.norm(np.subtract(end, start))) / 2.0))


def pieces_per_leaf(name: str) -> int:
    """Number of pieces of one leaf: 1 for the smooth leaves, one per edge for a polygon."""
    check_choice("curve", name, FAMILIES)
    return {"circles": 1, "viviani": 1, "triangle": 3, "square": 4}[name]


def leaf_pieces(name: str, index: int, side: float) -> tuple:
    """The pieces of one leaf of family ``name``, its size the curve parameter ``p[index]``, on ``side``."""
    check_choice("curve", name, FAMILIES)
    if name == "circles":
        return (Piece(lambda phi, p: circle_point(p[index], phi, side), circle_figure_eight().pieces[0].breaks,
                      lambda p: 2.0 * np.pi * p[index]),)
    if name == "viviani":
        return (Piece(lambda phi, p: viviani_point(p[index], phi, side), _VIVIANI_BREAKS,
                      lambda p: leaf_length("viviani", p[index])),)
    count = pieces_per_leaf(name)

    def corners(p, lib=ca):
        return [_POLE, *polygon_vertices(name, p[index], side, lib), _POLE]

    def edge(j):
        breaks = _TO_END if j == 0 else _TO_START if j == count - 1 else _BOTH
        return Piece(lambda phi, p: geodesic_point(corners(p)[j], corners(p)[j + 1], phi), breaks,
                     lambda p: _edge_angle(*[np.array(v, float) for v in
                                             corners([float(x) for x in np.atleast_1d(p)], np)[j:j + 2]]))

    return tuple(edge(j) for j in range(count))


def figure_eight(name: str = "circles") -> Curve:
    """The figure eight of family ``name``: leaf ``a`` on +y, then leaf ``b`` on -y; parameters ``(a, b)``."""
    check_choice("curve", name, FAMILIES)
    if name == "circles":
        return circle_figure_eight()
    return Curve(pieces=leaf_pieces(name, 0, 1.0) + leaf_pieces(name, 1, -1.0), param_names=("a", "b"))


def _elliptic_e(m):
    """Complete elliptic integral of the second kind E(m), parameter m in [0, 1), by the arithmetic-geometric mean."""
    a, b = 1.0, math.sqrt(1.0 - m)
    total, power, c2 = m / 2.0, 0.5, m
    while c2 > 1e-32:
        a, b, c = (a + b) / 2.0, math.sqrt(a * b), (a - b) / 2.0
        power *= 2.0
        c2 = c * c
        total += power * c2
    return math.pi / (2.0 * a) * (1.0 - total)


def leaf_length(name: str, a: float) -> float:
    """Length of one leaf of size ``a`` on the unit sphere (of the contact path on the plane, (15)-(16))."""
    check_choice("curve", name, FAMILIES)
    a = float(a)
    if name == "circles":
        return 2.0 * math.pi * a
    if name == "viviani":
        return 4.0 * a * _elliptic_e(1.0 - a * a)
    corners = [_POLE, *polygon_vertices(name, a, 1.0, np), _POLE]
    return sum(_edge_angle(np.array(u, float), np.array(v, float)) for u, v in zip(corners, corners[1:]))


def _edge_terms(start, end, k):
    """Area and k-term of the polar integral of docs/design/curve-families.md over one edge not through the pole."""
    n = np.cross(start, end)
    if n[2] < 0:
        n = -n
    nh = math.hypot(n[0], n[1])
    tan_p = n[2] / nh
    sin_p, cos_p = tan_p / math.sqrt(1 + tan_p**2), 1.0 / math.sqrt(1 + tan_p**2)
    theta_n = math.atan2(n[1], n[0])
    psi = [math.remainder(math.atan2(v[1], v[0]) - theta_n, 2 * math.pi) for v in (start, end)]

    def primitive(x):
        return x - math.asin(cos_p * math.sin(x)) - k * tan_p * math.asinh(sin_p * math.tan(x))

    return primitive(psi[1]) - primitive(psi[0])


def circle_turn(r, k):
    """Turn ``E(r, k)`` of psi over the +y circle of radius r from zero [rad] (closed form, (20) over (35)).

    ``2 pi r^2 / (1 + c) - 4 pi k c r^2 / (s (1 + s))`` with ``c = sqrt(1 - r^2)``, ``s = sqrt(1 - 2 r^2)``, the
    same as ``2 pi (1 - c) + 2 pi k c (1 - 1/s)`` without cancellation at small r.
    """
    r = np.asarray(r, float)
    c = np.sqrt(1.0 - r * r)
    s = np.sqrt(1.0 - 2.0 * r * r)
    return 2.0 * math.pi * r * r / (1.0 + c) - 2.0 * (2.0 * math.pi) * k * c * r * r / (s * (1.0 + s))


def turn(name: str, a, k: float):
    """Closed-form turn ``E(a, k)`` of psi over the +y leaf of size ``a`` from zero [rad]
    (``E = A - k * int (1 + 1/z^2) dA`` over the leaf, docs/design/curve-families.md)."""
    check_choice("curve", name, FAMILIES)
    if name == "circles":
        return circle_turn(a, k)
    a = np.asarray(a, float)
    c = np.sqrt(1.0 - a * a)
    if name == "viviani":
        s = np.sqrt(1.0 - 2.0 * a * a)
        return (4.0 * np.arcsin(a) - 4.0 * a * c
                - k * (2.0 * math.sqrt(2.0) * c / s * np.arctan(math.sqrt(2.0) * a / s) - 4.0 * a * c))
    out = []
    for r in np.atleast_1d(a).ravel():
        corners = [np.array(v, float) for v in polygon_vertices(name, float(r), 1.0, np)]
        out.append(sum(_edge_terms(u, v, k) for u, v in zip(corners, corners[1:])))
    return np.reshape(out, a.shape) if a.ndim else out[0]


def area(name: str, a):
    """Area of the +y leaf of size ``a`` on the unit sphere (the turn of pure rolling, ``turn(name, a, 0)``)."""
    return turn(name, a, 0.0)


@lru_cache(maxsize=len(FAMILIES))
def _integrators(name: str):
    from .integrate import CvodesIntegrator

    return CvodesIntegrator(figure_eight(name)).integrators()


def step(name: str, a: float, b: float | None = None, *, k: float, gamma: float = 0.0) -> np.ndarray:
    """End state (u_a, v_a, psi) of one figure eight (a, b) of family ``name`` rotated by gamma, from zero, by
    CVODES piece by piece (adaptive, so accurate for every k; docs/design/curve-families.md).
    ``k`` is checked by the caller."""
    from .integrate import CvodesIntegrator

    check_choice("curve", name, FAMILIES)
    b = a if b is None else b
    a, b = (check_range(n, v, 0.0, A_MAX, low_open=True) for n, v in (("a", a), ("b", b)))
    gamma = check_finite("gamma", gamma)
    integ = CvodesIntegrator(figure_eight(name))
    return integ.trace([a, b], float(k), gamma, integrators=_integrators(name))[1][-1]
