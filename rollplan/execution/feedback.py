"""Closed-loop execution: measure after every figure eight, re-estimate the robot, re-plan the rest, correct.

A plan of n figure eights from a start state to a goal (any two full states, issue 12's
composed planner) is executed on a real robot that is not exactly the model.

Open loop (``closed_loop=False``)
    The whole plan, timed for the model robot, is applied at once; nothing is measured.

Closed loop (``closed_loop=True``)
    The motion is applied one figure eight at a time. Before figure eight j > 0 (0-based):

    1. measure the full state ``(u_a, v_a, psi, u_o, v_o)`` at rest, at the end of the previous
       figure eight (with measurement noise, optionally averaged over ``rest_readings`` readings);
    2. update the estimate of the robot from everything observed so far
       (:class:`~rollplan.execution.estimate.RatioEstimator`, Jxx/J_r and Jzz/J_r, on the rate
       plant; :class:`~rollplan.execution.estimate.InertiaEstimator`, Jxx, Jzz, J_r and the
       bearing friction, on the torque plant) and build the estimated robot
       (:func:`robot_from_inertias`); an unphysical estimate is refused and the previous robot kept;
    3. plan the rest, ``n - j`` figure eights, from the measured state to the goal with the
       estimated robot (:func:`rollplan.planners.geometric.plan`: the contact point is a little off
       the pole after a figure eight on a mismatched robot, so the plan starts with an approach roll
       whose own motion the figure eights compensate), time it with the min-jerk law (every piece
       rest to rest, ``piece_duration`` each) on the estimated robot, and apply the approach and
       the first figure eight (all of it, departure included, when it is the last).

    The controller commands what the plant takes: the rotor rates of the timed re-plan (rate
    plant), or its torques plus the feed-forward ``c_hat phi_dot`` of the estimated friction
    (torque plant; only a friction the data establish,
    :func:`~rollplan.execution.estimate.established_friction`: one within the measurement noise,
    fed forward, would leave the rotors spinning after every motion). Why figure eights: their
    ends are rest points near the pole, where a measurement is clean and the remainder is again a
    whole number of figure eights.

    After the last figure eight, correcting motions follow: from the measured state (step 1), a
    composed plan of one figure eight to the goal with the estimated robot (step 2), applied whole,
    while the measured arrival error exceeds ``tolerance``, at most ``corrections`` of them; so
    n = 1 gets feedback too. :func:`execute_samples` runs the same loop from a motion given as
    samples (a plan file's: its own rates or torques first, then re-plans and corrections timed by
    the file's law); plans that are not figure eights (turns, routes) run whole, then the corrections.
    A plan of another leaf family than the circles (``Plan.curve``; any family runs on every plant)
    also runs whole, then the corrections: the planner plans such a family from rest at the origin
    only, and a re-plan from a measured state would not be of that family.

The estimated robot reproduces the real one exactly where the plant can tell: the rate-driven
motion depends only on ``Jxx/J_r`` and ``Jzz/J_r`` (divide (11) by J_r), so with rates the estimate
keeps the model's J_r and scales Jxx, Jzz.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..core.spline import CubicSpline
from ..errors import InputError, NoPlanError, check_finite, check_whole
from ..problem import STATE_NAMES, Problem, State, arrival_error
from ..robot import Robot
from ..timeseries import Arrival, TimeSeries
from .actuation import actuate, motion_samples
from .estimate import InertiaEstimator, RatioEstimator, established_friction
from .limits import Limits
from .plants import PLANT_NAMES, by_name, measure, run_rates, run_torques
from .timing import get_law

__all__ = ["joints", "robot_from_inertias", "ExecutionResult", "execute", "execute_samples", "Samples",
           "DEFAULT_SAMPLES_PER_PIECE", "DEFAULT_WINDOW", "DEFAULT_TOLERANCE", "DEFAULT_CORRECTIONS"]

#: Time samples per piece (leaf, roll) of the commanded series.
DEFAULT_SAMPLES_PER_PIECE = 400
#: Estimator window in sample intervals (8 windows per piece at the default sampling).
DEFAULT_WINDOW = 50


def robot_from_inertias(radius: float, j_xx: float, j_zz: float, j_r: float, like: Robot | None = None) -> Robot:
    """A :class:`~rollplan.robot.Robot` with the given Jxx, Jzz, J_r: all that (11), (13), (14) and (T) use.

    ``M = (Jxx - Jzz) / R^2``; the split of ``Jzz - J_r = 2/3 m_o R^2 + 2 J_p`` (14) between shell
    and transverse rotor inertia enters no equation: J_p is taken from ``like`` when that gives a
    possible robot (one that :class:`~rollplan.robot.Robot`'s own checks accept: ``m_o <= M``, ``J_r <=
    2 J_p``, ``J_r + 2 J_p <= 2 (M - m_o) R^2``), otherwise the rotors are thin disks (``2 J_p = J_r``,
    the least J_p allowed) and the shell takes the rest. Inertias that no possible robot has (``Jzz < 2 J_r``, or
    too little mass left for the rotors) are refused. The limits of ``like`` are kept.
    """
    if not (j_xx > j_zz > j_r > 0):
        raise InputError(f"inertias Jxx = {j_xx!r}, Jzz = {j_zz!r}, J_r = {j_r!r} are not allowed: "
                         "they must satisfy Jxx > Jzz > J_r > 0")
    if j_zz < 2.0 * j_r:
        raise InputError(f"inertias Jzz = {j_zz!r}, J_r = {j_r!r} are not those of a possible robot: Jzz >= 2 J_r "
                         "(a rotor, a body of revolution, has J_r <= 2 J_p)")
    r2 = radius * radius
    mass = (j_xx - j_zz) / r2
    limits = {} if like is None else {"max_rotor_rate": like.max_rotor_rate, "max_rotor_torque": like.max_rotor_torque}
    refusal = None
    for jp in ([like.rotor_inertia_transverse] if like is not None else []) + [0.5 * j_r]:
        try:   # the robot's own checks decide what is possible
            return Robot(radius=radius, mass_total=mass, mass_shell=1.5 * (j_zz - 2 * jp - j_r) / r2,
                         rotor_inertia_axial=j_r, rotor_inertia_transverse=jp, **limits)
        except InputError as exc:
            refusal = exc
    raise InputError(f"inertias Jxx = {j_xx!r}, Jzz = {j_zz!r}, J_r = {j_r!r} are not those of a possible robot: "
                     f"{refusal}")


@dataclass(frozen=True)
class ExecutionResult(Arrival):
    """A plan executed on a (real) robot, open or closed loop.

    Attributes
    ----------
    plant : str
        ``"rates"``, ``"torques"`` or ``"mujoco"``.
    closed_loop : bool
    goal : State
        [m, rad]; with it ``final``, ``error`` (:func:`rollplan.problem.arrival_error` of ``final`` to
        ``goal``), ``arrival_error`` and ``position_error`` [R and rad; R] (:class:`~rollplan.timeseries.Arrival`).
    series : TimeSeries
        One row per sample, the segments concatenated (a shared boundary sample once): the true ``state``
        (u_a, v_a, psi, u_o, v_o) [m, m, rad, rad, rad]; ``rotor_rates`` relative to the shell as applied
        [rad/s] (rate plant: the commands plus any rate noise); ``rotor_torques``, on the torque plant the
        torques commanded (with the friction feed-forward), on the rate plant the rate of change of the
        rotors' axial momenta (P), i.e. the torques the motors delivered [N m]; ``segment``, the index into
        ``segments`` of each sample.
    measured : (N, 5)
        What the sensors reported.
    segments : list of dict
        One per applied piece of motion: start and end time, the figure eights left, the plan's mode.
    estimates : list of dict
        The robot used for each figure eight (the model robot before any data): k, Jxx/J_r, Jzz/J_r,
        Jxx, Jzz, J_r (and on the torque plant ``friction``, the friction fed forward, and
        ``friction_estimated``, the least-squares value); ``rejected`` when an estimate was refused.
    stopped : str or None
        Closed loop: why the corrections ended before the tolerance was met (no correcting motion from
        the measured state, or the budget spent); None when they met it or none was asked.
    """

    plant: str
    closed_loop: bool
    goal: State
    series: TimeSeries
    measured: np.ndarray
    segments: list = field(default_factory=list)
    estimates: list = field(default_factory=list)
    stopped: str | None = None

    def to_dict(self) -> dict:
        """The keys of ``rollplan simulate --closed-loop --json``."""
        rows = lambda a: np.asarray(a, float).tolist()  # noqa: E731  (Python floats, row by row)
        m = self.series
        return {"plant": self.plant, "closed_loop": self.closed_loop, "goal": self.goal.as_dict(),
                "time": rows(m.time), "rotor_rates": rows(m.rotor_rates),
                "rotor_torques": rows(m.rotor_torques), "state": rows(m.state),
                "segment": np.asarray(m.segment).astype(int).tolist(), "final": self.final.as_dict(),
                "error": dict(zip(STATE_NAMES, map(float, self.error))), "arrival_error": self.arrival_error,
                "position_error": self.position_error, "estimates": self.estimates, "segments": self.segments,
                "stopped": self.stopped}


def _estimate_dict(robot: Robot, friction=None, estimated=None) -> dict:
    jr = robot.rotor_inertia_axial
    d = {"k": robot.k, "alpha": robot.j_xx / jr, "beta": robot.j_zz / jr, "j_xx": robot.j_xx, "j_zz": robot.j_zz,
         "j_r": jr}
    if friction is not None:
        d["friction"] = [float(c) for c in friction]
    if estimated is not None:
        d["friction_estimated"] = [float(c) for c in estimated]
    return d


class _Controller:
    """Runs the plant piece after piece, keeping the true state, the records and the estimators."""

    def __init__(self, real: Robot, plant: str, disturbances, closed_loop: bool, window: int, estimate_friction: bool,
                 x0, servo_gain: float = 0.0, session=None):
        self.servo_gain = servo_gain
        self.session = session     # the MuJoCo plant (rollplan.execution.mujoco_engine.Session)
        self.real, self.plant, self.dist, self.closed_loop = real, plant, tuple(disturbances), closed_loop
        self.by_name = by_name(self.dist, plant)
        self.x = np.asarray(x0, float)
        self.p = np.zeros(2)       # true rotor momenta
        self.P = np.zeros(2)       # integral of the commanded torques since rest
        self.phi = np.zeros(2)     # rotor angles since rest
        self.t0 = 0.0
        self.parts, self.segments = [], []
        self.friction_hat = np.zeros(2)
        self.friction_estimate = None   # the least-squares friction, before established_friction
        self.ratios = RatioEstimator(real.radius, window)
        self.inertias = InertiaEstimator(real.radius, window, friction=estimate_friction)

    def apply(self, motion, end: int, info: dict):
        """Apply samples ``0..end`` of a timed motion (:class:`Samples`); returns the plant's response."""
        sl = slice(0, end + 1)
        t_all = motion.time[sl] - motion.time[0] + self.t0
        rates_all, n = motion.rotor_rates[sl], len(self.segments)
        keep = np.ones(t_all.size, bool)
        keep[1:] = np.diff(t_all) > 0
        t, rates = t_all[keep], rates_all[keep]
        linear = getattr(motion, "interpolation", "spline") == "linear"
        breaks = [int(i) for i in joints(motion) if 0 < i < end]
        if self.plant == "rates":
            run = run_rates(self.real, t, rates, self.x, self.dist, n, self.phi)
            torques = _piecewise_derivative(t, run.series.rotor_momenta, [] if linear else breaks)
        else:
            torques = motion.rotor_torques[sl] + self.friction_hat * rates_all
            runner = run_torques if self.session is None else self.session.run
            run = runner(self.real, t_all, torques, self.x, self.p, self.phi, self.dist, n,
                         () if linear else breaks, "linear" if linear else "spline", commanded_p0=self.P,
                         servo_gain=self.servo_gain, reference_rates=rates_all if self.servo_gain > 0 else None)
            self.P = run.commanded_momenta[-1]
            torques = run.commanded
        r = run.series
        keep = slice(1, None) if self.parts else slice(None)
        self.parts.append((t[keep], r.state[keep], run.measured[keep], r.rotor_rates[keep], torques[keep],
                           np.full(t[keep].size, n)))
        self.segments.append({"t0": float(t[0]), "t1": float(t[-1]), **info})
        self.measured = run.measured[-1].copy()
        self.x, self.p, self.phi, self.t0 = r.state[-1].copy(), r.rotor_momenta[-1], r.rotor_angles[-1], float(t[-1])
        if self.closed_loop:
            if self.plant == "rates":
                self.ratios.add(r.time, run.measured, run.commanded)
            else:
                self.inertias.add(r.time, run.measured, run.commanded_momenta, r.rotor_angles)
        return run

    def estimate(self, model_robot: Robot) -> tuple[Robot, np.ndarray | None]:
        R = self.real.radius
        if self.plant == "rates":
            e = self.ratios.estimate()
            jr = model_robot.rotor_inertia_axial
            return robot_from_inertias(R, e.alpha * jr, e.beta * jr, jr, like=model_robot), None
        e = self.inertias.estimate()
        self.friction_estimate = np.array(e.friction)
        return robot_from_inertias(R, e.j_xx, e.j_zz, e.j_r, like=model_robot), np.array(established_friction(e))

    def arrays(self):
        return [np.concatenate(c) for c in zip(*self.parts)]


