"""The fair comparison (rollplan.studies.comparison), its pieces and `rollplan compare`.

References: closed forms of a rest-to-rest roll along a great circle (bang-bang acceleration: its
angular-velocity energy, length and torques), the paper's printed (15), (16), (20) integrated by
scipy's DOP853 (``references.integrate_contact_path``, ``references.replay``), the Cauchy-Schwarz
bound of a timing, and the JSON schema of the issue.
"""

from __future__ import annotations

import json
import math

import casadi as ca
import numpy as np
import pytest

from rollplan import Problem, default_robot, plan
from rollplan.cli import main
from rollplan.execution.optimal_timing import optimal_timing, timed_samples, timing_bound
from rollplan.execution.path import ContactPath
from rollplan.measures import integrate_samples, measure
from rollplan.planners.collocation.costs import N_PAR
from rollplan.planners.collocation.rest import (
    MAX_INTERVALS,
    MEMORY_GB,
    MIN_INTERVALS,
    RestToRestPlanner,
    certify,
    rest_parameters,
)
from rollplan.studies.comparison import SIDE_KEYS, TRAJECTORY_KEYS, compare, leaf_radius_bound, robot_for_k
from rollplan.timeseries import TimeSeries

import references

K = 2.5


def _polar(state):
    return np.arccos(np.clip(np.cos(state[:, 3]) * np.cos(state[:, 4]), -1, 1))


def test_integrate_samples_handles_jumps_and_matches_closed_forms():
    t = np.r_[np.linspace(0, 1, 11), np.linspace(1, 2, 11)]       # t = 1 twice: a jump
    y = np.r_[np.linspace(0, 1, 11) ** 2, np.full(11, 5.0)]
    assert integrate_samples(t, y) == pytest.approx(1 / 3 + 5.0, rel=1e-14)
    assert integrate_samples([0.0, 0.5, 2.0], [1.0, 1.0, 1.0]) == pytest.approx(2.0)


def test_rest_to_rest_roll_costs_in_closed_form():
    """u_o = 0, psi = 0, v_o'' = +a then -a: omega = (-v_o', 0, 0) by (18), (19), (13); then
    int |omega|^2 dt = a^2 T^3 / 12, the length is R a T^2 / 4, v_a ends at that length, psi stays 0,
    and the torques are tau_1 = +-(J_xx - J_r) a, tau_2 = 0 (n_1 = e_x, phi_1_dot = J_xx v_o' / J_r by (11))."""
    robot = default_robot()
    a, T = 1.6, 1.0
    V = a * T ** 2 / 4
    problem = Problem((0.0, robot.radius * V, 0.0, 0.0, V), robot=robot)
    m = certify([[0.0, a], [0.0, -a]], np.zeros(7), problem, T, per=40)
    c = measure(m)
    assert c["angular_velocity"] == pytest.approx(a ** 2 * T ** 3 / 12, rel=1e-10)
    assert c["path_length"] == pytest.approx(robot.radius * V, rel=1e-10)
    assert c["rotor_energy"] == pytest.approx((robot.j_xx - robot.rotor_inertia_axial) ** 2 * a ** 2 * T, rel=1e-9)
    assert c["peak_rotor_torque"] == pytest.approx((robot.j_xx - robot.rotor_inertia_axial) * a, rel=1e-9)
    assert c["peak_rotor_rate"] == pytest.approx(robot.j_xx / robot.rotor_inertia_axial * a * T / 2, rel=1e-9)
    assert problem.residual(m.state[-1]) < 1e-10
    assert np.abs(m.omega[[0, -1]]).max() < 1e-14


@pytest.mark.parametrize("degree, order", [(1, 2), (2, 4)])
def test_transcription_converges_at_its_order_to_the_printed_equations(degree, order):
    """The collocation of the rest-to-rest state (rates as states, accelerations constant) used as an implicit
    Runge-Kutta method: its end state converges to DOP853 on (15), (16), (20) at order 2d."""
    acc = np.array([1.3, -0.8])
    T = 1.0
    planner = RestToRestPlanner(intervals=MIN_INTERVALS, degree=degree)

    def path(t):   # u_o, v_o, rates: +acc up to T/2, -acc after
        if t <= T / 2:
            return (*(acc * t ** 2 / 2), *(acc * t))
        s = T - t
        return (*(acc * (T ** 2 / 4 - s ** 2 / 2)), *(acc * s))

    ref = np.concatenate([references.integrate_contact_path(path, np.zeros(3), (0, T / 2), K).y[:, -1]])
    ref = references.integrate_contact_path(path, ref, (T / 2, T), K).y[:, -1]
    errors = []
    for n in (4, 8, 16, 32):
        controls = np.repeat([acc, -acc], n // 2, axis=0)
        x = planner.transcription.simulate(planner.point, N_PAR, controls, rest_parameters(K, T))[-1]
        errors.append(np.abs(x[:3] - ref).max())
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates > order - 0.3), (errors, rates)


