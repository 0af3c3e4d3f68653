"""Geometric-phase plan versus direct-collocation optimum on the same target.

Both motions are measured the same way on the same horizon ``T``:

* contact path length ``int |v| dt`` [length unit] (the plan's ``2 pi n (a + b)``;
  the collocation's from its CVODES verification);
* effort: the angular-velocity energy ``int |omega|^2 dt`` [rad^2/s], omega from
  (18), (19) and (13), or, with a robot, the rotor effort
  ``int (phi1_dot^2 + phi2_dot^2) dt`` with the rotor rates of (11);
* peak ``|omega|`` [rad/s], the verified residual, solve time, iterations.

The geometric-phase plan has no time of its own: it is timed with ``t``
proportional to the curve parameter theta, ``t = T theta / (2 pi n)``, which
traces each circle of the figure eight at constant speed. Its angular velocity
is computed exactly along the CVODES samples of the plan: the contact rates are
the derivatives of (24)-(25) along the rotated circles (31) (automatic
differentiation, as in (27)), times ``d phi / dt = 4 pi n / T``, and omega is
:func:`rollplan.model.realizable_omega`; the integrals use Simpson's rule on
each circle, where the integrand is smooth.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from . import model
from .collocation import CONTACT_BOUND, CollocationResult, collocate
from .curves import figure_eight, rotated_point
from .geometric import Plan, plan as gp_plan
from .robot import Robot

__all__ = ["PlannerSummary", "Comparison", "compare", "summarize_plan", "summarize_collocation",
           "comparison_to_dict"]

TRAJECTORY_KEYS = ("t", "u_o", "v_o", "u_a", "v_a", "psi")


@dataclass(frozen=True)
class PlannerSummary:
    """One planner's motion, measured for the comparison.

    Attributes
    ----------
    name : str
        ``"geometric_phase"`` or ``"collocation"``.
    path_length : float
        Contact path length [length unit].
    effort : float
        ``int |omega|^2 dt`` without a robot, ``int |phi_dot|^2 dt`` with one [rad^2/s].
    effort_kind : str
        ``"angular_velocity"`` or ``"rotor"``.
    angular_velocity_energy : float
        ``int |omega|^2 dt`` [rad^2/s] (always).
    peak_omega : float
        Largest ``|omega|`` [rad/s].
    residual : float
        Verified residual to the target (lengths over R, psi wrapped).
    solve_time_s : float
        Planner wall time [s] (collocation: the IPOPT call only).
    iterations : int
        Solver iterations (geometric phase: of the chosen branch's root solve).
    status : str
        Solver status.
    t, u_o, v_o, u_a, v_a, psi : ndarray, shape (M,)
        The motion sampled on M >= 1000 points [s, rad, length unit, rad].
    contact : ndarray, shape (M, 3)
        Contact point on the sphere in the body frame [length unit].
    """

    name: str
    path_length: float
    effort: float
    effort_kind: str
    angular_velocity_energy: float
    peak_omega: float
    residual: float
    solve_time_s: float
    iterations: int
    status: str
    t: np.ndarray
    u_o: np.ndarray
    v_o: np.ndarray
    u_a: np.ndarray
    v_a: np.ndarray
    psi: np.ndarray
    contact: np.ndarray


@dataclass(frozen=True)
class Comparison:
    """Both planners on one target.

    Attributes
    ----------
    target : tuple of 3 float
        (u_a, v_a) [length unit], psi [rad].
    k, radius, horizon : float
        Inertia ratio, sphere radius [length unit], T [s].
    steps : int
        Traces of the figure eight.
    geometric_phase, collocation : PlannerSummary
    plan : Plan
    result : CollocationResult
    """

    target: tuple
    k: float
    radius: float
    horizon: float
    steps: int
    geometric_phase: PlannerSummary
    collocation: PlannerSummary
    plan: Plan
    result: CollocationResult


def _simpson(y, dx):
    """Composite Simpson rule on an odd number of uniform samples."""
    return dx / 3.0 * (y[0] + y[-1] + 4.0 * y[1:-1:2].sum() + 2.0 * y[2:-1:2].sum())


def _leaf_omega_functions():
    """Per circle of the figure eight: (phi, ab, gamma, psi, k, phi_rate) -> omega (3,)."""
    curve = figure_eight()
    out = []
    for piece in curve.pieces:
        phi = ca.SX.sym("phi")
        ab = ca.SX.sym("ab", 2)
        gamma, psi, k, rate = (ca.SX.sym(n) for n in ("gamma", "psi", "k", "rate"))
        u_o, v_o = model.contact_coordinates(rotated_point(piece, phi, ab, gamma))
        du = ca.jacobian(u_o, phi) * rate
        dv = ca.jacobian(v_o, phi) * rate
        w = model.realizable_omega(u_o, v_o, psi, du, dv, k)
        out.append(ca.Function("leaf_omega", [phi, ab, gamma, psi, k, rate], [w]))
    return out


def summarize_plan(p: Plan, horizon: float = 1.0, robot: Robot | None = None,
                   samples_per_leaf: int = 500) -> PlannerSummary:
    """Measure a geometric-phase plan timed by ``t = T theta / (2 pi n)`` (see module doc)."""
    m = samples_per_leaf + (samples_per_leaf % 2)  # even: Simpson on m + 1 points
    tr = p.trajectory(m)
    R = p.radius
    ab = np.array([p.a, p.b]) / R
    rate = 4.0 * math.pi * p.steps / horizon
    funcs = _leaf_omega_functions()
    dt = horizon / (2 * p.steps) / m  # each circle takes T / (2 n)
    energy = rotor = 0.0
    peak = 0.0
    phi = np.linspace(0.0, 2.0 * math.pi, m + 1)
    rot_fn = None
    if robot is not None:
        w = ca.SX.sym("w", 3)
        uo, vo, ps = ca.SX.sym("uo"), ca.SX.sym("vo"), ca.SX.sym("ps")
        rot_fn = ca.Function("rot", [w, uo, vo, ps], [model.rotor_rates(w, uo, vo, ps, robot.j_xx, robot.j_zz,
                                                                           robot.rotor_inertia_axial)])
    for j in range(2 * p.steps):
        sl = slice(j * m, (j + 1) * m + 1)  # samples of this circle, including its start
        psi = tr.psi[sl]
        om = np.array(funcs[j % 2].map(m + 1)(phi[None, :], ab, p.gamma, psi[None, :], p.k, rate)).T
        sq = (om ** 2).sum(axis=1)
        energy += _simpson(sq, dt)
        peak = max(peak, float(np.sqrt(sq.max())))
        if rot_fn is not None:
            ph = np.array(rot_fn.map(m + 1)(om.T, tr.u_o[sl][None, :], tr.v_o[sl][None, :], psi[None, :])).T
            rotor += _simpson((ph ** 2).sum(axis=1), dt)
    t = horizon * tr.theta / tr.theta[-1]
    effort, kind = (rotor, "rotor") if robot is not None else (energy, "angular_velocity")
    return PlannerSummary("geometric_phase", p.path_length, float(effort), kind, float(energy), peak, p.residual,
                          p.stats.time_s, p.stats.iterations, p.stats.status, t, tr.u_o, tr.v_o, tr.u_a, tr.v_a,
                          tr.psi, tr.contact)


def summarize_collocation(r: CollocationResult, robot: Robot | None = None) -> PlannerSummary:
    """Measure a collocation result (all numbers from its CVODES verification)."""
    tr = r.trajectory
    effort, kind = (r.rotor_effort, "rotor") if robot is not None else (r.effort, "angular_velocity")
    return PlannerSummary("collocation", r.path_length, float(effort), kind, r.effort, r.peak_omega, r.residual,
                          r.stats.solve_time_s, r.stats.iterations, r.stats.status, tr.t, tr.u_o, tr.v_o, tr.u_a,
                          tr.v_a, tr.psi, tr.contact)


def compare(target, steps: int = 1, k: float | None = None, robot: Robot | None = None,
            radius: float | None = None, horizon: float = 1.0, cost: str = "path_length", intervals: int = 100,
            degree: int = 3, scheme: str = "legendre", guess: str = "warm",
            contact_bound: float = CONTACT_BOUND) -> Comparison:
    """Plan by geometric phase (:func:`rollplan.plan`) and by collocation, and measure both.

    The collocation is warm-started from the same plan when ``guess="warm"``,
    and steers psi to the plan's final psi (same orientation, ``turns`` = its branch).

    Raises
    ------
    InputError, NoPlanError, SolverError
    """
    p = gp_plan(tuple(target), steps, k=None if robot is not None else k, robot=robot, radius=radius)
    g = p if guess == "warm" else guess
    r = collocate(target, k=None if robot is not None else k, robot=robot, radius=radius, cost=cost,
                  intervals=intervals, degree=degree, scheme=scheme, horizon=horizon, guess=g, steps=steps,
                  turns=p.branch, contact_bound=contact_bound)
    return Comparison((float(target[0]), float(target[1]), float(target[2])), p.k, p.radius, float(horizon),
                      p.steps, summarize_plan(p, horizon, robot), summarize_collocation(r, robot), p, r)


def _summary_dict(s: PlannerSummary) -> dict:
    f = lambda a: [float(x) for x in np.asarray(a).ravel()]
    return {"path_length": s.path_length, "effort": s.effort, "effort_kind": s.effort_kind,
            "angular_velocity_energy": s.angular_velocity_energy, "peak_omega": s.peak_omega,
            "residual": s.residual, "solve_time_s": s.solve_time_s, "iterations": s.iterations,
            "status": s.status, "trajectory": {key: f(getattr(s, key)) for key in TRAJECTORY_KEYS}}


def comparison_to_dict(c: Comparison) -> dict:
    """The JSON object of ``rollplan compare --json``."""
    r = c.result
    d = {"target": {"u_a": c.target[0], "v_a": c.target[1], "psi": c.target[2]}, "k": c.k, "radius": c.radius,
         "horizon": c.horizon, "steps": c.steps,
         "geometric_phase": _summary_dict(c.geometric_phase), "collocation": _summary_dict(c.collocation)}
    d["geometric_phase"].update({"figure_eight": {"a": c.plan.a, "b": c.plan.b, "gamma": c.plan.gamma},
                                 "branch": c.plan.branch})
    d["collocation"].update({"cost": r.cost, "objective": r.objective, "scheme": r.scheme, "degree": r.degree,
                             "intervals": r.intervals, "guess": r.guess, "turns": r.turns,
                             "guess_time_s": r.stats.guess_time_s, "verify_time_s": r.stats.verify_time_s,
                             "max_defect": r.max_defect, "contact_bound": r.contact_bound})
    return d