def _piecewise_derivative(t, y, breaks) -> np.ndarray:
    """d/dt of samples by not-a-knot cubic splines, one per piece between the sample indices ``breaks``
    (the joints, where the rate plant's momenta have a kink); a joint sample takes the piece that ends there."""
    out = np.empty_like(y)
    edges = [0, *breaks, t.size - 1]
    for a, b in reversed(list(zip(edges[:-1], edges[1:]))):
        out[a:b + 1] = CubicSpline(t[a:b + 1], y[a:b + 1], axis=0)(t[a:b + 1], 1)
    return out


@dataclass(frozen=True)
class Samples:
    """A timed motion as samples, as a plan file holds it (what :func:`execute_samples` applies first).

    Attributes
    ----------
    time : (N,) [s], nondecreasing; a time given twice is a step of the torques
    rotor_rates, rotor_torques : (N, 2) [rad/s, N m]
    segment : (N,) int
        Piece of each sample (a sample at a joint belongs to the piece that ends there).
    kinds : tuple of str
        The kind of every piece (``approach``, ``leaf``, ``departure``, ``circle``, ...), in order.
    interpolation : str
        How the torques are replayed between samples: ``"linear"`` (plan files: linear between samples,
        a step at a time given twice) or ``"spline"`` (split at the joints).
    """

    time: np.ndarray
    rotor_rates: np.ndarray
    rotor_torques: np.ndarray
    segment: np.ndarray
    kinds: tuple
    interpolation: str = "linear"