@pytest.fixture(scope="module")
def hard_path():
    """The path of the GP plan for (0.2, 0.1, 2) (branch m = -2, leaves 0.61 and 0.20 R)."""
    robot = robot_for_k(K)
    p = plan((0.2, 0.1, 2.0), 1, robot=robot)
    return p, ContactPath.of_plan(p, robot)


def test_optimal_timing_is_within_two_percent_of_the_bound(hard_path):
    p, path = hard_path
    bound = timing_bound(path, 1.0, "angular_velocity")
    m = timed_samples(path, optimal_timing(path, 1.0, "angular_velocity", 100))
    c = measure(m)
    assert bound * (1 - 1e-9) <= c["angular_velocity"] <= 1.02 * bound
    assert c["path_length"] == pytest.approx(2 * math.pi * (p.a + p.b), rel=1e-6)
    assert np.abs(m.omega[[0, -1]]).max() == 0.0 and np.abs(m.rotor_rates[[0, -1]]).max() == 0.0
    # the constant-theta-speed timing (each circle in T/2) is far above it: (int |omega| dt)^2 / T is the least
    assert bound == pytest.approx(238.1, rel=1e-3)


def test_contact_bound_and_leaf_radius():
    assert leaf_radius_bound(2 * math.asin(0.69)) == pytest.approx(0.69)
    far, _ = references.circle(0.5, np.pi, 1.0)   # the point of the circle opposite the pole
    assert math.acos(-far[2]) == pytest.approx(2 * math.asin(0.5), rel=1e-12)
    assert robot_for_k(K).k == pytest.approx(K, rel=1e-14) and robot_for_k(K).j_zz == pytest.approx(1.0)


#: The comparison of the module's tests (``comp``), and of the brute forces of its multistart.
COMPARED = dict(target=(0.5, 0.3, 0.4), steps=1, k=K, intervals=16, branches=1)


@pytest.fixture(scope="module")
def comp_calls():
    """The comparison of :data:`COMPARED` by two workers (the second with a twin solver), what its multistart
    called and the progress it reported: ``(comparison, corrections, solved, seen)``, ``solved`` each NLP solve's
    ``(planner or twin, solution)``, ``seen`` each report's ``(label, done, total, stage)``."""
    from rollplan.planners.collocation import rest
    from rollplan.progress import reporting

    calls, solved, real_correct, real_nlp = [], [], rest.correct, rest.RestToRestPlanner.solve_nlp
    seen = []
    with pytest.MonkeyPatch.context() as mp, \
            reporting(lambda label, done, total, **kw: seen.append((label, done, total, kw.get("stage")))):
        mp.setattr(rest, "correct", lambda *a, **kw: calls.append(a) or real_correct(*a, **kw))
        mp.setattr(rest.RestToRestPlanner, "solve_nlp",
                   lambda self, *a: solved.append((self, real_nlp(self, *a))) or solved[-1][1])
        c = compare(**COMPARED, workers=2)
    return c, calls, solved, seen


@pytest.fixture(scope="module")
def comp(comp_calls):
    return comp_calls[0]


def test_comparison_is_fair(comp):
    bound = comp.contact_bound
    for side in (comp.gp, comp.collocation):
        m = side.motion
        assert np.abs(m.omega[[0, -1]]).max() < 1e-9 and np.abs(m.velocity[[0, -1]]).max() < 1e-9   # at rest
        assert _polar(m.state).max() <= bound                                                       # same bound
        assert side.costs == measure(m) and side.residual < 1e-9
    assert comp.bound <= comp.gp.costs["angular_velocity"] <= 1.05 * comp.bound   # N = 16: ramps cost ~ 1/N
    for s in comp.starts:    # never worse than the GP plan it started from
        if s.start_cost is not None and s.cost is not None:
            assert s.cost <= s.start_cost * (1 + 1e-9)
    assert comp.collocation.costs["angular_velocity"] < comp.gp.costs["angular_velocity"]


