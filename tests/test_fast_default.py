"""The default plan between full states (issue 25): the pole plan and its fast polish, the shorter certified kept.

The independent references: :func:`references.optimal_control_length` (the minimum-path-length optimal-control
problem typed from the printed (15), (16), (20), multiple shooting with RK4, IPOPT from straight lines on the
turns m = -1, 0, 1; not the project's collocation), and DOP853 along the sampled contact coordinates alone
(:func:`references.replay`), which must land on the goal.
"""

import json
import math

import numpy as np
import pytest
from conftest import one_line, run
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import rollplan
from rollplan.errors import InputError
from rollplan.planners import geometric
from rollplan.planners.refined import FAST_INTERVALS, RefinedPlan

import references as ref

README_PAIR = ((0.0, 0.0, 0.0, 0.5, -0.3), (0.8, 0.2, 1.0, -0.4, 0.4), 2.5)
PAIRS = [README_PAIR,
         ((0.3, -0.2, 0.5, -0.3, 0.2), (-0.5, 0.6, -0.7, 0.35, 0.25), 4.0),
         ((0.1, 0.2, -0.4, 0.6, -0.5), (0.9, -0.3, 0.8, -0.2, 0.7), 8.0)]


def lands_on_goal(p):
    """|end - goal| of (15), (16), (20) by DOP853 along splines of the sampled contact coordinates of ``p`` (8001
    samples: the splines' own error stays well below the tolerance of the tests)."""
    traj = p.sample(8001)
    out = ref.replay(traj.u_o, traj.v_o, traj.segment, traj.state[0, :3], p.k)
    d = np.r_[out[-1], traj.state[-1, 3:]] - np.asarray(p.goal, float)
    d[2] = ref.wrap(d[2])
    return float(np.linalg.norm(d))


def test_the_default_between_full_states_is_the_certified_fast_polish_of_the_pole_plan():
    start, goal, k = README_PAIR
    p = rollplan.plan(goal, k=k, start=start)
    pole = rollplan.plan(goal, k=k, start=start, polish="off")
    assert isinstance(p, RefinedPlan) and p.stats.details["polish"] == "fast"
    assert p.collocation.transcription.intervals == FAST_INTERVALS
    assert pole.mode == "one" and [q.kind for q in pole.pieces] == ["approach", "leaf", "leaf", "departure"]
    assert p.unrefined_length == pytest.approx(pole.path_length, rel=1e-12)
    assert p.path_length < 0.5 * pole.path_length
    assert p.certificate.method == "cvodes" and p.residual <= 1e-9
    assert lands_on_goal(p) <= 1e-7
    # the length is the sampled path's own
    assert p.path_length == pytest.approx(p.sample(None).path_length(), rel=1e-3)


def test_the_fast_polish_is_finished_like_the_polish_and_names_its_own_starts(monkeypatch):
    """The fast polish corrects, certifies and backs off through the rest-to-rest planner's ``finish`` (the loop of
    the full polish), with the correction on fixed steps; its controls reach the goal at rest by DOP853 on the
    printed equations. Its straight-line starts are named apart from the full polish's ``line:m``."""
    from rollplan.planners.collocation.rest import RestToRestPlanner
    from rollplan.planners.refined import FIXED_STEPS

    finished = []
    real = RestToRestPlanner.finish
    monkeypatch.setattr(RestToRestPlanner, "finish",
                        lambda self, nlp, *a: finished.append((nlp.guess.name, a)) or real(self, nlp, *a))
    start, goal, k = README_PAIR
    p = rollplan.plan(goal, k=k, start=start)
    assert isinstance(p, RefinedPlan) and finished == [(p.collocation.guess, (FIXED_STEPS,))]
    starts = p.stats.details["starts"]
    assert [s["start"] for s in starts] == [f"fast-line:{p.turns}"] == [p.collocation.guess]
    assert starts[0]["correction_error"] <= 1e-9 and starts[0]["residual"] == p.residual
    x = printed_end(p.collocation.controls, start, k)
    d = np.r_[x[:5] - np.asarray(goal), x[5:]]
    d[2] = ref.wrap(d[2])
    assert np.linalg.norm(d) <= 1e-9


def test_goals_at_the_pole_from_rest_at_the_origin_keep_the_geometric_phase_plan():
    p, q = rollplan.plan((0.4, 0.3, 0.5), k=2.5), rollplan.plan((0.4, 0.3, 0.5), k=2.5, polish="off")
    assert isinstance(p, geometric.Plan) and (p.a, p.b, p.gamma) == (q.a, q.b, q.gamma)
    assert "refine" not in p.stats.details