def joints(motion) -> np.ndarray:
    """Sample indices of the joints between the pieces of a timed motion (a :class:`~rollplan.timeseries.TimeSeries`
    or :class:`Samples`: where its ``segment`` changes).

    A sample at a joint belongs to the piece that ends there; with the min-jerk law these are rest
    points, and the breaks at which torque samples must be split (:func:`~.plants.input_function`).
    """
    return np.nonzero(np.diff(motion.segment) != 0)[0]


def _first_eight_end(motion, kinds) -> int | None:
    """Sample index where the first figure eight of a timed plan ends, if the motion rests there and more
    follows; None otherwise (the motion is then applied whole)."""
    ends = joints(motion)
    if len(ends) != len(kinds) - 1 or any(k not in ("approach", "leaf", "departure") for k in kinds):
        return None
    leaves = np.cumsum([k == "leaf" for k in kinds])
    second = np.nonzero(leaves == 2)[0]
    if second.size == 0 or second[0] >= len(ends):
        return None
    i = int(ends[second[0]])
    scale = max(float(np.abs(motion.rotor_rates).max()), 1e-300)
    if kinds[second[0] + 1:].count("leaf") == 0 or np.abs(motion.rotor_rates[i]).max() > 1e-12 * scale:
        return None
    return i


def _pieces(plan):
    return plan.pieces


