"""The planning problem, stated once for every method: start and goal states, the robot, the radius.

A state of the robot is its five contact coordinates (Section II of the
paper), always in the order of :class:`State`:

``(u_a, v_a, psi, u_o, v_o)``
    ``u_a, v_a``: the contact point on the plane [length unit]; ``psi``: the
    contact angle [rad]; ``u_o, v_o``: the contact point on the sphere, (1)
    [rad], zero at the south pole.

:class:`Problem` validates its input once; planners, the CLI, batch runs and
studies take a Problem and never check the same numbers again.
:func:`arrival_error` is the one measure of how far a state is from a goal.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from .core.curves import A_MAX
from .core.plane import wrap, wrap_exact
from .errors import InputError, check_finite, check_range, check_whole
from .robot import Robot

__all__ = ["STATE_NAMES", "State", "Problem", "K_MIN", "K_MAX", "MAX_STEPS", "DEFAULT_K", "N3Z_MIN", "check_k",
           "check_steps", "check_contact", "check_reach", "MAX_DISTANCE", "arrival_error", "arrival_residual"]

#: Names of the state's entries, in the one order used everywhere (arrays, JSON, CSV).
STATE_NAMES = ("u_a", "v_a", "psi", "u_o", "v_o")
#: Smallest inertia ratio accepted (k = 0 is pure rolling).
K_MIN = 0.0
#: Largest inertia ratio accepted (physical robots have 1 < k < ~30).
K_MAX = 100.0
#: Largest number of figure-eight steps a plan may have.
MAX_STEPS = 1000
#: Farthest goal from its start [R] a plan can reach: two legs of MAX_STEPS figure eights, each at most
#: 4 pi A_MAX long (two circles of radius <= A_MAX R; a contact path is as long on the plane as on the sphere),
#: and the rolls to and from the pole (each shorter than pi/2), rounded up. Farther goals are refused.
MAX_DISTANCE = math.ceil(2 * MAX_STEPS * 4.0 * math.pi * A_MAX + math.pi)
#: k when none is given on the command line or in a batch row: the paper's case study (Section III.C).
DEFAULT_K = 2.5

#: Smallest ``n3z = cos(u_o) cos(v_o)`` of a start or goal contact point (87.13 deg from the south pole);
#: see :func:`check_contact`.
N3Z_MIN = 0.05


class State(NamedTuple):
    """Contact coordinates of the robot, eqs. (1)-(10): plane point, contact angle, sphere point.

    Attributes
    ----------
    u_a, v_a : float
        Contact point on the plane [length unit].
    psi : float
        Contact angle between the contact frames [rad].
    u_o, v_o : float
        Contact point on the sphere, (1) [rad]; zero at the south pole.
    """

    u_a: float = 0.0
    v_a: float = 0.0
    psi: float = 0.0
    u_o: float = 0.0
    v_o: float = 0.0

    @classmethod
    def of(cls, value, name: str = "state") -> State:
        """A State from a State, a mapping with the names of :data:`STATE_NAMES`, or a sequence of
        3 (``u_a, v_a, psi``; the contact point at the pole) or 5 numbers; InputError otherwise."""
        if isinstance(value, State):
            values = tuple(value)
        elif isinstance(value, dict):
            unknown = sorted(set(value) - set(STATE_NAMES))
            if unknown:
                raise InputError(f"{name} has unknown key {unknown[0]!r}; allowed: {', '.join(STATE_NAMES)}")
            values = tuple(value.get(n, 0.0) for n in STATE_NAMES)
        else:
            try:
                values = tuple(value)
            except TypeError:
                raise InputError(f"{name} = {value!r} is not allowed: give (u_a, v_a, psi) or "
                                 "(u_a, v_a, psi, u_o, v_o)") from None
            if len(values) not in (3, 5):
                raise InputError(f"{name} = {value!r} is not allowed: give (u_a, v_a, psi) or "
                                 "(u_a, v_a, psi, u_o, v_o)")
        return cls(*(check_finite(f"{name} {n}", v) for n, v in zip(STATE_NAMES, values)))

    def array(self) -> np.ndarray:
        """The state as an array of shape (5,)."""
        return np.array(self, float)

    def as_dict(self) -> dict:
        """``{"u_a": ..., "v_a": ..., "psi": ..., "u_o": ..., "v_o": ...}`` (the JSON form)."""
        return {n: float(v) for n, v in zip(STATE_NAMES, self)}

    def scaled(self, length: float) -> State:
        """The same state with its lengths (u_a, v_a) multiplied by ``length``."""
        return self._replace(u_a=self.u_a * length, v_a=self.v_a * length)

    @property
    def at_pole(self) -> bool:
        """True when the contact point on the sphere is the south pole (u_o = v_o = 0)."""
        return self.u_o == 0.0 and self.v_o == 0.0


def arrival_error(final, goal, radius: float = 1.0) -> np.ndarray:
    """How far ``final`` is from ``goal``, entry by entry: shape (5,), in :class:`State` order.

    Lengths are divided by ``radius`` (units of R), psi is the difference
    wrapped to (-pi, pi] (psi is an angle; each is first reduced exactly by
    :func:`~rollplan.core.plane.wrap_exact`, so a goal psi of 1e8 or 1e16 is
    compared to full accuracy), u_o and v_o are differences [rad].
    """
    f, g = np.asarray(final, float), np.asarray(goal, float)
    with np.errstate(over="ignore"):   # states 1e308 apart are infinitely far apart
        d = f - g
        d_psi = float(wrap(wrap_exact(f[2])[0] - wrap_exact(g[2])[0]))
        return np.array([d[0] / radius, d[1] / radius, d_psi, d[3], d[4]])


def arrival_residual(final, goal, radius: float = 1.0) -> float:
    """Euclidean norm of :func:`arrival_error`: the residual every certificate reports."""
    return float(math.hypot(*arrival_error(final, goal, radius)))   # no overflow for distances of any size


def check_k(k) -> float:
    """The inertia ratio k (14) as a float in [K_MIN, K_MAX]; InputError otherwise."""
    return check_range("k", k, K_MIN, K_MAX)


def check_contact(u_o, v_o, name: str = "contact") -> tuple[float, float]:
    """``(u_o, v_o)`` as floats if the contact point lies in the region where plans start and end.

    The region: the principal chart ``|u_o|, |v_o| < pi/2`` of (1) with
    ``n3z = cos(u_o) cos(v_o) >= N3Z_MIN`` (:data:`N3Z_MIN` = 0.05, at most 87.13 deg from the
    south pole). ``n3z`` is the vertical component of the body axis n3 (5); (13) is solved for
    the spin by dividing by it, so off a pure roll any rolling rate becomes a spin with the gain
    ``k / n3z``, 20 k at the margin. The figure eights themselves reach down to
    ``n3z = 1 - 2 A_MAX^2 = 0.048``; start and goal are held to the same band, rounded up.

    Raises
    ------
    InputError
        Not finite, outside the chart, or ``n3z < N3Z_MIN`` (the message names the limit).
    """
    u, v = check_finite(f"{name} u_o", u_o), check_finite(f"{name} v_o", v_o)
    if abs(u) >= math.pi / 2 or abs(v) >= math.pi / 2:
        raise InputError(f"{name} (u_o, v_o) = ({u!r}, {v!r}) is not allowed: |u_o| and |v_o| must be below "
                         "pi/2 (the lower hemisphere)")
    n3z = math.cos(u) * math.cos(v)
    if n3z < N3Z_MIN:
        raise InputError(f"{name} (u_o, v_o) = ({u!r}, {v!r}) is not allowed: cos(u_o) cos(v_o) = {n3z!r} is "
                         f"below {N3Z_MIN:g}; the contact point must lie within "
                         f"{math.degrees(math.acos(N3Z_MIN)):.2f} deg of the south pole")
    return u, v


def check_reach(start, goal, radius: float = 1.0, name: str = "goal", origin: str = "the start") -> float:
    """The distance [R] on the plane from ``start`` to ``goal`` (States, lengths in units of ``radius``);
    InputError naming :data:`MAX_DISTANCE` when it is farther than any plan reaches."""
    d = math.hypot(goal.u_a - start.u_a, goal.v_a - start.v_a)
    if not d <= MAX_DISTANCE * radius:
        far = d / radius if math.isfinite(d / radius) else math.inf
        raise InputError(f"{name} (u_a, v_a) = ({goal.u_a:.6g}, {goal.v_a:.6g}) is {far:.6g} R from {origin}: at "
                         f"most {MAX_DISTANCE} R is allowed (no plan reaches farther: two legs of {MAX_STEPS} "
                         f"figure eights of leaves <= {A_MAX:g} R and the rolls to and from the pole)")
    return d / radius


def check_steps(steps) -> int:
    """The number of figure-eight steps as an int in [1, MAX_STEPS]; InputError otherwise."""
    return check_whole("steps", steps, 1, MAX_STEPS)


@dataclass(frozen=True)
class Problem:
    """Reach ``goal`` from ``start``: the problem both planners solve.

    Validated on construction; every field is then safe to use.

    Parameters
    ----------
    goal : State or sequence
        Goal state [length unit, rad]; three numbers ``(u_a, v_a, psi)`` mean
        the contact point at the south pole.
    start : State or sequence, optional
        Start state (default: zero, at rest at the origin). The contact points of
        start and goal must lie in the region of :func:`check_contact`.
    k : float, optional
        Inertia ratio (14), ``0 <= k <= K_MAX`` (k = 0 is pure rolling). Or give ``robot``.
    robot : Robot, optional
        Robot parameters; sets k and, unless ``radius`` is given, the radius
        (lengths then in metres).
    radius : float, optional
        Sphere radius R > 0 in the length unit of the states (default 1, or the robot's).
    steps : int
        Number of figure eights n of a geometric-phase plan, ``1 <= n <= MAX_STEPS``.

    Attributes
    ----------
    goal, start : State
    k, radius : float
    robot : Robot or None
    steps : int
    """

    goal: State
    start: State = field(default_factory=State)
    k: float | None = None
    robot: Robot | None = None
    radius: float | None = None
    steps: int = 1

    def __post_init__(self) -> None:
        set_ = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen dataclass)
        if self.robot is not None and self.k is not None:
            raise InputError("give either k or robot, not both")
        if self.robot is None and self.k is None:
            raise InputError("k is missing: give k (>= 0) or a robot")
        if self.robot is not None and not isinstance(self.robot, Robot):
            raise InputError(f"robot = {self.robot!r} is not allowed: give a rollplan.Robot")
        set_("k", check_k(self.robot.k if self.robot is not None else self.k))
        radius = self.radius if self.radius is not None else (self.robot.radius if self.robot else 1.0)
        set_("radius", check_range("radius", radius, 0.0, None, low_open=True))
        set_("goal", State.of(self.goal, "goal"))
        set_("start", State.of(self.start, "start"))
        for name in ("start", "goal"):
            check_contact(getattr(self, name).u_o, getattr(self, name).v_o, name)
        set_("steps", check_steps(self.steps))

    @property
    def unit(self) -> str:
        """Name of the length unit: ``"R"`` for the unit sphere without a robot, else ``"m"`` (a robot's
        radius is in metres, and so is a radius given without one)."""
        return "R" if self.robot is None and self.radius == 1.0 else "m"

    def scaled(self, state: State) -> State:
        """A state of this problem in units of R (lengths divided by the radius)."""
        return State(*state).scaled(1.0 / self.radius)

    def residual(self, final) -> float:
        """:func:`arrival_residual` of ``final`` (length unit of the problem) to the goal."""
        return arrival_residual(final, self.goal, self.radius)

    def describe(self) -> str:
        """One line naming the problem, for messages."""
        g, u = self.goal, self.unit
        where = f"(u_a, v_a, psi) = ({g.u_a:g} {u}, {g.v_a:g} {u}, {g.psi:g} rad)"
        if u != "R":   # lengths in metres: also in radii, the unit the figure eights work in
            where += f" = ({g.u_a / self.radius:g} R, {g.v_a / self.radius:g} R) with R = {self.radius:g} {u}"
        if not g.at_pole:
            where += f", contact (u_o, v_o) = ({g.u_o:g} rad, {g.v_o:g} rad)"
        if tuple(self.start) != tuple(State()):
            where = f"from {tuple(float(v) for v in self.start)} to " + where
        return f"{where} in {self.steps} step(s) with k = {self.k:g}"