def test_a_polish_outside_the_contact_bound_keeps_the_pole_plan_with_a_note():
    """A start 85 deg from the pole is beyond the polish's 80 deg: the pole plan, with the reason."""
    start = (0.0, 0.0, 0.0, *ref.polar_contact(math.radians(85.0), 0.3))
    p = rollplan.plan((0.3, 0.2, 0.5, 0.1, -0.1), k=2.5, start=start)
    assert p.mode != "refined" and p.pieces and p.residual <= 1e-9
    assert p.stats.details["refine"].startswith("not polished")


def test_polish_is_checked():
    with pytest.raises(InputError, match="polish"):
        rollplan.plan((0.3, 0.2, 0.5, 0.1, -0.1), k=2.5, polish="slow")
    with pytest.raises(InputError, match="polish"):
        geometric.ComposedPlanner(polish=True)


@pytest.mark.slow
@pytest.mark.parametrize("start, goal, k", PAIRS)
def test_the_default_is_within_1_5x_of_an_independent_optimal_control_solve(start, goal, k):
    p = rollplan.plan(goal, k=k, start=start)
    assert isinstance(p, RefinedPlan) and p.residual <= 1e-9
    reference = ref.optimal_control_length(start, goal, k)[0]
    assert math.isfinite(reference)
    assert p.path_length <= 1.5 * reference
    assert lands_on_goal(p) <= 1e-7


def _contact(draw):
    return ref.polar_contact(draw(st.floats(0.0, math.radians(60.0))), draw(st.floats(-math.pi, math.pi)))


@st.composite
def full_pairs(draw):
    xy = st.floats(-1.0, 1.0)
    psi = st.floats(-math.pi, math.pi)
    start = (draw(xy), draw(xy), draw(psi), *_contact(draw))
    goal = (draw(xy), draw(xy), draw(psi), *_contact(draw))
    return start, goal, draw(st.floats(1.5, 8.0))


@pytest.mark.slow
@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pair=full_pairs())
def test_the_default_is_never_longer_than_the_pole_plan(pair):
    start, goal, k = pair
    p = rollplan.plan(goal, k=k, start=start)
    pole = rollplan.plan(goal, k=k, start=start, polish="off")
    assert p.path_length <= pole.path_length
    assert p.residual <= 1e-9
    if isinstance(p, RefinedPlan):
        assert lands_on_goal(p) <= 1e-7


def test_plan_command_polishes_by_default_and_plans_the_figure_eights_with_polish_off(tmp_path, capsys):
    start, goal, k = README_PAIR
    argv = ["plan", "--from", *map(str, start), "--to", str(goal[0]), str(goal[1]), "--psi", str(goal[2]),
            "--contact", *map(str, goal[3:]), "--k", str(k)]
    code, out, err = run(capsys, *argv, "--json", str(tmp_path / "d.json"))
    assert code == 0, err
    assert "fast polish" in out and "refined       path length" in out
    d = json.loads((tmp_path / "d.json").read_text())
    assert d["mode"] == "refined" and d["refined"]["intervals"] == FAST_INTERVALS and d["residual"] <= 1e-9
    assert d["unrefined"]["mode"] == "one" and d["unrefined_length"] == d["unrefined"]["path_length"]
    assert d["path_length"] < d["unrefined_length"]
    code, out, err = run(capsys, *argv, "--polish", "off", "--json", str(tmp_path / "e.json"))
    assert code == 0, err
    e = json.loads((tmp_path / "e.json").read_text())
    assert e["mode"] == "one" and "refined" not in e and e["path_length"] == d["unrefined_length"]
    # the outputs of closed-form pieces plan the figure eights: asked with the polish, one line and exit 2
    code, out, err = run(capsys, *argv, "--polish", "fast", "--duration", "5")
    assert code == 2 and one_line(err) and "--polish fast does not combine with --duration" in err
    code, out, err = run(capsys, *argv, "--polish", "fast", "--branch", "-1")
    assert code == 2 and one_line(err) and "--polish fast does not combine with --branch" in err


@pytest.mark.slow
def test_outputs_of_closed_form_pieces_plan_the_figure_eights(tmp_path, capsys):
    """--plot and --branch plan the figure eights (the outputs of closed-form pieces), not the polish."""
    start, goal, k = README_PAIR
    argv = ["plan", "--from", *map(str, start), "--to", str(goal[0]), str(goal[1]), "--psi", str(goal[2]),
            "--contact", *map(str, goal[3:]), "--k", str(k)]
    code, out, err = run(capsys, *argv, "--plot", str(tmp_path / "p.png"))
    assert code == 0 and (tmp_path / "p.png").exists() and "refined" not in out, err
    # one branch of the figure eights is the pole plan of that branch, never silently polished away
    code, out, err = run(capsys, *argv, "--branch", "-1", "--json", str(tmp_path / "b.json"))
    assert code == 0 and "refined" not in out, err
    b = json.loads((tmp_path / "b.json").read_text())
    assert b["mode"] == "one" and "refined" not in b