def test_comparison_figure_follows_the_colour_convention(comp):
    """Both planners in their colours (rollplan.plots.colors.PLANNER) on the paths and |omega|; each planner's
    rotor rates and torques in the rotor colours and omega's components in theirs; every colour in a legend."""
    from matplotlib.colors import to_rgba

    from rollplan.plots.colors import OMEGA, OMEGA_LABELS, PLANNER, PLANNER_LABELS, ROTOR, ROTOR_LABELS
    from rollplan.plots.compare import plot_comparison

    fig = plot_comparison(comp)
    by_title = {ax.get_title(): ax for ax in fig.axes}
    rgba = lambda ax: [to_rgba(ln.get_color()) for ln in ax.get_lines() if len(ln.get_xdata()) > 2]  # noqa: E731
    planners = [to_rgba(PLANNER[n]) for n in ("geometric", "collocation")]
    assert rgba(by_title["contact paths on the plane"]) == planners
    assert rgba(by_title["|omega| of both motions"]) == planners
    legends = {t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()}
    for name, side in (("geometric", comp.gp), ("collocation", comp.collocation)):
        who = PLANNER_LABELS[name]
        assert any(text.startswith(who) for text in legends)
        rates = by_title[f"{who}: rotor rates, eq. (11)"]
        assert rgba(rates) == [to_rgba(c) for c in ROTOR]
        assert np.array_equal(rates.get_lines()[1].get_ydata(), side.motion.rotor_rates[:, 1])
        assert rgba(by_title[f"{who}: motor torques"]) == [to_rgba(c) for c in ROTOR]
        assert rgba(by_title[f"{who}: omega (plane frame)"]) == [to_rgba(c) for c in OMEGA]
    assert all(any(lab in text for text in legends) for lab in (*ROTOR_LABELS, *OMEGA_LABELS, "start", "target"))
    below = by_title["contact paths on the sphere, seen from below"]   # the close-up, as in plan.png
    assert [c for c in rgba(below) if c in planners] == planners and below.get_aspect() == 1.0
    assert any(text.startswith("contact bound") for text in legends)


def test_corrected_controls_reach_the_goal_at_rest_by_the_printed_equations(comp):
    """The returned (Newton-corrected) accelerations, integrated by DOP853 on (15), (16), (20) with the contact
    path in closed form, end at the goal at rest within the tolerance 1e-9; the reported objective is their cost
    (for int |omega|^2 dt, the measure of the certified motion agrees to the sampling error)."""
    r = comp.result
    y, rates = references.rest_path_final(r.controls, r.horizon, K)
    assert np.abs(y - np.array([0.5, 0.3, 0.4 + 2 * math.pi * r.turns])).max() < 1e-9
    assert np.abs(rates).max() < 1e-9
    assert r.objective == pytest.approx(comp.collocation.costs["angular_velocity"], rel=1e-5)
    assert r.objective != r.stats.details["nlp_objective"]     # the correction changed the controls


@pytest.fixture(scope="module")
def small_planner():
    return RestToRestPlanner(8, 2, cost="angular_velocity")


@pytest.mark.slow
def test_horizon_scaling_law(small_planner, hard_path):
    """The problem is homogeneous in T: at T = 1e-6 the collocation's and the GP timing's costs are those of
    T = 1 times T^p (p = -1 for int |omega|^2 dt, -3 for int |tau|^2 dt, 0 for the path length), the peak rate
    times 1/T and the peak torque times 1/T^2."""
    from rollplan.studies.comparison import branch_guess

    problem = Problem((0.5, 0.3, 0.4), k=K)
    powers = {"path_length": 0, "angular_velocity": -1, "rotor_energy": -3, "peak_rotor_rate": -1,
              "peak_rotor_torque": -2, "duration": 1}
    T, costs = 1e-6, {}
    for h in (1.0, T):
        guess, m = branch_guess(problem, small_planner, h)
        r = small_planner.solve(problem, guess, h, m, robot_for_k(K))
        assert r.residual < 1e-9
        path = hard_path[1]
        costs[h] = (measure(r.motion), measure(timed_samples(path, optimal_timing(path, h, "angular_velocity", 8))))
    for small, one in zip(costs[T], costs[1.0]):
        for name, p in powers.items():
            assert small[name] == pytest.approx(one[name] * T ** p, rel=1e-9), name


