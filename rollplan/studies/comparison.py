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
is computed exactly along the CVODES samples of the plan
(:func:`rollplan.core.model.curve_omega` along the rotated circles (31), times
``d phi / dt = 4 pi n / T``); the integrals use Simpson's rule on each circle,
where the integrand is smooth. Both sides are results of one
:class:`~rollplan.problem.Problem` (:class:`~rollplan.result.PlanResult`),
measured as :class:`~rollplan.result.Measures` with a timed
:class:`~rollplan.result.Trajectory`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from functools import lru_cache

import casadi as ca
import numpy as np

from ..core import model
from ..core.curves import figure_eight, rotated_point
from ..planners.collocation import CONTACT_BOUND, CollocationResult, collocate
from ..planners.geometric import Plan
from ..planners.geometric import plan as gp_plan
from ..problem import Problem
from ..result import Measures, Trajectory
from ..robot import Robot

__all__ = ["Comparison", "compare", "measure_plan", "comparison_series", "comparison_to_dict"]

TRAJECTORY_KEYS = ("t", "u_o", "v_o", "u_a", "v_a", "psi")


@dataclass(frozen=True)
class Comparison:
    """Both planners on one problem.

    Attributes
    ----------
    problem : Problem
    horizon : float
        T [s] of both motions.
    plan : Plan
        The geometric-phase plan.
    result : CollocationResult
        The collocation optimum.
    plan_measures : Measures
        The plan timed by ``t = T theta / (2 pi n)`` (module docstring).
    plan_trajectory : Trajectory
        The plan's samples on that time law (``parameter == "t"``).
    effort_kind : str
        ``"angular_velocity"`` (``int |omega|^2 dt``) or, with a robot, ``"rotor"``
        (``int |phi_dot|^2 dt``): the effort compared.
    """

    problem: Problem
    horizon: float
    plan: Plan
    result: CollocationResult
    plan_measures: Measures
    plan_trajectory: Trajectory
    effort_kind: str

    def effort(self, measures: Measures) -> float:
        """The compared effort of one side's measures."""
        return measures.rotor_effort if self.effort_kind == "rotor" else measures.effort


def _simpson(y, dx):
    """Composite Simpson rule on an odd number of uniform samples."""
    return dx / 3.0 * (y[0] + y[-1] + 4.0 * y[1:-1:2].sum() + 2.0 * y[2:-1:2].sum())


@lru_cache(maxsize=1)
def _leaf_omega_functions():
    """Per circle of the figure eight: (phi, ab, gamma, psi, k, phi_rate) -> omega (3,)."""
    out = []
    for piece in figure_eight().pieces:
        phi = ca.SX.sym("phi")
        ab = ca.SX.sym("ab", 2)
        gamma, psi, k, rate = (ca.SX.sym(n) for n in ("gamma", "psi", "k", "rate"))
        w, _, _ = model.curve_omega(rotated_point(piece, phi, ab, gamma), phi, psi, k)
        out.append(ca.Function("leaf_omega", [phi, ab, gamma, psi, k, rate], [w * rate]))
    return out


@lru_cache(maxsize=4)
def _rotor_rate_function(jxx: float, jzz: float, jr: float) -> ca.Function:
    """``(omega[3], u_o, v_o, psi) -> rotor rates[2]`` of (11) for one robot's inertias."""
    w = ca.SX.sym("w", 3)
    uo, vo, ps = ca.SX.sym("uo"), ca.SX.sym("vo"), ca.SX.sym("ps")
    return ca.Function("rot", [w, uo, vo, ps], [model.rotor_rates(w, uo, vo, ps, jxx, jzz, jr)])


def _rotor_rates_along(robot: Robot, omega, traj, rows) -> np.ndarray:
    """Rotor rates (11), shape (M, 2), for angular velocities ``omega`` (M, 3) at the samples ``rows`` of ``traj``."""
    fn = _rotor_rate_function(robot.j_xx, robot.j_zz, robot.rotor_inertia_axial)
    omega = np.asarray(omega, float)
    return np.array(fn.map(omega.shape[0])(omega.T, traj.u_o[rows][None, :], traj.v_o[rows][None, :],
                                           traj.psi[rows][None, :])).T


def _timed_circles(p: Plan, horizon: float, robot: Robot | None, samples_per_leaf: int):
    """The plan timed by ``t = T theta / (2 pi n)``: its samples and, per circle of the figure eight, the
    sample rows (the circle's start included), omega and (with a robot) the rotor rates there."""
    m = samples_per_leaf + (samples_per_leaf % 2)  # even: Simpson on m + 1 points
    tr = p.sample(m)
    ab = np.array([p.a, p.b]) / p.radius
    rate = 4.0 * math.pi * p.steps / horizon
    funcs = _leaf_omega_functions()
    phi = np.linspace(0.0, 2.0 * math.pi, m + 1)
    circles = []
    for j in range(2 * p.steps):
        sl = slice(j * m, (j + 1) * m + 1)  # samples of this circle, including its start
        om = np.array(funcs[j % 2].map(m + 1)(phi[None, :], ab, p.gamma, tr.psi[sl][None, :], p.k, rate)).T
        circles.append((sl, om, _rotor_rates_along(robot, om, tr, sl) if robot is not None else None))
    timed = replace(tr, s=horizon * tr.s / tr.s[-1], parameter="t")
    return timed, m, circles