#: Closed loop: arrival error [R and rad] of the measured state below which no correction follows.
DEFAULT_TOLERANCE = 1e-6
#: Closed loop: most correcting motions after the plan.
DEFAULT_CORRECTIONS = 3


def execute(plan, model_robot: Robot, real_robot: Robot, piece_duration: float, *, plant: str = "rates",
            closed_loop: bool = True, disturbances=(), samples_per_piece: int = DEFAULT_SAMPLES_PER_PIECE,
            window: int = DEFAULT_WINDOW, estimate_friction: bool = True, rest_readings: int = 0,
            servo_gain: float = 0.0, mujoco_model=None, progress=None, timing: str = "min-jerk",
            tolerance: float = DEFAULT_TOLERANCE, corrections: int = DEFAULT_CORRECTIONS) -> ExecutionResult:
    """Execute a geometric-phase plan on ``real_robot``, open or closed loop (module docstring).

    Parameters
    ----------
    plan : Plan or ComposedPlan
        Made for ``model_robot`` (:func:`rollplan.plan` with ``robot=model_robot``): its start, goal
        and number of figure eights are what is executed.
    model_robot : Robot
        What the controller believes before any measurement.
    real_robot : Robot
        The simulated real robot (same radius: it is measured).
    piece_duration : float
        Duration of every piece (leaf, roll) [s]; each is timed by ``timing`` (min-jerk: rest to rest).
    plant : str
        ``"rates"`` or ``"torques"`` (:data:`rollplan.execution.plants.PLANTS`), or ``"mujoco"``: the
        torques applied to MuJoCo's model of the real robot (:mod:`rollplan.execution.mujoco_engine`,
        ``mujoco_model`` or the model of ``real_robot``), the state measured from its pose.
    closed_loop : bool
    disturbances : iterable
        Disturbances of :mod:`rollplan.execution.plants`, with their seeds.
    samples_per_piece : int
        Time samples per piece of the commanded series (>= 50).
    window : int
        Estimator window in sample intervals.
    estimate_friction : bool
        Torque plant: also estimate the bearing friction and feed forward what the data establish
        (:func:`~rollplan.execution.estimate.established_friction`).
    rest_readings : int
        Closed loop: the state used for a re-plan is the mean of this many sensor readings at the
        rest point (0: the last sample of the run, as measured).
    servo_gain : float
        Torque plant: gain K >= 0 [N m s/rad] of a proportional rotor-rate loop around the planned rates.
    mujoco_model : mujoco.MjModel, optional
        Plant ``"mujoco"``: the compiled model (:func:`~rollplan.execution.mujoco_engine.compile_model`).
    progress : callable(label, done, total), optional
        Called after each applied figure eight and correction.
    timing : str
        The timing law of the plan and of every re-plan and correction.
    tolerance, corrections : float, int
        Closed loop, after the plan: correcting motions from the measured state while its arrival error
        exceeds ``tolerance``, at most ``corrections`` of them.

    Returns
    -------
    ExecutionResult

    Raises
    ------
    InputError
        Bad input; NoPlanError: a re-plan from a measured state found no plan.
    """
    pieces = _pieces(plan)
    if not pieces:
        raise InputError("the plan is the empty motion (its start is its goal): nothing to execute")
    if any(p.kind not in ("approach", "leaf", "departure") for p in pieces):
        raise InputError("closed-loop execution needs a plan of figure eights (turns in place are not supported)")
    _check_plant_and_robots(plant, model_robot, real_robot)      # before the timing: bad input fails at once
    samples_per_piece = check_whole("samples_per_piece", samples_per_piece, 50, 100_000)
    piece_duration = _positive("piece_duration", piece_duration)
    m = _timer(timing, piece_duration, samples_per_piece)(plan, model_robot)
    first = _as_samples(m, (p.kind for p in pieces))
    return execute_samples(first, plan.problem.start, plan.goal, plan.steps, model_robot, real_robot, piece_duration,
                           replan=getattr(plan, "curve", "circles") == "circles", plant=plant,
                           closed_loop=closed_loop, disturbances=disturbances,
                           samples_per_piece=samples_per_piece, window=window, estimate_friction=estimate_friction,
                           rest_readings=rest_readings, servo_gain=servo_gain, mujoco_model=mujoco_model,
                           progress=progress, timing=timing, tolerance=tolerance, corrections=corrections)