@pytest.mark.slow
def test_contact_bound_holds_between_collocation_points():
    """With the bound active (path length, bound 0.6 rad) the NLP's bound at the collocation points is backed
    off until every sample of the certified motion is within it."""
    from rollplan.studies.comparison import branch_guess

    problem = Problem((0.5, 0.3, 0.4), k=K)
    planner = RestToRestPlanner(8, 3, cost="path_energy", contact_bound=0.6)
    guess, m = branch_guess(problem, planner)
    r = planner.solve(problem, guess, 1.0, m)
    polar, backed = _polar(r.motion.state).max(), r.stats.details["backed_off_bound"]
    assert backed < 0.6             # the first solve left the bound between its collocation points
    assert backed < polar <= 0.6    # the backed-off bound is active, the bound respected on the samples
    assert r.residual < 1e-9


def test_collocation_path_obeys_the_printed_equations(comp):
    tr = comp.collocation.motion.trajectory()
    x = references.replay(tr.u_o, tr.v_o, np.zeros(tr.s.size, int), np.zeros(3), K)
    assert np.abs(x - tr.state[:, :3]).max() < 1e-5


@pytest.mark.slow
def test_cli_compare_json_has_the_issues_keys(tmp_path, capsys):
    js, png = tmp_path / "c.json", tmp_path / "c.png"
    rc = main(["compare", "--to", "0.5", "0.3", "--psi", "0.4", "--k", "2.5", "--intervals", "20",
               "--branches", "1", "--json", str(js), "--plot", str(png)])
    assert rc == 0, capsys.readouterr().err
    out = capsys.readouterr().out   # the summary names the compared cost and, without a robot, the torque unit
    assert "compared cost: int|omega|^2 dt" in out and "peak rotor torque [J_zz rad/s^2]" in out and "N m" not in out
    d = json.loads(js.read_text())
    for side in ("geometric_phase", "collocation"):
        s = d[side]
        assert tuple(s) == SIDE_KEYS and tuple(s["trajectory"]) == TRAJECTORY_KEYS
        assert s["contact_bound"] == d["geometric_phase"]["contact_bound"]
        tr = s["trajectory"]
        assert len({len(v) for v in tr.values()}) == 1
        assert tr["u_a"][-1] == pytest.approx(0.5, abs=1e-6) and tr["psi"][-1] % (2 * math.pi) == \
            pytest.approx(0.4, abs=1e-6)
        assert s["effort"] == d["details"][side]["costs"]["angular_velocity"]
    assert png.stat().st_size > 1000


@pytest.mark.parametrize("argv, msg", [
    (["compare", "--to", "0.5", "0.3", "--k", "-1"], "k = -1"),
    (["compare", "--to", "0.5", "0.3", "--k", "0.5"], "k = 0.5"),
    (["compare", "--to", "0.5", "0.3", "--cost", "rotor_energy"], "needs robot parameters: give a robot (the robot "
                                                                   "argument; --robot FILE.toml on the command line)"),
    (["compare", "--to", "0.5", "0.3", "--intervals", "0"], "intervals"),
    (["compare", "--to", "0.5", "0.3", "--contact-bound", "2"], "contact_bound"),
    (["compare", "--to", "0.5", "0.3", "--horizon", "-1"], "horizon"),
    (["compare", "--to", "0.5", "0.3", "--horizon", "1e-300"], "[1e-06, 1000000]"),
    (["compare", "--to", "0.5", "0.3", "--intervals", "3"], f"in [4, {MAX_INTERVALS}]"),
    (["compare", "--to", "0.5", "0.3", "--k", "1"], "(1, 100]"),
    (["compare", "--to", "0.5", "0.3", "--json", "/nonexistent/dir/x.json"], "not writable"),
])
def test_cli_compare_bad_input(argv, msg, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("intervals", ["100000", str(MAX_INTERVALS + 1)])
def test_intervals_beyond_what_memory_serves_are_refused_at_once(intervals):
    """`compare --intervals 100000`, inside the range the help advertised, grew past 4.6 GB and was killed.
    Sizes above MAX_INTERVALS (whose NLP keeps within about 2 GB) are refused at once, in one line naming the
    limit and the memory."""
    import subprocess
    import sys
    import time

    t0 = time.perf_counter()
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "compare", "--to", "0.5", "0.3", "--intervals",
                        intervals], capture_output=True, text=True, timeout=120, check=False)
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert f"in [{MIN_INTERVALS}, {MAX_INTERVALS}]" in r.stderr and f"{MEMORY_GB} GB" in r.stderr
    assert "--intervals" in r.stderr or "intervals" in r.stderr
    assert time.perf_counter() - t0 < 60   # before any work (start-up of a loaded machine included)


