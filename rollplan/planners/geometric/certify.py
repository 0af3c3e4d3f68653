"""Certification of a geometric-phase plan: an independent integration of all n steps.

Two certifiers by name (:data:`CERTIFIERS`) integrate the model's curve ODE (28)-(30) along the rotated
figure eight (31), leaf after leaf, for all ``n`` steps from zero, and give the final state and a bound of
its error: ``"rk8"`` (the default, :class:`RK8Certifier`: compiled fixed-step RK8 in a graded variable, run
with N and 2N steps per leaf, the difference plus a rounding allowance as the bound) and ``"cvodes"``
(:class:`CvodesCertifier`). Neither shares the leaf map's closed forms, mirror or n-step law.

Error bound and why the certificate is independent: docs/design/geometric-planner.md (the certificate).
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from ...core import compiled as _compiled_mod
from ...core import curves, families, integrate, model
from ...core.compiled import compiled_lazy
from ...core.curves import circle_point, figure_eight, rotated_point
from ...core.integrate import CvodesIntegrator, rk8_step
from ...core.rewrite import algebraic
from ...errors import check_choice
from ...problem import State
from ...result import CERTIFICATE_TOLERANCE

__all__ = ["CERTIFIERS", "DEFAULT_CERTIFIER", "MAX_STEPS_PER_LEAF", "REFINE_BELOW", "ROUNDING_FACTOR", "grading",
           "initial_steps", "rounding_allowance", "RK8Certifier", "CvodesCertifier", "certifier"]

#: Largest number of RK steps per leaf of the finer of the two integrations.
MAX_STEPS_PER_LEAF = 1 << 14
#: The step count is doubled while the estimate exceeds this fraction of the tolerance.
REFINE_BELOW = 0.25
#: Safety factor of :func:`rounding_allowance`.
ROUNDING_FACTOR = 4.0
_TWO_PI = 2.0 * math.pi


def grading(r):
    """``beta(r) = r^2 / (1 - r^2 + sqrt(1 - 2 r^2))``: the step near ``phi = pi`` is ``(1 - beta) /
    (1 + beta) = sqrt(1 - 2 r^2)`` times the mean step, the distance scale of the equator singularity of
    (30) there. Floats or CasADi expressions."""
    lib = ca if isinstance(r, (ca.SX, ca.MX)) else np
    return r * r / (1.0 - r * r + lib.sqrt(1.0 - 2.0 * r * r))


def _leaf_rhs() -> ca.Function:
    """``f(tau, x[3], p[4]) -> dx/dtau``: (28)-(30) along one leaf in the graded variable, ``p = (r, side,
    k, gamma)``: the circle (35) of radius r on the side ``side`` (+1: +y, -1: -y) rotated by gamma (31).

    The model's right side in ``phi`` (:func:`rollplan.core.model.curve_rhs`) is put in
    :func:`~rollplan.core.rewrite.algebraic` form with ``cos phi`` and ``sin phi`` as inputs (no cos or sin of
    the contact coordinates' atan2 and asin; checked against the model's graph when built), which are then
    written in ``tau``: with ``phi = tau + 2 atan(q)``, ``q = beta sin tau / (1 - beta cos tau)``,
    ``cos 2 atan q = (1 - q^2) / (1 + q^2)`` and ``sin 2 atan q = 2 q / (1 + q^2)``; (28)-(30) are linear in
    the contact point's velocity, so ``d/dtau = (dphi/dtau) d/dphi`` (dphi/dtau by AD of phi(tau))."""
    phi, tau = ca.SX.sym("phi"), ca.SX.sym("tau")
    x = ca.SX.sym("x", 3)
    p = ca.SX.sym("p", 4)
    r, side, k, gamma = p[0], p[1], p[2], p[3]
    point = model.rot_z(gamma) @ circle_point(r, phi, side)
    rhs, psi = model.curve_rhs(point, phi, k)
    in_phi = algebraic(ca.Function("cert_rhs_phi", [phi, x, p], [ca.substitute(rhs, psi, x[2])]), angles=(0,))
    beta = grading(r)
    ct, st = ca.cos(tau), ca.sin(tau)
    num, den = beta * st, 1.0 - beta * ct                   # q = num / den
    norm = den * den + num * num
    c2, s2 = (den * den - num * num) / norm, 2.0 * num * den / norm
    dphi = ca.jacobian(tau + 2.0 * ca.atan(num / den), tau)
    rate = in_phi(ct * c2 - st * s2, st * c2 + ct * s2, x, p) * dphi
    return ca.Function("cert_rhs", [tau, x, p], [ca.cse(rate)], ["tau", "x", "p"], ["xdot"])


