"""Study: what feedback buys on a robot that is not the model (issue 13).

One run (:func:`run_case`) is a top-level function of one picklable dict, so a Monte Carlo is a map
of it over seeds on any executor (:func:`run_cases` uses local processes; a Dask or other executor can
map the same function). Each run draws a goal from its seed, plans ``steps`` figure eights for the
model robot and executes the plan on a real robot whose k (through the total mass, Jzz and J_r
unchanged, as ``scripts/sensitivity.py``) or rotor inertia J_r (axial) is off by ``error``, with a
random sign, open loop and closed loop (:func:`rollplan.execution.feedback.execute`), with or
without measurement noise. :func:`run_issue_case` is one run of the issue's mismatched robot
(:func:`issue_real_robot`) on any plant, MuJoCo included.
"""

from __future__ import annotations

import math
import time
from dataclasses import replace

import numpy as np

from ..errors import InputError, NoPlanError
from ..execution.feedback import execute
from ..execution.plants import disturbance
from ..planners import solve
from ..problem import Problem
from ..robot import Robot
from .executor import map_in_order

__all__ = ["ISSUE_MODEL", "issue_real_robot", "robot_with_error", "random_goal", "run_case", "run_cases",
           "run_issue_case", "summarize"]

#: A robot with k = 4.21 built from the issue's numbers (R = 0.1 m, M = 0.957 kg, m_o = 0.4 kg); its rotors are
#: possible bodies of revolution (J_r <= 2 J_p, also with J_r 10 % larger: :func:`robot_with_error`).
ISSUE_MODEL = Robot(radius=0.1, mass_total=0.957, mass_shell=0.4, rotor_inertia_axial=1.4e-4,
                    rotor_inertia_transverse=8.7e-5)


def issue_real_robot(model: Robot = ISSUE_MODEL, mass: float = 0.055, rotor: float = 0.075) -> Robot:
    """The issue's mismatched robot: total mass ``+mass``, rotor inertias (axial and transverse) ``+rotor``."""
    return replace(model, mass_total=model.mass_total * (1 + mass),
                   rotor_inertia_axial=model.rotor_inertia_axial * (1 + rotor),
                   rotor_inertia_transverse=model.rotor_inertia_transverse * (1 + rotor))


def robot_with_error(model: Robot, kind: str, error: float) -> Robot:
    """The model with k off by ``error`` (relative; through the total mass) or J_r off by ``error``."""
    if kind == "k":
        return replace(model, mass_total=(model.k * (1 + error) - 1.0) * model.j_zz / model.radius**2)
    if kind == "J_r":
        return replace(model, rotor_inertia_axial=model.rotor_inertia_axial * (1 + error))
    raise InputError(f"error kind {kind!r} is not known: choose k or J_r")


def random_goal(seed: int, radius: float, near: float = 1.5, far: float = 3.0) -> tuple:
    """A goal ``(u_a, v_a, psi)`` [m, rad] between ``near`` and ``far`` R away, any direction, psi in [-1, 1]."""
    rng = np.random.default_rng([int(seed), 13])
    d, phi, psi = rng.uniform(near, far), rng.uniform(-math.pi, math.pi), rng.uniform(-1.0, 1.0)
    return (d * radius * math.cos(phi), d * radius * math.sin(phi), psi)


def run_case(case: dict) -> dict:
    """One Monte Carlo run: ``case`` holds ``kind`` ('k' or 'J_r'), ``error`` (relative, > 0), ``seed``,
    ``noise`` (measurement sigma [R and rad], 0 for none), ``plant``, ``steps`` and ``piece_duration``.

    Returns the case with ``open`` and ``closed`` arrival errors (R and rad), the final estimate of k,
    the real k, the wall time, and ``failed`` (a message) when a plan or re-plan was refused.
    """
    t0 = time.perf_counter()
    model = case.get("model", ISSUE_MODEL)
    sign = 1.0 if np.random.default_rng([int(case["seed"]), 17]).random() < 0.5 else -1.0
    real = robot_with_error(model, case["kind"], sign * case["error"])
    goal = random_goal(case["seed"], model.radius)
    dist = (disturbance("measurement", sigma_length=case["noise"], sigma_angle=case["noise"], seed=case["seed"]),) \
        if case["noise"] > 0 else ()
    out = {k: v for k, v in case.items() if k != "model"}
    out.update(sign=sign, real_k=real.k, model_k=model.k, goal=list(goal))
    try:
        p = solve(Problem(goal, robot=model), "geometric", steps=case["steps"])
        runs = {name: execute(p, model, real, case["piece_duration"], plant=case["plant"], closed_loop=cl,
                              disturbances=dist) for name, cl in (("open", False), ("closed", True))}
    except NoPlanError as exc:
        out.update(failed=str(exc), seconds=time.perf_counter() - t0)
        return out
    out.update(open=runs["open"].arrival_error, closed=runs["closed"].arrival_error,
               closed_position=runs["closed"].position_error, estimated_k=runs["closed"].estimates[-1].get("k"),
               seconds=time.perf_counter() - t0, failed=None)
    return out


def run_issue_case(case: dict) -> dict:
    """One closed-loop run of the issue's case: ``case`` holds ``goal`` (u_a, v_a, psi), ``steps``,
    ``piece_duration``, ``plant`` ('rates', 'torques' or 'mujoco'), ``noise`` (measurement sigma [R and rad])
    and ``seed``; the plan is made for :data:`ISSUE_MODEL` and executed on :func:`issue_real_robot`.

    Returns the case with the closed-loop arrival error (R and rad), the final estimate of k, the real k, the
    number of samples, the motion's duration and the wall time.
    """
    t0 = time.perf_counter()
    model, real = ISSUE_MODEL, issue_real_robot()
    dist = (disturbance("measurement", sigma_length=case["noise"], sigma_angle=case["noise"], seed=case["seed"]),) \
        if case["noise"] > 0 else ()
    p = solve(Problem(tuple(case["goal"]), robot=model), "geometric", steps=case["steps"])
    run = execute(p, model, real, case["piece_duration"], plant=case["plant"], disturbances=dist)
    return {**case, "closed": run.arrival_error, "closed_position": run.position_error,
            "estimated_k": run.estimates[-1].get("k"), "real_k": real.k, "samples": int(run.time.size),
            "duration": float(run.time[-1] - run.time[0]), "seconds": time.perf_counter() - t0}


def run_cases(cases, workers: int = 2, progress=None, scheduler: str | None = None) -> list:
    """:func:`run_case` over ``cases``, in order: in this process (``workers`` 1), in ``workers`` local
    processes, or on the Dask cluster at ``scheduler`` (:func:`rollplan.studies.executor.map_in_order`).

    ``progress(done, total)`` after each run. Ctrl-C cancels the runs not started and stops the workers.
    """
    report = None if progress is None else (lambda label, done, total: progress(done, total))
    return map_in_order(run_case, list(cases), jobs=workers, scheduler=scheduler, progress=report,
                        label="closed-loop runs")


def summarize(results, key: str) -> dict:
    """Median and 95th percentile of ``key`` over the runs that did not fail, and the number of failures."""
    vals = np.array([r[key] for r in results if not r.get("failed")], float)
    if vals.size == 0:
        return {"median": None, "p95": None, "runs": 0, "failed": len(results)}
    return {"median": float(np.median(vals)), "p95": float(np.percentile(vals, 95)), "runs": int(vals.size),
            "failed": sum(bool(r.get("failed")) for r in results)}
