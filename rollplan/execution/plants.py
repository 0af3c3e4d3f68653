"""Plants: forward simulation of the robot driven by its rotors alone, by rates or by torques.

Given only sampled rotor rates ``phi_1_dot(t), phi_2_dot(t)`` and the robot,
the angular velocity of the sphere is recovered from the momentum integral
(11), ``Jc omega = -J_r (n_1 phi_1_dot + n_2 phi_2_dot)``
(:func:`rollplan.model.omega_from_rotor_rates`), and Montana's contact
kinematics (6)-(10) (:func:`rollplan.model.montana`) are integrated in time by
CVODES. The rates between samples come from an interpolating cubic spline
(CasADi's ``bspline`` interpolant, not-a-knot). Nothing of the planner is
used: this is the paper's "verified under simulation".

Two plants share one result, :class:`PlantResponse` (:data:`PLANTS`):

``rates`` (:func:`run_rates`)
    the rotors follow the commanded rates exactly (ideal velocity servos): :func:`simulate_rotors`.
``torques`` (:func:`run_torques`)
    the motors apply torques. State: the contact coordinates, the rotors' absolute axial
    momenta ``p_i = J_r (n_i . omega + phi_i_dot)`` (P) and the rotor angles. By (T) of
    :mod:`rollplan.execution.actuation`, ``dp_i/dt = tau_i - c_i phi_i_dot`` (with an optional
    viscous bearing friction ``c_i`` on the rate relative to the shell: an internal moment, so the
    momentum about the contact point stays conserved). omega and phi_dot follow from p by (11)
    solved with (P), (O) of :func:`rollplan.core.model.omega_from_momenta`, and the contact
    coordinates by Montana's (6)-(10). Driven by ``tau = dp/dt`` of a rate-driven motion, (O) gives
    back the same omega, so the two plants agree (the tests check it). The total angular momentum
    about the contact point is conserved because gravity acts above the contact point, the contact
    force acts at it, and the point moves parallel to the linear momentum
    (:func:`rollplan.core.model.momentum_about_contact`); the rotors exchange momentum with the shell.

Torque samples between sample times: timed torques have a kink (min-jerk) or a step (the non-stop
and time-optimal laws) at the joints of the contact path, so one spline across a joint converges
only as h^2 or rings. :func:`input_function` splits the samples at given ``breaks`` (the joints,
``Actuation.rest_indices`` for min-jerk) into not-a-knot cubic splines, or interpolates linearly.
Splines are integrated by CVODES. Linear inputs (the replay rule of plan files) have a kink at every
sample, and a step at every time given twice, where CVODES' error control fails over and over; they are
integrated sample interval by sample interval, where the inputs are linear in time, by classical RK4
(exact for the momenta, whose right side is the input) with ``m`` steps per interval. Each step's error
is estimated by the embedded third-order solution (the right side at the step's end, ``h/6 (k_4 - k_5)``:
an over-estimate of RK4's error); ``m`` is doubled until the estimates, summed over every interval, or
the change from the result of ``m / 2`` steps (Richardson: about 15 times the error), are within
:data:`RK_TOLERANCE` of each quantity's scale; samples so far apart for the motion that :data:`RK_MAX_STEPS`
steps do not reach it are integrated by CVODES on the same linear inputs instead.

Disturbances (:data:`DISTURBANCES`, by name with parameters and a seed, :func:`disturbance`):
``friction`` (bearing friction, torque plant), ``measurement`` (white noise on every measured state
sample; the true state is not changed), ``torque_noise`` (torque plant) and ``rate_noise`` (rate
plant): white noise on every input sample. Every draw is ``numpy.random.default_rng([seed,
segment, tag])``, so a controller that runs the plant segment after segment gets independent,
reproducible draws.

The integration runs in the normalized time ``tau = (t - t_0) / (t_N - t_0)``
in [0, 1], with the rates multiplied by the duration (rotor turns per unit
tau): the same motion timed over a microsecond or a year is the same
computation, at the same accuracy.
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
from ..core.plane import wrap_exact
from ..core.spline import CubicSpline
from ..errors import InputError, SolverError, check_finite
from ..problem import State
from ..progress import report
from ..robot import Robot
from ..timeseries import Arrival, TimeSeries

__all__ = ["RotorSimulation", "rate_spline", "check_samples", "simulate_rotors", "MAX_TURN", "STILL_TURN", "Friction",
           "MeasurementNoise", "TorqueNoise", "RateNoise", "DISTURBANCES", "disturbance", "PlantResponse",
           "input_function", "run_rates", "run_torques", "PLANTS", "PLANT_NAMES", "by_name", "measure",
           "rotor_momenta"]

#: Sample intervals per chunk of :func:`simulate_rotors` (a longer series runs in chunks, with progress: the
#: cost of one spline grows faster than its length).
CHUNK = 10_000
#: Samples on either side of a chunk that its spline also passes through.
OVERLAP = 40
#: Sample intervals per call of the torque plant's RK4 (progress and Ctrl-C between calls).
RK_CHUNK = 2000
#: Largest sum of the RK4 steps' error estimates of the torque plant's linear replay, relative to the scale
#: of each quantity (lengths: R; angles: 1 rad or their largest value; momenta: their largest value or the
#: torques' largest impulse).
RK_TOLERANCE = 1e-10
#: Most RK4 steps per sample interval.
RK_MAX_STEPS = 64
#: Largest rotation of the sphere [rad] that sampled rotor rates may ask for (bounded from the rates by
#: (11)); a real plan turns the sphere by a few rad per figure eight.
MAX_TURN = 1e6
#: Rotation [rad] below which sampled rotor rates are a sphere at rest: :func:`simulate_rotors` keeps the start
#: state (its error is about this turn, far below the integrator's tolerances) instead of integrating; CVODES fails on
#: some derivatives this small (rates of about 1e-70 and 1e-145 rad/s). Each sample turning it by less than
#: this per unit of normalised time is taken as rest (0), so a stretch of such rates in a moving file is not
#: integrated either.
STILL_TURN = 1e-30

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RotorSimulation(Arrival):
    """Result of a rotor-driven simulation (:func:`simulate_rotors`).

    Attributes
    ----------
    series : TimeSeries
        At the sample times given [s]: ``state`` (u_a [m], v_a [m], psi, u_o, v_o [rad]), ``omega`` from
        (11) [rad/s] (plane frame) and the ``rotor_rates`` given [rad/s].
    goal : State or None
        Planned arrival [m, rad]; with it ``final``, ``error``, ``arrival_error`` (the measure of a plan's
        residual) and ``position_error`` [units of R] (:class:`~rollplan.timeseries.Arrival`).
    """

    series: TimeSeries
    goal: State | None = None


def rate_spline(t, rates) -> ca.Function:
    """Interpolating cubic spline (not-a-knot) through sampled rates: ``f(t) -> (m,)``.

    Its coefficients solve the interpolation conditions by a sparse direct LU (CSparse): CasADi's default, an
    iterative least-squares solver, converges slowly on non-uniform sample times (the steps of a plan file
    given twice) and stops at about 1e-12 of the rates.
    """
    t = np.asarray(t, float)
    rates = np.asarray(rates, float)
    return ca.interpolant("rates", "bspline", [t], rates.ravel(order="C"), {"linear_solver": "csparse"})


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


@lru_cache(maxsize=1)
def _rotor_dynamics() -> ca.Function:
    """``(x, phi_dot, (Jxx, Jzz, J_r, R)) -> (dx/dt, omega)`` of the rate-driven robot: (11) and (6)-(10), in SX
    (one compact function for the integrator's right side)."""
    x, pd, r = ca.SX.sym("x", 5), ca.SX.sym("pd", 2), ca.SX.sym("robot", 4)
    omega = model.omega_from_rotor_rates(pd, x[3], x[4], x[2], r[0], r[1], r[2])
    return ca.Function("rotor_dynamics", [x, pd, r], [model.montana(omega, x[3], x[4], x[2], r[3]), omega])


@lru_cache(maxsize=1)
def _torque_dynamics() -> ca.Function:
    """``(z, u, reference, noise, K, c, (Jxx, Jzz, J_r, R)) -> (dz/dt, omega, phi_dot, cmd)`` of the torque plant
    (:func:`run_torques`), in SX. ``z`` = (state, p, rotor angles, integral of cmd); the command is ``cmd = u + K
    (reference - phi_dot)``, the rotors take ``cmd + noise - c phi_dot``."""
    z, u, ref, noise, gain, c, r = (ca.SX.sym(n, k) for n, k in (("z", 11), ("u", 2), ("ref", 2), ("noise", 2),
                                                                 ("gain", 1), ("c", 2), ("robot", 4)))
    x, p = z[0:5], z[5:7]
    omega, phi_dot = model.omega_from_momenta(p, x[3], x[4], x[2], r[0], r[1], r[2])
    cmd = u + gain * (ref - phi_dot)
    ode = ca.vertcat(model.montana(omega, x[3], x[4], x[2], r[3]), cmd + noise - c * phi_dot, phi_dot, cmd)
    return ca.Function("torque_dynamics", [z, u, ref, noise, gain, c, r], [ode, omega, phi_dot, cmd])


@lru_cache(maxsize=8)
def _rk4_interval(m: int) -> ca.Function:
    """``(z, u0, u1, h, params) -> (z, error)`` after ``m`` classical RK4 steps over a sample interval of length
    ``h`` of the torque plant (:func:`_torque_dynamics`), its inputs ``u = (torque, reference, noise)`` linear
    in time from ``u0`` to ``u1``; ``params = (K, c, Jxx, Jzz, J_r, R)``; ``error``: the sum of the steps'
    embedded error estimates ``|h/6 (k_4 - k_5)|`` (module docstring)."""
    z0, u0, u1, h, par = (ca.SX.sym(n, k) for n, k in (("z", 11), ("u0", 6), ("u1", 6), ("h", 1), ("p", 7)))
    dynamics = _torque_rhs()

    def f(z, w):
        u = u0 + w * (u1 - u0)
        return dynamics(z, u[0:2], u[2:4], u[4:6], par[0], par[1:3], par[3:7])

    z, dt, error = z0, h / m, ca.SX.zeros(11)
    k1 = f(z, 0.0)
    for j in range(m):
        k2 = f(z + 0.5 * dt * k1, (j + 0.5) / m)
        k3 = f(z + 0.5 * dt * k2, (j + 0.5) / m)
        k4 = f(z + dt * k3, (j + 1.0) / m)
        z = z + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        k5 = f(z, (j + 1.0) / m)   # the right side at the step's end: the next step's k_1
        error += ca.fabs(dt / 6 * (k4 - k5))
        k1 = k5
    return ca.Function("torque_rk4", [z0, u0, u1, h, par], [z, error])


@lru_cache(maxsize=1)
def _torque_rhs() -> ca.Function:
    """``dz/dt`` of :func:`_torque_dynamics` alone, each repeated subexpression computed once (CasADi's
    ``cse``): the right side that :func:`_rk4_interval` repeats."""
    z, u, ref, noise, gain, c, r = (ca.SX.sym(n, k) for n, k in (("z", 11), ("u", 2), ("ref", 2), ("noise", 2),
                                                                 ("gain", 1), ("c", 2), ("robot", 4)))
    ode = _torque_dynamics()(z, u, ref, noise, gain, c, r)[0]
    return ca.Function("torque_rhs", [z, u, ref, noise, gain, c, r], [ode], {"cse": True})


@lru_cache(maxsize=16)
def _rk4_intervals(m: int, n: int) -> ca.Function:
    """:func:`_rk4_interval` over ``n`` consecutive intervals (one column each): every state after each, and
    every error estimate."""
    return _rk4_interval(m).mapaccum(n)


def simulate_rotors(robot: Robot, t, rates, goal=None, x0=None, reltol: float = 1e-11,
                    abstol: float = 1e-13) -> RotorSimulation:
    """Integrate (6)-(10) with omega from (11), driven by sampled rotor rates.

    Solves ``x_dot = montana(omega(t, x), x)`` with
    ``Jc omega = -J_r (n_1 phi_1_dot(t) + n_2 phi_2_dot(t))`` (11), where the
    rates are a cubic spline through the samples. Rates that would turn the sphere by less than
    :data:`STILL_TURN` in all leave it at ``x0``; rates that would turn it by more than :data:`MAX_TURN` are
    refused.

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
    RotorSimulation
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
    if not np.all(np.isfinite(turns)):
        raise _too_far(math.inf)
    mean = 0.5 * (np.abs(turns[1:]) + np.abs(turns[:-1])).sum(axis=1) @ np.diff(tau)
    # a sample that turns the sphere by less than STILL_TURN per unit tau is rest: CVODES fails on a stretch of
    # derivatives that small (about 1e-70) even where other samples move the sphere
    turns = np.where(np.abs(turns) * jr / jzz < STILL_TURN, 0.0, turns)
    still = mean * jr / jzz < STILL_TURN or not np.any(turns)
    n = tau.size
    # a long series in chunks of CHUNK sample intervals, each with the spline through its samples and OVERLAP more
    # on either side (a cubic spline's dependence on far samples decays by 2 - sqrt(3) per sample: the chunks'
    # splines are the whole series' to rounding), its progress reported between them; the splines' turn is
    # bounded before any is integrated (they may swing far beyond the samples)
    chunks = []
    for a in range(0, n - 1, CHUNK):
        b = min(a + CHUNK, n - 1)
        lo, hi = (0, n) if n - 1 <= CHUNK else (max(0, a - OVERLAP), min(n, b + 1 + OVERLAP))
        chunks.append((a, b, rate_spline(tau[lo:hi], turns[lo:hi])))
    turned = sum(_spline_turn(spline, tau[a:b + 1], turns[a:b + 1]) for a, b, spline in chunks) * jr / jzz
    if not turned <= MAX_TURN:
        raise _too_far(turned)
    x = ca.MX.sym("x", 5)
    time = ca.MX.sym("tau")
    opts = {"abstol": abstol, "reltol": reltol, "max_num_steps": 500000}
    xs, omegas, xk = np.empty((n, 5)), np.empty((n, 3)), x0
    xs[0] = x0
    try:
        for a, b, spline in chunks:
            ode, omega = _rotor_dynamics()(x, spline(time), ca.DM([jxx, jzz, jr, R]))
            if still:
                xs[a + 1:b + 1] = xk
            else:
                integ = ca.integrator("rotor_sim", "cvodes", {"t": time, "x": x, "ode": ode}, float(tau[a]),
                                      list(tau[a + 1:b + 1]), opts)
                xs[a + 1:b + 1] = np.array(interrupts.call(integ, x0=xk)["xf"]).T
            xk = xs[b]
            om = ca.Function("omega", [time, x], [omega / span]).map(b + 1 - a)
            omegas[a:b + 1] = np.array(om(tau[None, a:b + 1], xs[a:b + 1].T)).T
            if n - 1 > CHUNK:
                report("rotor-driven simulation, samples", b, n - 1)
    except RuntimeError as exc:
        raise SolverError(f"CVODES could not integrate the rotor-driven motion: {str(exc).splitlines()[-1][:120]}",
                          "CVODES_failed") from None
    sim = RotorSimulation(TimeSeries(t, xs, omega=omegas, rotor_rates=rates, radius=R),
                          None if goal is None else State.of(goal, "goal"))
    if goal is not None:
        log.info("rotor-driven simulation: arrival error %.3e (position %.3e R)", sim.arrival_error,
                 sim.position_error)
    return sim


def _too_far(turn: float) -> InputError:
    """The refusal of rotor rates that would turn the sphere by ``turn`` [rad], more than :data:`MAX_TURN`."""
    return InputError(f"the rotor rates are not allowed: they would turn the sphere by about {turn:.3g} rad, more "
                      f"than {MAX_TURN:g} rad (not the rates of a plan)")


def _spline_turn(spline, knots, values) -> float:
    """An upper bound of the integral of ``|f_1| + |f_2|`` of the spline ``f`` (:func:`rate_spline`) between its
    ``knots`` (where it takes ``values``, shape (n, 2)): on a knot interval of width w the cubic is the Hermite
    combination of its end values (weights >= 0 summing to 1) and end slopes (weights within [-4/27, 4/27] times w),
    so ``|f| <= max(|f_0|, |f_1|) + 4/27 w (|f_0'| + |f_1'|)`` there."""
    t = ca.MX.sym("t")
    slope = ca.Function("slope", [t], [ca.jacobian(spline(t), t)]).map(knots.size)
    s = np.abs(np.array(slope(knots[None, :])).T)
    v, w = np.abs(values), np.diff(knots)[:, None]
    return float((w * (np.maximum(v[1:], v[:-1]) + 4.0 / 27.0 * w * (s[1:] + s[:-1]))).sum())


_TAG = {"measurement": 1, "torque_noise": 2, "rate_noise": 3, "rest": 4}


def _nonnegative(name, value) -> float:
    v = check_finite(name, value)
    if v < 0:
        raise InputError(f"{name} = {value!r} is not allowed: it must be >= 0")
    return v


@dataclass(frozen=True)
class Friction:
    """Viscous bearing friction ``-c_i phi_i_dot`` on rotor i's rate relative to the shell [N m s/rad]; torque plant."""

    c: tuple = (0.0, 0.0)
    name = "friction"

    def __post_init__(self):
        c = tuple(np.atleast_1d(self.c)) if np.ndim(self.c) else (self.c, self.c)
        if len(c) != 2:
            raise InputError(f"friction c = {self.c!r} is not allowed: give one number or two")
        object.__setattr__(self, "c", tuple(_nonnegative("friction c", v) for v in c))


@dataclass(frozen=True)
class MeasurementNoise:
    """White noise on every measured state: ``sigma_length`` [R] on u_a, v_a, ``sigma_angle`` [rad] on the angles."""

    sigma_length: float = 0.0
    sigma_angle: float = 0.0
    seed: int = 0
    name = "measurement"

    def __post_init__(self):
        object.__setattr__(self, "sigma_length", _nonnegative("measurement sigma_length", self.sigma_length))
        object.__setattr__(self, "sigma_angle", _nonnegative("measurement sigma_angle", self.sigma_angle))

    def draw(self, n: int, radius: float, segment: int, tag: str = "measurement") -> np.ndarray:
        """``(n, 5)`` noise for n samples of segment ``segment`` [m, m, rad, rad, rad]."""
        rng = np.random.default_rng([int(self.seed), int(segment), _TAG[tag]])
        return rng.normal(size=(n, 5)) * np.array([self.sigma_length * radius] * 2 + [self.sigma_angle] * 3)


@dataclass(frozen=True)
class TorqueNoise:
    """White noise of standard deviation ``sigma`` [N m] on every torque sample; torque plant."""

    sigma: float = 0.0
    seed: int = 0
    name = "torque_noise"

    def __post_init__(self):
        object.__setattr__(self, "sigma", _nonnegative("torque_noise sigma", self.sigma))

    def draw(self, n: int, segment: int) -> np.ndarray:
        return np.random.default_rng([int(self.seed), int(segment), _TAG[self.name]]).normal(0.0, self.sigma, (n, 2))


@dataclass(frozen=True)
class RateNoise(TorqueNoise):
    """White noise of standard deviation ``sigma`` [rad/s] on every rotor-rate sample; rate plant."""

    name = "rate_noise"

    def __post_init__(self):
        object.__setattr__(self, "sigma", _nonnegative("rate_noise sigma", self.sigma))


#: Disturbances by name.
DISTURBANCES = {"friction": Friction, "measurement": MeasurementNoise, "torque_noise": TorqueNoise,
                "rate_noise": RateNoise}
_NOT_FOR = {"rates": ("friction", "torque_noise"), "torques": ("rate_noise",),
            "mujoco": ("friction", "rate_noise")}   # MuJoCo (rollplan.execution.mujoco_engine), torque-driven


def disturbance(name: str, **params):
    """A disturbance by name, e.g. ``disturbance("measurement", sigma_length=1e-3, sigma_angle=1e-3, seed=3)``."""
    if name not in DISTURBANCES:
        raise InputError(f"disturbance {name!r} is not known: choose one of {', '.join(DISTURBANCES)}")
    try:
        return DISTURBANCES[name](**params)
    except TypeError as exc:
        raise InputError(f"disturbance {name!r}: {exc}") from None


def by_name(disturbances, plant: str) -> dict:
    """``{name: disturbance}``; InputError for a name given twice or one that does not apply to ``plant``."""
    if plant not in _NOT_FOR:
        raise InputError(f"plant {plant!r} is not known: choose one of {', '.join(_NOT_FOR)}")
    out = {}
    for d in disturbances:
        if d.name in out:
            raise InputError(f"disturbance {d.name!r} is given twice")
        if d.name in _NOT_FOR[plant]:
            raise InputError(f"disturbance {d.name!r} does not apply to the {plant} plant")
        out[d.name] = d
    return out


def measure(state, disturbances: dict, radius: float, segment: int, readings: int = 0) -> np.ndarray:
    """What the sensors report for ``state`` (N, 5): the state plus measurement noise, if any.

    ``readings > 0``: ``state`` is one state at rest, and the result is the mean of that many
    independent readings (drawn apart from the per-sample noise), as a controller that waits at a
    rest point and averages its sensor would see it.
    """
    m = disturbances.get("measurement")
    state = np.asarray(state, float)
    if m is None:
        return state.copy()
    if readings > 0:
        return state + m.draw(int(readings), radius, segment, "rest").mean(axis=0)
    return state + m.draw(state.shape[0], radius, segment)


@dataclass(frozen=True)
class PlantResponse:
    """What a plant did over one input series, one row per sample time.

    Attributes
    ----------
    plant : str
        ``"rates"``, ``"torques"`` or ``"mujoco"``.
    series : TimeSeries
        The true motion: ``state`` (u_a [m], v_a [m], psi, u_o, v_o [rad]), ``omega`` (of the shell, plane
        frame [rad/s]), ``rotor_rates`` (relative to the shell as realised [rad/s]), ``rotor_angles``
        (continuing from the run's start value [rad]) and ``rotor_momenta`` (the rotors' absolute axial
        momenta (P) [N m s]).
    measured : ndarray (N, 5)
        What the sensors report (``series.state`` plus measurement noise, if any).
    commanded : ndarray (N, 2)
        The input as commanded, before noise: rotor rates [rad/s] or torques [N m].
    commanded_momenta : ndarray (N, 2) or None
        Torque plant: the start value plus the integral of the commanded torque [N m s].
    """

    plant: str
    series: TimeSeries
    measured: np.ndarray
    commanded: np.ndarray
    commanded_momenta: np.ndarray | None = None


@lru_cache(maxsize=1)
def _momenta_function() -> ca.Function:
    x, w, pd, jr = ca.SX.sym("x", 5), ca.SX.sym("w", 3), ca.SX.sym("pd", 2), ca.SX.sym("jr")
    return ca.Function("p_of", [x, w, pd, jr], [model.rotor_axial_momenta(w, pd, x[3], x[4], x[2], jr)])


def rotor_momenta(robot: Robot, state, omega, rotor_rates) -> np.ndarray:
    """The rotors' axial momenta (P) along samples: ``(N, 2)`` [N m s]."""
    state, omega, rotor_rates = (np.atleast_2d(np.asarray(a, float)) for a in (state, omega, rotor_rates))
    f = _momenta_function().map(state.shape[0])
    return np.array(f(state.T, omega.T, rotor_rates.T, robot.rotor_inertia_axial)).T


def run_rates(robot: Robot, t, rates, x0=None, disturbances=(), segment: int = 0, phi0=(0.0, 0.0)) -> PlantResponse:
    """The rate-driven plant: :func:`simulate_rotors` from ``x0``, with the ``measurement`` and ``rate_noise``
    disturbances.

    Parameters
    ----------
    robot : Robot
        The real robot.
    t : (N,) sample times [s]; rates : (N, 2) commanded rotor rates [rad/s]
    x0 : (5,) start state [m, m, rad, rad, rad] (default zero), at rest
    disturbances : iterable of disturbances
    segment : int
        Index of this run in a sequence (decorrelates the noise draws).
    phi0 : (2,) rotor angles at ``t[0]`` [rad]
    """
    d = by_name(disturbances, "rates")
    t, rates = check_samples(t, rates)
    applied = rates + (d["rate_noise"].draw(t.size, segment) if "rate_noise" in d else 0.0)
    sim = simulate_rotors(robot, t, applied, x0=x0)
    angles = np.asarray(phi0, float) + CubicSpline(t, applied, axis=0).antiderivative()(t)
    m = sim.series
    p = rotor_momenta(robot, m.state, m.omega, applied)
    series = TimeSeries(t, m.state, omega=m.omega, rotor_rates=applied, rotor_angles=angles, rotor_momenta=p,
                        radius=robot.radius)
    return PlantResponse("rates", series, measure(m.state, d, robot.radius, segment), rates)


def _linear_input(t, y) -> ca.Function:
    """Linear interpolation through ``(t, y)`` (N, m), a step at a time given twice: ``f(t) -> (m,)``.

    The steps are taken out: ``f = g + J`` with ``g`` continuous (CasADi's linear interpolant through the
    distinct times) and ``J`` the sum of the steps at or before ``t``. The interpolant keeps its data: an
    evaluation costs a binary search, not a copy of every sample.
    """
    new = np.r_[True, np.diff(t) != 0]              # first row of each distinct time
    tk, left = t[new], y[new]
    right = y[np.r_[new[1:], True]]                 # last row of each distinct time: the value from there on
    right[-1] = left[-1]                            # the end: the value the last interval reaches
    jump = right - left
    jump[0] = 0.0                                   # no step at the start: the first interval's value holds
    steps = np.nonzero(np.abs(jump).max(axis=1) > 0)[0]
    cum = np.cumsum(jump, axis=0)
    tt = ca.MX.sym("t")
    expr = ca.interpolant("input", "linear", [tk], (right - cum).ravel(order="C"))(tt)
    if steps.size:
        # the number of steps at or before t, then the sum of those steps
        count = ca.low(ca.DM(np.r_[-np.inf, tk[steps], np.inf]), tt)
        sums = np.vstack([np.zeros(jump.shape[1]), cum[steps]])
        expr += ca.interpolant("steps", "linear", [np.arange(steps.size + 1.0)], sums.ravel(order="C"))(count)
    return ca.Function("input", [tt], [expr])


def input_function(t, y, breaks=(), interpolation: str = "spline") -> ca.Function:
    """``f(t) -> (m,)`` through the samples ``(t, y)``: splines split at the sample indices ``breaks``, or linear.

    ``"spline"``: a not-a-knot cubic spline per piece between breaks (fourth order where the input
    is smooth; a piece needs 4 samples); ``"linear"``: linear interpolation (second order, and no
    ringing at a step of the input). Outside ``[t[0], t[-1]]`` the end pieces extrapolate.
    """
    t, y = np.asarray(t, float), np.asarray(y, float)
    if interpolation == "linear":
        return _linear_input(t, y.reshape(t.size, -1))
    if interpolation != "spline":
        raise InputError(f"interpolation {interpolation!r} is not known: choose spline or linear")
    cuts = sorted({int(b) for b in breaks if 0 < int(b) < t.size - 1})
    edges = [0, *cuts, t.size - 1]
    if any(e1 - e0 < 3 for e0, e1 in zip(edges, edges[1:])):
        raise InputError("every piece of the input between breaks needs at least 4 samples")
    tt = ca.MX.sym("t")
    pieces = [rate_spline(t[e0:e1 + 1], y[e0:e1 + 1])(tt) for e0, e1 in zip(edges, edges[1:])]
    if len(pieces) == 1:
        return ca.Function("input", [tt], pieces)
    # the piece that starts at or before t (a break sample takes the next piece), and only that one evaluated
    index = ca.low(ca.DM(np.r_[-np.inf, t[cuts], np.inf]), tt)
    return ca.Function("input", [tt], [ca.conditional(index, pieces[:-1], pieces[-1], True)])


def run_torques(robot: Robot, t, torques, x0=None, p0=(0.0, 0.0), phi0=(0.0, 0.0), disturbances=(),
                segment: int = 0, breaks=(), interpolation: str = "spline", commanded_p0=None,
                servo_gain: float = 0.0, reference_rates=None, reltol: float = 1e-12,
                abstol: float = 1e-14) -> PlantResponse:
    """The torque-driven plant: integrate ``dp/dt = tau - c phi_dot``, (O) and Montana (6)-(10) (by CVODES for
    splines, by RK4 over each sample interval for linear inputs: module docstring).

    Parameters
    ----------
    robot : Robot
        The real robot (Jxx, Jzz, J_r, R).
    t : (N,) sample times [s]; torques : (N, 2) commanded motor torques [N m]
        With ``interpolation="linear"`` a time may be given twice: the torque steps there from the first
        row's value to the second's (the replay rule of plan files); the run's rows are the distinct times.
    x0 : (5,) start state (default zero)
    p0 : (2,) the rotors' axial momenta at ``t[0]`` [N m s] (zero at rest)
    phi0 : (2,) rotor angles at ``t[0]`` [rad]
    disturbances : ``friction``, ``torque_noise``, ``measurement``
    segment : int
        Index of this run in a sequence (decorrelates the noise draws).
    breaks, interpolation : how the torque samples are interpolated (:func:`input_function`)
    commanded_p0 : (2,), optional
        Start value of ``commanded_momenta`` (default ``p0``).
    servo_gain : float
        Gain K >= 0 [N m s/rad] of a proportional rotor-rate loop (a motor driver's velocity loop):
        with ``reference_rates`` (N, 2) the commanded torque is ``torques + K (reference - phi_dot)``.

    Returns
    -------
    PlantResponse
        ``commanded`` holds the commanded torques (with the servo's share).
    """
    d = by_name(disturbances, "torques")
    t_in, torques_in = np.asarray(t, float), np.asarray(torques, float)
    keep = np.ones(t_in.shape[0] if t_in.ndim == 1 else 0, bool)
    if keep.size > 1:   # times given twice (steps of the torques) only with linear interpolation
        keep[1:] = np.diff(t_in) != 0
    if not keep.all() and interpolation != "linear":
        raise InputError("times given twice (steps of the torques) need interpolation 'linear'")
    if torques_in.shape != (keep.size, 2):
        check_samples(t_in, torques_in)   # names what is wrong
    t, _ = check_samples(t_in[keep], torques_in[keep])
    if not np.all(np.isfinite(torques_in)):
        raise InputError("t and rates must be finite numbers")
    t_all, torques = t_in, torques_in
    x0 = np.zeros(5) if x0 is None else np.asarray(x0, float)
    c = np.array(d["friction"].c if "friction" in d else (0.0, 0.0))
    servo_gain = _nonnegative("servo_gain", servo_gain)
    if servo_gain > 0 and reference_rates is None:
        raise InputError("servo_gain > 0 needs reference_rates")
    z0 = np.concatenate([x0, p0, phi0, p0 if commanded_p0 is None else commanded_p0]).astype(float)
    params = np.r_[servo_gain, c, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, robot.radius]
    tau = input_function(t_all, torques, breaks, interpolation)   # the inputs as CasADi functions of time
    ref = input_function(t_all, reference_rates, breaks, interpolation) if servo_gain > 0 else None
    if interpolation == "linear":
        inputs = [torques, reference_rates if servo_gain > 0 else np.zeros_like(torques)]
        noise = d["torque_noise"].draw(t.size, segment) if "torque_noise" in d else np.zeros((t.size, 2))
        try:
            zs = _replay_linear(t_all, inputs, noise, z0, params)
        except _FarApart as exc:
            log.info("torque plant: %s; integrated by CVODES instead", exc)
            zs = _replay_cvodes(t, tau, ref, d, segment, z0, params, reltol, abstol)
    else:
        zs = _replay_cvodes(t, tau, ref, d, segment, z0, params, reltol, abstol)
    time, z = ca.MX.sym("t"), ca.MX.sym("z", 11)
    _, omega, phi_dot, cmd = _torque_dynamics()(z, tau(time), ca.DM.zeros(2) if ref is None else ref(time),
                                                ca.DM.zeros(2), servo_gain, c, ca.DM(params[3:]))
    om, pd, cm = (np.array(v).T for v in ca.Function("out", [time, z], [omega, phi_dot, cmd]).map(t.size)(t[None, :],
                                                                                                         zs.T))
    state = zs[:, 0:5]
    series = TimeSeries(t, state, omega=om, rotor_rates=pd, rotor_angles=zs[:, 7:9], rotor_momenta=zs[:, 5:7],
                        radius=robot.radius)
    return PlantResponse("torques", series, measure(state, d, robot.radius, segment), cm, zs[:, 9:11])


def _replay_cvodes(t, tau, ref, d, segment, z0, params, reltol, abstol) -> np.ndarray:
    """The torque plant's states at the distinct times ``t`` by CVODES, driven by the input functions ``tau`` and
    ``ref`` (None: no servo) of :func:`input_function`."""
    time, z = ca.MX.sym("t"), ca.MX.sym("z", 11)
    zero = ca.DM.zeros(2)
    servo_gain, c = params[0], params[1:3]
    noise = (input_function(t, d["torque_noise"].draw(t.size, segment), (), "linear")(time)
             if "torque_noise" in d else zero)
    ode = _torque_dynamics()(z, tau(time), zero if ref is None else ref(time), noise, servo_gain, c,
                             ca.DM(params[3:]))[0]
    opts = {"abstol": abstol, "reltol": reltol, "max_num_steps": 500000}
    integ = ca.integrator("torque_plant", "cvodes", {"t": time, "x": z, "ode": ode}, float(t[0]), list(t[1:]), opts)
    try:
        return np.hstack([z0[:, None], np.array(interrupts.call(integ, x0=z0)["xf"])]).T
    except RuntimeError as exc:
        raise SolverError(f"CVODES could not integrate the torque-driven motion: {str(exc).splitlines()[-1][:120]}",
                          "CVODES_failed") from None


class _FarApart(Exception):
    """RK4 did not reach :data:`RK_TOLERANCE` with :data:`RK_MAX_STEPS` steps per sample interval."""


def _replay_linear(t_all, inputs, noise, z0, params) -> np.ndarray:
    """The torque plant's states at the distinct times of ``t_all``, driven by ``inputs`` (torques and reference
    rates at ``t_all``, linear between rows, a step at a time given twice) and ``noise`` (at the distinct times):
    RK4 over every sample interval, the steps per interval doubled until its error estimates are within
    :data:`RK_TOLERANCE` (module docstring); :class:`_FarApart` if :data:`RK_MAX_STEPS` do not suffice."""
    new = np.r_[True, np.diff(t_all) != 0]
    last = np.r_[new[1:], True]
    tk = t_all[new]
    u0 = np.hstack([*(y[last][:-1] for y in inputs), noise[:-1]]).T     # the value from each distinct time on
    u1 = np.hstack([*(y[new][1:] for y in inputs), noise[1:]]).T       # the value each interval reaches
    h = np.diff(tk)[None, :]
    impulse = np.abs(inputs[0]).max(initial=0.0) * float(tk[-1] - tk[0]) + np.abs(z0[5:7]).max() + np.abs(z0[9:]).max()
    base = np.r_[[params[6]] * 2, [1.0] * 3, [impulse] * 2, [1.0] * 2, [impulse] * 2] + 1e-300
    n, z, m = h.size, z0, 1
    out = [z0[None, :]]
    for a in range(0, n, RK_CHUNK):
        b = min(n, a + RK_CHUNK)
        par = np.repeat(params[:, None], b - a, axis=1)
        # the doubling starts again from half the last chunk's steps: its result at those steps then has the
        # change from m / 2 to judge it by, as the first chunk's has (the embedded estimate alone over-estimates)
        m, previous = max(1, m // 2), None
        while True:
            zs, err = interrupts.call(_rk4_intervals(m, b - a), z, u0[:, a:b], u1[:, a:b], h[:, a:b], par)
            states = np.array(zs).T
            scale = np.maximum(base, np.abs(states).max(axis=0))
            estimate = float((np.array(err).sum(axis=1) / scale).max())
            if previous is not None:   # Richardson: the error of the m-step result is about 1/15 of the change
                estimate = min(estimate, float((np.abs(states - previous) / scale).max()))
            if estimate <= RK_TOLERANCE:
                break
            if m >= RK_MAX_STEPS:
                raise _FarApart(f"RK4 error estimate {estimate:.1e} > {RK_TOLERANCE:.0e} at {m} steps per sample "
                                f"interval (samples {a}-{b}): the samples are far apart for the motion")
            m, previous = 2 * m, states
        if not np.all(np.isfinite(states)):
            raise SolverError("the torque-driven motion overflows (RK4)", "RK4_failed")
        out.append(states)
        z = states[-1]
    return np.vstack(out)


#: Plants by name.
PLANTS = {"rates": run_rates, "torques": run_torques}
PLANT_NAMES = tuple(PLANTS)