def test_compare_shows_its_progress(comp_calls):
    """Long comparisons were silent: compare reports its stages (the NLP, the GP timing, each collocation start)."""
    seen = comp_calls[3]
    mine = [s for s in seen if s[0] == "compare"]
    stages = [s[3] for s in mine]
    assert stages[:2] == ["building the collocation NLP", "timing the geometric-phase branches"]
    assert any(s.startswith("collocation from gp0:") for s in stages) and "collocation from naive:0" in stages
    assert mine[-1][1] == mine[-1][2] and stages[-1] == "done"


@pytest.mark.parametrize("psi", ["0", "1"])
def test_cli_compare_needs_one_leg_of_figure_eights(psi, capsys):
    """The start itself and a turn in place have no one-leg figure-eight plan: exit 3, one line."""
    assert main(["compare", "--to", "0", "0", "--psi", psi]) == 3
    err = capsys.readouterr().err
    assert "one leg of figure eights" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_time_series_refuses_bad_shapes():
    from rollplan.errors import InputError

    with pytest.raises(InputError, match="velocity"):
        TimeSeries(np.arange(3.0), np.zeros((3, 5)), velocity=np.zeros((2, 2)), omega=np.zeros((3, 3)),
                   rotor_rates=np.zeros((3, 2)), rotor_torques=np.zeros((3, 2)))
    with pytest.raises(InputError, match="non-decreasing"):
        TimeSeries(np.array([0.0, 2.0, 1.0]), np.zeros((3, 5)), velocity=np.zeros((3, 2)), omega=np.zeros((3, 3)),
                   rotor_rates=np.zeros((3, 2)), rotor_torques=np.zeros((3, 2)))


@pytest.mark.slow
def test_empirical_order_of_the_collocation_optimum_is_one():
    """The optimum J(N) of the rest-to-rest collocation measured at N = 20, 40, 80, 160: the empirical order
    log2((J(N) - J(2N)) / (J(2N) - J(4N))) tends to 1, not to the transcription's 2d. The cost does not involve
    the accelerations, so the continuous problem's infimum has rates jumping at both ends and is not attained; the
    discrete optimum ramps the rates within about one interval at each end, which costs O(1/N)."""
    from rollplan.studies.comparison import branch_guess

    problem = Problem((0.5, 0.3, 0.4), k=K)
    J = []
    for n in (20, 40, 80, 160):
        planner = RestToRestPlanner(n, 3)
        guess, m = branch_guess(problem, planner)
        J.append(planner.solve(problem, guess, 1.0, m).objective)
    d = np.diff(J)
    orders = np.log2(d[:-1] / d[1:])
    assert np.all(d < 0)                        # monotone from above
    assert abs(orders[-1] - 1.0) < 0.2 and orders[-1] < orders[0]


@pytest.mark.slow
def test_minimum_time_within_the_limits():
    """Free final time under the rotor limits: the certified motion is at rest at both ends, on the goal within
    1e-9, and within the limits at every sample (the limits backed off where the samples exceeded them)."""
    from dataclasses import replace

    from rollplan.studies.comparison import minimum_time

    robot = replace(default_robot(), max_rotor_rate=300.0, max_rotor_torque=0.05)
    mt = minimum_time((0.05, 0.03, 0.4), robot, intervals=16)
    o, g = mt.collocation.costs, mt.gp.costs
    assert mt.collocation.residual < 1e-9 and mt.gp.residual < 1e-9
    assert o["duration"] == pytest.approx(mt.duration) and g["duration"] == pytest.approx(mt.gp_duration)
    assert o["peak_rotor_torque"] <= 0.05 and o["peak_rotor_rate"] <= 300.0
    assert g["peak_rotor_torque"] <= 0.05 * 1.01 and g["peak_rotor_rate"] <= 300.0 * 1.01
    assert np.abs(mt.collocation.motion.omega[[0, -1]]).max() < 1e-9
    # one limit is active: the motion could not be run faster
    assert max(o["peak_rotor_torque"] / 0.05, o["peak_rotor_rate"] / 300.0) > 0.95


