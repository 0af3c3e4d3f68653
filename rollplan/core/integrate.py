"""Integrators of the curve ODE (28)-(30) over the pieces of a closed curve.

Two integrators:

``"spectral"`` (the planner's)
    Along a curve, psi' in (30) does not depend on the state, and (28)-(29)
    depend on the state only through psi: the rates of (u_a, v_a) are their
    values at psi = 0 turned by -psi. So psi is a quadrature, and then
    (u_a, v_a) are quadratures. Each piece is split into panels; on each panel
    the integrals are taken by Chebyshev (Clenshaw-Curtis) spectral
    integration on ``nodes + 1`` points, which converges exponentially for the
    analytic integrands (:func:`spectral_leaf`). The result is a CasADi
    function: exactly differentiable and code-generatable (the C planner of
    :mod:`rollplan.codegen` uses the same quadrature). The structural
    assumption is checked when the function is built
    (:func:`check_heading_structure`).

``"cvodes"``
    CasADi's CVODES (SUNDIALS' variable-order Adams method by default) at
    tight tolerances: the independent, adaptive integrator that verifies plans.

The state is ``x = (u_a, v_a, psi)`` in units of R and rad.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np
from numpy.polynomial import chebyshev as cheb

from .. import interrupts
from ..errors import InputError, check_choice, check_range
from ..progress import report
from . import model
from .curves import Curve, rotated_point

__all__ = ["DEFAULT_NODES", "piece_rhs", "heading_free_rates", "check_heading_structure", "chebyshev_matrices",
           "spectral_leaf", "spectral_step", "CvodesIntegrator", "rk8_step"]

#: Chebyshev degree per panel of the spectral integrator.
DEFAULT_NODES = 32


@lru_cache(maxsize=8)
def chebyshev_matrices(n: int):
    """Chebyshev points on [-1, 1] (ascending) and the cumulative integration matrix.

    ``(Q @ f)[i]`` is the integral from -1 to ``x[i]`` of the degree-``n``
    interpolant of the values ``f`` at the points ``x``.
    """
    x = np.cos(np.pi * np.arange(n + 1) / n)[::-1]
    vinv = np.linalg.inv(cheb.chebvander(x, n))
    q = np.column_stack([cheb.chebval(x, cheb.chebint(vinv[:, i], lbnd=-1)) for i in range(n + 1)])
    return x, q


def piece_rhs(curve: Curve, index: int) -> ca.Function:
    """Right side of (28)-(30) along one piece of a curve rotated by gamma.

    ``f(phi, x[3], params[n], k, gamma) -> x'[3]``.
    """
    phi = ca.SX.sym("phi")
    params = ca.SX.sym("p", curve.n_params)
    k = ca.SX.sym("k")
    gamma = ca.SX.sym("gamma")
    x = ca.SX.sym("x", 3)
    point = rotated_point(curve.pieces[index], phi, params, gamma)
    rhs, psi = model.curve_rhs(point, phi, k)
    rhs = ca.substitute(rhs, psi, x[2])
    return ca.Function(f"rhs{index}", [phi, x, params, k, gamma], [rhs],
                       ["phi", "x", "p", "k", "gamma"], ["xdot"])


def heading_free_rates(f: ca.Function) -> ca.Function:
    """``f0(phi, params, k, gamma) = f(phi, (0, 0, 0), params, k, gamma)`` of a :func:`piece_rhs`.

    Checks the structure first (:func:`check_heading_structure`); common
    subexpressions are merged.
    """
    check_heading_structure(f)
    phi = ca.SX.sym("phi")
    params = ca.SX.sym("p", f.size1_in(2))
    k = ca.SX.sym("k")
    gamma = ca.SX.sym("gamma")
    out = ca.cse(f(phi, ca.DM.zeros(3), params, k, gamma))
    return ca.Function(f"{f.name()}_0", [phi, params, k, gamma], [out], ["phi", "p", "k", "gamma"], ["rates"])


def check_heading_structure(f: ca.Function, trials: int = 4) -> None:
    """Check the structure of (28)-(30) that :func:`spectral_leaf` rests on; ValueError if it fails.

    The rates of ``f`` (a :func:`piece_rhs`) must not depend on (u_a, v_a)
    (checked symbolically), and ``f(phi, (u, v, psi)) = (Rot(-psi) f(phi, 0)[:2],
    f(phi, 0)[2])``: psi' does not depend on psi, which holds because (20) has
    no psi (an identity the symbolic expression does not show), and the rates of
    (u_a, v_a) are those at psi = 0 turned by -psi (checked at random points).
    """
    n_params = f.size1_in(2)
    xs = ca.SX.sym("xs", 3)
    if ca.depends_on(f(ca.SX.sym("t"), xs, ca.SX.sym("p", n_params), ca.SX.sym("k"), ca.SX.sym("g")), xs[:2]):
        raise ValueError("curve ODE lacks the structure the spectral integrator needs: rates depend on (u_a, v_a)")
    rng = np.random.default_rng(12345)
    for _ in range(trials):
        phi = rng.uniform(0.0, 2.0 * np.pi)
        p = rng.uniform(0.05, 0.6, n_params)
        k, gamma, psi = rng.uniform(0.0, 5.0), rng.uniform(-np.pi, np.pi), rng.uniform(-np.pi, np.pi)
        d0 = np.array(f(phi, [0.0, 0.0, 0.0], p, k, gamma)).ravel()
        d = np.array(f(phi, [rng.normal(), rng.normal(), psi], p, k, gamma)).ravel()
        c, s = np.cos(psi), np.sin(psi)
        expect = np.array([c * d0[0] + s * d0[1], -s * d0[0] + c * d0[1], d0[2]])
        if not np.allclose(d, expect, rtol=1e-12, atol=1e-12 * (1.0 + np.abs(d0).max())):
            raise ValueError("curve ODE lacks the rotation structure the spectral integrator needs")


def spectral_leaf(rates: ca.Function, breaks, nodes: int, x0, *args, derivative: bool = False):
    """End state of one piece by Chebyshev spectral integration of (28)-(30) (SX or MX expression).

    ``rates(phi, *args)`` gives ``(A, B, psi')``, the rates of (u_a, v_a, psi)
    at psi = 0 (:func:`heading_free_rates`), evaluated once per node by one
    ``map`` over all nodes of all panels. psi at the nodes is the cumulative
    spectral integral of psi', and the end (u_a, v_a) are weighted sums of
    ``Rot(-psi) (A, B)``.

    With ``derivative``, ``rates`` returns three more rows, the derivatives of
    (A, B, psi') by one parameter r, and the derivative of the end state by r
    is returned too, propagated through the (linear) quadrature in forward
    mode, so one pass over the nodes gives the value and its derivative.

    Returns ``x_end`` (3,), or ``(x_end, dx_end/dr)`` with ``derivative``.
    """
    breaks = np.asarray(breaks, float)
    panels = breaks.size - 1
    xi, q = chebyshev_matrices(nodes)
    half = 0.5 * np.diff(breaks)
    points = breaks[:-1][None, :] + (xi[:, None] + 1.0) * half[None, :]   # (nodes + 1) x panels
    count = points.size
    r = rates.map(count, "serial")(ca.DM(points.reshape(-1, order="F")).T, *args)   # rows x count
    weights = ca.DM((q[-1][:, None] * half[None, :]).reshape(-1, order="F"))
    upper = ca.DM(np.triu(np.ones((panels, panels)), 1))
    scale = ca.repmat(ca.DM(half).T, nodes + 1, 1)

    def cumulative(rate):   # integral of the rate from the piece's start to each node
        within = ca.mtimes(ca.DM(q), ca.reshape(rate, nodes + 1, panels)) * scale
        starts = ca.mtimes(within[nodes, :], upper)
        return ca.reshape(within + ca.repmat(starts, nodes + 1, 1), 1, count)

    turn = cumulative(r[2, :])
    psi = x0[2] + turn
    c, s = ca.cos(psi), ca.sin(psi)
    du = r[0, :] * c + r[1, :] * s      # Rot(-psi) (A, B)
    dv = r[1, :] * c - r[0, :] * s
    x_end = ca.vertcat(x0[0] + ca.mtimes(du, weights), x0[1] + ca.mtimes(dv, weights), x0[2] + turn[count - 1])
    if not derivative:
        return x_end
    turn_r = cumulative(r[5, :])
    du_r = r[3, :] * c + r[4, :] * s + dv * turn_r
    dv_r = r[4, :] * c - r[3, :] * s - du * turn_r
    return x_end, ca.vertcat(ca.mtimes(du_r, weights), ca.mtimes(dv_r, weights), turn_r[count - 1])


def spectral_step(curve: Curve, nodes: int = DEFAULT_NODES, pieces=None) -> ca.Function:
    """One trace of ``curve`` by spectral integration of (28)-(30) (:func:`spectral_leaf` per piece).

    ``F(x0[3], params[n], k, gamma) -> x_end[3]`` as an SX function (exact AD).
    ``pieces`` restricts the trace to some pieces (default: all, in order).
    """
    x0 = ca.SX.sym("x0", 3)
    params = ca.SX.sym("p", curve.n_params)
    k = ca.SX.sym("k")
    gamma = ca.SX.sym("gamma")
    x = x0
    for i in range(len(curve.pieces)) if pieces is None else pieces:
        rates = heading_free_rates(piece_rhs(curve, i))
        x = spectral_leaf(rates, curve.pieces[i].breaks, nodes, x, params, k, gamma)
    return ca.Function("step", [x0, params, k, gamma], [x], ["x0", "p", "k", "gamma"], ["xf"])


@dataclass(frozen=True)
class CvodesIntegrator:
    """Adaptive CVODES integration of (28)-(30) along a curve, piece by piece.

    Used to verify plans and to sample trajectories; independent of the
    spectral scheme and of the step-composition rules the planner relies on.

    ``multistep`` is CVODES' linear multistep method: ``"adams"`` (default;
    the ODE is not stiff on the admissible range, and at tolerances near
    1e-13 the high-order Adams method takes far fewer steps than BDF, which
    is limited to order 5) or ``"bdf"``. Both are checked against scipy's
    DOP853 in the tests.
    """

    curve: Curve
    reltol: float = 1e-12
    abstol: float = 1e-13
    multistep: str = "adams"

    def __post_init__(self) -> None:
        if not isinstance(self.curve, Curve):
            raise InputError(f"curve = {self.curve!r:.60} is not allowed: give a rollplan.Curve")
        for name in ("reltol", "abstol"):
            object.__setattr__(self, name, check_range(name, getattr(self, name), 0.0, 1e-3, low_open=True))
        check_choice("multistep", self.multistep, ("adams", "bdf"))

    def piece_integrator(self, index: int, grid):
        """A CasADi integrator of piece ``index`` with outputs at ``grid`` (in (0, 2 pi])."""
        f = piece_rhs(self.curve, index)
        phi = ca.SX.sym("phi")
        x = ca.SX.sym("x", 3)
        p = ca.SX.sym("p", self.curve.n_params + 2)
        ode = f(phi, x, p[: self.curve.n_params], p[-2], p[-1])
        opts = {"abstol": self.abstol, "reltol": self.reltol, "max_num_steps": 200000,
                "linear_multistep_method": self.multistep}
        return ca.integrator(f"cvodes{index}", "cvodes", {"t": phi, "x": x, "p": p, "ode": ode},
                             0.0, list(grid), opts)

    def integrators(self, samples: int = 1):
        """One CasADi integrator per piece, with ``samples`` outputs on (0, 2 pi]."""
        grid = np.linspace(0.0, 2.0 * np.pi, samples + 1)[1:]
        return [self.piece_integrator(i, grid) for i in range(len(self.curve.pieces))]

    def trace(self, params, k, gamma, steps=1, samples=1, x0=(0.0, 0.0, 0.0), integrators=None):
        """Trace the curve ``steps`` times.

        Returns
        -------
        phi : (steps * pieces * samples,) piece parameter of each sample
        states : (steps * pieces * samples, 3) state (u_a, v_a, psi) at the samples
        """
        ints = integrators or self.integrators(samples)
        p = np.concatenate([np.asarray(params, float), [k, gamma]])
        x = np.asarray(x0, float)
        out = []
        for step in range(steps):
            for integ in ints:
                xs = np.array(interrupts.call(integ, x0=x, p=p)["xf"])
                out.append(xs.T)
                x = xs[:, -1]
            report("CVODES trace, steps", step + 1, steps)
        grid = np.linspace(0.0, 2.0 * np.pi, samples + 1)[1:]
        return np.tile(grid, steps * len(ints)), np.vstack(out)


def rk8_step(f: ca.Function) -> ca.Function:
    """One step of the explicit eighth-order Runge-Kutta formula of Dormand and Prince.

    The 12-stage order-8 formula of DOP853 (Hairer, Norsett, Wanner, *Solving Ordinary Differential
    Equations I*, 2nd ed., Springer 1993, II.10), with scipy's coefficients, used at fixed steps: no
    error control inside; callers estimate the error by step doubling.

    Parameters
    ----------
    f : casadi.Function
        ``f(t, x, *params) -> x'`` (e.g. :func:`piece_rhs`, ``t = phi``).

    Returns
    -------
    casadi.Function
        ``step(x, t, h, *params) -> x(t + h)`` (SX).
    """
    from scipy.integrate._ivp import dop853_coefficients as dop

    x, t, h = ca.SX.sym("x", f.size1_in(1)), ca.SX.sym("t"), ca.SX.sym("h")
    params = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(2, f.n_in())]
    stages = []
    for s in range(dop.N_STAGES):
        xs = x
        for j in range(s):
            if dop.A[s, j] != 0.0:
                xs = xs + h * float(dop.A[s, j]) * stages[j]
        stages.append(f(t + float(dop.C[s]) * h, xs, *params))
    x_new = x
    for s in range(dop.N_STAGES):
        if dop.B[s] != 0.0:
            x_new = x_new + h * float(dop.B[s]) * stages[s]
    return ca.Function(f"{f.name()}_rk8", [x, t, h, *params], [x_new],
                       ["x", "t", "h", *[f.name_in(i) for i in range(2, f.n_in())]], ["x_next"])
