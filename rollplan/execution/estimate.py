"""Estimating the robot's unknown inertia parameters from its observed motion.

Rate-driven robot: the ratios alpha = Jxx/J_r, beta = Jzz/J_r
---------------------------------------------------------------------
Dividing (11) by J_r,

    alpha (omega_x, omega_y, 0) + beta (0, 0, omega_z) = -(n_1 phi_1_dot + n_2 phi_2_dot),

linear in (alpha, beta) once omega is known. These are the only parameters of the robot
that the rate-driven motion depends on: (11) fixes omega from the rotor rates up to them,
and k = alpha/beta is the planner's (14). Differentiating measured states to get omega
amplifies noise, so the estimator integrates (11) over time windows [t_a, t_b]:

    alpha (W_x, W_y, 0) + beta (0, 0, W_z) = Y,
    W = int omega dt = int L(x) d(u_a, v_a, psi),    Y = -int (n_1 phi_1_dot + n_2 phi_2_dot) dt,

where ``L(x)`` inverts Montana's rows (6), (7), (10) (:func:`rollplan.core.model.omega_line_element`):
W is a line integral along the measured state path, with no time derivative of the data
(its x, y parts are just ``(-dv_a, du_a)/R`` over the window). The rows decouple:

    alpha = sum(W_x Y_x + W_y Y_y) / sum(W_x^2 + W_y^2),   beta = sum(W_z Y_z) / sum(W_z^2),

linear least squares over all windows seen so far. Quadrature: the measured states and
the commanded rates are interpolated by not-a-knot cubic splines and every sample interval
is integrated by 3-point Gauss-Legendre (fourth order; the rate plant's own input is that
spline). alpha and beta are identifiable as soon as a window has W_xy != 0 resp. W_z != 0:
any figure eight gives both (the spin omega_z of (13) is nonzero off the pole).

Torque-driven robot: Jxx - J_r, Jzz - J_r, J_r and the bearing friction
------------------------------------------------------------------------------
With commanded torques the controller knows ``P_i(t) = int_0^t tau_i dt`` (from rest) and,
with encoders, the rotor angles ``Phi_i(t) = phi_i(t) - phi_i(0)``; by
``dp_i/dt = tau_i - c_i phi_i_dot`` (:mod:`rollplan.execution.plants`), ``p_i = P_i - c_i Phi_i``.
(O) of :func:`rollplan.core.model.omega_from_momenta`, integrated over a window, is linear in
``theta = (X, Z, J_r, c_1, c_2)``, ``X = Jxx - J_r``, ``Z = Jzz - J_r``:

    X (W_x, W_y, 0) + Z (0, 0, W_z) + J_r V - c_1 Q_1 - c_2 Q_2 = -S,
    V = int n_3 (n_3 . omega) dt = int n_3 n_3^T L(x) d(u_a, v_a, psi),
    Q_i = int n_i Phi_i dt,     S = int (n_1 P_1 + n_2 P_2) dt,

solved by linear least squares (absolute inertias: the momenta carry units). J_r is
separated from X only through ``V``, i.e. through the tilt of n_3 away from the vertical
along the figure eight, so it is less well determined than X and Z (the tests and the
report give the numbers); ``friction=False`` drops c.

A friction fed forward must be the robot's, not the noise's: a feed-forward ``c_hat phi_dot``
with an error ``dc`` leaves the rotors the momentum ``dc Phi`` at the end of a motion that
turned them by ``Phi``, and without real friction to take it out the robot never comes to
rest again. :func:`established_friction` keeps only what the data establish: ``c_i > 0`` (a
bearing dissipates) and more than :data:`FRICTION_SIGNIFICANCE` standard errors from zero.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core import model
from ..core.spline import CubicSpline
from ..errors import InputError

__all__ = ["RatioEstimate", "RatioEstimator", "InertiaEstimate", "InertiaEstimator", "window_integrals",
           "FRICTION_SIGNIFICANCE", "established_friction"]

#: Standard errors by which an estimated friction coefficient must exceed zero to be fed forward.
FRICTION_SIGNIFICANCE = 3.0

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(3)


def _nodes(t):
    """Gauss-Legendre nodes and weights on every sample interval: (M,), (M,) and interval index (M,)."""
    h = np.diff(t)
    mid = 0.5 * (t[1:] + t[:-1])
    tn = (mid[:, None] + 0.5 * h[:, None] * _GL_NODES[None, :]).ravel()
    wn = (0.5 * h[:, None] * _GL_WEIGHTS[None, :]).ravel()
    idx = np.repeat(np.arange(h.size), _GL_NODES.size)
    return tn, wn, idx


def window_integrals(time, measured, radius, window: int, rates=None, momenta=None, angles=None):
    """Integrals of (11) over consecutive windows of ``window`` sample intervals.

    Parameters
    ----------
    time : (N,) sample times [s]
    measured : (N, 5) measured states (u_a, v_a, psi, u_o, v_o) [m, m, rad, rad, rad]; psi unwrapped.
    radius : R [m]
    window : int >= 1, sample intervals per window (the last window takes the remainder)
    rates : (N, 2), optional -- commanded rotor rates; gives ``Y``
    momenta : (N, 2), optional -- ``P``, integral of the commanded torques since rest; gives ``S``
    angles : (N, 2), optional -- rotor angles since rest; gives ``Q``

    Returns
    -------
    dict of arrays with one row per window: ``W`` (n, 3), ``V`` (n, 3), and when their inputs
    are given ``Y`` (n, 3), ``S`` (n, 3), ``Q`` (n, 2, 3).
    """
    t = np.asarray(time, float)
    x = np.asarray(measured, float)
    if t.ndim != 1 or t.size < 4 or x.shape != (t.size, 5) or np.any(np.diff(t) <= 0):
        raise InputError("window_integrals needs >= 4 strictly increasing times and (N, 5) states")
    tn, wn, idx = _nodes(t)
    sx = CubicSpline(t, x, axis=0)
    xn = sx(tn)
    dyn = sx(tn, 1)[:, 0:3]
    L = np.array(model.omega_line_element(radius).map(tn.size)(xn.T))  # (3, 3 M): blocks L_m side by side
    L = L.reshape(3, tn.size, 3).transpose(1, 0, 2)                    # (M, 3, 3)
    omega = np.einsum("mij,mj->mi", L, dyn)                             # omega at the nodes
    axes = model.orientations(xn[:, 3], xn[:, 4], xn[:, 2])            # (M, 3, 3), columns n_1, n_2, n_3
    n1, n2, n3 = axes[:, :, 0], axes[:, :, 1], axes[:, :, 2]
    n_int = t.size - 1
    win = np.minimum(idx // window, max((n_int - 1) // window, 0))
    nwin = win.max() + 1

    def wsum(f):
        out = np.zeros((nwin,) + f.shape[1:])
        np.add.at(out, win, wn.reshape((-1,) + (1,) * (f.ndim - 1)) * f)
        return out

    res = {"W": wsum(omega), "V": wsum(n3 * np.einsum("mi,mi->m", n3, omega)[:, None])}
    if rates is not None:
        r = CubicSpline(t, np.asarray(rates, float), axis=0)(tn)
        res["Y"] = -wsum(n1 * r[:, :1] + n2 * r[:, 1:2])
    if momenta is not None:
        P = CubicSpline(t, np.asarray(momenta, float), axis=0)(tn)
        res["S"] = wsum(n1 * P[:, :1] + n2 * P[:, 1:2])
    if angles is not None:
        A = CubicSpline(t, np.asarray(angles, float), axis=0)(tn)
        res["Q"] = np.stack([wsum(n1 * A[:, :1]), wsum(n2 * A[:, 1:2])], axis=1)
    return res


@dataclass(frozen=True)
class RatioEstimate:
    """Estimate of the inertia ratios from rate-driven motion.

    Attributes
    ----------
    alpha, beta : float
        Jxx/J_r and Jzz/J_r.
    k : float
        alpha / beta, the planner's (14).
    std_alpha, std_beta : float
        Standard errors from the least-squares residuals (a statistical statement that
        assumes independent window errors; not a bound).
    windows : int
        Number of windows used.
    """

    alpha: float
    beta: float
    k: float
    std_alpha: float
    std_beta: float
    windows: int


class RatioEstimator:
    """Accumulating least squares for (alpha, beta) = (Jxx/J_r, Jzz/J_r); see the module docstring.

    Parameters
    ----------
    radius : float
        R [m] of the robot (known).
    window : int
        Sample intervals per window (default 50: 8 windows per leaf at 400 samples per leaf).
    """

    def __init__(self, radius: float, window: int = 50):
        self.radius = float(radius)
        self.window = int(window)
        self._W = np.zeros((0, 3))
        self._Y = np.zeros((0, 3))

    def add(self, time, measured, rates) -> None:
        """Add one stretch of observed motion: measured states and the commanded rotor rates."""
        r = window_integrals(time, measured, self.radius, self.window, rates=rates)
        self._W = np.vstack([self._W, r["W"]])
        self._Y = np.vstack([self._Y, r["Y"]])

    @property
    def windows(self) -> int:
        return self._W.shape[0]

    def estimate(self) -> RatioEstimate:
        """The least-squares (alpha, beta); InputError before any motion was seen."""
        W, Y = self._W, self._Y
        sxy = float(np.sum(W[:, :2] ** 2))
        sz = float(np.sum(W[:, 2] ** 2))
        if sxy == 0.0 or sz == 0.0:
            raise InputError("no motion observed yet: nothing to estimate from")
        alpha = float(np.sum(W[:, :2] * Y[:, :2]) / sxy)
        beta = float(np.sum(W[:, 2] * Y[:, 2]) / sz)
        n = W.shape[0]
        ra = (Y[:, :2] - alpha * W[:, :2]).ravel()
        rb = Y[:, 2] - beta * W[:, 2]
        sa = float(np.sqrt(ra @ ra / max(2 * n - 1, 1) / sxy))
        sb = float(np.sqrt(rb @ rb / max(n - 1, 1) / sz))
        return RatioEstimate(alpha, beta, alpha / beta, sa, sb, n)


@dataclass(frozen=True)
class InertiaEstimate:
    """Estimate of the absolute inertias (and bearing friction) from torque-driven motion.

    Attributes
    ----------
    j_xx, j_zz, j_r : float
        [kg m^2].
    friction : (2,) float
        Viscous coefficients c_i [N m s/rad] (zeros when not estimated).
    k : float
        Jxx / Jzz.
    std : ndarray
        Standard errors of (Jxx - J_r, Jzz - J_r, J_r[, c_1, c_2]) from the residuals.
    condition : float
        Condition number of the scaled regression matrix.
    windows : int
    """

    j_xx: float
    j_zz: float
    j_r: float
    friction: tuple
    k: float
    std: np.ndarray
    condition: float
    windows: int

    @property
    def alpha(self) -> float:
        return self.j_xx / self.j_r

    @property
    def beta(self) -> float:
        return self.j_zz / self.j_r


class InertiaEstimator:
    """Accumulating least squares for (Jxx - J_r, Jzz - J_r, J_r[, c_1, c_2]); see the module docstring.

    Parameters
    ----------
    radius : float
        R [m].
    window : int
        Sample intervals per window.
    friction : bool
        Also estimate the viscous bearing friction (needs the rotor angles).
    """

    def __init__(self, radius: float, window: int = 50, friction: bool = True):
        self.radius = float(radius)
        self.window = int(window)
        self.friction = bool(friction)
        self._rows = []
        self._rhs = []

    def add(self, time, measured, commanded_momenta, rotor_angles=None) -> None:
        """Add observed motion: measured states, ``P`` (integral of the commanded torque since rest), rotor angles."""
        if self.friction and rotor_angles is None:
            raise InputError("estimating friction needs the rotor angles")
        r = window_integrals(time, measured, self.radius, self.window, momenta=commanded_momenta,
                             angles=rotor_angles if self.friction else None)
        W, V, S = r["W"], r["V"], r["S"]
        cols = [np.column_stack([W[:, 0], W[:, 1], np.zeros(len(W))]),
                np.column_stack([np.zeros(len(W)), np.zeros(len(W)), W[:, 2]]), V]
        if self.friction:
            cols += [-r["Q"][:, 0, :], -r["Q"][:, 1, :]]
        A = np.stack(cols, axis=-1).reshape(-1, len(cols))  # rows: window-major, 3 components each
        self._rows.append(A)
        self._rhs.append(-S.reshape(-1))

    def estimate(self) -> InertiaEstimate:
        if not self._rows:
            raise InputError("no motion observed yet: nothing to estimate from")
        A = np.vstack(self._rows)
        b = np.concatenate(self._rhs)
        scale = np.linalg.norm(A, axis=0)
        scale[scale == 0] = 1.0
        As = A / scale
        sol, *_ = np.linalg.lstsq(As, b, rcond=None)
        theta = sol / scale
        res = b - A @ theta
        dof = max(A.shape[0] - A.shape[1], 1)
        cov = np.linalg.pinv(As.T @ As) * (res @ res / dof)
        std = np.sqrt(np.diag(cov)) / scale
        X, Z, jr = theta[:3]
        c = tuple(theta[3:5]) if self.friction else (0.0, 0.0)
        return InertiaEstimate(float(X + jr), float(Z + jr), float(jr), tuple(float(v) for v in c),
                               float((X + jr) / (Z + jr)), std, float(np.linalg.cond(As)), A.shape[0] // 3)


def established_friction(estimate: InertiaEstimate, significance: float = FRICTION_SIGNIFICANCE) -> tuple:
    """The friction coefficients the data establish: ``c_i`` where ``c_i > significance * std(c_i)``, else 0.

    A negative ``c_i`` (a bearing that gives energy) or one within the noise is taken as none: fed forward, it
    would leave the rotors spinning at the end of every motion (module docstring).
    """
    if estimate.std.size < 5:     # friction not estimated
        return (0.0, 0.0)
    return tuple(float(c) if c > significance * float(s) else 0.0 for c, s in zip(estimate.friction, estimate.std[3:5]))
