"""``refine=True`` / ``rollplan plan --refine`` (issue 25): the certified polish of a geometric plan.

The independent reference is :func:`references.optimal_control_length`: the minimum-path-length optimal-control
problem typed from the printed (15), (16), (20) alone, by multiple shooting with RK4 steps (not the project's
collocation), solved by IPOPT from straight-line starts on the whole turns m = -1, 0, 1 of psi.
"""

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from conftest import run
from test_interrupts import moments, moments_in, phase, run_and_interrupt, stderr_times

from rollplan.errors import InputError
from rollplan.planners import solve
from rollplan.planners.refined import RefinedPlan
from rollplan.problem import Problem

import references as ref

README_PAIR = ((0.0, 0.0, 0.0, 0.5, -0.3), (0.8, 0.2, 1.0, -0.4, 0.4), 2.5)
PAIRS = [README_PAIR,
         ((0.3, -0.2, 0.5, -0.3, 0.2), (-0.5, 0.6, -0.7, 0.35, 0.25), 4.0),
         ((0.1, 0.2, -0.4, 0.6, -0.5), (0.9, -0.3, 0.8, -0.2, 0.7), 8.0)]


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
    reference = ref.optimal_control_length(start, goal, k)[0]
    assert math.isfinite(reference)
    assert p.path_length <= 1.05 * reference
    assert lands_on_goal(p.sample(4001), problem) <= 1e-7
    # the length is the sampled path's own (polyline of the CVODES samples on the plane)
    assert p.path_length == pytest.approx(p.sample(None).path_length(), rel=1e-3)


@pytest.mark.slow
def test_plan_refine_command_prints_and_writes_both_lengths(tmp_path, capsys):
    """`rollplan plan --refine` on the README example: the polished length beside the plan's, in the text and
    the JSON; the JSON's trajectory lands on the goal integrated independently; within 5 % of the reference.
    (In this process: the command needs no process of its own.)"""
    start, goal, k = README_PAIR
    out = tmp_path / "r.json"
    code, text, err = run(capsys, "plan", "--from", *start, "--to", *goal[:2], "--psi", goal[2],
                          "--contact", *goal[3:], "--k", k, "--refine", "--json", out, "--samples", 4001)
    assert code == 0, err
    assert "refined       path length" in text and "unrefined" in text
    d = json.loads(out.read_text())
    assert d["mode"] == "refined" and d["refined"]["path_length"] == d["path_length"]
    assert d["unrefined_length"] == d["unrefined"]["path_length"] > d["path_length"]
    assert d["residual"] <= 1e-9
    reference = ref.optimal_control_length(start, goal, k)[0]
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


#: `plan --refine` whose polish the Ctrl-C test interrupts, and the stderr line that announces the polish.
REFINE = ["-v", "plan", "--from", "0.3", "-0.2", "0.5", "-0.3", "0.2", "--to", "-0.5", "0.6", "--psi", "-0.7",
          "--contact", "0.35", "0.25", "--k", "4", "--refine"]
POLISH = "building the collocation NLP"


@pytest.fixture(scope="module")
def polish_length():
    """Seconds from the polish's announcement to the exit of one uninterrupted REFINE on this machine."""
    return phase(stderr_times(REFINE), POLISH)[1]


@pytest.mark.slow
@pytest.mark.parametrize("draw", moments(25, 0.05, 0.45, 2))
def test_ctrl_c_during_plan_refine_acts_at_once(draw, polish_length):
    """SIGINT at a random moment of the polish of `plan --refine` (NLP construction, IPOPT, correction,
    certificate; a random fraction of its length, from its announcement to the exit, measured here): exit 130
    within a few seconds on a loaded machine, one line, no traceback."""
    delay, = moments_in(polish_length, [draw])
    code, elapsed, _, err = run_and_interrupt(REFINE, delay, wait_for=POLISH)
    assert code == 130, (delay, err)
    assert elapsed < 3.0, (delay, elapsed, err)
    assert "Traceback" not in err and "KeyboardInterruptException" not in err
    assert err.strip().splitlines()[-1] == "rollplan: interrupted"