def _eight_pair(steps: int) -> ca.Function:
    """``(xc, xf, pa, pb) -> (yc, yf, mid)``: one figure eight integrated from ``xc`` with ``steps`` and
    from ``xf`` with ``2 steps`` RK8 steps per leaf; ``mid`` is the finer state between the leaves;
    ``pa = (a, 1, k, gamma)``, ``pb = (b, -1, k, gamma)``."""
    rk = rk8_step(_leaf_rhs())
    x, t, h, p = ca.SX.sym("x", 3), ca.SX.sym("t"), ca.SX.sym("h"), ca.SX.sym("p", 4)
    one = ca.Function("cert_step", [x, t, h, p], [ca.cse(rk(x, t, h, p))])
    coarse, fine = one.mapaccum("cert_coarse", steps), one.mapaccum("cert_fine", 2 * steps)
    xc, xf = ca.MX.sym("xc", 3), ca.MX.sym("xf", 3)
    pa, pb = ca.MX.sym("pa", 4), ca.MX.sym("pb", 4)
    hc, hf = _TWO_PI / steps, _TWO_PI / (2 * steps)
    tc, tf = ca.DM(np.arange(steps) * hc).T, ca.DM(np.arange(2 * steps) * hf).T
    yc, yf, mids = xc, xf, []
    for p_ in (pa, pb):
        yc = coarse(yc, tc, hc, p_)[:, -1]
        yf = fine(yf, tf, hf, p_)[:, -1]
        mids.append(yf)
    return ca.Function(f"cert_eight_{steps}", [xc, xf, pa, pb], [yc, yf, mids[0]], ["xc", "xf", "pa", "pb"],
                       ["yc", "yf", "mid"])


#: The files whose code defines the certificate's functions (the key of their compiled libraries).
_SOURCES = tuple(Path(m.__file__) for m in (model, curves, integrate, _compiled_mod)) + (Path(__file__),)


@lru_cache(maxsize=16)
def _eight_pair_function(steps: int, compile: bool) -> ca.Function:
    if not compile:
        return _eight_pair(steps)
    return compiled_lazy(f"cert_eight_{steps}", lambda: _eight_pair(steps), f"steps={steps}", _SOURCES)


def initial_steps(a: float, b: float, k: float, steps: int = 1, tol: float = CERTIFICATE_TOLERANCE) -> int:
    """RK steps per leaf to start with: a power of two, at least 16 (doubled on demand).

    A speed heuristic only (the estimate decides acceptance): ``max(10 + 14.5 r / s^1.5, 1.45 k r c /
    s)`` for the larger radius ``r`` (``c = sqrt(1 - r^2)``, ``s = sqrt(1 - 2 r^2)``); the first term
    resolves the approach to the equator near ``phi = pi``, the second the fastest turn of psi, about
    ``k c / s`` per unit of ``tau``; scaled by ``(n 1e-9 / tol)^(1/8)`` (the global error of n steps
    grows about linearly in n).
    """
    r = max(a, b)
    s = math.sqrt(max(1.0 - 2.0 * r * r, 1e-12))
    c = math.sqrt(1.0 - r * r)
    need = max(10.0 + 14.5 * r / s ** 1.5, 1.45 * k * r * c / s) * (steps * 1e-9 / tol) ** 0.125
    return 1 << max(4, math.ceil(math.log2(need)))


def rounding_allowance(psi_scale: float, steps: int, steps_per_leaf: int) -> float:
    """Bound of the rounding error of the finer run (docs/design/geometric-planner.md):
    ``ROUNDING_FACTOR eps (1 + psi_scale) sqrt(2 n N_fine)``."""
    return ROUNDING_FACTOR * float(np.finfo(float).eps) * (1.0 + psi_scale) * math.sqrt(2.0 * steps * steps_per_leaf)


@lru_cache(maxsize=1)
def _end_contact() -> ca.Function:
    """``(b, gamma) -> (u_o, v_o)`` of the figure eight's end point (24)-(25) (the pole, up to rounding)."""
    b, gamma = ca.SX.sym("b"), ca.SX.sym("gamma")
    u, v = model.contact_coordinates(model.rot_z(gamma) @ circle_point(b, _TWO_PI, -1.0))
    return ca.Function("cert_end_contact", [b, gamma], [u, v])


