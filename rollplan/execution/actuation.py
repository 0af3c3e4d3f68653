"""From path to motors: a time law for a plan, the body's angular velocity, and the rotors' rates, angles and torques.

Time law
--------
A plan's contact path is a sequence of smooth pieces ``c(phi)``,
``phi in [0, 2 pi]`` (:class:`rollplan.core.paths.PathPiece`): the two leaves
(half-steps) of each of the ``n`` figure eights of a geometric-phase plan, and
for a composed plan also the approach and departure rolls and the circles of a
turn in place (:mod:`rollplan.planners.geometric.composed`). Every piece gets
the same duration ``T_l = T / P`` (``P`` pieces) and is traced with the
rest-to-rest (minimum-jerk) profile

    phi(t) = 2 pi s(tau),   s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5,   tau = (t - t_j) / T_l,

so ``phi_dot`` and ``phi_ddot`` vanish at both ends of every piece: the robot
starts from rest, stops at every joint of the contact path (the joints between
the pieces of a composed plan are corners, where the contact path's tangent
jumps; a time law that did not stop there would need an infinite angular
acceleration), and does not start impulsively, as the momentum integral (11)
assumes.

Angular velocity and rotor rates
--------------------------------
Along a piece the contact rates are ``(u_o_dot, v_o_dot) = (du_o/dphi, dv_o/dphi) phi_dot``
with (u_o, v_o) from (24)-(25); the rolling components of omega are (18)-(19),
the spin is fixed by the realizability condition (13) (:func:`rollplan.model.realizable_omega`),
and the rotor rates follow from the momentum integral (11)
(:func:`rollplan.model.rotor_rates`). Both are ``phi_dot`` times a function
``w(phi, psi)`` resp. ``g(phi, psi)`` of the geometry only. The state
``(u_a, v_a, psi)`` and the rotor angles ``phi_i = int phi_i_dot dt`` are
integrated in time by CVODES with the right side ``phi_dot (x'(phi), g)``,
where ``x'(phi)`` is the curve ODE (28)-(30) (:func:`rollplan.integrate.piece_rhs`).

Rotor torques (derivation)
--------------------------
Rotor ``i`` is axisymmetric about the unit vector ``n_i`` fixed in the shell
(``n_1``, ``n_2`` are the first two columns of (2)); its absolute angular
velocity is ``omega + phi_i_dot n_i``. About its centre of mass its angular
momentum is

    H_i = J_p omega + (J_r - J_p)(n_i . omega) n_i + J_r phi_i_dot n_i.

Euler's law for the rotor is ``dH_i/dt = M_i``, the moment on it about its
centre. The shell acts on the rotor through frictionless bearings, whose moments
are perpendicular to ``n_i``, and through the motor, whose moment
``tau_i n_i`` is along it. So ``tau_i = n_i . dH_i/dt``. Since ``n_i`` is fixed
in the shell, ``dn_i/dt = omega x n_i``, and
``H_i . (omega x n_i) = 0`` (``H_i`` lies in the span of ``omega`` and ``n_i``). Hence

    tau_i = d/dt (n_i . H_i) = J_r d/dt (n_i . omega + phi_i_dot),          (T)

the motor torque is the rate of change of the rotor's absolute axial spin
momentum. The reaction ``-tau_i n_i`` acts on the shell. With
``omega = phi_dot w`` and ``phi_i_dot = phi_dot g_i``,
``n_i . omega + phi_i_dot = phi_dot a_i(phi, psi)`` with ``a_i = n_i . w + g_i``, and

    tau_i = J_r (phi_ddot a_i + phi_dot^2 da_i/dphi),
    da_i/dphi = d a_i/d phi + (d a_i/d psi) psi'(phi),

with ``psi'(phi)`` from (30). The derivatives are taken by CasADi's automatic
differentiation of the model; no equation is typed twice. ``J_r`` is the
axial inertia that multiplies ``phi_i_dot`` in (11) (if an axis carries two
rotors in tandem, tau_i is the sum of their motor torques).
``tests/test_actuation.py`` checks (T) against finite differences of the full
vector ``H_i`` projected on ``n_i``, which does not use the simplification above.

Units: time [s], angles [rad], rates [rad/s], torques [N m], lengths in the
robot's unit [m].
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ..core import model
from ..core.curves import rotated_point
from ..core.integrate import piece_rhs
from ..core.paths import CURVES
from ..core.plane import wrap_exact
from ..errors import InputError, check_range, check_whole
from ..planners.geometric.composed import as_composed
from ..problem import State
from ..robot import Robot
from .timing import rest_to_rest

__all__ = ["Motion", "piece_function", "actuate", "motion_to_dict", "DEFAULT_SAMPLES", "MIN_SAMPLES_PER_LEAF"]

log = logging.getLogger(__name__)

#: Default total number of time samples of a motion (at least).
DEFAULT_SAMPLES = 2000
#: Least number of samples per piece (leaf): a cubic spline through the rotor rates then drives the
#: rotor-only simulation to the target within ~1e-8 R (the error falls as h^4; see the tests).
MIN_SAMPLES_PER_LEAF = 400


@lru_cache(maxsize=8)
def piece_function(curve: str, index: int) -> ca.Function:
    """Geometry of piece ``index`` of the curve ``CURVES[curve]``, per unit ``phi_dot`` (all from the model).

    ``F(phi, psi, p[n], gamma, k, jxx, jzz, jr) -> (xdot[5], uv[2], w[3], g[2], a[2], da[2], n[3x2])``
    with ``p`` the curve's parameters:

    * ``xdot`` -- d/dphi of (u_a, v_a, psi, rotor angle 1, rotor angle 2); the first three are (28)-(30)
      (units of R), the last two ``g``;
    * ``uv`` -- contact coordinates (u_o, v_o), (24)-(25);
    * ``w`` -- omega / phi_dot, (18), (19), (13);
    * ``g`` -- rotor rates / phi_dot, (11);
    * ``a`` -- ``n_i . w + g_i`` (axial spin per phi_dot);
    * ``da`` -- total derivative of ``a`` along the piece, d/dphi with psi' from (30);
    * ``n`` -- rotor axes n_1, n_2 in the plane frame, (3)-(4).
    """
    c = CURVES[curve]
    phi, psi, gamma, k = (ca.SX.sym(n) for n in ("phi", "psi", "gamma", "k"))
    p = ca.SX.sym("p", c.n_params)
    jxx, jzz, jr = ca.SX.sym("jxx"), ca.SX.sym("jzz"), ca.SX.sym("jr")
    w, u_o, v_o = model.curve_omega(rotated_point(c.pieces[index], phi, p, gamma), phi, psi, k)
    g = model.rotor_rates(w, u_o, v_o, psi, jxx, jzz, jr)
    rot = model.orientation(u_o, v_o, psi)
    a = ca.vertcat(ca.dot(rot[:, 0], w), ca.dot(rot[:, 1], w)) + g
    xdot3 = piece_rhs(c, index)(phi, ca.vertcat(0, 0, psi), p, k, gamma)
    da = ca.jacobian(a, phi) + ca.jacobian(a, psi) * xdot3[2]
    return ca.Function(f"{curve}{index}", [phi, psi, p, gamma, k, jxx, jzz, jr],
                       [ca.vertcat(xdot3, g), ca.vertcat(u_o, v_o), w, g, a, da, rot[:, :2]],
                       ["phi", "psi", "p", "gamma", "k", "jxx", "jzz", "jr"],
                       ["xdot", "uv", "w", "g", "a", "da", "n"])


@lru_cache(maxsize=16)
def _piece_integrator(curve: str, index: int, samples: int):
    """CVODES over one piece in the normalized time tau in [0, 1], outputs at ``samples`` uniform points."""
    n = CURVES[curve].n_params
    tau = ca.SX.sym("tau")
    x = ca.SX.sym("x", 5)
    par = ca.SX.sym("par", n + 5)  # curve parameters, gamma, k, jxx, jzz, jr
    s, ds, _ = rest_to_rest()(tau)
    # d/dtau x = phi'(tau) xdot(phi) with phi = 2 pi s(tau)
    xdot = piece_function(curve, index)(2 * np.pi * s, x[2], par[:n], *(par[n + i] for i in range(5)))[0]
    ode = 2 * np.pi * ds * xdot
    grid = np.linspace(0.0, 1.0, samples + 1)[1:]
    opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 200000}
    return ca.integrator(f"time_{curve}{index}_{samples}", "cvodes", {"t": tau, "x": x, "p": par, "ode": ode},
                         0.0, list(grid), opts)


@dataclass(frozen=True)
class Motion:
    """A plan turned into a motion in time, with what the two rotors must do.

    All arrays have ``N`` rows, one per time sample (uniform in time, leaf
    boundaries included). Lengths in the robot's unit [m].

    Attributes
    ----------
    time : ndarray, shape (N,)
        Time [s], from 0 to ``duration``.
    phi : ndarray, shape (N,)
        Parameter of the current piece (leaf), ``2 pi s(tau)`` [rad].
    phi_dot : ndarray, shape (N,)
        Its rate [rad/s].
    leaf : ndarray, shape (N,), int
        Index of the piece of the contact path (a leaf, a half-step, of a figure eight; a roll...)
        the sample belongs to, from 0 (a boundary sample belongs to the piece that ends there;
        sample 0 to piece 0).
    state : ndarray, shape (N, 5)
        Contact coordinates in :class:`~rollplan.problem.State` order (u_a [m], v_a [m], psi, u_o, v_o [rad]).
    omega : ndarray, shape (N, 3)
        Angular velocity of the sphere in the plane frame, as in (6)-(11) [rad/s].
    rotor_rates : ndarray, shape (N, 2)
        phi_1_dot, phi_2_dot from (11) [rad/s].
    rotor_angles : ndarray, shape (N, 2)
        phi_1, phi_2, zero at t = 0 [rad].
    rotor_torques : ndarray, shape (N, 2)
        Motor torques about n_1, n_2 (see the module docstring) [N m].
    robot : Robot
    duration : float
        Total time T [s].
    goal : State
        The plan's goal [m, rad].
    """

    time: np.ndarray
    phi: np.ndarray
    phi_dot: np.ndarray
    leaf: np.ndarray
    state: np.ndarray
    omega: np.ndarray
    rotor_rates: np.ndarray
    rotor_angles: np.ndarray
    rotor_torques: np.ndarray
    robot: Robot
    duration: float
    goal: State

    @property
    def rest_indices(self) -> np.ndarray:
        """Indices of the rest points: t = 0 and the end of every piece (leaf)."""
        return np.concatenate([[0], np.nonzero(np.diff(self.leaf) != 0)[0], [self.time.size - 1]])


def _samples_per_leaf(samples: int, leaves: int) -> int:
    return max(MIN_SAMPLES_PER_LEAF, math.ceil((samples - 1) / leaves))


def actuate(plan, robot: Robot, duration: float, samples: int = DEFAULT_SAMPLES) -> Motion:
    """Time a plan rest-to-rest per piece and compute omega, rotor rates, angles and torques.

    Solves, for each piece of the plan's contact path, ``phi(t) = 2 pi s(tau)``
    with the minimum-jerk ``s``; then omega from (18), (19), (13), the rotor
    rates from (11), the rotor angles by integration, and the torques from (T)
    of the module docstring. The motion starts at the plan's start state.

    Parameters
    ----------
    plan : Plan, ComposedPlan or Route
        A geometric-phase plan (:mod:`rollplan.planners.geometric`), made for this robot (same k and radius).
    robot : Robot
        The robot's parameters.
    duration : float
        Total time T > 0 [s]; each of the P pieces (the ``2 n`` leaves of n figure eights) takes ``T / P``.
    samples : int
        Least number of time samples (>= 3); rounded up to fill the pieces evenly,
        with at least :data:`MIN_SAMPLES_PER_LEAF` per piece.

    Returns
    -------
    Motion
    """
    duration = check_range("duration", duration, 0.0, None, low_open=True)
    samples = check_whole("samples", samples, 3)
    if not math.isclose(plan.k, robot.k, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan was made for k = {plan.k:.12g}, the robot has k = {robot.k:.12g}: "
                         "plan with this robot")
    if not math.isclose(plan.radius, robot.radius, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan's radius = {plan.radius:g} differs from the robot's radius = {robot.radius:g}")
    R = robot.radius
    path = as_composed(plan)
    start = path.problem.scaled(path.problem.start).array()
    start[2], turns = wrap_exact(start[2])   # psi is an angle: integrate it reduced, report it as given
    pieces = path.pieces
    if not pieces:   # the empty motion: at rest at the start
        time = np.linspace(0.0, duration, samples)
        state = np.repeat(path.problem.start.array()[None, :], samples, axis=0)
        zero = lambda m: np.zeros((samples, m))  # noqa: E731
        return Motion(time, zero(1)[:, 0], zero(1)[:, 0], np.zeros(samples, int), state, zero(3), zero(2), zero(2),
                      zero(2), robot, duration, plan.goal)
    m = _samples_per_leaf(samples, len(pieces))
    t_leaf = duration / len(pieces)
    jxx, jzz, jr = robot.j_xx, robot.j_zz, robot.rotor_inertia_axial
    tau = np.linspace(0.0, 1.0, m + 1)
    s, ds, dds = (np.array(v).ravel() for v in rest_to_rest().map(m + 1)(tau[None, :]))
    phi, phi_dot, phi_ddot = 2 * np.pi * s, 2 * np.pi * ds / t_leaf, 2 * np.pi * dds / t_leaf**2

    x = np.concatenate([start[:3], [0.0, 0.0]])   # (u_a, v_a, psi) [R], rotor angles
    rows = {k: [] for k in ("time", "phi", "phi_dot", "phi_ddot", "leaf", "x", "uv", "w", "g", "a", "da")}
    for j, piece in enumerate(pieces):
        par = np.array([*piece.params, piece.gamma, plan.k, jxx, jzz, jr])
        xs = np.array(_piece_integrator(piece.curve, piece.index, m)(x0=x, p=par)["xf"])
        xs = np.hstack([x[:, None], xs])  # (5, m + 1)
        out = piece_function(piece.curve, piece.index).map(m + 1)(
            phi[None, :], xs[2][None, :], list(piece.params), piece.gamma, plan.k, jxx, jzz, jr)
        keep = slice(0, None) if j == 0 else slice(1, None)
        rows["time"].append((j + tau[keep]) * t_leaf)
        rows["phi"].append(phi[keep])
        rows["phi_dot"].append(phi_dot[keep])
        rows["leaf"].append(np.full(tau[keep].size, j))
        rows["x"].append(xs[:, keep].T)
        for name, val in zip(("uv", "w", "g", "a", "da"), out[1:6]):
            rows[name].append(np.array(val)[:, keep].T)
        rows["phi_ddot"].append(phi_ddot[keep])
        x = xs[:, -1]
    cat = {k: np.concatenate(v) for k, v in rows.items()}
    pd, pdd = cat["phi_dot"], cat["phi_ddot"]
    xs = cat["x"]
    state = np.column_stack([xs[:, 0] * R, xs[:, 1] * R, xs[:, 2] + 2 * np.pi * turns, cat["uv"]])
    omega = pd[:, None] * cat["w"]
    rates = pd[:, None] * cat["g"]
    torques = jr * (pdd[:, None] * cat["a"] + pd[:, None] ** 2 * cat["da"])
    time = cat["time"]
    time[-1] = duration
    log.info("motion: %d pieces x %d samples, T = %g s, max |rotor rate| = %.3g rad/s, max |torque| = %.3g N m",
             len(pieces), m, duration, np.abs(rates).max(), np.abs(torques).max())
    return Motion(time, cat["phi"], pd, cat["leaf"], state, omega, rates, xs[:, 3:5], torques, robot,
                  duration, plan.goal)


def motion_to_dict(motion: Motion) -> dict:
    """The motion's keys of ``rollplan plan --duration T --json``: time series as lists of rows."""
    rows = lambda a: [[float(v) for v in r] for r in np.asarray(a)]
    return {
        "duration": motion.duration,
        "time": [float(v) for v in motion.time],
        "omega": rows(motion.omega),
        "rotor_rates": rows(motion.rotor_rates),
        "rotor_angles": rows(motion.rotor_angles),
        "rotor_torques": rows(motion.rotor_torques),
        "state": rows(motion.state),
        "robot": motion.robot.as_dict(),
    }
