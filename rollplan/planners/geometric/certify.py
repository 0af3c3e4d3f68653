"""Certification of a geometric-phase plan: an independent integration of all n steps.

:class:`CvodesCertifier` traces the rotated figure eight (31) ``n`` times with
CasADi's CVODES (Adams, relative tolerance 3e-15) on the full right side of
(28)-(30): it does not use the spectral quadrature, the leaf tables or the
n-step law (33) the planner relies on, and composes the steps by integration.
At this tolerance it agrees with scipy's DOP853 on the printed equations to
about 1e-11 over ten steps of large leaves, far below the 1e-9 it certifies.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ...core import model
from ...core.curves import figure_eight, rotated_point
from ...core.integrate import CvodesIntegrator
from ...problem import State

__all__ = ["CvodesCertifier"]


class CvodesCertifier:
    """Final state of n traces of the figure eight (a, b) rotated by gamma, by CVODES (units of R)."""

    name = "cvodes"

    def __init__(self, reltol: float = 3e-15, abstol: float = 1e-16) -> None:
        self.curve = figure_eight()
        self.integrator = CvodesIntegrator(self.curve, reltol=reltol, abstol=abstol)
        self._ints = self.integrator.integrators(1)

    def final(self, a: float, b: float, k: float, gamma: float, steps: int) -> State:
        """(u_a, v_a, psi, u_o, v_o) after ``steps`` traces from zero [R, rad]."""
        _, xs = self.integrator.trace([a, b], k, gamma, steps, integrators=self._ints)
        end = rotated_point(self.curve.pieces[-1], 2 * np.pi, ca.DM([a, b]), gamma)
        u_o, v_o = (float(c) for c in model.contact_coordinates(end))
        return State(*(float(v) for v in xs[-1]), u_o, v_o)
