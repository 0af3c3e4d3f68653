"""From path to motors: a time law for a plan, the body's angular velocity, and the rotors' rates, angles and torques.

Time law
--------
A plan traces a closed curve ``n`` times; each trace is two leaves (half-steps),
each leaf a smooth piece ``c(phi)``, ``phi in [0, 2 pi]`` (see :mod:`rollplan.curves`).
Every leaf gets the same duration ``T_l = T / (2 n)`` and is traced with the
rest-to-rest (minimum-jerk) profile

    phi(t) = 2 pi s(tau),   s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5,   tau = (t - t_j) / T_l,

so ``phi_dot`` and ``phi_ddot`` vanish at both ends of every leaf: the robot
starts from rest, stops at the south pole between leaves, and does not start
impulsively, as the momentum integral (11) assumes.

Angular velocity and rotor rates
--------------------------------
Along a leaf the contact rates are ``(u_o_dot, v_o_dot) = (du_o/dphi, dv_o/dphi) phi_dot``
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

from .. import interrupts
from ..core import model
from ..core.curves import figure_eight, rotated_point
from ..core.integrate import piece_rhs
from ..errors import InputError, NoPlanError, check_range, check_whole
from ..planners.geometric import Plan
from ..problem import State
from ..robot import Robot
from .plants import Simulation, simulate_rotors
from .timing import rest_to_rest

__all__ = ["Motion", "leaf_function", "actuate", "motion_to_dict", "DEFAULT_SAMPLES", "MIN_SAMPLES_PER_LEAF",
           "MAX_SAMPLES", "MIN_DURATION", "MAX_DURATION", "MOTION_TOLERANCE", "check_timing", "certify_motion"]

log = logging.getLogger(__name__)

#: Default total number of time samples of a motion (at least).
DEFAULT_SAMPLES = 2000
#: Least number of samples per leaf: a cubic spline through the rotor rates then drives the
#: rotor-only simulation to the target within ~1e-8 R (the error falls as h^4; see the tests).
MIN_SAMPLES_PER_LEAF = 400
#: Most time samples a motion may ask for (a plan of 1000 steps needs 800 000 at the least per leaf).
MAX_SAMPLES = 10**6
#: Shortest and longest duration of a motion [s]: outside, rotor rates and torques (which scale as 1/T and
#: 1/T^2) leave every motor's reach by far, and the time samples approach under- and overflow.
MIN_DURATION, MAX_DURATION = 1e-6, 1e9
#: Largest arrival error (units of R and rad) of the rotor-only simulation of a motion (its certificate).
MOTION_TOLERANCE = 1e-6


@lru_cache(maxsize=4)
def leaf_function(index: int) -> ca.Function:
    """Geometry of one leaf of the figure eight, per unit ``phi_dot`` (all from :mod:`rollplan.model`).

    ``F(phi, psi, p[2], gamma, k, jxx, jzz, jr) -> (xdot[5], uv[2], w[3], g[2], a[2], da[2], n[3x2])``:

    * ``xdot`` -- d/dphi of (u_a, v_a, psi, rotor angle 1, rotor angle 2); the first three are (28)-(30)
      (units of R), the last two ``g``;
    * ``uv`` -- contact coordinates (u_o, v_o), (24)-(25);
    * ``w`` -- omega / phi_dot, (18), (19), (13);
    * ``g`` -- rotor rates / phi_dot, (11);
    * ``a`` -- ``n_i . w + g_i`` (axial spin per phi_dot);
    * ``da`` -- total derivative of ``a`` along the leaf, d/dphi with psi' from (30);
    * ``n`` -- rotor axes n_1, n_2 in the plane frame, (3)-(4).
    """
    curve = figure_eight()
    phi, psi, gamma, k = (ca.SX.sym(n) for n in ("phi", "psi", "gamma", "k"))
    p = ca.SX.sym("p", 2)
    jxx, jzz, jr = ca.SX.sym("jxx"), ca.SX.sym("jzz"), ca.SX.sym("jr")
    w, u_o, v_o = model.curve_omega(rotated_point(curve.pieces[index], phi, p, gamma), phi, psi, k)
    g = model.rotor_rates(w, u_o, v_o, psi, jxx, jzz, jr)
    rot = model.orientation(u_o, v_o, psi)
    a = ca.vertcat(ca.dot(rot[:, 0], w), ca.dot(rot[:, 1], w)) + g
    xdot3 = piece_rhs(curve, index)(phi, ca.vertcat(0, 0, psi), p, k, gamma)
    da = ca.jacobian(a, phi) + ca.jacobian(a, psi) * xdot3[2]
    return ca.Function(f"leaf{index}", [phi, psi, p, gamma, k, jxx, jzz, jr],
                       [ca.vertcat(xdot3, g), ca.vertcat(u_o, v_o), w, g, a, da, rot[:, :2]],
                       ["phi", "psi", "p", "gamma", "k", "jxx", "jzz", "jr"],
                       ["xdot", "uv", "w", "g", "a", "da", "n"])


@lru_cache(maxsize=4)
def _leaf_integrator(index: int, samples: int):
    """CVODES over one leaf in the normalized time tau in [0, 1], outputs at ``samples`` uniform points."""
    tau = ca.SX.sym("tau")
    x = ca.SX.sym("x", 5)
    par = ca.SX.sym("par", 7)  # a, b, gamma, k, jxx, jzz, jr
    s, ds, _ = rest_to_rest()(tau)
    # d/dtau x = phi'(tau) xdot(phi) with phi = 2 pi s(tau)
    xdot = leaf_function(index)(2 * np.pi * s, x[2], par[0:2], par[2], par[3], par[4], par[5], par[6])[0]
    ode = 2 * np.pi * ds * xdot
    grid = np.linspace(0.0, 1.0, samples + 1)[1:]
    opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 200000}
    return ca.integrator(f"leaf_time{index}_{samples}", "cvodes", {"t": tau, "x": x, "p": par, "ode": ode},
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
        Parameter of the current leaf, ``2 pi s(tau)`` [rad].
    phi_dot : ndarray, shape (N,)
        Its rate [rad/s].
    leaf : ndarray, shape (N,), int
        Index of the leaf (half-step) the sample belongs to, from 0 (a boundary
        sample belongs to the leaf that ends there; sample 0 to leaf 0).
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
        """Indices of the rest points: t = 0 and the end of every leaf."""
        return np.concatenate([[0], np.nonzero(np.diff(self.leaf) != 0)[0], [self.time.size - 1]])


def check_timing(duration, samples) -> tuple:
    """``(duration, samples)`` of :func:`actuate` if allowed, else InputError (checked before any work)."""
    return (check_range("duration", duration, MIN_DURATION, MAX_DURATION),
            check_whole("samples", samples, 3, MAX_SAMPLES))


def _samples_per_leaf(samples: int, leaves: int) -> int:
    return max(MIN_SAMPLES_PER_LEAF, math.ceil((samples - 1) / leaves))


def actuate(plan, robot: Robot, duration: float, samples: int = DEFAULT_SAMPLES) -> Motion:
    """Time a plan rest-to-rest per leaf and compute omega, rotor rates, angles and torques.

    Solves, for each leaf of the plan's figure eight, ``phi(t) = 2 pi s(tau)``
    with the minimum-jerk ``s``; then omega from (18), (19), (13), the rotor
    rates from (11), the rotor angles by integration, and the torques from (T)
    of the module docstring.

    Parameters
    ----------
    plan : rollplan.planners.geometric.Plan
        A geometric-phase plan, made for this robot (same k and radius).
    robot : Robot
        The robot's parameters.
    duration : float
        Total time T [s] in [:data:`MIN_DURATION`, :data:`MAX_DURATION`]; each of the
        ``2 n`` leaves takes ``T / (2 n)``.
    samples : int
        Least number of time samples, in [3, :data:`MAX_SAMPLES`]; rounded up to fill the
        leaves evenly, with at least :data:`MIN_SAMPLES_PER_LEAF` per leaf.

    Returns
    -------
    Motion
    """
    if not isinstance(plan, Plan):
        raise InputError(f"plan = {plan!r:.60} is not allowed: give a geometric-phase Plan (rollplan.plan)")
    if not isinstance(robot, Robot):
        raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
    duration, samples = check_timing(duration, samples)
    if not math.isclose(plan.k, robot.k, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan was made for k = {plan.k:.12g}, the robot has k = {robot.k:.12g}: "
                         "plan with this robot")
    if not math.isclose(plan.radius, robot.radius, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan's radius = {plan.radius:g} differs from the robot's radius = {robot.radius:g}")
    R = robot.radius
    leaves = 2 * plan.steps
    m = _samples_per_leaf(samples, leaves)
    t_leaf = duration / leaves
    jxx, jzz, jr = robot.j_xx, robot.j_zz, robot.rotor_inertia_axial
    ab = [plan.a / R, plan.b / R]
    par = np.array([ab[0], ab[1], plan.gamma, plan.k, jxx, jzz, jr])
    tau = np.linspace(0.0, 1.0, m + 1)
    s, ds, dds = (np.array(v).ravel() for v in rest_to_rest().map(m + 1)(tau[None, :]))
    phi, phi_dot, phi_ddot = 2 * np.pi * s, 2 * np.pi * ds / t_leaf, 2 * np.pi * dds / t_leaf**2

    x = np.zeros(5)
    rows = {k: [] for k in ("time", "phi", "phi_dot", "phi_ddot", "leaf", "x", "uv", "w", "g", "a", "da")}
    for j in range(leaves):
        piece = j % 2
        xs = np.array(interrupts.call(_leaf_integrator(piece, m), x0=x, p=par)["xf"])
        xs = np.hstack([x[:, None], xs])  # (5, m + 1)
        out = leaf_function(piece).map(m + 1)(phi[None, :], xs[2][None, :], ab, plan.gamma, plan.k, jxx, jzz, jr)
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
    state = np.column_stack([xs[:, 0] * R, xs[:, 1] * R, xs[:, 2], cat["uv"]])
    omega = pd[:, None] * cat["w"]
    rates = pd[:, None] * cat["g"]
    torques = jr * (pdd[:, None] * cat["a"] + pd[:, None] ** 2 * cat["da"])
    time = cat["time"]
    time[-1] = duration
    if not (np.all(np.isfinite(rates)) and np.all(np.isfinite(torques))):
        raise InputError(f"duration = {duration!r} is not allowed for this plan: the rotor rates or torques overflow")
    log.info("motion: %d leaves x %d samples, T = %g s, max |rotor rate| = %.3g rad/s, max |torque| = %.3g N m",
             leaves, m, duration, np.abs(rates).max(), np.abs(torques).max())
    return Motion(time, cat["phi"], pd, cat["leaf"], state, omega, rates, xs[:, 3:5], torques, robot,
                  duration, plan.goal)


def certify_motion(motion: Motion, tol: float = MOTION_TOLERANCE) -> Simulation:
    """A motion's certificate: drive the robot by its sampled rotor rates alone and compare with the goal.

    Runs :func:`~rollplan.execution.plants.simulate_rotors` (the momentum integral
    (11) and (6)-(10) by CVODES, nothing of the planner); returns the simulation if
    its arrival error is at most ``tol``, else raises NoPlanError: a motion that its
    own rotors do not carry to the goal is never reported as a success.
    """
    tol = check_range("tol", tol, 0.0, None, low_open=True)
    sim = simulate_rotors(motion.robot, motion.time, motion.rotor_rates, motion.goal)
    if not sim.arrival_error <= tol:
        raise NoPlanError(f"the motion over T = {motion.duration!r} s misses the goal when driven by its rotor rates "
                          f"alone: arrival error {sim.arrival_error:.2e} > {tol:.0e}; try more samples or another "
                          "duration")
    return sim


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
