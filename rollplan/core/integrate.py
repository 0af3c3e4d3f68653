"""Integrators of the curve ODE (28)-(30) over the pieces of a closed curve.

``"spectral"`` (:func:`spectral_leaf`, :func:`spectral_step`): psi' does not depend on the state and the
rates of (u_a, v_a) are those at psi = 0 turned by -psi, so psi and then (u_a, v_a) are quadratures, taken by
Chebyshev spectral integration on panels (a CasADi function, exactly differentiable; the structure is checked
by :func:`check_heading_structure`). ``"cvodes"`` (:class:`CvodesIntegrator`): the independent, adaptive
integrator that verifies plans. :func:`rk8_formula`, :func:`rk8_step`: the fixed-step order-8 formula of
DOP853 used by the certificates. :func:`curve_piece_function`: everything along one piece per unit of its
parameter (the right side, the contact point, omega, the rotor rates). The state is ``x = (u_a, v_a, psi)`` in
units of R and rad.

Derivation and who uses which: docs/design/integration.md.
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

__all__ = ["DEFAULT_NODES", "piece_rhs", "curve_piece_function", "heading_free_rates", "check_heading_structure",
           "chebyshev_matrices", "spectral_leaf", "spectral_step", "CvodesIntegrator", "DOP853_C", "DOP853_A",
           "DOP853_B", "rk8_formula", "rk8_step"]

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


def curve_piece_function(curve: Curve, index: int) -> ca.Function:
    """Geometry of one piece of a curve, per unit of its parameter phi (all from :mod:`rollplan.core.model`).

    ``F(phi, psi, p[n], gamma, k, jxx, jzz, jr) -> (xdot[5], uv[2], w[3], g[2], a[2], da[2])`` for the
    piece ``index`` of ``curve`` rotated by gamma about OZ (31):

    * ``xdot`` -- d/dphi of (u_a, v_a, psi, rotor angle 1, rotor angle 2); the first three are
      (28)-(30) (units of R), the last two ``g``;
    * ``uv`` -- contact coordinates (u_o, v_o), (24)-(25);
    * ``w`` -- omega / phi_dot, (18), (19), (13);
    * ``g`` -- rotor rates / phi_dot, (11);
    * ``a`` -- ``n_i . w + g_i``, the rotors' axial spins per phi_dot;
    * ``da`` -- total derivative of ``a`` along the piece, d/dphi with psi' from (30).
    """
    phi, psi, gamma, k = (ca.SX.sym(n) for n in ("phi", "psi", "gamma", "k"))
    p = ca.SX.sym("p", curve.n_params)
    jxx, jzz, jr = ca.SX.sym("jxx"), ca.SX.sym("jzz"), ca.SX.sym("jr")
    w, u_o, v_o = model.curve_omega(rotated_point(curve.pieces[index], phi, p, gamma), phi, psi, k)
    g = model.rotor_rates(w, u_o, v_o, psi, jxx, jzz, jr)
    a = model.rotor_axial_spins(w, u_o, v_o, psi, jxx, jzz, jr)
    xdot3 = piece_rhs(curve, index)(phi, ca.vertcat(0, 0, psi), p, k, gamma)
    da = ca.jacobian(a, phi) + ca.jacobian(a, psi) * xdot3[2]
    return ca.Function(f"piece{index}", [phi, psi, p, gamma, k, jxx, jzz, jr],
                       [ca.vertcat(xdot3, g), ca.vertcat(u_o, v_o), w, g, a, da],
                       ["phi", "psi", "p", "gamma", "k", "jxx", "jzz", "jr"],
                       ["xdot", "uv", "w", "g", "a", "da"])


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


#: The 12-stage order-8 formula of DOP853 (Hairer's dop853.f): nodes C, the nonzero coefficients A[(i, j)]
#: and the weights B (equal to scipy's ``scipy.integrate._ivp.dop853_coefficients``, checked in the tests).
DOP853_C = (0.0, 0.526001519587677318785587544488e-01, 0.789002279381515978178381316732e-01,
            0.118350341907227396726757197510, 0.281649658092772603273242802490,
            0.333333333333333333333333333333, 0.25, 0.307692307692307692307692307692,
            0.651282051282051282051282051282, 0.6, 0.857142857142857142857142857142, 1.0)
DOP853_A = {
    (1, 0): 5.26001519587677318785587544488e-2,
    (2, 0): 1.97250569845378994544595329183e-2, (2, 1): 5.91751709536136983633785987549e-2,
    (3, 0): 2.95875854768068491816892993775e-2, (3, 2): 8.87627564304205475450678981324e-2,
    (4, 0): 2.41365134159266685502369798665e-1, (4, 2): -8.84549479328286085344864962717e-1,
    (4, 3): 9.24834003261792003115737966543e-1,
    (5, 0): 3.7037037037037037037037037037e-2, (5, 3): 1.70828608729473871279604482173e-1,
    (5, 4): 1.25467687566822425016691814123e-1,
    (6, 0): 3.7109375e-2, (6, 3): 1.70252211019544039314978060272e-1,
    (6, 4): 6.02165389804559606850219397283e-2, (6, 5): -1.7578125e-2,
    (7, 0): 3.70920001185047927108779319836e-2, (7, 3): 1.70383925712239993810214054705e-1,
    (7, 4): 1.07262030446373284651809199168e-1, (7, 5): -1.53194377486244017527936158236e-2,
    (7, 6): 8.27378916381402288758473766002e-3,
    (8, 0): 6.24110958716075717114429577812e-1, (8, 3): -3.36089262944694129406857109825,
    (8, 4): -8.68219346841726006818189891453e-1, (8, 5): 2.75920996994467083049415600797e1,
    (8, 6): 2.01540675504778934086186788979e1, (8, 7): -4.34898841810699588477366255144e1,
    (9, 0): 4.77662536438264365890433908527e-1, (9, 3): -2.48811461997166764192642586468,
    (9, 4): -5.90290826836842996371446475743e-1, (9, 5): 2.12300514481811942347288949897e1,
    (9, 6): 1.52792336328824235832596922938e1, (9, 7): -3.32882109689848629194453265587e1,
    (9, 8): -2.03312017085086261358222928593e-2,
    (10, 0): -9.3714243008598732571704021658e-1, (10, 3): 5.18637242884406370830023853209,
    (10, 4): 1.09143734899672957818500254654, (10, 5): -8.14978701074692612513997267357,
    (10, 6): -1.85200656599969598641566180701e1, (10, 7): 2.27394870993505042818970056734e1,
    (10, 8): 2.49360555267965238987089396762, (10, 9): -3.0467644718982195003823669022,
    (11, 0): 2.27331014751653820792359768449, (11, 3): -1.05344954667372501984066689879e1,
    (11, 4): -2.00087205822486249909675718444, (11, 5): -1.79589318631187989172765950534e1,
    (11, 6): 2.79488845294199600508499808837e1, (11, 7): -2.85899827713502369474065508674,
    (11, 8): -8.87285693353062954433549289258, (11, 9): 1.23605671757943030647266201528e1,
    (11, 10): 6.43392746015763530355970484046e-1,
}
DOP853_B = (5.42937341165687622380535766363e-2, 0.0, 0.0, 0.0, 0.0, 4.45031289275240888144113950566,
            1.89151789931450038304281599044, -5.8012039600105847814672114227,
            3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
            2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2)


def rk8_formula(x, h, stage):
    """``x(t + h)`` by the order-8 formula of DOP853 (:data:`DOP853_A`, :data:`DOP853_B`) from ``x = x(t)``.

    ``stage(s, x_s)`` returns the derivative at stage ``s`` (``0 <= s < 12``), at the time ``t + DOP853_C[s] h``
    and the stage state ``x_s``; it is called once per stage, in order (symbolic or numeric ``x``).
    """
    stages = []
    for s in range(len(DOP853_C)):
        xs = x
        for j in range(s):
            if (s, j) in DOP853_A:
                xs = xs + h * DOP853_A[s, j] * stages[j]
        stages.append(stage(s, xs))
    x_new = x
    for s, weight in enumerate(DOP853_B):
        if weight != 0.0:
            x_new = x_new + h * weight * stages[s]
    return x_new


def rk8_step(f: ca.Function) -> ca.Function:
    """One step of the explicit eighth-order Runge-Kutta formula of Dormand and Prince.

    The 12-stage order-8 formula of DOP853 (Hairer, Norsett, Wanner, *Solving Ordinary Differential
    Equations I*, 2nd ed., Springer 1993, II.10; :data:`DOP853_C`, :data:`DOP853_A`, :data:`DOP853_B`),
    used at fixed steps: no error control inside; callers estimate the error by step doubling.

    Parameters
    ----------
    f : casadi.Function
        ``f(t, x, *params) -> x'`` (e.g. :func:`piece_rhs`, ``t = phi``).

    Returns
    -------
    casadi.Function
        ``step(x, t, h, *params) -> x(t + h)`` (SX).
    """
    x, t, h = ca.SX.sym("x", f.size1_in(1)), ca.SX.sym("t"), ca.SX.sym("h")
    params = [ca.SX.sym(f.name_in(i), f.sparsity_in(i)) for i in range(2, f.n_in())]
    x_new = rk8_formula(x, h, lambda s, xs: f(t + DOP853_C[s] * h, xs, *params))
    return ca.Function(f"{f.name()}_rk8", [x, t, h, *params], [x_new],
                       ["x", "t", "h", *[f.name_in(i) for i in range(2, f.n_in())]], ["x_next"])