def _written_out_minimum_time_nlp(planner):
    """The minimum-time NLP written out whole, as one expression graph: the transcription's NLP with T substituted,
    then the limits' rows of every interval (start, d points, end) after all of them; f = T."""
    from rollplan.planners.collocation.rest import motion_function

    tr = planner.base.transcription
    N, d, nx, nu = tr.intervals, tr.degree, tr.nx, tr.nu
    nlp, _ = tr.contact_nlp(planner.base.point, N_PAR)
    V, par = nlp["x"], nlp["p"]
    T, limits, fixed = ca.SX.sym("T"), ca.SX.sym("limits", 2), ca.SX.sym("fixed", N_PAR)
    sub = ca.vertcat(fixed[0], T, fixed[2:])
    f, lim, block = motion_function(), [], nx * d + nu + nx
    for i in range(N):
        o = nx + i * block
        w = V[o + nx * d: o + nx * d + nu]
        for xp in [V[o - nx: o], *(V[o + nx * j: o + nx * (j + 1)] for j in range(d)), V[o + nx * d + nu: o + block]]:
            _, _, rates, torque = f(xp, w, sub)
            lim += [rates / limits[0], torque / limits[1]]
    g_dyn = ca.substitute(nlp["g"], par, sub)
    return {"x": ca.vertcat(V, T), "p": ca.vertcat(fixed, limits), "f": T, "g": ca.vertcat(g_dyn, *lim)}, \
        g_dyn.numel()


