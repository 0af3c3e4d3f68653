"""Running costs of the optimal-control planner, by name.

A cost is ``L(x, w, xdot, omega, par)``: state x (u_a, v_a, psi, u_o, v_o),
contact rates w = (u_o_dot, v_o_dot), the state rates, the angular velocity
(18), (19), (13) and the parameters ``par = (k, T, eps, j_xx, j_zz, j_r)``.
Lengths are in units of R inside the NLP.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca

from ...core import model

__all__ = ["Cost", "COSTS", "N_PAR"]

#: Length of the NLP parameter vector ``(k, T, eps, j_xx, j_zz, j_r)``.
N_PAR = 6


@dataclass(frozen=True)
class Cost:
    """A running cost: its name, a description, the unit of its integral, whether it needs a robot."""

    name: str
    description: str
    unit: str
    needs_robot: bool
    integrand: Callable


def _path_length(x, w, xdot, omega, par):
    return xdot[0] ** 2 + xdot[1] ** 2


def _path_length_smooth(x, w, xdot, omega, par):
    return ca.sqrt(par[2] + xdot[0] ** 2 + xdot[1] ** 2)


def _angular_velocity(x, w, xdot, omega, par):
    return ca.sumsqr(omega)


def _rotor_effort(x, w, xdot, omega, par):
    return ca.sumsqr(model.rotor_rates(omega, x[3], x[4], x[2], par[3], par[4], par[5]))


#: Costs by name (``"path_energy"`` was ``"path_length"``: :data:`rollplan.measures.RENAMED_COSTS`).
COSTS = {
    "path_energy": Cost("path_energy", "contact path length in its energy form int |v|^2 dt (on a fixed horizon "
                        "its minimizers are the shortest paths at constant speed)", "R^2/s", False, _path_length),
    "path_length_smooth": Cost("path_length_smooth", "contact path length int sqrt(eps + |v|^2) dt", "R", False,
                               _path_length_smooth),
    "angular_velocity": Cost("angular_velocity", "angular-velocity energy int |omega|^2 dt", "rad^2/s", False,
                             _angular_velocity),
    "rotor_effort": Cost("rotor_effort", "rotor effort int (phi1_dot^2 + phi2_dot^2) dt (eq. 11)", "rad^2/s", True,
                         _rotor_effort),
}