class RK8Certifier:
    """Final state of n traces of the figure eight (a, b) rotated by gamma, with an error bound, by the
    compiled fixed-step RK8 integration with step doubling (docs/design/geometric-planner.md); units of R.

    Parameters
    ----------
    compile : bool
        Compile the integration to C (cached on disk; :mod:`rollplan.core.compiled`); False runs
        CasADi's virtual machine.
    """

    name = "rk8"

    def __init__(self, compile: bool = True) -> None:
        self.compile = bool(compile)

    def certify(self, a: float, b: float, k: float, gamma: float, steps: int, tol: float = CERTIFICATE_TOLERANCE,
                start: int | None = None):
        """``(final State, estimate, steps per leaf)``: the finer run's final state (u_o, v_o of the end
        point), the bound of its error [R, rad] and its RK steps per leaf; ``start`` overrides the
        coarse run's first step count (:func:`initial_steps`, a power of two; for studies)."""
        n = int(start) if start else initial_steps(a, b, k, steps, tol)
        pa = np.array([a, 1.0, k, gamma])
        pb = np.array([b, -1.0, k, gamma])
        while True:
            f = _eight_pair_function(n, self.compile)
            xc = xf = np.zeros(3)
            scale = 0.0
            for _ in range(int(steps)):
                yc, yf, mid = f.call([xc, xf, pa, pb])
                xc, xf = yc.nonzeros(), yf.nonzeros()    # dense (3,): lists of floats
                scale = max(scale, abs(mid.nonzeros()[2]), abs(xf[2]))
            xc, xf = np.array(xc), np.array(xf)
            est = float(np.linalg.norm(xf - xc) + rounding_allowance(scale, steps, 2 * n))
            if not math.isfinite(est):
                est = math.inf
                break
            if est <= REFINE_BELOW * tol or 4 * n > MAX_STEPS_PER_LEAF:
                break
            n *= 2
        u_o, v_o = (v.nonzeros()[0] for v in _end_contact().call([b, gamma]))
        return State(float(xf[0]), float(xf[1]), float(xf[2]), u_o, v_o), est, 2 * n

    def final(self, a: float, b: float, k: float, gamma: float, steps: int) -> State:
        """(u_a, v_a, psi, u_o, v_o) after ``steps`` traces from zero [R, rad]."""
        return self.certify(a, b, k, gamma, steps)[0]


class CvodesCertifier:
    """Final state of n traces of the figure eight (a, b) rotated by gamma, by CVODES (units of R); ``curve`` the
    leaf family (:data:`rollplan.core.families.FAMILIES`; its figure eight piece by piece)."""

    name = "cvodes"

    def __init__(self, reltol: float = 3e-15, abstol: float = 1e-16, curve: str = "circles") -> None:
        self.family = curve
        self.curve = figure_eight() if curve == "circles" else families.figure_eight(curve)
        self.integrator = CvodesIntegrator(self.curve, reltol=reltol, abstol=abstol)
        self._ints = None

    def final(self, a: float, b: float, k: float, gamma: float, steps: int) -> State:
        """(u_a, v_a, psi, u_o, v_o) after ``steps`` traces from zero [R, rad]."""
        if self._ints is None:
            self._ints = self.integrator.integrators(1)
        _, xs = self.integrator.trace([a, b], k, gamma, steps, integrators=self._ints)
        end = rotated_point(self.curve.pieces[-1], 2 * np.pi, ca.DM([a, b]), gamma)
        u_o, v_o = (float(c) for c in model.contact_coordinates(end))
        return State(*(float(v) for v in xs[-1]), u_o, v_o)

    def certify(self, a: float, b: float, k: float, gamma: float, steps: int, tol: float = CERTIFICATE_TOLERANCE):
        """``(final State, 0.0, 0)``: CVODES gives no error estimate (docs/design/geometric-planner.md)."""
        return self.final(a, b, k, gamma, steps), 0.0, 0


#: Certifiers by name: ``CERTIFIERS[name]()`` has ``name``, ``final(a, b, k, gamma, steps) -> State`` and
#: ``certify(a, b, k, gamma, steps, tol) -> (State, error bound, steps per leaf)`` (units of R, rad).
CERTIFIERS = {"rk8": RK8Certifier, "cvodes": CvodesCertifier}
DEFAULT_CERTIFIER = "rk8"


def certifier(name: str = DEFAULT_CERTIFIER):
    """A new certifier by name from :data:`CERTIFIERS` (InputError naming the choices otherwise)."""
    return CERTIFIERS[check_choice("certifier", name, CERTIFIERS)]()
