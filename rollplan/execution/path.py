"""A planned contact path as smooth pieces along one path parameter s, with what the rotors need along it.

The path parameter
------------------
A plan's contact path is a sequence of smooth pieces (:class:`ArcLengthPiece`); piece
``j`` is a curve on the sphere traced by its own parameter ``phi in [0, phi_end_j]``
(a leaf of the figure eight: the circle (35) of radius ``r_j``, ``phi in [0, 2 pi]``).
One global parameter runs over the whole path,

    s = S_j + c_j phi,        S_j = sum_{i<j} c_i phi_end_i,

with a constant scale ``c_j`` per piece. For a circle of radius ``r_j`` (units of R)
``|dc/dphi| = r_j`` exactly on the unit sphere, so with ``c_j = r_j``, ``s`` is the
arc length of the contact point (units of R; equal to the contact path length on the
plane, ``2 pi n (a + b)`` for n figure eights). The pieces are numbered like the
``segment`` of :class:`rollplan.result.Trajectory`.

Joints: smooth or corner
------------------------
omega, the rotor rates and the rotors' axial spins are first order in the contact
velocity: per unit ``s'`` they are functions of s alone, ``W(s)``, ``G(s)``, ``A(s)/J_r``
below. Where ``W`` is continuous across a joint (the contact curve is C1 in s there),
a motion may pass the joint at a speed ``s' > 0``: the rates stay continuous and the
torques stay finite. Every leaf of the figure eight leaves the south pole along the
same tangent ``R_z(gamma) e_x`` and returns along it, so its joints are smooth, also
when ``a != b``; what jumps there is the geodesic curvature (``+1/a``, ``-1/b``), which
enters the torque's velocity term ``B(s)``: a motion passing a pole at ``s'`` has a
finite torque step ``(B(S_j^+) - B(S_j^-)) s'^2``. Where ``W`` jumps (a *corner*:
the tangent turns, or the speed per unit s differs on the two sides), every motion
must come to rest (``s' = 0``), or omega would jump. :class:`ContactPath` marks a
joint as a corner when the piece after it says so (``ArcLengthPiece.corner``) or when
``W`` differs on its two sides by more than :data:`SMOOTH_JOINT_RTOL` of its size.

Coefficients along s
--------------------
With ``phi' = s'/c_j``, ``phi'' = s''/c_j`` in the per-unit-phi quantities of
:func:`curve_piece_function` (omega ``phi' w``, rotor rates ``phi' g``, axial spin
momenta ``J_r phi' a`` with ``a_i = n_i . w + g_i``):

    omega            = W(s) s',                W = w / c_j                 [rad]
    rotor rates      phi_i_dot = G_i(s) s',    G = g / c_j                 [rad]
    rotor torques    tau_i = A_i(s) s'' + B_i(s) s'^2,
                     A = J_r a / c_j,   B = J_r (da/dphi) / c_j^2          [N m s^2]

where ``tau_i = J_r d/dt (n_i . omega + phi_i_dot)`` is the motor torque (derived in
:mod:`rollplan.execution.actuation`) and ``da/dphi`` the total derivative along the
piece (psi' from (30)). The state (u_a, v_a, psi) and the rotor angles
``phi_i(s) = int G_i ds`` are integrated along the pieces by CVODES (Adams: the right side is smooth and not
stiff; it takes about a third of the steps of BDF at the same tolerance, and errs less); all
functions come from :mod:`rollplan.core.model` through :func:`curve_piece_function`.

Plans of any start and goal
---------------------------
A composed plan (:mod:`rollplan.planners.geometric.composed`: approach roll, figure
eights, turns in place, legs, departure roll) and a route give their contact path as
pieces of the named curves of :data:`rollplan.core.paths.CURVES`, each traced over
``phi in [0, 2 pi]``; :meth:`ContactPath.of_plan` makes every one a :class:`ArcLengthPiece`
with ``c_j = length_j / (2 pi)`` (the leaf radius for a circle, ``|sigma_1 - sigma_0| / (2 pi)``
for a roll along a great circle), and starts the path at the plan's start state. On a piece
traced at constant speed (circles, rolls, the edges of a geodesic polygon) s is the contact arc
length; a Viviani lobe is not (``|p'(phi)|^2 = a^2 (1 - c^2 sin^2(phi/2))``), so there s is
proportional to phi, equal to the arc length at the lobe's ends and over the whole path. The joints where a
roll meets a figure eight, where the direction gamma changes between two legs or two
circles of a turn, or where a route turns back, are corners by the test on ``W`` above:
every law rests there.

Leaf families (:mod:`rollplan.core.families`, docs/design/curve-families.md): the vertices of a
figure eight of geodesic polygons are declared corners (:data:`CORNER_CURVES`; the W test finds
them too). Its pole is no corner: the edge that ends a leaf and the edge that starts the next lie
on one great circle through the pole (the leaves' edges there point along ``+-30`` degrees (triangle)
or ``+-45`` degrees (square) from the leaf's axis, mirrored by the next leaf), and the geodesic
curvature is zero on both, so ``B`` is continuous too: a polygon's figure eight is straight rolls
that stop only at the vertices. A Viviani figure eight
of equal lobes is one analytic curve through its double point, traced by phi at the same scale on
both lobes, so W and also B are continuous there: a non-stop law passes it with continuous
torques. Lobes of different sizes meet at the angle ``asin a - asin b``: a corner by the W test.
psi of the start is reduced exactly to [-pi, pi]
(:func:`rollplan.core.plane.wrap_exact`) for the integration and the whole turns are
added back to the states reported, so a start psi of any size costs no accuracy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from .. import interrupts
from ..core import families
from ..core.integrate import curve_piece_function
from ..core.paths import CURVES, family_curve
from ..core.plane import wrap_exact
from ..errors import InputError
from ..planners.geometric.composed import as_composed
from ..robot import Robot

__all__ = ["SMOOTH_JOINT_RTOL", "CORNER_CURVES", "curve_piece_function", "piece_function", "leaf_function",
           "ArcLengthPiece", "PathSample", "PathGrid", "ContactPath", "plan_pieces", "arc_length_pieces"]

#: A joint is smooth when omega per unit s' (``W``) agrees on its two sides to this fraction of its size.
SMOOTH_JOINT_RTOL = 1e-8

_CVODES = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 200000, "linear_multistep_method": "adams"}

#: Curves of :data:`rollplan.core.paths.CURVES` with vertices, and their pieces per leaf: the figure eights of the
#: geodesic polygons. Every piece of a leaf but its first starts at a vertex (a corner); at the pole the edge
#: that ends a leaf and the one that starts the next lie on one great circle (a smooth joint).
CORNER_CURVES = {family_curve(name): families.pieces_per_leaf(name) for name in families.FAMILIES
                 if families.pieces_per_leaf(name) > 1}


@lru_cache(maxsize=16)
def piece_function(curve: str, index: int) -> ca.Function:
    """:func:`curve_piece_function` of piece ``index`` of the curve named ``curve`` in
    :data:`rollplan.core.paths.CURVES` (built once)."""
    if curve not in CURVES:
        raise InputError(f"curve = {curve!r:.40} is not allowed: choose one of {', '.join(CURVES)}")
    return curve_piece_function(CURVES[curve], index)


def leaf_function(index: int) -> ca.Function:
    """:func:`piece_function` of leaf ``index`` (0: circle a, 1: circle b) of the figure eight (31), (35)."""
    return piece_function("figure_eight", index)


@dataclass(frozen=True)
class ArcLengthPiece:
    """One smooth piece of a :class:`ContactPath`, compiled for timing: the curve's function, its range and its
    arc length per unit phi (made from a plan's :class:`rollplan.core.paths.CurvePiece` by :func:`plan_pieces`).

    Attributes
    ----------
    function : casadi.Function
        Its :func:`curve_piece_function`.
    params : tuple of float
        The curve's parameters ``p`` (for the figure eight: a, b in units of R).
    gamma : float
        Rotation of the curve about OZ, eq. (31) [rad].
    phi_end : float
        The piece runs over ``phi in [0, phi_end]``.
    scale : float
        ``ds/dphi`` on the piece, constant (the arc length per unit phi for a circle: its radius) [R].
    corner : bool
        The path has a corner at the start of this piece: every timing law comes to rest there
        (ignored for the first piece, which starts at rest anyway).
    """

    function: ca.Function
    params: tuple
    gamma: float
    phi_end: float
    scale: float
    corner: bool = False


@dataclass(frozen=True)
class PathSample:
    """Path functions at given values of s (all arrays have N rows).

    Attributes
    ----------
    s : ndarray, shape (N,)
        Path parameter [R].
    segment : ndarray, shape (N,), int
        Piece the values are taken from.
    W : ndarray, shape (N, 3)
        Angular velocity of the sphere per unit s', plane frame [rad/R].
    G : ndarray, shape (N, 2)
        Rotor rates per unit s' [rad/R].
    A, B : ndarray, shape (N, 2)
        Torque coefficients of s'' and s'^2 [N m s^2 / R, N m s^2 / R^2].
    state : ndarray, shape (N, 5)
        (u_a, v_a, psi, u_o, v_o) in :class:`~rollplan.problem.State` order [R, rad].
    rotor_angles : ndarray, shape (N, 2)
        phi_1, phi_2 from the start of the path [rad].
    """

    s: np.ndarray
    segment: np.ndarray
    W: np.ndarray
    G: np.ndarray
    A: np.ndarray
    B: np.ndarray
    state: np.ndarray
    rotor_angles: np.ndarray


@dataclass(frozen=True)
class PathGrid:
    """The rotor coefficients on a grid of s, with both one-sided values at the joints.

    ``*_left[k]`` hold the limits from below ``s_k`` (the piece that ends there),
    ``*_right[k]`` from above; they differ only at joints (``B`` at every joint of the
    figure eight, ``G`` and ``A`` only at corners). At ``s = 0`` and ``s = L`` both are
    the one piece's values.

    Attributes
    ----------
    s : ndarray, shape (N + 1,)
        Nodes [R], every joint a node.
    G_left, G_right, A_left, A_right, B_left, B_right : ndarray, shape (N + 1, 2)
    joints : ndarray of int
        Node indices of the joints between pieces.
    corners : ndarray of int
        Node indices of the joints where every motion must be at rest.
    """

    s: np.ndarray
    G_left: np.ndarray
    G_right: np.ndarray
    A_left: np.ndarray
    A_right: np.ndarray
    B_left: np.ndarray
    B_right: np.ndarray
    joints: np.ndarray
    corners: np.ndarray

    @property
    def size(self) -> int:
        return self.s.size


class ContactPath:
    """A contact path along its path parameter s, with the robot's rotor coefficients (see the module docstring).

    It satisfies :class:`rollplan.execution.timing.TimingPath`, what a timing law needs.

    Parameters
    ----------
    pieces : sequence of ArcLengthPiece
    robot : Robot
    start : (u_a, v_a, psi)
        State at the start of the path [R, rad] (psi of any size, module docstring).

    Attributes
    ----------
    pieces : tuple of ArcLengthPiece
    robot : Robot
    starts : ndarray, shape (P + 1,)
        s at the start of every piece, and the length L at the end [R].
    length : float
        L [R].
    corners : ndarray, shape (P - 1,), bool
        For every joint ``starts[1:-1]``: must every motion be at rest there.
    """

    def __init__(self, pieces, robot: Robot, start=(0.0, 0.0, 0.0)):
        if not isinstance(robot, Robot):
            raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
        self.pieces = tuple(pieces)
        if not self.pieces:
            raise InputError("a contact path needs at least one piece")
        self.robot = robot
        lengths = np.array([p.scale * p.phi_end for p in self.pieces], float)
        if not np.all(np.isfinite(lengths) & (lengths > 0)):
            raise InputError("every piece of a contact path needs a finite phi_end > 0 and scale > 0")
        self.starts = np.concatenate([[0.0], np.cumsum(lengths)])
        self.length = float(self.starts[-1])
        self._odes: dict = {}
        x = np.concatenate([np.asarray(start, float), [0.0, 0.0]])
        if x.shape != (5,) or not np.all(np.isfinite(x)):
            raise InputError(f"start = {start!r:.60} is not allowed: give three finite numbers (u_a, v_a, psi)")
        x[2], self._turns = wrap_exact(x[2])   # integrate psi reduced; report it as given (module docstring)
        x0 = [x]
        for j, piece in enumerate(self.pieces):
            x = self._integrate(j, x, np.array([piece.phi_end]))[-1]
            x0.append(x)
        self._x0 = np.array(x0)
        joints = self.starts[1:-1]
        if joints.size:
            left, right = self.evaluate(joints, "left"), self.evaluate(joints, "right")
            size = np.maximum(np.abs(left.W).max(axis=1), np.abs(right.W).max(axis=1))
            jump = np.abs(left.W - right.W).max(axis=1) > SMOOTH_JOINT_RTOL * np.maximum(size, 1e-300)
            declared = np.array([p.corner for p in self.pieces[1:]], bool)
            self.corners = declared | jump
        else:
            self.corners = np.zeros(0, bool)

    @classmethod
    def of_plan(cls, plan, robot: Robot) -> ContactPath:
        """The path of a plan from its start state: its pieces along the contact arc length s.

        Parameters
        ----------
        plan : Plan, ComposedPlan or Route
            A geometric-phase plan (:mod:`rollplan.planners.geometric`), made for this robot (same k
            and radius), with at least one piece (see :func:`plan_pieces`).
        robot : Robot
        """
        pieces, start = plan_pieces(plan, robot)
        if not pieces:
            raise InputError("the plan is the empty motion (its start is its goal): it has no contact path")
        return cls(pieces, robot, start)

    @classmethod
    def of_pieces(cls, pieces, robot: Robot, start=(0.0, 0.0, 0.0)) -> ContactPath:
        """The path of a sequence of :class:`rollplan.core.paths.CurvePiece` (units of R) from ``start``
        ``(u_a, v_a, psi)`` [R, rad], e.g. ``figure_eight_pieces(a, b, gamma, n, family=NAME)``."""
        if not isinstance(robot, Robot):
            raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
        return cls(arc_length_pieces(pieces), robot, start)

    # ------------------------------------------------------------------ internals
    def _parameters(self, piece: ArcLengthPiece) -> np.ndarray:
        r = self.robot
        return np.concatenate([np.asarray(piece.params, float),
                               [piece.gamma, r.k, r.j_xx, r.j_zz, r.rotor_inertia_axial]])

    def _ode(self, piece: ArcLengthPiece) -> dict:
        """The 5-state ODE in phi along a piece: (u_a, v_a, psi, rotor angle 1, rotor angle 2)."""
        f = piece.function
        if id(f) not in self._odes:
            phi = ca.SX.sym("phi")
            x = ca.SX.sym("x", 5)
            n = f.size1_in(2)
            par = ca.SX.sym("par", n + 5)  # p, gamma, k, jxx, jzz, jr
            xdot = f(phi, x[2], par[:n], par[n], par[n + 1], par[n + 2], par[n + 3], par[n + 4])[0]
            self._odes[id(f)] = {"t": phi, "x": x, "p": par, "ode": xdot}
        return self._odes[id(f)]

    def _integrate(self, j: int, x0: np.ndarray, phis: np.ndarray) -> np.ndarray:
        """States at increasing ``phis`` (>= 0) along piece j from ``x0`` at phi = 0: shape (len, 5)."""
        out = np.empty((phis.size, 5))
        pos = phis > 0
        out[~pos] = x0
        if pos.any():
            piece = self.pieces[j]
            integ = ca.integrator(f"path{j}", "cvodes", self._ode(piece), 0.0, list(phis[pos]), _CVODES)
            out[pos] = np.array(interrupts.call(integ, x0=x0, p=self._parameters(piece))["xf"]).T
        return out

    def _states(self, j: int, phis: np.ndarray) -> np.ndarray:
        """States at increasing ``phis`` along piece j: at its ends those of the construction (the same on both
        sides of a joint, no integration), in between integrated from its start."""
        out = np.empty((phis.size, 5))
        end = phis >= self.pieces[j].phi_end
        out[end] = self._x0[j + 1]
        out[~end] = self._integrate(j, self._x0[j], phis[~end])
        return out

    # ------------------------------------------------------------------ public
    @property
    def joints(self) -> np.ndarray:
        """s at the joints between pieces [R]."""
        return self.starts[1:-1]

    def segment_of(self, s, side: str = "left") -> np.ndarray:
        """Piece index of each s; at a joint ``side`` picks the piece that ends (left) or starts (right) there."""
        return np.searchsorted(self.joints, np.asarray(s, float), side=side).astype(int)

    def evaluate(self, s, side: str = "left") -> PathSample:
        """All path functions at the values ``s`` (any order, within [0, L]).

        Parameters
        ----------
        s : array_like, shape (N,)
            Path parameter [R]; values within 1e-12 L outside [0, L] are clipped, values within 1e-12 L of
            a joint are taken at the joint.
        side : {"left", "right"}
            Which one-sided value to return at a joint (``B`` jumps at every pole of the figure eight).
        """
        if side not in ("left", "right"):
            raise InputError(f"side = {side!r} is not allowed: choose 'left' or 'right'")
        s = np.atleast_1d(np.asarray(s, float))
        tol = 1e-12 * self.length
        if not np.all(np.isfinite(s)) or np.any(s < -tol) or np.any(s > self.length + tol):
            raise InputError(f"path parameter s outside [0, {self.length:g}]")
        s = np.clip(s, 0.0, self.length)
        for sj in self.joints:
            s = np.where(np.abs(s - sj) <= tol, sj, s)
        seg = self.segment_of(s, side)
        n = s.size
        W, G, A, B = np.empty((n, 3)), np.empty((n, 2)), np.empty((n, 2)), np.empty((n, 2))
        state, angles = np.empty((n, 5)), np.empty((n, 2))
        jr = self.robot.rotor_inertia_axial
        for j in np.unique(seg):
            piece = self.pieces[j]
            c = piece.scale
            sel = np.nonzero(seg == j)[0]
            phi = np.where(s[sel] >= self.starts[j + 1], piece.phi_end,
                           np.clip((s[sel] - self.starts[j]) / c, 0.0, piece.phi_end))
            order = np.argsort(phi, kind="stable")
            uq, inv = np.unique(phi[order], return_inverse=True)
            xs = self._states(j, uq)
            p = self._parameters(piece)
            m = len(piece.params)
            # CasADi's evaluation and its conversion to arrays (a Ctrl-C during it: KeyboardInterrupt, not an error)
            uv, w, g, a, da = (v[inv] for v in interrupts.call(_piece_values, piece.function, uq, xs[:, 2], p, m))
            rows = sel[order]
            x = xs[inv]
            W[rows], G[rows], A[rows], B[rows] = w / c, g / c, jr * a / c, jr * da / c**2
            state[rows] = np.column_stack([x[:, 0], x[:, 1], x[:, 2] + 2 * np.pi * self._turns, uv])
            angles[rows] = x[:, 3:5]
        return PathSample(s, seg, W, G, A, B, state, angles)

    def stretches(self) -> list:
        """The path cut at its corners: one :class:`ContactPath` per stretch between corners (the path itself
        when it has none), each starting at the state where the previous one ends."""
        cuts = [0, *(np.nonzero(self.corners)[0] + 1), len(self.pieces)]
        if len(cuts) == 2:
            return [self]
        out = []
        for i, j in zip(cuts[:-1], cuts[1:]):
            start = self._x0[i, :3] + np.array([0.0, 0.0, 2 * np.pi * self._turns])
            out.append(ContactPath(self.pieces[i:j], self.robot, start))
        return out

    def continuous_passages(self) -> np.ndarray:
        """For every joint: can a motion pass it at a speed ``s' > 0`` with both torques continuous?

        Not at a corner. At a smooth joint the torques ``A s'' + B s'^2`` stay continuous iff one step of s''
        cancels the step of ``B`` for both rotors: ``A_i ds'' + dB_i s'^2 = 0``, i.e. ``dB = 0`` (to
        :data:`SMOOTH_JOINT_RTOL` of the path's largest ``|B|``) or ``dB`` parallel to ``A``.
        """
        joints = self.joints
        if not joints.size:
            return np.zeros(0, bool)
        left, right = self.evaluate(joints, "left"), self.evaluate(joints, "right")
        grid = self.grid(8 * len(self.pieces))
        scale = max(float(np.abs(grid.B_left).max()), float(np.abs(grid.B_right).max()), 1e-300)
        dB = right.B - left.B
        size = np.linalg.norm(dB, axis=1)
        cross = np.abs(dB[:, 0] * left.A[:, 1] - dB[:, 1] * left.A[:, 0])
        parallel = cross <= SMOOTH_JOINT_RTOL * size * np.linalg.norm(left.A, axis=1)
        return ~self.corners & ((size <= SMOOTH_JOINT_RTOL * scale) | parallel)

    @property
    def nonstop_continuous(self) -> bool:
        """A non-stop timing with continuous torques exists: no corner, and every joint passable with continuous
        torques (:meth:`continuous_passages`; then ``nonstop-min-jerk`` is one when ``B`` is continuous)."""
        return bool(np.all(self.continuous_passages()))

    def coefficients(self, s, side: str = "left"):
        """``(G, A, B)`` at the values ``s`` (see :meth:`evaluate`)."""
        ps = self.evaluate(s, side)
        return ps.G, ps.A, ps.B

    def grid(self, n: int) -> PathGrid:
        """A grid of about ``n`` intervals, uniform within each piece, every joint a node.

        Piece j gets ``max(4, round(n L_j / L))`` intervals.
        """
        lengths = np.diff(self.starts)
        counts = np.maximum(4, np.round(n * lengths / self.length)).astype(int)
        nodes = [np.linspace(self.starts[j], self.starts[j + 1], c + 1)[:-1] for j, c in enumerate(counts)]
        s = np.concatenate([*nodes, [self.length]])
        joints = np.cumsum(counts)[:-1]
        left = self.evaluate(s, "left")
        right = [left.G.copy(), left.A.copy(), left.B.copy()]
        if joints.size:
            r = self.evaluate(s[joints], "right")
            for arr, val in zip(right, (r.G, r.A, r.B)):
                arr[joints] = val
        # s = 0 belongs to the first piece only: its right value is the one evaluated
        return PathGrid(s, left.G, right[0], left.A, right[1], left.B, right[2], joints, joints[self.corners])

    @property
    def final_state(self) -> np.ndarray:
        """(u_a, v_a, psi, rotor angle 1, rotor angle 2) at the end of the path, by CVODES [R, rad]."""
        out = self._x0[-1].copy()
        out[2] += 2 * np.pi * self._turns
        return out


def _piece_values(function: ca.Function, phi: np.ndarray, psi: np.ndarray, p: np.ndarray, m: int) -> list:
    """A piece's function at every ``phi`` (with its ``psi``) as arrays, one row a point: u_o v_o, w, g, a, da."""
    out = function.map(phi.size)(phi[None, :], psi[None, :], p[:m], *p[m:])
    return [np.array(out[i]).T for i in (1, 2, 3, 4, 5)]


def plan_pieces(plan, robot: Robot) -> tuple[list, tuple]:
    """The pieces of a plan's contact path as :class:`ArcLengthPiece` objects, and its start ``(u_a, v_a, psi)``
    [R, rad].

    Every piece of :func:`rollplan.planners.geometric.as_composed` (leaves, rolls, circles of a
    turn, legs; a route's legs one after the other) becomes a piece over ``phi in [0, 2 pi]``
    with the scale ``length / (2 pi)`` (module docstring); no integration is done. The empty
    motion (start = goal) has no pieces.

    Raises
    ------
    InputError
        Not a geometric-phase plan, not a Robot, or a plan made for another k or radius.
    """
    if getattr(plan, "method", None) != "geometric" or not all(hasattr(plan, n) for n in ("k", "radius", "problem")):
        raise InputError(f"plan = {plan!r:.60} is not allowed: timing needs a geometric-phase plan (rollplan.plan)")
    if not isinstance(robot, Robot):
        raise InputError(f"robot = {robot!r:.60} is not allowed: give a rollplan.Robot")
    if not math.isclose(plan.k, robot.k, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan was made for k = {plan.k:.12g}, the robot has k = {robot.k:.12g}: "
                         "plan with this robot")
    if not math.isclose(plan.radius, robot.radius, rel_tol=1e-12, abs_tol=0.0):
        raise InputError(f"the plan's radius = {plan.radius!r} differs from the robot's radius = {robot.radius!r}")
    composed = as_composed(plan)
    start = composed.problem.scaled(composed.problem.start)
    return arc_length_pieces(composed.pieces), (start.u_a, start.v_a, start.psi)


def arc_length_pieces(pieces) -> list:
    """:class:`ArcLengthPiece` objects of :class:`rollplan.core.paths.CurvePiece` objects: each over
    ``phi in [0, 2 pi]`` with the scale ``length / (2 pi)``; a piece of a polygon's figure eight
    (:data:`CORNER_CURVES`) that starts at a vertex is declared a corner."""
    return [ArcLengthPiece(piece_function(p.curve, p.index), tuple(float(v) for v in p.params), float(p.gamma),
                           2 * np.pi, p.length / (2 * np.pi), p.index % CORNER_CURVES.get(p.curve, 1) != 0)
            for p in pieces]
