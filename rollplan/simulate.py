"""Forward simulation of the robot driven by its rotors alone.

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
import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import model
from .errors import InputError
from .robot import Robot

__all__ = ["Simulation", "RotorPlan", "rate_spline", "simulate_rotors", "arrival_error", "load_rotor_plan"]

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Simulation:
    """Result of a rotor-driven simulation.

    Attributes
    ----------
    time : ndarray, shape (N,)
        Output times [s] (the sample times given).
    state : ndarray, shape (N, 5)
        Contact coordinates (u_a [m], v_a [m], u_o, v_o, psi [rad]) at ``time``.
    omega : ndarray, shape (N, 3)
        Angular velocity from (11) at ``time`` [rad/s], plane frame.
    final : ndarray, shape (5,)
        ``state[-1]``.
    error : ndarray, shape (5,) or None
        ``final`` minus the target (u_a, v_a in units of R, psi wrapped to
        (-pi, pi], u_o, v_o in rad); None without a target.
    arrival_error : float or None
        Euclidean norm of ``error`` (the measure of ``Plan.residual``).
    position_error : float or None
        Distance of the final contact point from the target [units of R].
    """

    time: np.ndarray
    state: np.ndarray
    omega: np.ndarray
    final: np.ndarray
    error: np.ndarray | None
    arrival_error: float | None
    position_error: float | None


def rate_spline(t, rates) -> ca.Function:
    """Interpolating cubic spline (not-a-knot) through sampled rates: ``f(t) -> (m,)``."""
    t = np.asarray(t, float)
    rates = np.asarray(rates, float)
    return ca.interpolant("rates", "bspline", [t], rates.ravel(order="C"))


def _check_samples(t, rates):
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


def arrival_error(final, target, radius):
    """Error vector of (u_a, v_a, psi, u_o, v_o) at arrival (lengths / R, psi wrapped); see :class:`Simulation`."""
    d = np.array([(final[0] - target[0]) / radius, (final[1] - target[1]) / radius,
                  math.remainder(final[4] - target[2], 2 * math.pi), final[2], final[3]])
    return d


def simulate_rotors(robot: Robot, t, rates, target=None, x0=None, reltol: float = 1e-11,
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
    target : (u_a, v_a, psi), optional
        Planned arrival [m, m, rad]; gives the arrival error.
    x0 : (5,), optional
        Initial (u_a, v_a, u_o, v_o, psi) (default zero).

    Returns
    -------
    Simulation
    """
    t, rates = _check_samples(t, rates)
    x0 = np.zeros(5) if x0 is None else np.asarray(x0, float)
    spline = rate_spline(t, rates)
    x = ca.MX.sym("x", 5)
    time = ca.MX.sym("t")
    jxx, jzz, jr, R = robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, robot.radius
    omega = model.omega_from_rotor_rates(spline(time), x[2], x[3], x[4], jxx, jzz, jr)
    ode = model.montana(omega, x[2], x[3], x[4], R)
    opts = {"abstol": abstol, "reltol": reltol, "max_num_steps": 500000}
    integ = ca.integrator("rotor_sim", "cvodes", {"t": time, "x": x, "ode": ode}, float(t[0]), list(t[1:]), opts)
    xs = np.hstack([x0[:, None], np.array(integ(x0=x0)["xf"])]).T
    om = ca.Function("omega", [time, x], [omega]).map(t.size)
    omegas = np.array(om(t[None, :], xs.T)).T
    final = xs[-1].copy()
    err = arr = pos = None
    if target is not None:
        err = arrival_error(final, target, R)
        arr = float(np.linalg.norm(err))
        pos = float(np.hypot(err[0], err[1]))
        log.info("rotor-driven simulation: arrival error %.3e (position %.3e R)", arr, pos)
    return Simulation(t, xs, omegas, final, err, arr, pos)


@dataclass(frozen=True)
class RotorPlan:
    """What a rotor-driven simulation needs from a plan file.

    Attributes
    ----------
    robot : Robot
        The robot the plan was made for.
    time : ndarray, shape (N,)
        Sample times [s].
    rotor_rates : ndarray, shape (N, 2)
        Rotor rates [rad/s].
    target : tuple of 3 float
        Planned arrival (u_a [m], v_a [m], psi [rad]).
    data : dict
        The whole JSON object.
    """

    robot: Robot
    time: np.ndarray
    rotor_rates: np.ndarray
    target: tuple
    data: dict


def load_rotor_plan(path) -> RotorPlan:
    """Read a plan written by ``rollplan plan --duration T --json FILE``; InputError if it lacks the motion."""
    import json

    from dataclasses import fields

    try:
        with open(path, encoding="utf-8") as fh:
            data = json.load(fh)
    except OSError as exc:
        raise InputError(f"plan file {str(path)!r} cannot be read: {exc.strerror}") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise InputError(f"plan file {str(path)!r} is not valid JSON: {exc}") from None
    if not isinstance(data, dict):
        raise InputError(f"plan file {str(path)!r} is not a rollplan plan (a JSON object)")
    for key in ("time", "rotor_rates", "robot", "target"):
        if key not in data:
            hint = " (make it with: rollplan plan ... --duration T --json FILE)" if key != "target" else ""
            raise InputError(f"plan file {str(path)!r} has no key {key!r}{hint}")
    rob = data["robot"]
    names = [f.name for f in fields(Robot)]
    if not isinstance(rob, dict) or any(n not in rob for n in names):
        raise InputError(f"plan file {str(path)!r}: 'robot' must hold {', '.join(names)}")
    robot = Robot(**{n: rob[n] for n in names})
    tg = data["target"]
    try:
        target = (float(tg["u_a"]), float(tg["v_a"]), float(tg["psi"]))
        t = np.asarray(data["time"], float)
        rates = np.asarray(data["rotor_rates"], float)
    except (TypeError, KeyError, ValueError):
        raise InputError(f"plan file {str(path)!r}: 'target', 'time' or 'rotor_rates' is malformed") from None
    t, rates = _check_samples(t, rates)
    return RotorPlan(robot, t, rates, target, data)