@pytest.mark.slow
def test_the_benchmark_measures_the_warm_default_with_its_budget(tmp_path):
    """The warm time of the default is measured by scripts/bench_default.py through scripts/benchmark.py (a
    section and a budget row), per pair with the stages where the time goes."""
    from test_scripts import run_script_here

    run_script_here("benchmark.py", tmp_path, "--quick", "--only", "fast_default", "budgets")
    report = json.loads((tmp_path / "benchmarks.json").read_text())
    sections = {sec["function"]: sec for sec in report["sections"]}
    summary = sections["section_fast_default"]["summary"]
    assert summary["budget_ms"] == 100.0 and summary["median_one_leg_ms"] > 0 and summary["median_one_leg_cpu_ms"] > 0
    rows = sections["section_fast_default"]["rows"]
    assert rows and all(r["IPOPT [ms]"] > 0 and r["correction + certificate [ms]"] > 0 for r in rows)
    assert any("default plan between full states" in row["budget"] for row in sections["section_budgets"]["rows"])


def printed_end(controls, start, k):
    """The 7-state end (u_a, v_a, psi, u_o, v_o and their rates) of the piecewise-constant contact accelerations
    ``controls`` (N, 2) on [0, 1] from ``start`` at rest, (15), (16), (20) as printed, by DOP853 interval by
    interval (rtol 1e-13)."""
    from scipy.integrate import solve_ivp

    def rhs(t, x, a):
        return np.r_[ref.rates_15_16_20(x[2], x[3], x[4], x[5], x[6], k), x[5], x[6], a]

    x, n = np.r_[start, 0.0, 0.0], len(controls)
    for j, a in enumerate(controls):
        x = solve_ivp(rhs, (j / n, (j + 1) / n), x, method="DOP853", rtol=1e-13, atol=1e-14, args=(a,)).y[:, -1]
    return x


@pytest.mark.slow
@pytest.mark.parametrize("index", [14, 20])
def test_the_certificate_bounds_the_arrival_error_of_an_independent_integration(index):
    """Random pairs (contacts <= 60 deg, k 1.5-8) where the certificate's integration once understated the
    arrival error: the polished controls driven through the printed equations by DOP853 land within the
    certificate's tolerance."""
    rng = np.random.default_rng(1)
    start, goal, k = [random_pair(rng) for _ in range(index + 1)][index]
    p = rollplan.plan(goal, k=k, start=start)
    assert isinstance(p, RefinedPlan) and p.residual <= 1e-9
    x = printed_end(p.collocation.controls, start, k)
    d = np.r_[x[:5] - np.asarray(goal), x[5:]]
    d[2] = ref.wrap(d[2])
    assert np.linalg.norm(d) <= 1e-9


def random_pair(rng):
    """A start and a goal state with contact points up to 60 deg from the pole, and k in [1.5, 8]."""
    def contact():
        return ref.polar_contact(rng.uniform(0.0, math.radians(60.0)), rng.uniform(-math.pi, math.pi))
    s = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-math.pi, math.pi), *contact())
    g = (rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-math.pi, math.pi), *contact())
    return s, g, rng.uniform(1.5, 8.0)


@pytest.mark.parametrize("turns", [1, -1, 3])
def test_the_goal_psi_written_with_whole_turns_is_the_same_goal(turns):
    """psi is an angle: the goal written with whole extra turns is the same state and gets the same plan."""
    start, goal, k = README_PAIR
    p = rollplan.plan(goal, k=k, start=start)
    q = rollplan.plan((*goal[:2], goal[2] + 2 * math.pi * turns, *goal[3:]), k=k, start=start)
    assert isinstance(q, RefinedPlan) and q.residual <= 1e-9
    assert q.path_length == pytest.approx(p.path_length, rel=1e-9)


@pytest.mark.slow
def test_a_failed_straight_line_start_is_followed_by_the_next_turns():
    """A pair (contacts <= 60 deg, k 1.5-8) whose straight line on the nearest turns leaves IPOPT at its
    iteration limit: the next turns' start is polished, within 1.5x the optimal-control reference."""
    start = (-0.6055624633100081, 0.8636908465283903, -1.6091457902698765, -0.028978531792153237,
             -0.15127563737285094)
    goal = (-0.3205512453029373, -0.5497680146812769, 0.22818299173369105, 0.8098385281061004, -0.6328620916643164)
    k = 4.198569983741798
    p = rollplan.plan(goal, k=k, start=start)
    assert isinstance(p, RefinedPlan) and p.residual <= 1e-9
    assert p.path_length <= 1.5 * ref.optimal_control_length(start, goal, k)[0]
