"""``refine=True`` / ``rollplan plan --refine`` (issue 25): the certified polish of a geometric plan.

The independent reference is a minimum-path-length optimal-control problem written here from the printed
(15), (16), (20) alone: multiple shooting with RK4 steps (not the project's collocation), contact accelerations
piecewise constant, rest at both ends, polar angle of the contact point <= 80 deg, solved by IPOPT from
straight-line starts on the whole turns m = -1, 0, 1 of psi, the shortest kept.
"""

import json
import math
import random
import subprocess
import sys
from types import SimpleNamespace

import casadi as ca
import numpy as np
import pytest
from test_interrupts import run_and_interrupt

from rollplan.errors import InputError
from rollplan.planners import solve
from rollplan.planners.refined import RefinedPlan
from rollplan.problem import Problem

import references as ref

README_PAIR = ((0.0, 0.0, 0.0, 0.5, -0.3), (0.8, 0.2, 1.0, -0.4, 0.4), 2.5)
PAIRS = [README_PAIR,
         ((0.3, -0.2, 0.5, -0.3, 0.2), (-0.5, 0.6, -0.7, 0.35, 0.25), 4.0),
         ((0.1, 0.2, -0.4, 0.6, -0.5), (0.9, -0.3, 0.8, -0.2, 0.7), 8.0)]


def printed_rates(x, acc, k):
    """d/dt of (u_a, v_a, psi, u_o, v_o, u_o', v_o'): (15), (16), (20) as printed (R = 1), the accelerations."""
    psi, u, v, du, dv = x[2], x[3], x[4], x[5], x[6]
    return ca.vertcat(-ca.cos(psi) * ca.cos(v) * du + ca.sin(psi) * dv,        # (15)
                      ca.sin(psi) * ca.cos(v) * du + ca.cos(psi) * dv,         # (16)
                      (1 - k) * ca.sin(v) * du + k * ca.tan(u) / ca.cos(v) * dv,  # (20)
                      du, dv, acc[0], acc[1])


BOUND = math.radians(80.0)