def test_minimum_time_nlp_built_by_intervals_is_the_written_out_nlp():
    """The minimum-time NLP was one expression graph that CasADi differentiated whole (seconds to build); now it
    and its derivatives are built interval by interval, T a variable shared by every interval. Against the NLP
    written out whole: the same cost, the same rows (each interval's rows, then its limits', instead of all
    transcription rows, then all limits), the same gradient, Jacobian and Hessian of the Lagrangian at random
    points."""
    from rollplan.planners.collocation.rest import MinimumTimePlanner

    planner = MinimumTimePlanner(intervals=4, degree=2)
    ref_nlp, n_dyn = _written_out_minimum_time_nlp(planner)
    ref = ca.nlpsol("whole", "ipopt", ref_nlp, {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
    N, n_lim = planner.base.transcription.intervals, planner.n_lim
    per = n_dyn // N
    perm = np.concatenate([np.r_[np.arange(i * per, (i + 1) * per), n_dyn + np.arange(i * n_lim, (i + 1) * n_lim)]
                           for i in range(N)])           # row r of the new NLP is row perm[r] of the written-out one
    assert sorted(perm) == list(range(ref_nlp["g"].numel()))
    rng = np.random.default_rng(3)
    nx, npar = ref_nlp["x"].numel(), ref_nlp["p"].numel()
    dense = lambda v: np.atleast_2d(np.array(ca.DM(v)))  # noqa: E731
    for _ in range(3):
        x, p = rng.normal(size=nx), rng.uniform(0.5, 2.0, size=npar)
        x[-1] = rng.uniform(0.5, 3.0)   # T
        sigma, lam = rng.normal(), rng.normal(size=perm.size)
        lam_ref = np.empty_like(lam)
        lam_ref[perm] = lam
        for name, args, args_ref, rows in (("nlp_grad_f", [x, p], [x, p], None), ("nlp_jac_g", [x, p], [x, p], perm),
                                           ("nlp_hess_l", [x, p, sigma, lam], [x, p, sigma, lam_ref], None)):
            mine, theirs = planner.solver.get_function(name).call(args), ref.get_function(name).call(args_ref)
            for k, (a, b) in enumerate(zip(mine, theirs)):
                a, b = dense(a), dense(b)
                if rows is not None:
                    b = b[rows]
                if name == "nlp_hess_l":   # upper triangles
                    a, b = np.triu(a), np.triu(b)
                assert a.shape == b.shape and np.abs(a - b).max() <= 1e-12 * max(1.0, np.abs(b).max()), (name, k)


def test_multistart_corrects_only_the_best_start_and_keeps_the_best_certified_optimum(comp_calls):
    """The Gauss-Newton correction and the CVODES certificate cost more than an IPOPT solve; the multistart
    corrected and certified every converged start. Now only the start with the least NLP optimum is finished,
    and it is the one a brute force keeps: every converged start finished on its own, the least certified cost."""
    c, calls, solved, _ = comp_calls
    converged = [s for s in c.starts if s.status == "ok"]
    assert len(converged) >= 2 and len(calls) == 1 and len(solved) == len(converged)
    brute = [measure(planner.finish(nlp).motion)["angular_velocity"] for planner, nlp in solved]
    assert c.collocation.costs["angular_velocity"] == pytest.approx(min(brute), rel=1e-12)
    assert c.result.stats.details["nlp_objective"] == min(nlp.objective for _, nlp in solved)


def test_gauss_newton_integrates_sensitivities_only_where_it_steps():
    """The sensitivities cost about ten times a plain CVODES integration and were computed for every trial,
    also for the controls that end the correction. Now trials are integrated plainly and the sensitivities
    only at the controls a step starts from. x1' = w, x2' = x1^2 with w constant on each of 4 intervals: the
    corrected controls reach the end state by the closed form, and one sensitivity run per step is made."""
    from rollplan.planners.collocation.transcription import gauss_newton, sensitivity_step

    x, w, par = ca.SX.sym("x", 2), ca.SX.sym("w", 1), ca.SX.sym("par", 1)
    xdot = ca.vertcat(w, x[0] ** 2)
    counts = {"jacobians": 0, "plain": 0}

    def counted(fn, key):
        def call(**kw):
            counts[key] += 1
            return fn(**kw)
        return call

    step = counted(sensitivity_step("gn_test", x, w, par, xdot, ca.SX(0.0)), "jacobians")
    plain = counted(sensitivity_step("gn_test", x, w, par, xdot, ca.SX(0.0), False), "plain")
    N, final = 4, np.array([0.3, 0.2])
    a, _, size, first = gauss_newton(step, np.zeros((N, 1)), np.zeros(2), final, np.zeros(1), 1e-12, 8, plain)
    x1, x2, h = 0.0, 0.0, 1.0 / N     # closed form: x1 linear, x2 the integral of its square
    for wi in a[:, 0]:
        x2 += x1 ** 2 * h + x1 * wi * h ** 2 + wi ** 2 * h ** 3 / 3.0
        x1 += wi * h
    assert first > 0.1 and size <= 1e-12
    assert np.abs([x1 - final[0], x2 - final[1]]).max() <= 1e-11
    assert counts["jacobians"] % N == 0 and counts["plain"] % N == 0
    steps = counts["jacobians"] // N
    assert steps >= 1 and counts["plain"] // N >= steps + 1    # the first controls and one trial per step, plainly


@pytest.mark.slow
def test_starts_solved_in_parallel_are_those_solved_one_after_the_other(comp):
    """The starts of the multistart ran one after the other on one core; now by two workers at once, the second
    with a twin of the NLP's IPOPT solver (its derivatives shared). The brute force: the same comparison with
    one worker gives the same starts (names, statuses, NLP optima) and the same kept optimum."""
    two = comp
    assert len(two.starts) >= 4       # each worker solves more than one start
    one = compare(**COMPARED, workers=1)
    assert [(s.name, s.turns, s.status) for s in two.starts] == [(s.name, s.turns, s.status) for s in one.starts]
    for a, b in zip(one.starts, two.starts):
        assert (a.cost is None) == (b.cost is None)
        if a.cost is not None:
            assert b.cost == pytest.approx(a.cost, rel=1e-12)
    assert two.result.guess == one.result.guess
    assert np.abs(two.result.controls - one.result.controls).max() <= 1e-9
    assert two.collocation.residual <= 1e-9 and one.collocation.residual <= 1e-9


@pytest.mark.slow
def test_twin_solver_solves_the_same_nlp_alone_and_at_the_same_time():
    """A twin's IPOPT (derivatives shared with its planner) solves the NLP to the planner's own optimum, also while
    the planner solves another start in another thread (each solver's statistics its own)."""
    import threading

    from rollplan.planners.collocation.rest import RestToRestPlanner
    from rollplan.studies.comparison import branch_guess

    planner = RestToRestPlanner(16)
    twin = planner.twin()
    problem = Problem((0.5, 0.3, 0.4), k=K)
    guess, m = branch_guess(problem, planner)
    alone = planner.solve_nlp(problem, guess, 1.0, m)
    out = {}
    worker = threading.Thread(target=lambda: out.update(twin=twin.solve_nlp(problem, guess, 1.0, m)))
    worker.start()
    out["planner"] = planner.solve_nlp(problem, guess, 1.0, m)
    worker.join()
    for r in out.values():
        assert r.iterations == alone.iterations and r.status == alone.status
        assert np.abs(r.x - alone.x).max() <= 1e-12


@pytest.mark.slow
def test_cli_compare_curve_times_the_familys_plan(tmp_path, capsys):
    """compare --curve viviani: the GP side is the Viviani plan (its figure eight integrated by DOP853 along the
    typed lobes, printed (28)-(30), lands on the target) timed over the horizon; JSON and summary name the family."""
    js = tmp_path / "c.json"
    rc = main(["compare", "--to", "0.5", "0.3", "--psi", "0.4", "--k", "2.5", "--intervals", "20",
               "--branches", "1", "--curve", "viviani", "--json", str(js)])
    assert rc == 0, capsys.readouterr().err
    assert "curve viviani" in capsys.readouterr().out
    d = json.loads(js.read_text())
    fe = d["details"]["geometric_phase"]["figure_eight"]
    assert fe["curve"] == "viviani"
    end = references.family_trace("viviani", fe["a"], fe["b"], 2.5, fe["gamma"])
    assert end[:2] == pytest.approx([0.5, 0.3], abs=1e-9)
    assert (end[2] - 0.4) / (2 * math.pi) == pytest.approx(round((end[2] - 0.4) / (2 * math.pi)), abs=1e-9)
    tr = d["geometric_phase"]["trajectory"]
    assert tr["u_a"][-1] == pytest.approx(0.5, abs=1e-6) and tr["v_a"][-1] == pytest.approx(0.3, abs=1e-6)


@pytest.mark.slow
# the hard target only: the default one, (0.5, 0.3, 0.4), keeps its optimum even when every start but gp0 is
# screened out, so it cannot tell a screening that drops the start of the optimum
@pytest.mark.parametrize("target", [(0.2, 0.1, 2.0)])
def test_screened_multistart_keeps_the_optimum_of_the_full_multistart(target, monkeypatch):
    """Every start was solved on the full grid, the hard ones for up to 150 IPOPT iterations each. Now the starts
    are screened on the coarse grid and only gp0 and the promising ones solved on the full grid. The brute force:
    every start solved on the full grid (screen=False) keeps the same certified optimum, with the same turns; no
    start screened out reaches a better full-grid optimum."""
    from rollplan.planners.collocation import rest
    from rollplan.studies.comparison import SCREEN_INTERVALS, comparison_to_dict

    solved, real_nlp = [], rest.RestToRestPlanner.solve_nlp
    monkeypatch.setattr(rest.RestToRestPlanner, "solve_nlp", lambda self, problem, guess, *a: solved.append(
        (self.transcription.intervals, guess.name)) or real_nlp(self, problem, guess, *a))
    screened = compare(target, 1, k=K, intervals=40)
    fine = [name for n, name in solved if n == 40]
    assert len([name for n, name in solved if n == SCREEN_INTERVALS]) == len(screened.starts)
    assert 1 <= len(fine) < len(screened.starts) and fine[0] == screened.starts[0].name
    full = compare(target, 1, k=K, intervals=40, screen=False)
    kept = full.collocation.costs["angular_velocity"]
    assert screened.collocation.costs["angular_velocity"] == pytest.approx(kept, rel=1e-9)
    assert screened.result.turns == full.result.turns and screened.collocation.residual <= 1e-9
    by_name = {s.name: s for s in full.starts}
    out = [s for s in screened.starts if s.status == "Screened_Out"]
    assert out and all(s.coarse_cost is not None and s.cost is None for s in out)
    listed = comparison_to_dict(screened)["details"]["starts"]
    assert [d["coarse_cost"] for d in listed] == [s.coarse_cost for s in screened.starts]
    least = full.result.stats.details["nlp_objective"]     # the other starts' costs are their NLP optima
    for s in out:
        assert by_name[s.name].cost is None or by_name[s.name].cost >= least * (1 - 1e-6)