def _check_plant_and_robots(plant, model_robot, real_robot) -> None:
    """InputError unless ``plant`` is known and both robots are Robots of the same radius."""
    if plant not in (*PLANT_NAMES, "mujoco"):
        raise InputError(f"plant {plant!r} is not known: choose one of {', '.join(PLANT_NAMES)}, mujoco")
    for name, rob in (("model_robot", model_robot), ("real_robot", real_robot)):
        if not isinstance(rob, Robot):
            raise InputError(f"{name} = {rob!r:.60} is not allowed: give a rollplan.Robot")
    if not math.isclose(model_robot.radius, real_robot.radius, rel_tol=1e-12):
        raise InputError(f"the model's radius {model_robot.radius:g} m and the real robot's "
                         f"{real_robot.radius:g} m differ: the radius is measured, give the same")


def _as_samples(m, kinds) -> Samples:
    """A timed motion as the controller applies it: min-jerk (continuous torques) as its uniform samples with
    splines split at the joints; a law whose torques step, with the steps as times given twice, linearly."""
    ms = motion_samples(m)
    interpolation = "linear" if ms.repeated_times().size else "spline"
    return Samples(ms.time, ms.rotor_rates, ms.rotor_torques, ms.segment, tuple(kinds), interpolation)


def _positive(name, value) -> float:
    v = check_finite(name, value)
    if not v > 0:
        raise InputError(f"{name} = {value!r} is not allowed: it must be > 0")
    return v