def reference_length(start, goal, k, intervals=60, substeps=4, bound=BOUND):
    """Shortest contact path [R] of the multiple-shooting problem (module docstring) over m = -1, 0, 1."""
    x, a = ca.SX.sym("x", 7), ca.SX.sym("a", 2)
    h = 1.0 / (intervals * substeps)

    def f(z):
        xdot = printed_rates(z, a, k)
        return xdot, xdot[0] ** 2 + xdot[1] ** 2, ca.sqrt(xdot[0] ** 2 + xdot[1] ** 2 + 1e-300)

    z, energy, length = x, 0.0, 0.0
    for _ in range(substeps):   # RK4, the integrals by the same stages
        k1, e1, l1 = f(z)
        k2, e2, l2 = f(z + h / 2 * k1)
        k3, e3, l3 = f(z + h / 2 * k2)
        k4, e4, l4 = f(z + h * k3)
        z = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        energy += h / 6 * (e1 + 2 * e2 + 2 * e3 + e4)
        length += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4)
    step = ca.Function("step", [x, a], [z, energy, length])
    X, A = ca.SX.sym("X", 7, intervals + 1), ca.SX.sym("A", 2, intervals)
    Z, E, L = step.map(intervals)(X[:, :-1], A)
    g = [ca.vec(Z - X[:, 1:]), (ca.cos(X[3, :]) * ca.cos(X[4, :])).T]
    solver = ca.nlpsol("reference", "ipopt", {"x": ca.veccat(X, A), "f": ca.sum2(E), "g": ca.vertcat(*g)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.max_iter": 500, "ipopt.tol": 1e-10})
    ng = 7 * intervals
    lbg = np.r_[np.zeros(ng), np.full(intervals + 1, math.cos(bound))]
    ubg = np.r_[np.zeros(ng), np.full(intervals + 1, np.inf)]
    best = math.inf
    for m in (-1, 0, 1):
        x0 = np.r_[start, 0.0, 0.0]
        x1 = np.r_[goal, 0.0, 0.0]
        x1[2] += 2 * math.pi * m
        lbx = np.full((7, intervals + 1), -np.inf)
        ubx = np.full((7, intervals + 1), np.inf)
        lbx[:, 0] = ubx[:, 0] = x0
        lbx[:, -1] = ubx[:, -1] = x1
        guess = x0[:, None] + (x1 - x0)[:, None] * np.linspace(0.0, 1.0, intervals + 1)
        lb = np.r_[lbx.ravel(order="F"), np.full(2 * intervals, -np.inf)]
        ub = np.r_[ubx.ravel(order="F"), np.full(2 * intervals, np.inf)]
        sol = solver(x0=np.r_[guess.ravel(order="F"), np.zeros(2 * intervals)], lbx=lb, ubx=ub, lbg=lbg, ubg=ubg)
        if solver.stats()["success"]:
            v = np.array(sol["x"]).ravel()
            Xs = v[:7 * (intervals + 1)].reshape((7, intervals + 1), order="F")
            As = v[7 * (intervals + 1):].reshape((2, intervals), order="F")
            best = min(best, float(np.sum(np.array(step.map(intervals)(Xs[:, :-1], As)[2]))))
    return best


def lands_on_goal(traj, problem):
    """|end - goal| of (15), (16), (20) by DOP853 along splines of the sampled contact coordinates alone."""
    out = ref.replay(traj.u_o, traj.v_o, traj.segment, traj.state[0, :3], problem.k)
    d = np.r_[out[-1], traj.state[-1, 3:]] - np.asarray(problem.goal, float)
    d[2] = ref.wrap(d[2])
    return float(np.linalg.norm(d))


@pytest.mark.slow
@pytest.mark.parametrize("start, goal, k", PAIRS[1:])
def test_refined_plan_is_exact_and_within_5_percent_of_an_independent_optimal_control_solve(start, goal, k):
    problem = Problem(goal, start=start, k=k)
    p = solve(problem, "geometric", refine=True)
    assert isinstance(p, RefinedPlan)
    assert p.certificate.method == "cvodes" and p.residual <= 1e-9
    assert p.path_length < p.unrefined_length
    reference = reference_length(start, goal, k)
    assert math.isfinite(reference)
    assert p.path_length <= 1.05 * reference
    assert lands_on_goal(p.sample(4001), problem) <= 1e-7
    # the length is the sampled path's own (polyline of the CVODES samples on the plane)
    assert p.path_length == pytest.approx(p.sample(None).path_length(), rel=1e-3)


@pytest.mark.slow
def test_plan_refine_command_prints_and_writes_both_lengths(tmp_path):
    """`rollplan plan --refine` on the README example: the polished length beside the plan's, in the text and
    the JSON; the JSON's trajectory lands on the goal integrated independently; within 5 % of the reference."""
    start, goal, k = README_PAIR
    out = tmp_path / "r.json"
    argv = [sys.executable, "-m", "rollplan.cli", "plan", "--from", *map(str, start), "--to", *map(str, goal[:2]),
            "--psi", str(goal[2]), "--contact", *map(str, goal[3:]), "--k", str(k), "--refine", "--json", str(out),
            "--samples", "4001"]
    proc = subprocess.run(argv, check=False, capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "refined       path length" in proc.stdout and "unrefined" in proc.stdout
    d = json.loads(out.read_text())
    assert d["mode"] == "refined" and d["refined"]["path_length"] == d["path_length"]
    assert d["unrefined_length"] == d["unrefined"]["path_length"] > d["path_length"]
    assert d["residual"] <= 1e-9
    reference = reference_length(start, goal, k)
    assert math.isfinite(reference)
    assert d["path_length"] <= 1.05 * reference
    problem = Problem(goal, start=start, k=k)
    tr = d["trajectory"]
    traj = SimpleNamespace(u_o=np.array(tr["u_o"]), v_o=np.array(tr["v_o"]), segment=np.array(tr["segment"]),
                               state=np.column_stack([tr[n] for n in ("u_a", "v_a", "psi", "u_o", "v_o")]))
    assert lands_on_goal(traj, problem) <= 1e-7


def test_refine_keeps_the_plan_with_a_note_when_the_goal_is_beyond_the_bound():
    """A goal contact point at 85 deg from the pole (the geometric planner serves it; the polish keeps 80 deg)."""
    goal = (0.5, 0.2, 0.3, *ref.polar_contact(math.radians(85.0), 0.4))
    p = solve(Problem(goal, k=2.5), "geometric", refine=True)
    assert not isinstance(p, RefinedPlan) and p.residual <= 1e-9
    assert p.stats.details["refine"].startswith("not refined")


def test_refine_and_all_solutions_do_not_combine():
    with pytest.raises(InputError, match="refine"):
        solve(Problem((0.0, 1.0, 0.0), k=2.5), "geometric", refine=True, all_solutions=True)
    with pytest.raises(InputError, match="refine"):
        solve(Problem((0.0, 1.0, 0.0), k=2.5), "geometric", refine="yes")


@pytest.mark.slow
@pytest.mark.parametrize("delay", [random.Random(25).uniform(0.0, 8.0) for _ in range(2)])
def test_ctrl_c_during_plan_refine_acts_at_once(delay):
    """SIGINT at a random moment of `plan --refine` (NLP construction, IPOPT, correction, certificate): exit 130
    within a few seconds on a loaded machine, or the finished run's 0; one line, no traceback."""
    code, elapsed, _, err = run_and_interrupt(["-v", "plan", "--from", "0.3", "-0.2", "0.5", "-0.3", "0.2", "--to",
                                               "-0.5", "0.6", "--psi", "-0.7", "--contact", "0.35", "0.25", "--k", "4",
                                               "--refine"], delay, wait_for="building the collocation NLP")
    assert code in (0, 130), err
    assert elapsed < 3.0, (delay, elapsed, err)
    assert "Traceback" not in err and "KeyboardInterruptException" not in err
    if code == 130:
        assert err.strip().splitlines()[-1] == "rollplan: interrupted"
