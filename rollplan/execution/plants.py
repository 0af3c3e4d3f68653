"""Plants: forward simulation of the robot driven by its rotors alone.

Given only sampled rotor rates ``phi_1_dot(t), phi_2_dot(t)`` and the robot,
the angular velocity of the sphere is recovered from the momentum integral
(11), ``Jc omega = -J_r (n_1 phi_1_dot + n_2 phi_2_dot)``
(:func:`rollplan.model.omega_from_rotor_rates`), and Montana's contact
kinematics (6)-(10) (:func:`rollplan.model.montana`) are integrated in time by
CVODES. The rates between samples come from an interpolating cubic spline
(CasADi's ``bspline`` interpolant, not-a-knot). Nothing of the planner is
used: this is the paper's "verified under simulation".
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ..core import model
from ..errors import InputError
from ..problem import State, arrival_error
from ..robot import Robot

__all__ = ["Simulation", "rate_spline", "check_samples", "simulate_rotors"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Simulation:
    """Result of a rotor-driven simulation.

    Attributes
    ----------
    time : ndarray, shape (N,)
        Output times [s] (the sample times given).
    state : ndarray, shape (N, 5)
        Contact coordinates in :class:`~rollplan.problem.State` order (u_a [m], v_a [m], psi, u_o, v_o [rad])
        at ``time``.
    omega : ndarray, shape (N, 3)
        Angular velocity from (11) at ``time`` [rad/s], plane frame.
    final : State
        ``state[-1]``.
    error : ndarray, shape (5,) or None
        :func:`rollplan.problem.arrival_error` of ``final`` to the goal (u_a, v_a
        in units of R, psi wrapped to (-pi, pi], u_o, v_o in rad); None without a goal.
    arrival_error : float or None
        Euclidean norm of ``error`` (the measure of a plan's residual).
    position_error : float or None
        Distance of the final contact point from the goal's [units of R].
    """

    time: np.ndarray
    state: np.ndarray
    omega: np.ndarray
    final: State
    error: np.ndarray | None
    arrival_error: float | None
    position_error: float | None


def rate_spline(t, rates) -> ca.Function:
    """Interpolating cubic spline (not-a-knot) through sampled rates: ``f(t) -> (m,)``."""
    t = np.asarray(t, float)
    rates = np.asarray(rates, float)
    return ca.interpolant("rates", "bspline", [t], rates.ravel(order="C"))


def check_samples(t, rates):
    """``(t, rates)`` as float arrays if they are valid samples of the rotor rates; InputError otherwise."""
    t = np.asarray(t, float)
    rates = np.asarray(rates, float)
    if t.ndim != 1 or t.size < 4:
        raise InputError(f"t has shape {t.shape}: give at least 4 sample times")
    if rates.shape != (t.size, 2):
        raise InputError(f"rates has shape {rates.shape}: it must be ({t.size}, 2), one row per sample time")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(rates))):
        raise InputError("t and rates must be finite numbers")
    if np.any(np.diff(t) <= 0):
        raise InputError("t is not allowed: sample times must increase strictly")
    return t, rates


def simulate_rotors(robot: Robot, t, rates, goal=None, x0=None, reltol: float = 1e-11,
                    abstol: float = 1e-13) -> Simulation:
    """Integrate (6)-(10) with omega from (11), driven by sampled rotor rates.

    Solves ``x_dot = montana(omega(t, x), x)`` with
    ``Jc omega = -J_r (n_1 phi_1_dot(t) + n_2 phi_2_dot(t))`` (11), where the
    rates are a cubic spline through the samples.

    Parameters
    ----------
    robot : Robot
        The real robot (its Jxx, Jzz, J_r and R are used).
    t : array, shape (N,)
        Strictly increasing sample times [s].
    rates : array, shape (N, 2)
        Rotor rates phi_1_dot, phi_2_dot at ``t`` [rad/s].
    goal : State or (u_a, v_a, psi), optional
        Planned arrival [m, rad]; gives the arrival error.
    x0 : (5,), optional
        Initial state in :class:`~rollplan.problem.State` order (default zero).

    Returns
    -------
    Simulation
    """
    t, rates = check_samples(t, rates)
    x0 = np.zeros(5) if x0 is None else np.asarray(x0, float)
    spline = rate_spline(t, rates)
    x = ca.MX.sym("x", 5)
    time = ca.MX.sym("t")
    jxx, jzz, jr, R = robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, robot.radius
    omega = model.omega_from_rotor_rates(spline(time), x[3], x[4], x[2], jxx, jzz, jr)
    ode = model.montana(omega, x[3], x[4], x[2], R)
    opts = {"abstol": abstol, "reltol": reltol, "max_num_steps": 500000}
    integ = ca.integrator("rotor_sim", "cvodes", {"t": time, "x": x, "ode": ode}, float(t[0]), list(t[1:]), opts)
    xs = np.hstack([x0[:, None], np.array(integ(x0=x0)["xf"])]).T
    om = ca.Function("omega", [time, x], [omega]).map(t.size)
    omegas = np.array(om(t[None, :], xs.T)).T
    final = State(*(float(v) for v in xs[-1]))
    err = arr = pos = None
    if goal is not None:
        err = arrival_error(final, State.of(goal, "goal"), R)
        arr = float(np.linalg.norm(err))
        pos = float(np.hypot(err[0], err[1]))
        log.info("rotor-driven simulation: arrival error %.3e (position %.3e R)", arr, pos)
    return Simulation(t, xs, omegas, final, err, arr, pos)
