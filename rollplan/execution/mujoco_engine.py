"""MuJoCo as an independent physics engine: the robot as a three-body MJCF model, driven by a plan's torques.

The model (:func:`mjcf`): a shell body with a free joint (its frame at the sphere's centre, its axes the body
frame of (2)), a sphere geom of radius R on the plane z = 0, and two rotor bodies on hinges along the shell's
x and y axes (n1, n2), each driven by a torque motor. The inertias are those of the robot file: each rotor has
``diag(J_r, J_p, J_p)`` about its own axis and a quarter of the mass that is not shell, ``(M - m_o) / 4``; the
shell body has the rest of the mass and ``diag(2/3 m_o R^2 + J_p, 2/3 m_o R^2 + J_p, 2/3 m_o R^2 + J_r)``, so
that the three bodies together have ``Jzz I`` about the centre, ``Jzz = 2/3 m_o R^2 + 2 J_p + J_r`` and mass M:
the composite body of (11) and (14). Nothing of the paper's equations is used by the engine: MuJoCo integrates
the rigid bodies with their contact; the state (u_a, v_a, psi, u_o, v_o) is read back from the shell's pose
(:func:`rollplan.execution.poses.state_from_pose`).

Contact and integrator (:class:`Settings`): RK4, a sphere-plane contact with condim 3 (or 6 with rolling
resistance), elliptic friction cones, high friction, a stiff contact; what the paper cannot model is an option:
a centre of mass off the centre, a softer floor, rolling resistance.

The replay (:func:`replay`) applies the plan's motor torques feed-forward, interpolated linearly between the
samples (a repeated sample time is a step: left and right values), each MuJoCo step getting the mean of the
interpolant over the step (the impulse of the samples is applied exactly); optionally a proportional
rotor-rate loop around the planned rates. mujoco is imported only when used (``pip install 'rollplan[mujoco]'``).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import asdict, dataclass

import numpy as np

from ..errors import InputError, check_finite, check_range
from ..problem import State
from ..progress import report
from ..robot import Robot
from ..timeseries import Arrival, TimeSeries
from .poses import pose_of_state, rotation_from_quaternion, state_from_pose

__all__ = ["INSTALL_HINT", "require", "Settings", "DEFAULT_SETTINGS", "mjcf", "compile_model", "radius_of",
           "composite_inertia", "step_means", "Replay", "Session", "replay", "torque_samples", "SETTLE_TIME",
           "MAX_STEPS", "ROLLOUT_CHUNK"]

#: What to do when MuJoCo is missing.
INSTALL_HINT = "MuJoCo is not installed: install rollplan[mujoco] (pip install 'rollplan[mujoco]')"
#: Seconds the model settles on the floor at rest, motors off, before the replay starts.
SETTLE_TIME = 0.05
#: Most MuJoCo steps of one replay (each step's state is kept: 136 bytes a step).
MAX_STEPS = 2_000_000
#: Most MuJoCo steps run in one call without returning to Python (progress and Ctrl-C come between calls).
ROLLOUT_CHUNK = 2000
#: Names the replay needs in a model: the shell body (free joint, sphere geom), the rotor hinges, the motors.
SHELL, ROTORS, MOTORS = "shell", ("rotor1", "rotor2"), ("motor1", "motor2")


def require():
    """The ``mujoco`` module; InputError with :data:`INSTALL_HINT` if it cannot be imported."""
    try:
        import mujoco
    except ImportError as exc:
        raise InputError(f"{INSTALL_HINT}; import failed: {str(exc).splitlines()[0][:120]}") from None
    return mujoco


@dataclass(frozen=True)
class Settings:
    """Contact, integrator and the model's departures from the paper.

    Attributes
    ----------
    timestep : float
        MuJoCo's step [s] (RK4); the replay shortens it so that a whole number of steps spans the plan.
    solref : (time constant [s], damping ratio)
        The contact's reference: a spring-damper of this time constant (>= 2 timesteps, MuJoCo's own bound).
    solimp : (dmin, dmax, width [m], midpoint, power)
        The contact's impedance.
    friction : float
        Sliding friction coefficient of the contact (elliptic cone).
    rolling : float
        Rolling resistance [m] (MuJoCo's rolling friction; 0: none, condim 3; > 0: condim 6, with MuJoCo's least
        torsional friction: MuJoCo raises any coefficient below ``mjMINMU`` = 1e-5 to it, the torsional one given
        as 0 included, so a rolling resistance below 1e-5 m acts as 1e-5 m).
    com_offset : (3,) [m]
        The composite centre of mass in the shell's frame (0: the centre, as the paper assumes); the shell body's
        centre of mass moves by ``com_offset M / m_shell_body``.
    """

    timestep: float = 1e-4
    solref: tuple = (2e-4, 1.0)
    solimp: tuple = (0.99, 0.999, 1e-4, 0.5, 2.0)
    friction: float = 2.0
    rolling: float = 0.0
    com_offset: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        ts = check_range("timestep", self.timestep, 1e-6, 1e-2)
        object.__setattr__(self, "timestep", ts)
        sr = tuple(self.solref)
        if len(sr) != 2:
            raise InputError(f"floor solref = {self.solref!r} is not allowed: give a time constant [s] and a "
                             "damping ratio")
        tc = check_finite("floor solref time constant", sr[0])
        if not 2.0 * ts <= tc <= 10.0:
            raise InputError(f"floor solref time constant = {sr[0]!r} s is not allowed: it must lie in "
                             f"[2 timestep, 10 s] = [{2 * ts:g}, 10] (MuJoCo needs two steps per time constant)")
        dr = check_range("floor solref damping ratio", sr[1], 0.01, 100.0)
        object.__setattr__(self, "solref", (tc, dr))
        si = tuple(float(check_finite("solimp", v)) for v in self.solimp)
        if len(si) != 5 or not (0 < si[0] <= si[1] < 1 and si[2] > 0 and 0 < si[3] < 1 and si[4] >= 1):
            raise InputError(f"solimp = {self.solimp!r} is not allowed: give dmin <= dmax in (0, 1), width > 0, "
                             "midpoint in (0, 1), power >= 1")
        object.__setattr__(self, "solimp", si)
        object.__setattr__(self, "friction", check_range("friction", self.friction, 1e-3, 1e3))
        object.__setattr__(self, "rolling", check_range("rolling resistance", self.rolling, 0.0, 1.0))
        off = tuple(self.com_offset)
        if len(off) != 3:
            raise InputError(f"com_offset = {self.com_offset!r} is not allowed: give three numbers DX DY DZ [m]")
        object.__setattr__(self, "com_offset", tuple(check_finite("com offset", v) for v in off))

    def as_dict(self) -> dict:
        return {k: (list(v) if isinstance(v, tuple) else v) for k, v in asdict(self).items()}


#: The settings `rollplan mjcf` and `rollplan simulate --engine mujoco` use unless told otherwise
#: (chosen by measurement: results/mujoco_replay.md).
DEFAULT_SETTINGS = Settings()


def _f(x) -> str:
    return repr(float(x))


def _v(xs) -> str:
    return " ".join(_f(x) for x in xs)


def mjcf(robot: Robot, settings: Settings = DEFAULT_SETTINGS) -> str:
    """The MJCF model (module docstring) of ``robot`` with ``settings``, as XML text."""
    if not isinstance(robot, Robot):
        raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
    R, M, mo = robot.radius, robot.mass_total, robot.mass_shell
    jr, jp = robot.rotor_inertia_axial, robot.rotor_inertia_transverse
    m_rotor = (M - mo) / 4.0
    m_body = M - 2.0 * m_rotor
    offset = np.asarray(settings.com_offset, float)
    if np.linalg.norm(offset) >= 0.5 * R:
        raise InputError(f"com offset {_v(offset)} m is not allowed: its length must be below R/2 = {0.5 * R:g} m")
    ipos = offset * M / m_body
    shell = 2.0 / 3.0 * mo * R * R
    s = settings
    if s.rolling > 0:
        contact = f'condim="6" friction="{_f(s.friction)} 0 {_f(s.rolling)}"'
    else:
        contact = f'condim="3" friction="{_f(s.friction)} 0 0"'
    disc = f'size="{_f(0.45 * R)} {_f(0.04 * R)}" contype="0" conaffinity="0" group="1"'
    return f"""<mujoco model="rollplan robot">
  <!-- rollplan: radius {_f(R)} m, mass_total {_f(M)} kg, mass_shell {_f(mo)} kg, J_r {_f(jr)} kg m^2,
       J_p {_f(jp)} kg m^2; composite inertia about the centre Jzz = 2/3 m_o R^2 + 2 J_p + J_r = {_f(robot.j_zz)},
       k = {_f(robot.k)} (14). Settings: {s.as_dict()} -->
  <compiler angle="radian" inertiafromgeom="false"/>
  <option timestep="{_f(s.timestep)}" integrator="RK4" cone="elliptic"/>
  <worldbody>
    <light pos="0 0 {_f(10 * R)}" dir="0 0 -1"/>
    <geom name="floor" type="plane" size="0 0 {_f(R)}" priority="1" {contact}
          solref="{_v(s.solref)}" solimp="{_v(s.solimp)}" rgba="0.8 0.8 0.8 1"/>
    <body name="{SHELL}" pos="0 0 {_f(R)}">
      <freejoint name="{SHELL}"/>
      <inertial pos="{_v(ipos)}" mass="{_f(m_body)}" diaginertia="{_f(shell + jp)} {_f(shell + jp)} {_f(shell + jr)}"/>
      <geom name="{SHELL}" type="sphere" size="{_f(R)}" rgba="0.6 0.7 0.9 0.3"/>
      <body name="{ROTORS[0]}">
        <joint name="{ROTORS[0]}" type="hinge" axis="1 0 0"/>
        <inertial pos="0 0 0" mass="{_f(m_rotor)}" diaginertia="{_f(jr)} {_f(jp)} {_f(jp)}"/>
        <geom type="cylinder" zaxis="1 0 0" {disc} rgba="0.5 0.2 0.6 1"/>
      </body>
      <body name="{ROTORS[1]}">
        <joint name="{ROTORS[1]}" type="hinge" axis="0 1 0"/>
        <inertial pos="0 0 0" mass="{_f(m_rotor)}" diaginertia="{_f(jp)} {_f(jr)} {_f(jp)}"/>
        <geom type="cylinder" zaxis="0 1 0" {disc} rgba="0.2 0.6 0.3 1"/>
      </body>
    </body>
  </worldbody>
  <actuator>
    <motor name="{MOTORS[0]}" joint="{ROTORS[0]}"/>
    <motor name="{MOTORS[1]}" joint="{ROTORS[1]}"/>
  </actuator>