def measure_plan(p: Plan, horizon: float = 1.0, robot: Robot | None = None,
                 samples_per_leaf: int = 500) -> tuple:
    """Measures of a geometric-phase plan timed by ``t = T theta / (2 pi n)``, and its timed trajectory."""
    timed, m, circles = _timed_circles(p, horizon, robot, samples_per_leaf)
    dt = horizon / (2 * p.steps) / m  # each circle takes T / (2 n)
    energy = rotor = peak = 0.0
    for _, om, ph in circles:
        sq = (om ** 2).sum(axis=1)
        energy += _simpson(sq, dt)
        peak = max(peak, float(np.sqrt(sq.max())))
        if ph is not None:
            rotor += _simpson((ph ** 2).sum(axis=1), dt)
    return Measures(p.path_length, float(energy), float(rotor) if robot is not None else float("nan"), peak), timed


def comparison_series(c: Comparison, samples_per_leaf: int = 200) -> dict:
    """Time series of both motions of a comparison, for :func:`rollplan.plots.compare.plot_comparison`.

    ``{"geometric_phase": {...}, "collocation": {...}}``, each with ``t`` (N,) [s],
    ``omega`` (N, 3) [rad/s, plane frame] and ``rotor_rates`` (N, 2) [rad/s] (None
    without a robot). The plan's series repeats the time of each joint between
    circles, where omega jumps under this timing; the collocation's is at the
    samples of its certified trajectory.
    """
    robot = c.problem.robot
    timed, _, circles = _timed_circles(c.plan, c.horizon, robot, samples_per_leaf)
    t = np.concatenate([timed.s[sl] for sl, _, _ in circles])
    gp = {"t": t, "omega": np.vstack([om for _, om, _ in circles]),
          "rotor_rates": np.vstack([ph for _, _, ph in circles]) if robot is not None else None}
    r = c.result
    rows = slice(0, r.trajectory.s.size)
    coll = {"t": r.trajectory.s, "omega": np.asarray(r.omega, float),
            "rotor_rates": _rotor_rates_along(robot, r.omega, r.trajectory, rows) if robot is not None else None}
    return {"geometric_phase": gp, "collocation": coll}


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
    p = gp_plan(tuple(target), steps, k=None if robot is not None else k, robot=robot, radius=radius,
                legs="one")   # one leg of figure eights: the paper's plan
    r = collocate(target, k=None if robot is not None else k, robot=robot, radius=radius, cost=cost,
                  intervals=intervals, degree=degree, scheme=scheme, horizon=horizon, guess=guess, steps=steps,
                  turns=p.branch, contact_bound=contact_bound, warm_start=p if guess == "warm" else None)
    measures, timed = measure_plan(p, horizon, robot)
    return Comparison(p.problem, float(horizon), p, r, measures, timed, "rotor" if robot is not None else
                      "angular_velocity")


def _side(c: Comparison, res, measures: Measures, traj: Trajectory) -> dict:
    f = lambda a: [float(x) for x in np.asarray(a).ravel()]  # noqa: E731
    cols = {"t": traj.s, "u_o": traj.u_o, "v_o": traj.v_o, "u_a": traj.u_a, "v_a": traj.v_a, "psi": traj.psi}
    return {"path_length": measures.path_length, "effort": c.effort(measures), "effort_kind": c.effort_kind,
            "angular_velocity_energy": measures.effort, "peak_omega": measures.peak_omega,
            "residual": res.residual, "solve_time_s": res.stats.time_s, "iterations": res.stats.iterations,
            "status": res.stats.status, "trajectory": {key: f(cols[key]) for key in TRAJECTORY_KEYS}}


def comparison_to_dict(c: Comparison) -> dict:
    """The JSON object of ``rollplan compare --json``."""
    r, p, g = c.result, c.plan, c.problem.goal
    d = {"target": {"u_a": g.u_a, "v_a": g.v_a, "psi": g.psi}, "k": c.problem.k, "radius": c.problem.radius,
         "horizon": c.horizon, "steps": c.problem.steps,
         "geometric_phase": _side(c, p, c.plan_measures, c.plan_trajectory),
         "collocation": _side(c, r, r.measures, r.trajectory)}
    d["geometric_phase"].update({"figure_eight": {"a": p.a, "b": p.b, "gamma": p.gamma}, "branch": p.branch})
    tr = r.transcription
    d["collocation"].update({"cost": r.cost, "objective": r.solution.objective, "scheme": tr.scheme,
                             "degree": tr.degree, "intervals": tr.intervals, "guess": r.guess, "turns": r.turns,
                             "guess_time_s": r.stats.details["guess_time_s"],
                             "verify_time_s": r.stats.details["verify_time_s"],
                             "max_defect": r.solution.max_defect, "contact_bound": r.contact_bound})
    return d
