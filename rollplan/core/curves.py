"""Spherical curves, the inputs of the planners: closed curves through the south pole, and arcs.

A :class:`Curve` is a piecewise-smooth curve on the unit sphere, given as
CasADi expressions. It is traced piece by piece; each piece is smooth on
``phi in [0, 2*pi]``. The planner's curve is the spherical figure eight of two
circles (35), rotated about OZ by gamma (31), each of whose pieces starts and
ends at the south pole ``(0, 0, -1)``; any other curve can be plugged in the
same way. :func:`great_circle` is the arc of a great circle through the pole,
the approach and departure of the full-reconfiguration planner (a piece that
starts or ends off the pole).

The circle (35) of radius ``a`` through the south pole reaches the equator
``z = 0`` of the body frame, where (30) is singular (``tan u_o`` blows up), at
``a = R/sqrt(2)``. Radii are therefore restricted to the admissible range
``0 < a <= A_MAX`` with :data:`A_MAX` = 0.69 R, where the step map still
converges to 1e-10 (see ``tests/test_integrate.py``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import model

__all__ = ["A_MAX", "Piece", "Curve", "circle_point", "figure_eight", "great_circle_point", "great_circle",
           "polar_point", "based_figure_eight", "arc"]

#: Largest admissible circle radius, in units of R (R/sqrt(2) ~ 0.7071 is singular).
A_MAX = 0.69


@dataclass(frozen=True)
class Piece:
    """One smooth piece of a closed curve.

    Attributes
    ----------
    point : callable ``(phi, params) -> (3,) casadi expression``
        The point on the unit sphere for ``phi in [0, 2 pi]``; ``params`` is the
        curve's parameter vector (a CasADi symbol).
    breaks : tuple of float
        Panel boundaries in ``[0, 2 pi]`` for the spectral integrator; grade them
        towards places where the right side of (30) is steep.
    length : callable ``params -> float``, optional
        Length of the piece on the unit sphere (= of the contact path on the
        plane, (15)-(16)) for numeric parameters.
    """

    point: Callable
    breaks: tuple = tuple(np.linspace(0.0, 2.0 * np.pi, 5))
    length: Callable | None = None


@dataclass(frozen=True)
class Curve:
    """A curve on the unit sphere (closed through the south pole, or an arc), traced as a sequence of pieces."""

    pieces: tuple
    param_names: tuple

    @property
    def n_params(self) -> int:
        return len(self.param_names)


def circle_point(a, phi, side=1.0):
    """Spherical circle (35) of radius ``a`` (units of R) through the south pole.

    ``side=+1`` puts the circle on the +y side (the paper's (35)), ``side=-1``
    mirrors it to the -y side. Both leave the pole along +x at ``phi = 0``, so
    two of them on opposite sides join with a continuous tangent.
    """
    d = ca.sqrt(1 - a**2)  # d = R sqrt(1 - (a/R)^2), cos(alpha) = d, sin(alpha) = a
    return ca.vertcat(
        a * ca.sin(phi),
        side * (-a * d * ca.cos(phi) + d * a),
        -a * a * ca.cos(phi) - d * d,
    )


# Panels graded towards phi = pi, the point of the circle nearest the equator,
# where the complex singularity of 1/z in (30) approaches the real axis.
_CIRCLE_BREAKS = tuple(np.pi * np.array([0.0, 0.4, 0.65, 0.82, 0.93, 1.0, 1.07, 1.18, 1.35, 1.6, 2.0]))


def figure_eight() -> Curve:
    """Spherical figure eight: circle ``a`` on the +y side, then circle ``b`` on the -y side."""
    return Curve(
        pieces=(
            Piece(lambda phi, p: circle_point(p[0], phi, 1.0), _CIRCLE_BREAKS, lambda p: 2.0 * np.pi * p[0]),
            Piece(lambda phi, p: circle_point(p[1], phi, -1.0), _CIRCLE_BREAKS, lambda p: 2.0 * np.pi * p[1]),
        ),
        param_names=("a", "b"),
    )


def great_circle_point(angle):
    """Point of the great circle through the south pole in the x-z plane, ``angle`` [rad] from the pole
    towards +x: ``(sin(angle), 0, -cos(angle))`` on the unit sphere (rotate it by gamma about OZ, (31),
    for another direction)."""
    return ca.vertcat(ca.sin(angle), 0, -ca.cos(angle))


def great_circle() -> Curve:
    """Arc of a great circle through the south pole: one piece, parameters ``(sigma_0, sigma_1)``.

    The polar angle of the point runs linearly from ``sigma_0`` at ``phi = 0``
    to ``sigma_1`` at ``phi = 2 pi`` (the arc is traced at constant speed);
    rotated by gamma about OZ (31), the arc leaves the pole in the direction
    gamma of the body x-y plane. Its length is ``|sigma_1 - sigma_0|``.
    """
    return Curve(
        pieces=(Piece(lambda phi, p: great_circle_point(p[0] + (p[1] - p[0]) * phi / (2.0 * np.pi)),
                      length=lambda p: abs(p[1] - p[0])),),
        param_names=("sigma_0", "sigma_1"),
    )


def polar_point(sigma, beta):
    """Point of the unit sphere at angular distance ``sigma`` from the south pole in the direction ``beta``
    of the body x-y plane: ``(sin sigma cos beta, sin sigma sin beta, -cos sigma)``."""
    return ca.vertcat(ca.sin(sigma) * ca.cos(beta), ca.sin(sigma) * ca.sin(beta), -ca.cos(sigma))


def _based_circle(side):
    def point(phi, p):   # p = (a, b, sigma, orientation); gamma (31) = beta, the direction of the base point
        a = p[0] if side > 0 else p[1]
        return model.rot_y(-p[2]) @ (model.rot_z(p[3]) @ circle_point(a, phi, side))
    return point


def based_figure_eight() -> Curve:
    """The figure eight (a, b) turned by an orientation about its base, carried to a base point off the pole.

    Parameters ``(a, b, sigma, orientation)``: the figure eight of :func:`figure_eight` rotated by the
    orientation about OZ, then by ``sigma`` about OY so that its base (the pole) moves to the point at
    angular distance sigma from the pole towards +x; rotated by gamma = beta about OZ (31), its base is
    :func:`polar_point` ``(sigma, beta)``. Each leaf starts and ends at the base; ``sigma = 0`` is the
    figure eight of :func:`figure_eight` rotated by ``beta + orientation`` (docs/design/basepoint.md).
    """
    return Curve(
        pieces=(Piece(_based_circle(1.0), _CIRCLE_BREAKS, lambda p: 2.0 * np.pi * p[0]),
                Piece(_based_circle(-1.0), _CIRCLE_BREAKS, lambda p: 2.0 * np.pi * p[1])),
        param_names=("a", "b", "sigma", "orientation"),
    )


def _arc_angle(p):
    """Angle between the ends of an :func:`arc` (numeric parameters), by atan2 (accurate for short arcs)."""
    e0 = np.array([np.sin(p[0]) * np.cos(p[1]), np.sin(p[0]) * np.sin(p[1]), -np.cos(p[0])])
    e1 = np.array([np.sin(p[2]) * np.cos(p[3]), np.sin(p[2]) * np.sin(p[3]), -np.cos(p[2])])
    return float(np.arctan2(np.linalg.norm(np.cross(e0, e1)), float(e0 @ e1)))


def _arc_point(phi, p):
    e0, e1 = polar_point(p[0], p[1]), polar_point(p[2], p[3])
    cross = ca.cross(e0, e1)
    angle = ca.atan2(ca.norm_2(cross), ca.dot(e0, e1))
    axis = cross / ca.norm_2(cross)
    t = angle * phi / (2.0 * np.pi)
    return ca.cos(t) * e0 + ca.sin(t) * ca.cross(axis, e0)   # e0 turned about the arc's axis (Rodrigues)


def arc() -> Curve:
    """The shorter arc of the great circle between two points of the sphere, traced at constant speed.

    Parameters ``(sigma_0, beta_0, sigma_1, beta_1)``: the ends as :func:`polar_point`; the ends must be
    distinct and not antipodal. Its length is the angle between them. Use gamma = 0.
    """
    return Curve(pieces=(Piece(_arc_point, length=_arc_angle),), param_names=("sigma_0", "beta_0", "sigma_1",
                                                                          "beta_1"))


def rotated_point(piece: Piece, phi, params, gamma):
    """Point of ``piece`` rotated about OZ of the body frame by gamma, eq. (31)."""
    return model.rot_z(gamma) @ piece.point(phi, params)