</mujoco>
"""


def compile_model(xml: str, where: str = "MJCF model"):
    """The compiled ``MjModel`` of ``xml``; InputError if MuJoCo refuses it or it lacks what the replay drives
    (a body ``shell`` with a free joint and a sphere geom ``shell``, hinges ``rotor1``, ``rotor2`` driven by
    motors ``motor1``, ``motor2``)."""
    mujoco = require()
    try:
        model = mujoco.MjModel.from_xml_string(xml)
    except ValueError as exc:
        raise InputError(f"{where} does not compile in MuJoCo: {' '.join(str(exc).split())[:200]}") from None
    obj = mujoco.mjtObj
    body = mujoco.mj_name2id(model, obj.mjOBJ_BODY, SHELL)
    geom = mujoco.mj_name2id(model, obj.mjOBJ_GEOM, SHELL)
    free = model.body_jntadr[body] if body >= 0 else -1
    if body < 0 or model.body_jntnum[body] != 1 or model.jnt_type[free] != mujoco.mjtJoint.mjJNT_FREE \
            or model.jnt_qposadr[free] != 0:
        raise InputError(f"{where} has no body 'shell' with a free joint as its first joint")
    if geom < 0 or model.geom_type[geom] != mujoco.mjtGeom.mjGEOM_SPHERE or model.geom_bodyid[geom] != body:
        raise InputError(f"{where} has no sphere geom 'shell' on the body 'shell'")
    for i, (joint, motor) in enumerate(zip(ROTORS, MOTORS)):
        j = mujoco.mj_name2id(model, obj.mjOBJ_JOINT, joint)
        a = mujoco.mj_name2id(model, obj.mjOBJ_ACTUATOR, motor)
        if j < 0 or model.jnt_type[j] != mujoco.mjtJoint.mjJNT_HINGE or model.jnt_dofadr[j] != 6 + i:
            raise InputError(f"{where} has no hinge '{joint}' (the shell's dof {6 + i})")
        if a < 0 or model.actuator_trnid[a, 0] != j or a != i:
            raise InputError(f"{where} has no motor '{motor}' (actuator {i}) on the hinge '{joint}'")
    return model


def radius_of(model) -> float:
    """The radius of the sphere geom ``shell`` [m]."""
    mujoco = require()
    return float(model.geom_size[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, SHELL), 0])


def composite_inertia(model) -> tuple[float, np.ndarray, np.ndarray]:
    """MuJoCo's compiled bodies in the zero pose (after ``mj_forward``): total mass [kg], the composite centre of
    mass relative to the shell's origin (3,) [m] and the composite inertia about that origin (3, 3) [kg m^2],
    from ``body_mass``, ``body_inertia`` and the bodies' inertial frames (parallel-axis theorem)."""
    mujoco = require()
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    shell = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, SHELL)
    centre = data.xpos[shell]
    mass, moment, inertia = 0.0, np.zeros(3), np.zeros((3, 3))
    for b in range(1, model.nbody):
        m = float(model.body_mass[b])
        rot = data.ximat[b].reshape(3, 3)
        r = data.xipos[b] - centre
        inertia += rot @ np.diag(model.body_inertia[b]) @ rot.T + m * (r @ r * np.eye(3) - np.outer(r, r))
        mass += m
        moment += m * r
    return mass, moment / mass, inertia


