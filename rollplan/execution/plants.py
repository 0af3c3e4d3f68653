"""Plants: forward simulation of the robot driven by its rotors alone.

Given only sampled rotor rates ``phi_1_dot(t), phi_2_dot(t)`` and the robot,
the angular velocity of the sphere is recovered from the momentum integral
(11), ``Jc omega = -J_r (n_1 phi_1_dot + n_2 phi_2_dot)``
(:func:`rollplan.model.omega_from_rotor_rates`), and Montana's contact
kinematics (6)-(10) (:func:`rollplan.model.montana`) are integrated in time by
CVODES. The rates between samples come from an interpolating cubic spline
(CasADi's ``bspline`` interpolant, not-a-knot). Nothing of the planner is
used: this is the paper's "verified under simulation".

The integration runs in the normalized time ``tau = (t - t_0) / (t_N - t_0)``
in [0, 1], with the rates multiplied by the duration (rotor turns per unit
tau): the same motion timed over a microsecond or a year is the same
computation, at the same accuracy.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import casadi as ca
import numpy as np

from .. import interrupts
from ..core import model
from ..core.plane import wrap_exact
from ..errors import InputError, SolverError
from ..problem import State, arrival_error
from ..robot import Robot

__all__ = ["Simulation", "rate_spline", "check_samples", "simulate_rotors", "MAX_TURN"]

#: Largest rotation of the sphere [rad] that sampled rotor rates may ask for (bounded from the rates by
#: (11)); a real plan turns the sphere by a few rad per figure eight.
MAX_TURN = 1e6

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
    if not np.isfinite(t[-1] - t[0]):
        raise InputError("t is not allowed: its span t[-1] - t[0] overflows")
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
    if not isinstance(robot, Robot):
        raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
    t, rates = check_samples(t, rates)
    x0 = State.of(np.zeros(5) if x0 is None else x0, "x0").array()
    x0[2] = wrap_exact(x0[2])[0]   # psi is an angle: reduced exactly, so a large one loses no accuracy
    jxx, jzz, jr, R = robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, robot.radius
    span = float(t[-1] - t[0])
    tau = (t - t[0]) / span
    tau[-1] = 1.0
    if np.any(np.diff(tau) <= 0):
        raise InputError("t is not allowed: sample times lie too close together for their span")
    turns = rates * span                            # rotor turn per unit tau [rad]
    mean = 0.5 * (np.abs(turns[1:]) + np.abs(turns[:-1])).sum(axis=1) @ np.diff(tau)
    if not np.all(np.isfinite(turns)) or mean * jr / jzz > MAX_TURN:
        raise InputError(f"the rotor rates are not allowed: they would turn the sphere by about "
                         f"{mean * jr / jzz:.3g} rad, more than {MAX_TURN:g} rad (not the rates of a plan)")
    spline = rate_spline(tau, turns)
    x = ca.MX.sym("x", 5)
    time = ca.MX.sym("tau")
    omega = model.omega_from_rotor_rates(spline(time), x[3], x[4], x[2], jxx, jzz, jr)
    ode = model.montana(omega, x[3], x[4], x[2], R)
    opts = {"abstol": abstol, "reltol": reltol, "max_num_steps": 500000}
    integ = ca.integrator("rotor_sim", "cvodes", {"t": time, "x": x, "ode": ode}, 0.0, list(tau[1:]), opts)
    try:
        xs = np.hstack([x0[:, None], np.array(interrupts.call(integ, x0=x0)["xf"])]).T
    except RuntimeError as exc:
        raise SolverError(f"CVODES could not integrate the rotor-driven motion: {str(exc).splitlines()[-1][:120]}",
                          "CVODES_failed") from None
    om = ca.Function("omega", [time, x], [omega / span]).map(t.size)
    omegas = np.array(om(tau[None, :], xs.T)).T
    final = State(*(float(v) for v in xs[-1]))
    err = arr = pos = None
    if goal is not None:
        err = arrival_error(final, State.of(goal, "goal"), R)
        arr = float(np.linalg.norm(err))
        pos = float(np.hypot(err[0], err[1]))
        log.info("rotor-driven simulation: arrival error %.3e (position %.3e R)", arr, pos)
    return Simulation(t, xs, omegas, final, err, arr, pos)