def _timer(timing, piece_duration: float, samples_per_piece: int):
    """``timed(plan, robot)``: the plan timed by the law, ``piece_duration`` a piece, or the law's shortest
    duration within the robot's limits when that is longer."""
    law = get_law(timing)

    def timed(p, robot):
        n = len(_pieces(p))
        samples = n * samples_per_piece
        try:
            return actuate(p, robot, n * piece_duration, samples, law)
        except InputError:
            if not Limits.of(robot).any:
                raise
            return actuate(p, robot, None, samples, law)
    return timed


def execute_samples(first: Samples, start: State, goal: State, steps: int, model_robot: Robot, real_robot: Robot,
                    piece_duration: float, *, replan: bool = True, plant: str = "rates", closed_loop: bool = True,
                    disturbances=(),
                    samples_per_piece: int = DEFAULT_SAMPLES_PER_PIECE, window: int = DEFAULT_WINDOW,
                    estimate_friction: bool = True, rest_readings: int = 0, servo_gain: float = 0.0,
                    mujoco_model=None, progress=None, timing: str = "min-jerk", tolerance: float = DEFAULT_TOLERANCE,
                    corrections: int = DEFAULT_CORRECTIONS) -> ExecutionResult:
    """Execute a timed motion given as samples (a plan file's) on ``real_robot``, open or closed loop.

    Open loop: ``first`` is applied whole. Closed loop: ``first`` is applied up to the end of its first
    figure eight when it rests there and more figure eights follow (else whole); then, after every figure
    eight, the robot is estimated and the rest re-planned from the measured state (``steps`` figure eights
    in all); after the last, correcting motions (:func:`rollplan.plan` of one figure eight from the
    measured state to ``goal``, with the estimated robot) follow while the measured arrival error exceeds
    ``tolerance``, at most ``corrections``. Every re-plan and correction is timed by ``timing``,
    ``piece_duration`` a piece (or the law's shortest duration within the limits, if longer). ``replan=False``
    applies ``first`` whole also in the closed loop, then corrects: :func:`execute` passes it for a plan of a
    leaf family other than the circles, which plans from rest at the origin only, so a re-plan from a measured
    state is not of that family (the corrections are figure eights of circles). The other parameters are
    those of :func:`execute`.
    """
    from ..planners import solve

    def make_plan(n: int, robot: Robot, start: State):
        """Re-plan by the method "geometric": ``n`` figure eights from ``start`` to the goal."""
        return solve(Problem(goal, start=start, robot=robot), "geometric", steps=n)

    _check_plant_and_robots(plant, model_robot, real_robot)
    piece_duration = _positive("piece_duration", piece_duration)
    samples_per_piece = check_whole("samples_per_piece", samples_per_piece, 50, 100_000)
    window = check_whole("window", window, 4, 100_000)
    rest_readings = check_whole("rest_readings", rest_readings, 0, 1_000_000)
    corrections = check_whole("corrections", corrections, 0, 100)
    tolerance = _positive("tolerance", tolerance)
    steps = check_whole("steps", steps, 1)
    R = real_robot.radius
    servo_gain = check_finite("servo_gain", servo_gain)
    if servo_gain < 0:
        raise InputError(f"servo_gain = {servo_gain!r} is not allowed: it must be >= 0")
    session = None
    if plant == "mujoco":
        from . import mujoco_engine

        model = mujoco_engine.compile_model(mujoco_engine.mjcf(real_robot)) if mujoco_model is None else mujoco_model
        if not math.isclose(mujoco_engine.radius_of(model), R, rel_tol=1e-9):
            raise InputError(f"the MuJoCo model's radius {mujoco_engine.radius_of(model):g} m is not the real "
                             f"robot's {R:g} m")
        session = mujoco_engine.Session(model, start)
    timed = _timer(timing, piece_duration, samples_per_piece)
    ctl = _Controller(real_robot, plant, disturbances, closed_loop, window, estimate_friction, start.array(),
                      servo_gain, session)
    robot_est, friction, estimates = model_robot, None, []

    def update(j):
        nonlocal robot_est, friction
        try:
            robot_est, friction = ctl.estimate(model_robot)
            if friction is not None:
                ctl.friction_hat = friction
        except InputError as exc:
            estimates.append({"rejected": str(exc)})
        if rest_readings:
            return measure(ctl.x, ctl.by_name, R, 10**6 + j, rest_readings)
        return ctl.measured

    motion, kinds, j, mode = first, tuple(first.kinds), 0, "file"
    label = "closed loop, figure eights" if closed_loop else "open loop"
    while True:
        cut = _first_eight_end(motion, kinds) if closed_loop and replan and j < steps - 1 else None
        end = motion.time.size - 1 if cut is None else cut
        estimates.append(_estimate_dict(robot_est, friction, ctl.friction_estimate))
        ctl.apply(motion, end, {"figure_eights_left": steps - j, "mode": mode, "k": robot_est.k,
                                "applied": "all" if cut is None else "first figure eight"})
        if progress:
            progress(label, j + 1 if cut is not None else steps, steps)
        if cut is None:
            break
        j += 1
        measured = update(j)
        try:
            current = make_plan(steps - j, robot_est, State(*measured))
        except (NoPlanError, InputError) as exc:
            raise type(exc)(f"re-planning {steps - j} figure eights from the measured state "
                            f"{tuple(round(float(v), 6) for v in measured)} failed: {exc}") from None
        motion = _as_samples(timed(current, robot_est), (p.kind for p in _pieces(current)))
        kinds, mode = motion.kinds, current.mode
    stopped = None
    for c in range(corrections + 1 if closed_loop else 0):
        measured = update(steps + c + 1)
        if float(np.linalg.norm(arrival_error(State(*measured), goal, R))) <= tolerance:
            break
        if c == corrections:
            stopped = f"the budget of {corrections} corrections is spent"
            break
        try:
            current = make_plan(1, robot_est, State(*measured))
        except (NoPlanError, InputError) as exc:
            stopped = f"no correcting motion from the measured state: {exc}"
            break
        if not _pieces(current):
            break
        m = timed(current, robot_est)
        estimates.append(_estimate_dict(robot_est, friction, ctl.friction_estimate))
        correction = _as_samples(m, ())
        ctl.apply(correction, correction.time.size - 1,
                  {"figure_eights_left": 0, "mode": "correction", "k": robot_est.k, "applied": "all"})
        if progress:
            progress("closed loop, corrections", c + 1, corrections)
    time, state, meas, rates, torques, seg = ctl.arrays()
    series = TimeSeries(time, state, seg, rotor_rates=rates, rotor_torques=torques, radius=R)
    return ExecutionResult(plant, closed_loop, goal, series, meas, ctl.segments, estimates, stopped)