def step_means(t, y, edges) -> np.ndarray:
    """Mean over each interval ``[edges[i], edges[i+1]]`` of the piecewise-linear interpolant of ``(t, y)``.

    ``t`` is non-decreasing; a repeated time is a step of the input (the first value its left limit, the
    second its right). Returns ``(len(edges) - 1, m)``.
    """
    t, y, e = np.asarray(t, float), np.asarray(y, float), np.asarray(edges, float)
    h = np.diff(t)
    cum = np.vstack([np.zeros((1, y.shape[1])), np.cumsum(h[:, None] * (y[1:] + y[:-1]) / 2.0, axis=0)])
    j = np.clip(np.searchsorted(t, e, side="right") - 1, 0, t.size - 2)
    width = t[j + 1] - t[j]
    s = np.clip(e - t[j], 0.0, None)
    frac = np.divide(s, width, out=np.zeros_like(s), where=width > 0)
    y_e = y[j] + (y[j + 1] - y[j]) * frac[:, None]
    integral = cum[j] + s[:, None] * (y[j] + y_e) / 2.0
    integral[e >= t[-1]] = cum[-1] + (e[e >= t[-1]] - t[-1])[:, None] * y[-1]
    return np.diff(integral, axis=0) / np.diff(e)[:, None]


def torque_samples(time, torques, where: str = "plan file") -> tuple[np.ndarray, np.ndarray]:
    """``(t, torques)`` as float arrays if they are torque samples: ``t`` finite, non-decreasing (a time at most
    twice: a step), spanning > 0; ``torques`` (N, 2) finite. InputError (naming ``where``) otherwise."""
    try:
        t, tau = np.asarray(time, float), np.asarray(torques, float)
    except (TypeError, ValueError):
        raise InputError(f"{where}: 'time' or 'rotor_torques' is not an array of numbers") from None
    if t.ndim != 1 or t.size < 2 or tau.shape != (t.size, 2):
        raise InputError(f"{where}: 'rotor_torques' must have one row of two torques per sample time "
                         f"(time has shape {t.shape}, rotor_torques {tau.shape})")
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(tau))):
        raise InputError(f"{where}: 'time' and 'rotor_torques' must be finite numbers")
    d = np.diff(t)
    if np.any(d < 0) or np.any((d[1:] == 0) & (d[:-1] == 0)) or not t[-1] > t[0]:
        raise InputError(f"{where}: 'time' is not allowed: sample times must not decrease, a time may repeat once "
                         "(a step of the torque), and the span must be > 0")
    return t, tau


