"""From path to motors: a plan timed by a law, the body's angular velocity, and the rotors' rates, angles and torques.

Time law
--------
A plan's contact path is run along its path parameter s (the contact arc length,
:mod:`rollplan.execution.path`) by a timing law of :mod:`rollplan.execution.timing`
(``min-jerk`` by default: every piece rest-to-rest in ``T / P`` with the
minimum-jerk profile, as the momentum integral (11) assumes no impulsive start;
``time-optimal`` and the non-stop laws within the robot's ``max_rotor_rate`` and
``max_rotor_torque``). The path is that of any plan from its start state: the ``2 n``
leaves of a pole-to-pole plan, or the pieces of a composed plan or a route
(approach and departure rolls, figure eights, circles of a turn in place, legs;
:func:`rollplan.planners.geometric.as_composed`). Every law rests at the start, at
the goal and at every corner of the contact path (where a roll meets a figure eight,
or the direction of the figure eights changes between legs or circles): there the
angular velocity per unit speed jumps, so passing at a speed would need an infinite
angular acceleration. The empty motion (start = goal) stays at rest for ``T``.

Angular velocity and rotor rates
--------------------------------
Along the path, omega and the rotor rates are ``s'`` times functions of s alone
(:class:`~rollplan.execution.path.ContactPath`): the rolling components of omega are
(18)-(19) with the contact rates of the curve (24)-(27), the spin is fixed by the
realizability condition (13) (:func:`rollplan.core.model.curve_omega`), and the rotor
rates follow from the momentum integral (11) (:func:`rollplan.core.model.rotor_rates`).
The state (u_a, v_a, psi) and the rotor angles ``phi_i = int G_i ds`` are integrated
along the path by CVODES with the curve ODE (28)-(30): they do not depend on the timing.

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
momentum. The reaction ``-tau_i n_i`` acts on the shell. Along the path,
``n_i . omega + phi_i_dot = s' a_i(s)`` with ``a_i = n_i . W + G_i`` (per unit s'), so

    tau_i = A_i(s) s'' + B_i(s) s'^2,     A_i = J_r a_i,   B_i = J_r da_i/ds,

with ``da_i/ds`` the total derivative along the path (psi' from (30)). The derivatives
are taken by CasADi's automatic differentiation of the model; no equation is typed
twice. ``J_r`` is the axial inertia that multiplies ``phi_i_dot`` in (11) (if an axis
carries two rotors in tandem, tau_i is the sum of their motor torques).
``tests/test_actuation.py`` checks (T) against finite differences of the full
vector ``H_i`` projected on ``n_i``, which does not use the simplification above.

Samples and how to replay them
------------------------------
An :class:`Actuation` is sampled uniformly in time, at least the law's
``samples_per_piece`` per piece on average (so that a cubic spline through the rotor rates
drives the rotor-only simulation onto the target; see
:mod:`rollplan.execution.timing`). The rotor rates and angles are continuous in
time. The torques are piecewise continuous: for the non-stop laws they step at
every smooth joint passed at a speed (the poles of a figure eight) by
``(B(S_j^+) - B(S_j^-)) s'^2`` (the curvature of the contact path jumps there),
and the time-optimal torques are bang-bang with steps at the switches and
piecewise-constant s''. A sample at a joint holds the value of the piece that
ends there. A plant driven by the torques should interpolate them
linearly between samples (not by a spline, which rings at the steps); integrated so
(trapezoid rule), they reproduce the change of the axial momenta
``J_r (n_i . omega + phi_i_dot)`` between samples to O(h^2) where the torque is
smooth and O(h x step) across a step, so a torque-driven replay should re-anchor on
the sampled rates (the momentum integral (11)) rather than integrate torques over a
whole run.

Units: time [s], angles [rad], rates [rad/s], torques [N m], lengths in the
robot's unit [m].
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError, NoPlanError, check_range, check_whole
from ..problem import State
from ..result import DEFAULT_SAMPLES, certify
from ..robot import Robot
from ..timeseries import TimeSeries
from .limits import Limits
from .path import ContactPath, plan_pieces
from .plants import RotorSimulation, simulate_rotors
from .timing import TimeLaw, TimeProfile, get_law, joint_times, resting_sides

__all__ = ["Actuation", "actuate", "sample_motion", "samples_per_piece", "certify_motion", "torque_breaks",
           "motion_samples", "TORQUE_STEP", "DEFAULT_SAMPLES",
           "MIN_SAMPLES_PER_LEAF", "MAX_SAMPLES", "MOTION_TOLERANCE"]

log = logging.getLogger(__name__)

#: Least number of samples per leaf of the min-jerk law: a cubic spline through the rotor rates then drives
#: the rotor-only simulation to the target within ~1e-8 R (the error falls as h^4; see the tests).
MIN_SAMPLES_PER_LEAF = get_law("min-jerk").samples_per_piece
#: Largest number of samples of a motion.
MAX_SAMPLES = 1_000_000
#: Largest arrival error (units of R and rad) of the rotor-only simulation of a motion (its certificate).
MOTION_TOLERANCE = 1e-6


@dataclass(frozen=True)
class Actuation:
    """A plan's path timed by a law: what the two rotors must do, as a :class:`~rollplan.timeseries.TimeSeries`.

    Attributes
    ----------
    series : TimeSeries
        ``N`` samples uniform in time from 0 to ``duration`` [s]: ``state`` (u_a [m], v_a [m], psi, u_o,
        v_o [rad]), ``segment`` (the piece of the contact path: a leaf, a half-step, of a figure eight; a
        roll; a circle of a turn; numbered as in the plan's ``pieces``), ``omega`` (as in (6)-(11)),
        ``rotor_rates`` (11), ``rotor_angles`` (zero at t = 0) and ``rotor_torques`` ((T) of the module
        docstring); lengths in the robot's unit [m].
    s, s_dot, s_ddot : ndarray, shape (N,)
        Path parameter (contact arc length) [R] and its time derivatives [R/s, R/s^2] at the samples.
    robot : Robot
        With its limits (``Limits.of(robot)``).
    duration : float
        Total time T [s].
    goal : State
        The plan's goal [m, rad].
    timing : str
        Name of the timing law.
    minimum_duration : float or None
        The law's shortest duration within the robot's limits [s]; None without limits (and for the
        empty motion).
    profile : TimeProfile
        ``s(t)`` of the law.
    path : ContactPath or None
        The plan's path with the robot's rotor coefficients (None for the empty motion).
    """

    series: TimeSeries
    s: np.ndarray
    s_dot: np.ndarray
    s_ddot: np.ndarray
    robot: Robot
    duration: float
    goal: State
    timing: str
    minimum_duration: float | None
    profile: TimeProfile
    path: ContactPath | None

    @property
    def limits(self) -> Limits:
        return Limits.of(self.robot)

    @property
    def rest_indices(self) -> np.ndarray:
        """Indices of the samples at rest (``s' = 0``): t = 0, t = T, and every stop on the way."""
        return np.nonzero(self.s_dot <= 1e-12 * max(float(self.s_dot.max()), 1e-300))[0]


def samples_per_piece(pieces: int, samples: int, per_piece: int, law: str = "") -> int:
    """Samples per piece of a motion of ``pieces`` pieces: at least ``per_piece``, in all at least ``samples``.

    InputError when ``samples`` is not a whole number >= 4 or the motion would need more than
    :data:`MAX_SAMPLES` samples.
    """
    samples = check_whole("samples", samples, 4)
    m = max(per_piece, math.ceil((samples - 1) / pieces))
    if pieces * m + 1 > MAX_SAMPLES:
        raise InputError(f"timing '{law}' of {pieces} pieces (half-steps, rolls) needs {pieces * m + 1} samples (at "
                         f"least {m} per piece); at most {MAX_SAMPLES} are allowed: plan fewer steps or ask fewer "
                         "samples")
    return m


def sample_motion(path: ContactPath, profile: TimeProfile, samples: int, goal=None,
                  per_piece: int = MIN_SAMPLES_PER_LEAF) -> Actuation:
    """Sample a timed path uniformly in time: state, omega, rotor rates, angles and torques.

    Parameters
    ----------
    path : ContactPath
    profile : TimeProfile
        A law's ``s(t)`` on this path.
    samples : int
        Least total number of samples (>= 4), rounded up to ``P m + 1`` with
        ``m >= per_piece`` samples per piece, at most :data:`MAX_SAMPLES`.
    goal : State, optional
        The plan's goal [m, rad] (default: the path's end state).
    per_piece : int
        Least number of samples per piece (the law's ``samples_per_piece``).

    Returns
    -------
    Actuation
    """
    pieces = len(path.pieces)
    m = samples_per_piece(pieces, samples, per_piece, profile.law)
    total = pieces * m + 1
    T = profile.duration
    t = np.linspace(0.0, T, total)
    b = profile.breaks
    near = np.clip(np.searchsorted(b, t), 1, b.size - 1)
    for cand in (near - 1, near):   # samples on a break (the stops of min-jerk) exactly there
        t = np.where(np.abs(t - b[cand]) <= 1e-12 * T, b[cand], t)
    s, sd, sdd = profile.evaluate(t)
    s[0], s[-1] = 0.0, path.length
    sd[0] = sd[-1] = 0.0
    ps = path.evaluate(np.clip(s, 0.0, path.length), "left")
    flip = resting_sides(path, ps.s, sdd)
    if flip.any():   # at rest on a corner, leaving it: the piece after's coefficients (s'' is that piece's)
        after = path.evaluate(ps.s[flip], "right")
        for name in ("W", "G", "A", "B"):
            getattr(ps, name)[flip] = getattr(after, name)
    R = path.robot.radius
    state = ps.state * np.array([R, R, 1.0, 1.0, 1.0])
    rates = ps.G * sd[:, None]
    torques = ps.A * sdd[:, None] + ps.B * sd[:, None] ** 2
    if not (np.all(np.isfinite(rates)) and np.all(np.isfinite(torques))):
        raise InputError(f"duration = {T!r} s is not allowed: the rotor rates or torques overflow")
    if goal is None:
        fin = path.final_state
        goal = State(fin[0] * R, fin[1] * R, fin[2])
    log.info("motion (%s): %d pieces x %d samples, T = %g s, max |rotor rate| = %.3g rad/s, "
             "max |torque| = %.3g N m", profile.law, pieces, m, T, np.abs(rates).max(), np.abs(torques).max())
    series = TimeSeries(t, state, ps.segment, omega=ps.W * sd[:, None], rotor_rates=rates,
                        rotor_angles=ps.rotor_angles, rotor_torques=torques, radius=R)
    return Actuation(series, s, sd, sdd, path.robot, T, goal, profile.law, profile.minimum_duration, profile, path)


#: Smallest step of the torques listed as a break, relative to the motion's largest torque.
TORQUE_STEP = 1e-9


def torque_breaks(motion: Actuation) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Where a motion's torques step: ``(times, left, right)``, the times in (0, T) and the one-sided torques.

    Candidates are the law's breaks (where s'' may jump: the switches of the time-optimal law, the ends of
    the non-stop laws' stretches) and the passages of the path's joints (where ``B`` jumps); listed are
    those where the torque steps by more than :data:`TORQUE_STEP` times the motion's largest torque. The
    left value is the limit from earlier times (the law's piece that ends there, the path's piece that
    ends there), the right value the limit from later times.
    """
    empty = np.zeros(0), np.zeros((0, 2)), np.zeros((0, 2))
    if motion.path is None:
        return empty
    prof, path, T = motion.profile, motion.path, motion.duration
    cand = np.concatenate([prof.breaks[1:-1], joint_times(path, prof)])
    cand = np.unique(cand[(cand > 1e-12 * T) & (cand < T * (1 - 1e-12))])
    if cand.size == 0:
        return empty
    b = prof.breaks
    values = []
    for side in ("left", "right"):
        piece = np.clip(np.searchsorted(b, cand, side=side) - 1, 0, b.size - 2)
        sv, sd, sdd = prof.evaluate(cand, piece)
        ps = path.evaluate(np.clip(sv, 0.0, path.length), side)
        values.append(ps.A * sdd[:, None] + ps.B * sd[:, None] ** 2)
    left, right = values
    scale = max(float(np.abs(motion.series.rotor_torques).max()), 1e-300)
    jump = np.abs(right - left).max(axis=1) > TORQUE_STEP * scale
    return cand[jump], left[jump], right[jump]


def motion_samples(motion: Actuation) -> TimeSeries:
    """The motion's samples with every step of the torques as a time given twice (:func:`torque_breaks`).

    A :class:`~rollplan.timeseries.TimeSeries` like ``motion.series`` with the rows of the breaks inserted:
    at a break the first row holds the torque's limit from the left and the piece that ends there, the
    second the limit from the right and the piece that starts there; the other quantities are continuous
    (both rows agree). A uniform sample on a break is replaced by the two rows. Replayed linearly between
    rows of different times, with the step at a time given twice, the torques are the law's
    piecewise-smooth profile to second order. The times given twice are the breaks (``repeated_times()``).
    """
    tb, left, right = torque_breaks(motion)
    m = motion.series
    if tb.size == 0:
        return m
    keys = ("omega", "rotor_rates", "rotor_angles", "rotor_torques", "state", "segment")
    T, path, prof = motion.duration, motion.path, motion.profile
    t = m.time
    on = np.zeros(t.size, bool)
    near = np.clip(np.searchsorted(tb, t), 0, tb.size - 1)
    for cand in (near, np.clip(near - 1, 0, None)):
        on |= np.abs(t - tb[cand]) <= 1e-12 * T
    s, sd, _ = prof.evaluate(tb)
    R = path.robot.radius
    rows = {}
    ps = path.evaluate(np.clip(s, 0.0, path.length), "left")   # the continuous quantities: one value for both rows
    for side, tq in (("left", left), ("right", right)):
        rows[side] = {"omega": ps.W * sd[:, None], "rotor_rates": ps.G * sd[:, None], "rotor_angles": ps.rotor_angles,
                      "rotor_torques": tq, "state": ps.state * np.array([R, R, 1.0, 1.0, 1.0]),
                      "segment": path.segment_of(ps.s, side)}
    time = np.concatenate([t[~on], tb, tb])
    order = np.lexsort((np.r_[np.zeros((~on).sum()), np.zeros(tb.size), np.ones(tb.size)], time))
    out = {key: np.concatenate([getattr(m, key)[~on], rows["left"][key], rows["right"][key]])[order] for key in keys}
    return TimeSeries(time[order], radius=m.radius, **out)


def actuate(plan, robot: Robot, duration: float | None = None, samples: int = DEFAULT_SAMPLES,
            timing: str | TimeLaw = "min-jerk") -> Actuation:
    """Time a plan by a law within the robot's limits and compute omega, rotor rates, angles and torques.

    The plan's path from its start state along its contact arc length
    (:meth:`ContactPath.of_plan`) is run by the law ``timing`` (:mod:`rollplan.execution.timing`);
    then omega from (18), (19), (13), the rotor rates from (11), the rotor angles by integration
    along the path, and the torques from (T) of the module docstring.

    Parameters
    ----------
    plan : Plan, ComposedPlan or Route
        A geometric-phase plan (:mod:`rollplan.planners.geometric`), made for this robot (same k and
        radius): pole to pole, between any two states, or a route.
    robot : Robot
        The robot's parameters and its optional ``max_rotor_rate``, ``max_rotor_torque``.
    duration : float, optional
        Total time T [s] in :data:`rollplan.execution.timing.DURATION_RANGE`; None: the law's
        shortest duration within the robot's limits (which must be set).
    samples : int
        Least number of time samples (>= 4); see :func:`sample_motion`.
    timing : str or TimeLaw
        A name in :data:`rollplan.execution.timing.LAWS` (default ``"min-jerk"``: every piece in
        ``T / P``, rest-to-rest).

    Returns
    -------
    Actuation
        Starting at the plan's start state. The empty motion (start = goal) is ``samples`` samples
        at rest over the given duration.

    Raises
    ------
    InputError
        Bad input, or a duration that would exceed a limit (the message names the limit and the
        shortest feasible duration); no duration for the empty motion.
    """
    law = get_law(timing)
    pieces, start = plan_pieces(plan, robot)
    if not pieces:
        return _at_rest(plan, robot, law, duration, samples)
    samples_per_piece(len(pieces), samples, law.samples_per_piece, law.name)  # the sample count before the work
    path = ContactPath(pieces, robot, start)
    profile = law.profile(path, Limits.of(robot), duration)
    return sample_motion(path, profile, samples, plan.goal, law.samples_per_piece)


def _at_rest(plan, robot: Robot, law: TimeLaw, duration, samples: int) -> Actuation:
    """The empty motion: ``samples`` samples at the start state over ``duration``, every rate zero."""
    duration = law.check(Limits.of(robot), duration)
    if duration is None:
        raise InputError("the plan is the empty motion (its start is its goal): it has no shortest duration; "
                         "give a duration to stay at rest that long")
    samples = check_whole("samples", samples, 4, MAX_SAMPLES)
    zero = lambda m: np.zeros((samples, m)) if m else np.zeros(samples)  # noqa: E731
    state = np.repeat(plan.problem.start.array()[None, :], samples, axis=0)
    profile = TimeProfile(np.array([0.0, duration]), np.zeros((1, 1)), law.name, 0.0)
    series = TimeSeries(np.linspace(0.0, duration, samples), state, np.zeros(samples, int), omega=zero(3),
                        rotor_rates=zero(2), rotor_angles=zero(2), rotor_torques=zero(2), radius=robot.radius)
    return Actuation(series, zero(0), zero(0), zero(0), robot, duration, plan.goal, law.name, None, profile, None)


def certify_motion(motion: Actuation, tol: float = MOTION_TOLERANCE) -> RotorSimulation:
    """A motion's certificate: drive the robot by its sampled rotor rates alone, from the motion's start
    state, and compare with the goal.

    Runs :func:`~rollplan.execution.plants.simulate_rotors` (the momentum integral
    (11) and (6)-(10) by CVODES, nothing of the planner or of the timing law);
    returns the simulation if its arrival error is at most ``tol``, else raises
    NoPlanError: a motion that its own rotors do not carry to the goal is never
    reported as a success.
    """
    tol = check_range("tol", tol, 0.0, None, low_open=True)
    m = motion.series
    sim = simulate_rotors(motion.robot, m.time, m.rotor_rates, motion.goal, x0=m.state[0])
    if not certify(None, sim.final, "cvodes", residual=sim.arrival_error, tolerance=tol).passed:
        raise NoPlanError(f"the motion over T = {motion.duration!r} s misses the goal when driven by its rotor rates "
                          f"alone: arrival error {sim.arrival_error:.2e} > {tol:.0e}; try more samples or another "
                          "duration")
    return sim
