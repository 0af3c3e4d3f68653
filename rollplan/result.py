"""What every planner returns: the result protocol, its certificate and the one trajectory type.

A plan of any method (see :mod:`rollplan.planners`) satisfies :class:`PlanResult`:
it names its :class:`~rollplan.problem.Problem`, carries a :class:`Certificate`
(an independent integration of the whole motion from the start state and its
residual to the goal), solver statistics (:class:`SolverStats`), its contact
path length, and samples itself as a :class:`Trajectory`. :func:`certify` makes every certificate.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol, runtime_checkable

import numpy as np

from .core import model
from .errors import InputError, NoPlanError, check_whole
from .problem import STATE_NAMES, Problem, State

__all__ = ["CERTIFICATE_TOLERANCE", "DEFAULT_SAMPLES", "Certificate", "SolverStats", "Trajectory", "Measures",
           "CertifiedMotion", "PlanResult", "certify", "require_certified"]

#: Largest accepted ``residual + error_bound`` of a plan's certificate, lengths in units of R and angles in
#: rad (:func:`rollplan.problem.arrival_residual`): every planner's default, the generated C planner's too.
CERTIFICATE_TOLERANCE = 1e-9
#: Samples of ``result.sample()`` when none are asked for: in all, over the whole motion.
DEFAULT_SAMPLES = 2000


@dataclass(frozen=True)
class Certificate:
    """An independent check of a whole motion: integrated from the start state, compared with the goal.

    Attributes
    ----------
    method : str
        The integrator that produced ``final`` (e.g. ``"cvodes"``).
    final : State
        Final state of that integration [length unit, rad].
    residual : float
        :func:`rollplan.problem.arrival_residual` of ``final`` to the goal (lengths
        in units of R, psi wrapped, u_o and v_o in rad).
    error_bound : float
        Estimated bound on the integration error of ``final`` (0 when the
        integrator gives none; it is then run at tolerances far below ``tolerance``).
    tolerance : float
        Largest accepted ``residual + error_bound``.
    """

    method: str
    final: State
    residual: float
    error_bound: float
    tolerance: float

    @property
    def passed(self) -> bool:
        """True when ``residual + error_bound <= tolerance``."""
        return bool(self.residual + self.error_bound <= self.tolerance)

    def as_dict(self) -> dict:
        return {"method": self.method, "residual": self.residual, "error_bound": self.error_bound,
                "tolerance": self.tolerance}


@dataclass(frozen=True)
class SolverStats:
    """How a plan was found.

    Attributes
    ----------
    method : str
        Name of the solver (e.g. ``"ipopt"``, ``"newton"``).
    status : str
        The solver's return status for the returned plan.
    iterations : int
        Its iterations.
    time_s : float
        Wall time of the whole solve, certification included [s].
    details : dict
        Method-specific counts and timings (JSON-serializable numbers and strings).
    """

    method: str
    status: str
    iterations: int
    time_s: float
    details: dict = field(default_factory=dict)

    def as_dict(self) -> dict:
        return {"method": self.method, "status": self.status, "iterations": self.iterations,
                "time_s": self.time_s, **self.details}


@dataclass(frozen=True)
class Trajectory:
    """A motion sampled along its path: the one trajectory type of rollplan.

    Attributes
    ----------
    s : ndarray, shape (N,)
        Path parameter of each sample: the curve parameter theta [rad] of a
        geometric-phase plan (one step is 2 pi; in a composed plan or a route every
        piece of the contact path, a leaf or a roll, spans pi) or the time t [s];
        see ``parameter``.
    state : ndarray, shape (N, 5)
        States in :class:`~rollplan.problem.State` order (u_a, v_a, psi, u_o, v_o)
        [length unit, rad].
    segment : ndarray, shape (N,), int
        Piece of the contact path each sample lies on, counted from 0 (a new
        number wherever the contact path changes piece, e.g. each leaf of a
        figure eight); a sample at a joint belongs to the piece that ends there.
    radius : float
        Sphere radius [length unit].
    parameter : str
        ``"theta"`` or ``"t"``: what ``s`` is.
    """

    s: np.ndarray
    state: np.ndarray
    segment: np.ndarray
    radius: float = 1.0
    parameter: str = "theta"

    @property
    def u_a(self) -> np.ndarray:
        return self.state[:, 0]

    @property
    def v_a(self) -> np.ndarray:
        return self.state[:, 1]

    @property
    def psi(self) -> np.ndarray:
        return self.state[:, 2]

    @property
    def u_o(self) -> np.ndarray:
        return self.state[:, 3]

    @property
    def v_o(self) -> np.ndarray:
        return self.state[:, 4]

    @property
    def contact(self) -> np.ndarray:
        """Contact point on the sphere in the body frame, eq. (1), shape (N, 3) [length unit]."""
        return model.contact_points(self.u_o, self.v_o) * self.radius

    def path_length(self) -> float:
        """Length of the sampled contact path on the plane (polyline) [length unit]."""
        return float(np.hypot(np.diff(self.u_a), np.diff(self.v_a)).sum())

    def subsampled(self, samples: int) -> Trajectory:
        """``samples`` of these samples, evenly by index, the first and the last included (no interpolation:
        every sample stays one of the integration's). InputError if there are fewer than ``samples``."""
        n = self.s.size
        samples = check_whole("samples", samples, min(2, n), n)
        idx = np.unique(np.round(np.linspace(0, n - 1, samples)).astype(int))
        return Trajectory(self.s[idx], self.state[idx], self.segment[idx], self.radius, self.parameter)

    def as_dict(self) -> dict:
        """Columns as lists: the parameter (``theta`` or ``t``), the state names and ``segment``."""
        d = {self.parameter: [float(v) for v in self.s]}
        d.update({n: [float(v) for v in self.state[:, i]] for i, n in enumerate(STATE_NAMES)})
        d["segment"] = [int(v) for v in self.segment]
        return d


@dataclass(frozen=True)
class Measures:
    """What a motion costs, measured along it.

    Attributes
    ----------
    path_length : float
        Contact path length [length unit].
    effort : float
        Angular-velocity energy ``int |omega|^2 dt`` [rad^2/s].
    rotor_effort : float
        ``int |phi_dot|^2 dt`` [rad^2/s]; nan without a robot.
    peak_omega : float
        Largest ``|omega|`` on the certification grid [rad/s].
    """

    path_length: float
    effort: float
    rotor_effort: float
    peak_omega: float



class CertifiedMotion:
    """Base of the planners' results: what follows from their ``problem`` and ``certificate`` fields."""

    @property
    def final(self) -> State:
        """Certified final state [length unit, rad]."""
        return self.certificate.final

    @property
    def residual(self) -> float:
        """Certified residual to the goal (units of R and rad)."""
        return self.certificate.residual

    @property
    def goal(self) -> State:
        return self.problem.goal

    @property
    def k(self) -> float:
        return self.problem.k

    @property
    def radius(self) -> float:
        return self.problem.radius


@runtime_checkable
class PlanResult(Protocol):
    """The protocol every planner's result satisfies.

    Attributes
    ----------
    problem : Problem
        What was solved.
    method : str
        The planner's name in :data:`rollplan.planners.METHODS`.
    certificate : Certificate
        Independent integration of the whole motion and its residual to the goal.
    stats : SolverStats
    path_length : float
        Length of the contact path on the plane (= on the sphere) [length unit].
    final : State
        ``certificate.final``.
    residual : float
        ``certificate.residual``.
    pieces : tuple
        The contact path piece by piece (leaves, rolls, circles) [units of R]; ``()`` for a motion that is not
        made of closed-form pieces (collocation).
    legs : tuple of Plan
        The legs of figure eights in the motion (a one-leg plan is its own only leg); ``()`` for collocation.
    alternatives : tuple
        Other certified solutions, best first (``()`` unless asked for, e.g. ``all_solutions``).
    """

    problem: Problem
    method: str
    certificate: Certificate
    stats: SolverStats
    path_length: float
    alternatives: tuple

    @property
    def pieces(self) -> tuple: ...

    @property
    def legs(self) -> tuple: ...

    @property
    def final(self) -> State: ...

    @property
    def residual(self) -> float: ...

    def sample(self, samples: int = DEFAULT_SAMPLES) -> Trajectory:
        """The motion sampled as a :class:`Trajectory`: ``samples`` samples in all, both ends included."""
        ...


def certify(problem: Problem | None, final, integrator: str, *, error_bound: float = 0.0,
            tolerance: float = CERTIFICATE_TOLERANCE, residual: float | None = None) -> Certificate:
    """The certificate of a motion of ``problem`` whose independent integration ``integrator`` ended at ``final``
    [length unit of the problem, rad]: its residual to the goal (:meth:`Problem.residual`, or ``residual`` when
    the caller measures it itself, e.g. in a frame with psi reduced, with the end rates of a rest-to-rest
    motion, or for a motion without a Problem), the integration's ``error_bound`` and the accepted
    ``tolerance``. Every method, and the rotor-only check of a timed motion, makes its certificate here."""
    final = State(*(float(v) for v in final))
    if residual is None and problem is None:
        raise InputError("certify needs the problem or the residual")
    residual = problem.residual(final) if residual is None else float(residual)
    return Certificate(integrator, final, residual, float(error_bound), float(tolerance))


def require_certified(result, where: str = ""):
    """``result`` if its certificate (and every alternative's) has passed; NoPlanError naming the residual
    otherwise: no method returns a plan above its tolerance."""
    for r in (result, *getattr(result, "alternatives", ())):
        c = r.certificate
        if not c.passed:
            raise NoPlanError(f"no certified plan{' for ' + where if where else ''}: the certified residual plus "
                              f"error bound {c.residual + c.error_bound:.2e} exceeds {c.tolerance:.0e}")
    return result