@dataclass(frozen=True)
class Replay(Arrival):
    """A plan's torques applied to the MuJoCo model.

    Attributes
    ----------
    series : TimeSeries
        At the plan's sample times [s]: ``state`` read from MuJoCo's pose (u_a, v_a [m], psi unwrapped, u_o,
        v_o [rad]) and ``rotor_rates``, the hinges' rates relative to the shell [rad/s].
    goal : State or None
        With it ``final``, ``error``, ``arrival_error`` and ``position_error`` [R and rad; R]
        (:class:`~rollplan.timeseries.Arrival`).
    slip : float
        Distance slid at the contact [m]: the integral of the horizontal speed of the shell's material point at
        the contact.
    max_penetration : float
        Largest depth of the sphere in the floor during the motion, R minus the centre's height [m].
    final_rotor_rates : (2,) [rad/s]; final_speed : float, the centre's speed at the end [m/s]
    steps : int; timestep : float [s]
    """

    series: TimeSeries
    goal: State | None
    slip: float
    max_penetration: float
    final_rotor_rates: np.ndarray
    final_speed: float
    steps: int
    timestep: float

    def summary(self) -> dict:
        """The scalars (JSON-ready)."""
        return {"final": self.final.as_dict(), "arrival_error": self.arrival_error,
                "position_error": self.position_error,
                "error": None if self.error is None else [float(v) for v in self.error],
                "slip": self.slip, "max_penetration": self.max_penetration,
                "final_rotor_rates": [float(v) for v in self.final_rotor_rates], "final_speed": self.final_speed,
                "steps": self.steps, "timestep": self.timestep}


def _rollout_function():
    """``mujoco.rollout.rollout`` if this MuJoCo has it with a warm start argument, else None (step by step)."""
    try:
        from mujoco import rollout
    except ImportError:
        return None
    return rollout.rollout if "initial_warmstart" in inspect.signature(rollout.rollout).parameters else None


class Session:
    """A MuJoCo model run piece after piece: the state carries over from one :meth:`advance` to the next.

    Created at rest in ``start`` (default zero state), settled on the floor for ``settle`` s with the motors off.
    ``slip`` [m] and ``max_penetration`` [m] accumulate over everything run after settling (:class:`Replay`).
    """

    def __init__(self, model, start=None, settle: float = SETTLE_TIME):
        self.mujoco = require()
        self.model = model
        self.radius = radius_of(model)
        self.step_max = float(model.opt.timestep)
        self.start = State.of(np.zeros(5) if start is None else start, "start").array()
        self.data = self.mujoco.MjData(model)
        self.rollout = _rollout_function()
        xy, rot = pose_of_state(self.start)
        quat = np.zeros(4)
        self.mujoco.mju_mat2Quat(quat, rot[0].ravel())
        self.data.qpos[0:3] = [xy[0, 0], xy[0, 1], self.radius]
        self.data.qpos[3:7] = quat
        for _ in range(int(math.ceil(settle / self.step_max))):
            self.mujoco.mj_step(model, self.data)
        self.max_penetration, self.slip, self.steps = 0.0, 0.0, 0   # of the motion: the settling is left out
        self.psi = float(self.start[2])   # psi continues from the start's turn (unwrapped)

    def advance(self, time, torques, rates=None, servo_gain: float = 0.0, noise=None) -> dict:
        """Apply the torque samples over ``[time[0], time[-1]]`` (:func:`replay`); the steps' records.

        ``noise`` (N, 2) [N m], optional: added to the torque samples. Returns a dict of arrays at the step
        edges: ``t`` (S + 1,), ``state`` (S + 1, 5) (psi unwrapped), ``omega`` (plane frame), ``rotor_rates``,
        ``rotor_angles``, and ``torque`` (S, 2), the torque applied during each step.
        """
        mujoco, model, data = self.mujoco, self.model, self.data
        t, tau = torque_samples(time, torques, "torque samples")
        if noise is not None:
            tau = tau + np.asarray(noise, float)
        servo_gain = check_range("servo gain", servo_gain, 0.0, 1e6)
        if servo_gain > 0 and rates is None:
            raise InputError("a servo gain > 0 needs the planned rotor rates")
        span = float(t[-1] - t[0])
        n = max(1, int(math.ceil(span / self.step_max - 1e-9)))
        if n > MAX_STEPS:
            raise InputError(f"the motion's {span:g} s need {n} steps of the model's timestep {self.step_max:g} s, "
                             f"more than {MAX_STEPS}: give the model a larger timestep (rollplan mjcf --timestep)")
        model.opt.timestep = span / n
        edges = t[0] + span * np.arange(n + 1) / n
        edges[-1] = t[-1]
        ctrl = step_means(t, tau, edges)
        ref = step_means(t, np.asarray(rates, float), edges) if servo_gain > 0 else None
        qpos, qvel = np.empty((n + 1, 9)), np.empty((n + 1, 8))
        qpos[0], qvel[0] = data.qpos[:9], data.qvel[:8]
        every = max(1, n // 100)
        try:
            if ref is None and model.nu == 2 and self.rollout is not None:
                applied = ctrl
                self._roll_out(ctrl, qpos, qvel, every)
            else:
                applied = np.empty((n, 2))
                for i in range(n):
                    applied[i] = ctrl[i] if ref is None else ctrl[i] + servo_gain * (ref[i] - data.qvel[6:8])
                    data.ctrl[:2] = applied[i]
                    mujoco.mj_step(model, data)
                    qpos[i + 1], qvel[i + 1] = data.qpos[:9], data.qvel[:8]
                    if (i + 1) % every == 0:
                        report("MuJoCo replay", i + 1, n)
        finally:
            model.opt.timestep = self.step_max
        rotation = rotation_from_quaternion(qpos[:, 3:7])
        states = state_from_pose(qpos[:, 0:2], rotation)
        states[:, 2] = np.unwrap(states[:, 2])
        states[:, 2] += 2 * np.pi * np.round((self.psi - states[0, 2]) / (2 * np.pi))
        self.psi = float(states[-1, 2])
        omega = np.einsum("nij,nj->ni", rotation, qvel[:, 3:6])          # the free joint's angular velocity is local
        z = qpos[:, 2]
        slip_speed = np.hypot(qvel[:, 0] - omega[:, 1] * z, qvel[:, 1] + omega[:, 0] * z)
        self.slip += float(np.sum(0.5 * (slip_speed[1:] + slip_speed[:-1]) * np.diff(edges)))
        self.max_penetration = max(self.max_penetration, float(np.max(self.radius - z)))
        self.steps += n
        return {"t": edges, "state": states, "omega": omega, "rotor_rates": qvel[:, 6:8], "rotor_angles": qpos[:, 7:9],
                "torque": applied, "speed": float(np.linalg.norm(qvel[-1, 0:3])), "timestep": span / n}

    def _roll_out(self, ctrl, qpos, qvel, every: int) -> None:
        """Step the model by the controls ``ctrl`` (n, 2) in MuJoCo's rollout (no Python work per step), in
        chunks of at most :data:`ROLLOUT_CHUNK` steps (progress and Ctrl-C between them); each step's qpos and
        qvel into rows 1.. of ``qpos``, ``qvel``. The same steps as ``mj_step`` one by one (warm start included)."""
        mujoco, model, data = self.mujoco, self.model, self.data
        spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
        iq = mujoco.mj_stateSize(model, mujoco.mjtState.mjSTATE_TIME)
        iv = iq + model.nq
        state = np.empty(mujoco.mj_stateSize(model, spec))
        n, done = len(ctrl), 0
        while done < n:
            c = min(ROLLOUT_CHUNK, n - done)
            mujoco.mj_getState(model, data, state, spec)
            out, _ = self.rollout(model, data, state, ctrl[done:done + c], initial_warmstart=data.qacc_warmstart.copy())
            qpos[done + 1:done + c + 1], qvel[done + 1:done + c + 1] = out[0, :, iq:iq + 9], out[0, :, iv:iv + 8]
            mujoco.mj_setState(model, data, out[0, -1], spec)
            if (done + c) // every > done // every:
                report("MuJoCo replay", done + c, n)
            done += c
        data.ctrl[:2] = ctrl[-1]

    def run(self, robot: Robot, t, torques, x0=None, p0=(0.0, 0.0), phi0=(0.0, 0.0), disturbances=(),
            segment: int = 0, breaks=(), interpolation: str = "linear", commanded_p0=None, servo_gain: float = 0.0,
            reference_rates=None):
        """:func:`rollplan.execution.plants.run_torques` on MuJoCo (the closed loop's plant ``"mujoco"``).

        The state continues from the previous run (``x0``, ``p0``, ``phi0`` are the controller's record of it);
        ``robot`` is the real robot of the model (for the rotors' momenta). ``breaks`` and ``interpolation`` are
        not needed: the samples are always interpolated linearly, a time given twice being a step. Disturbances:
        ``measurement``, ``torque_noise``.
        """
        from .plants import PlantResponse, by_name, measure, rotor_momenta

        d = by_name(disturbances, "mujoco")
        t = np.asarray(t, float)
        noise = d["torque_noise"].draw(t.size, segment) if "torque_noise" in d else None
        rec = self.advance(t, torques, reference_rates, servo_gain, noise)
        at = lambda a: np.column_stack([np.interp(t, rec["t"], a[:, j]) for j in range(a.shape[1])])  # noqa: E731
        state, omega, rates = at(rec["state"]), at(rec["omega"]), at(rec["rotor_rates"])
        angles = np.asarray(phi0, float) + at(rec["rotor_angles"] - rec["rotor_angles"][0])
        momenta = rotor_momenta(robot, state, omega, rates)
        commanded = at(np.vstack([rec["torque"], rec["torque"][-1:]]))   # the step-held torques at the samples
        impulse = np.vstack([np.zeros((1, 2)), np.cumsum(rec["torque"] * np.diff(rec["t"])[:, None], axis=0)])
        start_p = np.asarray(p0 if commanded_p0 is None else commanded_p0, float)
        cmd_p = start_p + at(impulse)
        series = TimeSeries(t, state, omega=omega, rotor_rates=rates, rotor_angles=angles, rotor_momenta=momenta,
                            radius=robot.radius)
        return PlantResponse("mujoco", series, measure(state, d, robot.radius, segment), commanded, cmd_p)


def replay(model, time, torques, start=None, goal=None, rates=None, servo_gain: float = 0.0,
           settle: float = SETTLE_TIME) -> Replay:
    """Drive the compiled ``model`` (:func:`compile_model`) by the torque samples ``(time, torques)``.

    Parameters
    ----------
    model : mujoco.MjModel
        Its timestep is the largest step; the replay shortens it so that whole steps span ``time``.
    time, torques : (N,), (N, 2)
        Motor torque samples [s, N m] (:func:`torque_samples`), interpolated linearly; each step applies the
        interpolant's mean over the step.
    start : State or (5,), optional
        Start state (default zero), at rest; the model first settles on the floor for ``settle`` s.
    goal : State, optional
        Gives the arrival error.
    rates : (N, 2), optional
        Planned rotor rates at ``time`` [rad/s], the reference of the rate loop.
    servo_gain : float
        Gain K >= 0 [N m s/rad]: each step adds ``K (rate reference - hinge rate)`` to the torque.
    """
    t, _ = torque_samples(time, torques, "torque samples")
    session = Session(model, start, settle)
    rec = session.advance(t, torques, rates, servo_gain)
    R = session.radius
    at = lambda a: np.column_stack([np.interp(t, rec["t"], a[:, j]) for j in range(a.shape[1])])  # noqa: E731
    series = TimeSeries(t, at(rec["state"]), rotor_rates=at(rec["rotor_rates"]), radius=R)
    return Replay(series, None if goal is None else State.of(goal, "goal"), session.slip,
                  session.max_penetration, rec["rotor_rates"][-1].copy(), rec["speed"], session.steps,
                  rec["timestep"])
