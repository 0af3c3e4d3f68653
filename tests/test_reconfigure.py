"""Full reconfiguration (rollplan.planners.geometric.composed, .maneuvers, .turn, .legs, .route): plans between
any two states, certified by an independent integration of the whole composed motion from the start state:
scipy's DOP853 on the printed (15), (16), (20) along the contact path, typed in tests/references.py from the
pieces' parameters alone (references.great_circle_path, references.circle_path)."""

import functools
import math

import numpy as np
import pytest
from test_cli import run

import rollplan
from rollplan import InputError, NoPlanError, Problem, State
from rollplan.core.plane import compose
from rollplan.planners.geometric.composed import ComposedPlanner, as_composed
from rollplan.planners.geometric.legs import LEAF_FLOOR
from rollplan.planners.geometric.maneuvers import StraightRoll
from rollplan.planners.geometric.turn import turn_in_place
from rollplan.problem import N3Z_MIN, check_contact

import references as ref

TOL = 1e-9
SIGMA_MAX = math.acos(N3Z_MIN)


contact_at = ref.polar_contact


def random_state(rng, reach=1.0):
    return (*rng.uniform(-reach, reach, 2), rng.uniform(-4, 4),
            *contact_at(rng.uniform(0.0, SIGMA_MAX), rng.uniform(-np.pi, np.pi)))


reference_final = ref.composed_final


def reference_residual(p):
    """Residual to the goal of the independent integration of the whole motion of plan ``p`` from its start."""
    c = as_composed(p)
    final = reference_final(c.pieces, c.problem.scaled(c.problem.start), c.k)
    err = final - np.asarray(c.problem.scaled(c.goal))
    err[2] = ref.wrap(err[2])
    return float(np.linalg.norm(err))


@pytest.fixture(scope="module")
def planner():
    return ComposedPlanner()


# ----------------------------------------------------------------------------- the region and the rolls


@pytest.mark.parametrize("u,v", [(1.6, 0.0), (0.0, -1.58), (1.5, 1.5), (np.nan, 0.0), (0.0, np.inf), (1.53, 0.1)])
def test_contact_outside_the_region_is_refused_in_one_line(u, v):
    with pytest.raises(InputError) as err:
        check_contact(u, v)
    assert "\n" not in str(err.value)
    for name, kw in (("goal", dict(goal=(0, 1, 0, u, v))), ("start", dict(goal=(0, 1, 0), start=(0, 0, 0, u, v)))):
        with pytest.raises(InputError, match=name):
            Problem(k=2.5, **kw)


def test_the_margin_itself_is_accepted():
    u = SIGMA_MAX - 1e-12
    assert check_contact(u, 0.0) == (u, 0.0)
    assert math.cos(u) >= N3Z_MIN


@pytest.mark.parametrize("sigma,beta", [(0.05, -2.9), (0.6, 0.4), (1.2, 1.9), (SIGMA_MAX, -1.0)])
@pytest.mark.parametrize("kind", ["approach", "departure"])
def test_straight_roll_closed_form_against_the_printed_equations_for_every_k(sigma, beta, kind):
    roll = StraightRoll.make(*contact_at(sigma, beta), kind)
    assert roll.sigma == pytest.approx(sigma, abs=1e-14)
    ends = (sigma, 0.0) if kind == "approach" else (0.0, sigma)
    for k in (0.0, 2.5, 10.0, 100.0):
        x = ref.integrate_contact_path(ref.great_circle_path(roll.beta, *ends), np.zeros(3), (0, 1), k).y[:, -1]
        err = x - roll.element()
        err[2] = ref.wrap(err[2])
        assert np.abs(err).max() < 1e-11


def test_departure_rolls_straight_for_sigma_without_yaw_and_n3z_falls_monotonically():
    roll = StraightRoll.make(*contact_at(1.3, 2.2), "departure")
    t = np.linspace(0, 1, 50)
    path = ref.great_circle_path(roll.beta, 0.0, roll.sigma)
    y = ref.integrate_contact_path(path, np.zeros(3), (0, 1), 7.0, t).y
    np.testing.assert_allclose(y[0], roll.sigma * t * np.cos(roll.beta), atol=1e-11)
    np.testing.assert_allclose(y[1], roll.sigma * t * np.sin(roll.beta), atol=1e-11)
    n3z = np.array([np.cos(u) * np.cos(v) for u, v, *_ in map(path, t)])
    assert np.all(np.diff(n3z) < 0)
    # zero spin: (13) with omega_z = 0, omega from (18)-(19) and n3 of (5)
    for ti in t[1:-1]:
        u, v, du, dv = path(ti)
        psi = np.interp(ti, t, y[2])
        w = np.array([*ref.rolling_18_19(u, v, psi, du, dv), 0.0])
        assert abs(ref.realizability(ref.axes(u, v, psi)[2], w, 7.0)) < 1e-12


# ----------------------------------------------------------------------------- composed plans


@pytest.mark.parametrize("seed", range(3))
def test_random_start_goal_pairs_are_certified_independently(planner, seed):
    rng = np.random.default_rng(1000 + seed)
    k, steps = float(rng.uniform(0.5, 12)), int(rng.integers(1, 3))
    p = planner.solve(Problem(random_state(rng), start=random_state(rng), k=k, steps=steps))
    assert p.residual < TOL and reference_residual(p) < TOL
    kinds = [q.kind for q in p.pieces]
    assert kinds[0] == "approach" and kinds[-1] == "departure"
    assert p.path_length == pytest.approx(sum(q.length for q in p.pieces), rel=1e-14)
    assert p.pieces[-1].end_contact() == pytest.approx(p.goal[3:], abs=1e-14)


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(3, 12))
def test_more_random_start_goal_pairs(planner, seed):
    test_random_start_goal_pairs_are_certified_independently(planner, seed)


def test_radius_scales_lengths():
    p1 = rollplan.plan((0.3, 0.5, 0.2, 0.1, -0.2), k=2.5, start=(0.1, 0.0, 0.0, -0.3, 0.1), polish="off")
    p2 = rollplan.plan((0.6, 1.0, 0.2, 0.1, -0.2), k=2.5, start=(0.2, 0.0, 0.0, -0.3, 0.1), radius=2.0,
                       polish="off")
    assert p2.path_length == pytest.approx(2 * p1.path_length, rel=1e-12)
    assert p2.final[:2] == pytest.approx(2 * np.array(p1.final[:2]), abs=1e-9)
    assert reference_residual(p2) < TOL


def test_a_start_at_the_pole_off_the_origin_solves_the_relative_target(planner):
    """From (x0, y0, psi0) at the pole the figure eights solve Rot(psi0)(goal - start), psi_g - psi0."""
    s, g = np.array([0.4, -0.3, 1.1]), np.array([0.9, 0.6, 1.5])
    p = planner.solve(Problem(tuple(g), start=tuple(s), k=2.5, steps=2))
    d = ref.rotate(s[2], g[:2] - s[:2])
    q = rollplan.plan((d[0], d[1], g[2] - s[2]), steps=2, k=2.5)
    assert p.mode == "one" and p.approach is None and p.departure is None
    assert (p.legs[0].a, p.legs[0].b, p.legs[0].gamma) == pytest.approx((q.a, q.b, q.gamma), abs=1e-9)
    assert reference_residual(p) < TOL


def test_the_papers_problem_gets_the_papers_plan():
    p = rollplan.plan((0.0, 1.0, 0.0), k=2.5)
    assert isinstance(p, rollplan.Plan) and p.a == pytest.approx(0.300429, abs=1e-6)
    c = as_composed(p)
    assert [q.kind for q in c.pieces] == ["leaf", "leaf"] and c.certificate is p.certificate


def test_start_equal_to_goal_is_the_empty_motion(planner):
    state = (0.2, 0.1, 0.3, 0.2, -0.1)
    for goal in (state, (0.2, 0.1, 0.3 + 2 * np.pi, 0.2, -0.1)):
        p = planner.solve(Problem(goal, start=state, k=2.5))
        assert p.mode == "empty" and p.pieces == () and p.residual < 1e-15 and p.path_length == 0.0
        assert p.sample(5).state.shape == (5, 5)


def test_the_rolls_alone_when_they_reach_the_goal(planner):
    """goal = start * g_A * g_B: the approach and the departure are the whole motion."""
    start = np.array([0.3, 0.2, 0.5, 0.4, -0.3])
    contact = (-0.2, 0.5)
    g = compose(compose(start[:3], StraightRoll.make(*start[3:], "approach").element()),
                StraightRoll.make(*contact, "departure").element())
    p = planner.solve(Problem((*g, *contact), start=tuple(start), k=2.5))
    assert p.mode == "rolls" and [q.kind for q in p.pieces] == ["approach", "departure"]
    assert reference_residual(p) < TOL


# ----------------------------------------------------------------------------- turning in place


@pytest.mark.parametrize("psi", [0.3, 1.0, -2.0, 3.0, 7.0])
@pytest.mark.parametrize("k", [0.0, 2.5, 30.0])
def test_turning_in_place(planner, psi, k):
    """A pair of equal circles whose shifts cancel, certified by DOP853 on the printed equations."""
    p = planner.solve(Problem((0.0, 0.0, psi), k=k))
    assert p.mode == "turn" and len(p.pieces) == 2 and p.residual < TOL
    assert reference_residual(p) < TOL
    assert p.path_length == pytest.approx(4 * np.pi * p.turn.b, rel=1e-14)


@pytest.mark.parametrize("steps", [2, 3])
def test_turning_in_place_with_more_pairs(planner, steps):
    p = planner.solve(Problem((0.0, 0.0, 1.2), k=6.0, steps=steps))
    assert p.mode == "turn" and len(p.pieces) == 2 * steps and reference_residual(p) < TOL


def test_turning_in_place_off_the_pole(planner):
    """Off the pole the rolls make the figure eights' target a shift with a turn: one leg."""
    p = planner.solve(Problem((1.0, -0.5, 2.2, 0.3, 0.2), start=(1.0, -0.5, 0.7, 0.3, 0.2), k=2.5))
    assert reference_residual(p) < TOL


#: The brute force's uniform grid of circle radii b.
HOLONOMY_GRID = np.linspace(1e-3, 0.69, 700)
_HOLONOMY: dict = {}


def circle_holonomy(k, i):
    """eta_1(b) at HOLONOMY_GRID[i]: psi after one -y circle (35) of radius b from zero, by DOP853 on the
    printed equations (the whole grid as one system, once per k; two radii checked against the circle alone)."""
    if k not in _HOLONOMY:
        grid = HOLONOMY_GRID
        ends = ref.integrate_contact_paths(ref.circle_path(grid, -1.0, 0.0), np.zeros((3, grid.size)),
                                           (0, 2 * np.pi), k, rtol=1e-9, atol=1e-11)
        for j in (grid.size // 2, grid.size - 1):
            alone = ref.integrate_contact_path(ref.circle_path(grid[j], -1.0, 0.0), np.zeros(3), (0, 2 * np.pi), k,
                                               rtol=1e-9, atol=1e-11).y[2, -1]
            assert abs(alone - ends[2, j]) < 1e-7, (k, grid[j], alone, ends[2, j])
        _HOLONOMY[k] = ends[2]
    return _HOLONOMY[k][i]


@pytest.mark.slow
@pytest.mark.parametrize("psi,k,steps", [(0.3, 2.5, 1), (3.0, 2.5, 1), (-2.0, 2.5, 2), (5.0, 2.5, 1),
                                         (-2.0, 0.0, 1), (1.0, 0.0, 2), (1.0, 10.0, 2)])
def test_the_turn_is_the_smallest_circle_of_a_brute_force(psi, k, steps):
    """Brute force: the first crossing of eta_1(b) (DOP853 on a uniform grid, walked up from the smallest b)
    with any level +-(psi + 2 pi m)/(2n); its b must be the turn's, to the grid spacing."""
    b = HOLONOMY_GRID
    m = np.arange(-200, 201)
    levels = np.concatenate([sign * (psi + 2 * np.pi * m) / (2 * steps) for sign in (1.0, -1.0)])
    best = np.inf
    for i in range(b.size - 1):
        if np.any(np.sign(circle_holonomy(k, i) - levels) * np.sign(circle_holonomy(k, i + 1) - levels) <= 0):
            best = b[i]
            break
    t = turn_in_place(psi, k, steps)
    assert best - 1e-12 <= t.b <= best + (b[1] - b[0]) * 1.01


@pytest.mark.parametrize("psi,k", [(1.0, 2.5), (-2.0, 0.0), (3.0, 30.0)])
def test_one_circle_turns_by_half_the_turn(psi, k):
    t = turn_in_place(psi, k, 1)
    x = ref.integrate_contact_path(ref.circle_path(t.b, 1.0 if t.side == 0 else -1.0, 0.0), np.zeros(3),
                                   (0, 2 * np.pi), k).y[:, -1]
    assert x[2] == pytest.approx(t.eta, abs=1e-11) and abs(ref.wrap(2 * x[2] - psi)) < 1e-11


# ----------------------------------------------------------------------------- two legs


def test_a_tiny_shift_with_a_turn_takes_two_legs(planner):
    p = planner.solve(Problem((1e-7, -2e-7, 0.8), k=2.5))
    assert p.mode == "two" and len(p.legs) == 2 and reference_residual(p) < TOL


def test_one_leg_without_a_plan_falls_back_to_two_legs_or_says_so():
    with pytest.raises(NoPlanError, match="more steps") as err:
        rollplan.plan((1e-7, -2e-7, 0.8), k=2.5, legs="one")
    assert "\n" not in str(err.value)
    with pytest.raises(NoPlanError, match="more steps"):
        rollplan.plan((30.0, 0.0, 0.0), k=2.5)


@pytest.mark.slow
def test_two_legs_forced_on_a_reachable_target_and_shortest(planner):
    two = ComposedPlanner(legs="two").solve(Problem((0.4, 0.3, 0.5), k=2.5))
    assert two.mode == "two" and reference_residual(two) < TOL
    one = rollplan.plan((0.4, 0.3, 0.5), k=2.5)
    best = rollplan.plan((0.4, 0.3, 0.5), k=2.5, legs="shortest")
    assert best.path_length == min(one.path_length, two.path_length)


@pytest.mark.slow
@pytest.mark.parametrize("psi,k", [(1.0, 2.5), (-2.0, 6.0)])
def test_two_legs_of_a_turn_tend_to_the_circle_pair(psi, k):
    """The two-leg optimum of a turn in place is the circle pair plus one floor-size leaf per leg."""
    turn = ComposedPlanner().solve(Problem((0.0, 0.0, psi), k=k))
    two = ComposedPlanner(legs="two").solve(Problem((0.0, 0.0, psi), k=k))
    assert reference_residual(two) < TOL and turn.path_length <= two.path_length
    assert two.path_length == pytest.approx(turn.path_length + 4 * np.pi * LEAF_FLOOR, abs=2e-3)


# ----------------------------------------------------------------------------- routes


WAYPOINTS = """# five waypoints: start, a move, a turn in place, a full state off the pole, back home
u_a,v_a,psi,u_o,v_o,steps,label
0,0,0,,,,home
1.0,0.5,0.3,,,1,a
1.0,0.5,1.3,,,1,turn
1.2,0.4,1.5,0.3,-0.2,2,inspect
0,0,0,0,0,1,home again
"""


def test_route_of_five_waypoints_certified_independently(tmp_path):
    path = tmp_path / "w.csv"
    path.write_text(WAYPOINTS)
    wps = rollplan.read_waypoints(path)
    assert len(wps) == 5 and wps[3].steps == 2 and wps[4].label == "home again" and wps[3].state.u_o == 0.3
    r = rollplan.plan_route(wps, k=2.5)
    assert r.stats.details["modes"][1] == "turn"
    assert r.residual < TOL and (r.waypoint_residuals < TOL).all()
    # DOP853 on the printed equations through the whole route from the first waypoint, every waypoint on the way
    x = np.asarray(wps[0].state, float)
    for p, w in zip(r.plans, wps[1:]):
        x = reference_final(as_composed(p).pieces, x, 2.5)
        err = x - np.asarray(w.state)
        err[2] = ref.wrap(err[2])
        assert np.linalg.norm(err) < TOL
    t = r.sample(3001)
    assert t.state.shape == (3001, 5) and t.segment.max() + 1 == len(r.pieces)
    assert r.path_length == pytest.approx(sum(q.length for q in r.pieces), rel=1e-12)


@pytest.mark.parametrize("text,where", [
    ("u_a,v_a,psi,w\n0,0,0,1\n1,0,0,1\n", "line 1: unknown column 'w'"),
    ("u_a,psi\n0,0\n1,0\n", "lacks column(s) v_a"),
    ("u_a,v_a,psi\n0,0,0\n1,x,0\n", "line 3: v_a = 'x'"),
    ("u_a,v_a,psi\n0,0,0\n1,nan,0\n", "line 3: v_a"),
    ("u_a,v_a,psi,steps\n0,0,0,2\n1,0,0,1\n", "line 2: the first row is the start"),
    ("u_a,v_a,psi\n0,0,0\n", "at least two waypoints"),
    ("u_a,v_a,psi,u_o,v_o\n0,0,0,,\n1,0,0,1.56,0\n", "line 3: waypoint (u_o, v_o)"),
    ("u_a,v_a,psi,steps\n0,0,0,\n1,0,0,0\n", "line 3: steps = 0"),
    ("u_a,v_a,psi\n0,0,0\n1,0\n", "line 3: has 2 field(s), the header 3"),
    ("", "is empty"),
    ("# only a comment\n\n", "is empty"),
    ("u_a,v_a,psi,psi\n0,0,0,0\n1,0,0,0\n", "column 'psi' appears twice"),
    ("# a comment, then the header on line 2\nu_a,v_a,psi,w\n0,0,0,1\n1,0,0,1\n", "line 2: unknown column 'w'"),
    ("u_a,v_a,psi\n0,0,0\n1_0,0,0\n", "line 3: u_a = '1_0'"),
    ("u_a,v_a,psi\n0,0,0\n\uff11,0,0\n", "line 3: u_a"),
    ("u_a,v_a,psi,steps\n0,0,0,\n1,0,0,2.0\n", "line 3: steps = '2.0'"),
])
def test_waypoint_file_errors_name_the_line(tmp_path, text, where):
    path = tmp_path / "w.csv"
    path.write_text(text)
    with pytest.raises(InputError) as err:
        rollplan.read_waypoints(path)
    assert where in str(err.value) and "\n" not in str(err.value) and "w.csv" in str(err.value)


def test_waypoint_file_that_is_missing_or_binary(tmp_path):
    with pytest.raises(InputError, match="cannot be read"):
        rollplan.read_waypoints(tmp_path / "none.csv")
    (tmp_path / "b.csv").write_bytes(b"\xff\xfe\x00\x01")
    with pytest.raises(InputError, match="UTF-16"):
        rollplan.read_waypoints(tmp_path / "b.csv")


def test_route_of_states_and_its_leg_without_a_plan():
    r = rollplan.plan_route([(0, 0, 0), (0.5, 0.0, 0.0, 0.2, 0.1), (0.5, 0.5, -1.0)], k=5.0, steps=2)
    assert r.residual < TOL and len(r.plans) == 2 and r.problem.start == State()
    with pytest.raises(NoPlanError, match="route leg 2"):
        rollplan.plan_route([(0, 0, 0), (0.5, 0, 0), (40, 0, 0)], k=2.5)
    with pytest.raises(InputError, match="two waypoints"):
        rollplan.plan_route([(0, 0, 0)], k=2.5)


# ----------------------------------------------------------------------------- the sampled trajectory


@pytest.mark.parametrize("goal,start,steps,k", [
    pytest.param((0.5, 0.7, 0.8, 0.3, -0.2), (0.2, -0.1, 0.4, -0.5, 0.6), 2, 2.5, marks=pytest.mark.slow),
    ((0.3, -0.2, -0.5, -0.2, 0.1), (0.1, 0.1, 0.3, 0.3, 0.2), 1, 3.0),
    ((0.0, 0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 0.0, 0.0, 0.0), 1, 5.0),      # turn in place
])
def test_json_trajectory_replays_to_the_goal(tmp_path, capsys, goal, start, steps, k):
    """The plan JSON of the command: integrating (15), (16), (20) along its sampled contact path alone
    reproduces its u_a, v_a, psi and lands on the goal."""
    import json

    from rollplan.cli import main

    out = tmp_path / "p.json"
    argv = ["plan", "--from", *map(str, start), "--to", str(goal[0]), str(goal[1]), "--psi", str(goal[2]),
            "--contact", str(goal[3]), str(goal[4]), "--steps", str(steps), "--k", str(k), "--json", str(out),
            "--samples", "801", "--polish", "off"]
    assert main(argv) == 0
    d = json.loads(out.read_text())
    tr = d["trajectory"]
    assert all(len(tr[n]) == 801 for n in ("u_a", "v_a", "psi", "u_o", "v_o", "segment"))
    seg = np.array(tr["segment"])
    assert seg[0] == 0 and np.all(np.diff(seg) >= 0) and seg.max() + 1 == len(d["segments"])
    sampled = np.column_stack([tr["u_a"], tr["v_a"], tr["psi"]])
    replayed = ref.replay(tr["u_o"], tr["v_o"], tr["segment"], sampled[0], k)
    err = sampled - replayed
    err[:, 2] = ref.wrap(err[:, 2])
    assert np.abs(err).max() < 1e-5
    end = np.r_[replayed[-1], tr["u_o"][-1], tr["v_o"][-1]] - np.array(goal)
    end[2] = ref.wrap(end[2])
    assert np.linalg.norm(end) < 1e-5
    assert d["residual"] < TOL and d["final"] == pytest.approx(dict(zip(rollplan.STATE_NAMES, goal)), abs=1e-9)


# ----------------------------------------------------------------------------- execution, collocation, command


@pytest.fixture(scope="module")
def timed():
    """A composed plan for the default robot (start and goal off the pole) timed over 12 s."""
    from rollplan.execution.actuation import actuate

    robot = rollplan.default_robot()
    p = rollplan.plan((0.05, 0.02, 0.8, 0.3, -0.2), robot=robot, start=(0.01, -0.02, 0.4, -0.5, 0.6), polish="off")
    return p, actuate(p, robot, 12.0, 2000), robot


def test_actuation_of_a_composed_plan_rests_at_every_joint(timed):
    p, m, robot = timed
    assert [q.kind for q in p.pieces] == ["approach", "leaf", "leaf", "departure"]
    rest = m.rest_indices
    assert rest.size == len(p.pieces) + 1
    assert np.all(m.series.omega[rest] == 0) and np.all(m.series.rotor_rates[rest] == 0)
    assert np.abs(m.series.omega).max() > 0.1
    np.testing.assert_allclose(m.series.state[0], p.problem.start, atol=1e-15)
    err = m.series.state[-1] - np.asarray(p.goal)
    err[2] = ref.wrap(err[2])
    assert np.abs(err).max() < 1e-9
    # the joints are where the pieces end: at the pole between the rolls and the figure eights
    assert np.abs(m.series.state[rest[1:-1], 3:]).max() < 1e-12
    _, _, n3 = ref.axes(m.series.state[:, 3], m.series.state[:, 4], m.series.state[:, 2])
    assert np.abs(ref.realizability(n3, m.series.omega, robot.k)).max() < 1e-12 * np.abs(m.series.omega).max()


def test_the_rotor_rates_alone_drive_the_robot_from_the_start_to_the_goal(timed):
    from rollplan.execution.plants import simulate_rotors

    p, m, robot = timed
    sim = simulate_rotors(robot, m.series.time, m.series.rotor_rates, p.goal, x0=p.problem.start.array())
    assert sim.arrival_error < 1e-6


@pytest.mark.slow
def test_a_composed_plan_timed_time_optimally_is_driven_onto_the_goal_by_its_rotor_rates():
    """Start off the pole, a turn in place, a goal off the pole, timed by the time-optimal law within the motors'
    limits: the motion rests at the start, the goal and every corner of the contact path, stays within the
    limits with one of them active, and its rotor rates alone (scipy's not-a-knot spline) drive the printed
    (2), (6)-(10), (11) by DOP853 from the start state onto the goal to 1e-5 R (rtol 1e-9: its final state is
    within 1.1e-7 of rtol 1e-11's, 90 times below the tolerance, at a quarter of the cost)."""
    from dataclasses import replace

    from scipy.integrate import solve_ivp
    from scipy.interpolate import CubicSpline

    from rollplan.execution.actuation import actuate
    from rollplan.execution.timing import joint_times

    robot = replace(rollplan.default_robot(), max_rotor_rate=300.0, max_rotor_torque=0.05)
    R = robot.radius
    start = np.array([0.02, -0.01, 0.4, 0.3, -0.2])
    contact = (-0.2, 0.25)
    g = compose(compose(start[:3] / [R, R, 1.0], StraightRoll.make(*start[3:], "approach").element()),
                np.array([0.0, 0.0, 1.0]))   # the figure eights must turn in place by 1 rad
    g = compose(g, StraightRoll.make(*contact, "departure").element())
    goal = np.array([g[0] * R, g[1] * R, g[2], *contact])
    p = rollplan.plan(tuple(goal), robot=robot, start=tuple(start), polish="off")
    assert p.mode == "turn" and [q.kind for q in p.pieces] == ["approach", "turn", "turn", "departure"]
    m = actuate(p, robot, None, 2000, "time-optimal")
    assert m.duration == m.minimum_duration and m.timing == "time-optimal"
    assert m.path.corners.all()   # roll to circle, circle to circle (another gamma), circle to roll
    _, s_dot, _ = m.profile.evaluate(joint_times(m.path, m.profile))
    assert np.abs(s_dot).max() < 1e-9 * m.s_dot.max() and m.s_dot[0] == m.s_dot[-1] == 0.0
    util = m.limits.utilisation(m.series.rotor_rates, m.series.rotor_torques)
    assert util.max() <= 1 + 1e-6 and np.mean(util > 0.99) > 0.8
    np.testing.assert_allclose(m.series.state[0], start, atol=1e-15)
    f = ref.rotor_driven_rhs(robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, R,
                             CubicSpline(m.series.time, m.series.rotor_rates, bc_type="not-a-knot"))
    sol = solve_ivp(f, (0.0, m.duration), start, method="DOP853", rtol=1e-9, atol=1e-11)
    err = sol.y[:, -1] - goal
    err[2] = ref.wrap(err[2])
    assert np.hypot(err[0], err[1]) / R < 1e-5 and np.abs(err[2:]).max() < 1e-5


def test_the_empty_motion_is_at_rest():
    from rollplan.execution.actuation import actuate

    robot = rollplan.default_robot()
    state = (0.01, 0.02, 0.3, 0.1, 0.1)
    m = actuate(rollplan.plan(state, robot=robot, start=state), robot, 2.0, 10)
    s = m.series
    assert s.time.size == 10 and np.all(s.rotor_rates == 0) and np.all(s.state == np.asarray(state))


def test_collocation_refuses_a_start_beyond_its_contact_bound_clearly():
    from rollplan.planners.collocation import CollocationPlanner

    problem = Problem((0.5, 0.3, 0.4), start=(0, 0, 0, *contact_at(1.45, 0.3)), k=2.5)
    with pytest.raises(InputError, match="start contact point lies 1.45 rad from the south pole") as err:
        CollocationPlanner(intervals=10).solve(problem, guess="naive")
    assert "\n" not in str(err.value)


@pytest.mark.slow
@pytest.mark.parametrize("polish", ["fast", "off"])
def test_collocation_warm_started_from_a_composed_plan(polish):
    """Start and goal off the pole: the warm start is the plan (polished by default, or the composed geometric
    plan); the optimum is certified."""
    problem = _off_the_pole()
    warm = rollplan.plan(problem.goal, k=2.5, start=problem.start, polish=polish)
    r = rollplan.collocate(problem.goal, k=2.5, start=problem.start, intervals=60, warm_start=warm)
    assert r.certificate.passed and r.residual < 1e-6 and r.turns == warm.turns
    assert r.path_length <= warm.path_length * (1 + 1e-6)
    assert _collocated_without_a_warm_start().certificate.passed


def _off_the_pole():
    """The problem of test_collocation_warm_started_from_a_composed_plan: start and goal off the pole."""
    return Problem((0.3, 0.2, 0.5, 0.2, -0.1), start=(0.0, 0.0, 0.0, -0.2, 0.3), k=2.5)


@functools.cache
def _collocated_without_a_warm_start():
    """:func:`_off_the_pole` solved by collocation with no warm start given (the composed planner plans it): the
    same for both cases of test_collocation_warm_started_from_a_composed_plan, solved once."""
    return rollplan.solve(_off_the_pole(), "collocation", intervals=60)


@pytest.mark.parametrize("argv,needle", [
    (["plan", "--to", "0", "1", "--contact", "1.6", "0"], "goal (u_o, v_o) = (1.6, 0.0)"),
    (["plan", "--to", "0", "1", "--contact", "1.5", "1.2"], "below 0.05"),
    (["plan", "--from", "0", "0", "0", "0.2", "nan", "--to", "0", "1"], "'nan' is not allowed"),
    (["plan", "--from", "0", "0", "0", "0", "-1.58", "--to", "0", "1"], "start (u_o, v_o)"),
    (["plan", "--from", "0", "0", "0", "--to", "0", "1"], "--from"),
    (["plan", "--to", "0", "1", "--legs", "three"], "--legs"),
    (["plan", "--to", "0", "1", "--samples", "1"], "samples = 1"),
    (["route", "missing.csv"], "cannot be read"),
    (["route", "missing.csv", "--timing-plot", "t.png"], "--timing-plot needs a timed motion"),
    (["route", "missing.csv", "--timing", "time-optimal"], "needs max_rotor_torque"),
])
def test_command_refuses_bad_states_with_exit_2(capsys, argv, needle):
    code, _, err = run(capsys, *argv)
    assert code == 2 and needle in err and err.count("\n") == 1


@pytest.mark.slow
def test_command_route_writes_json_and_figure(tmp_path, capsys):
    import json

    path = tmp_path / "w.csv"
    path.write_text("u_a,v_a,psi,u_o,v_o\n0,0,0,0.1,0\n0.6,0.2,0.5,,\n0.6,0.2,-0.5,0,0.2\n")
    code, out, _ = run(capsys, "route", str(path), "--k", "2.5", "--json", str(tmp_path / "r.json"),
                       "--plot", str(tmp_path / "r.png"), "--samples", "777")
    assert code == 0 and "leg 2 to waypoint 3" in out and (tmp_path / "r.png").stat().st_size > 0
    d = json.loads((tmp_path / "r.json").read_text())
    assert len(d["trajectory"]["u_a"]) == 777 and len(d["waypoints"]) == 3 and len(d["legs"]) == 2
    assert d["residual"] < TOL and max(d["waypoint_residuals"]) < TOL
    assert d["trajectory"]["u_o"][0] == 0.1 and d["start"]["u_o"] == 0.1


@pytest.mark.slow
def test_command_times_simulates_and_animates_a_composed_plan(tmp_path, capsys):
    plan_file = tmp_path / "p.json"
    code, out, _ = run(capsys, "plan", "--from", "0.01", "-0.02", "0.4", "-0.5", "0.6", "--to", "0.05", "0.07",
                       "--psi", "0.8", "--contact", "0.3", "-0.2", "--duration", "12", "--json", str(plan_file),
                       "--plot", str(tmp_path / "m.png"))
    assert code == 0 and "rotor-only" in out
    code, out, _ = run(capsys, "simulate", str(plan_file))
    error = float(out.split("arrival error")[1].split()[0])
    assert code == 0 and error < 1e-6
    code, _, _ = run(capsys, "animate", str(plan_file), "--out", str(tmp_path / "a.gif"), "--frames", "5")
    assert code == 0 and (tmp_path / "a.gif").stat().st_size > 0
    # a route timed the same way, simulated from its first waypoint
    path = tmp_path / "w.csv"
    path.write_text("u_a,v_a,psi,u_o,v_o\n0,0,0,0.1,0\n0.06,0.02,0.5,,\n0.06,0.02,-0.5,0,0.2\n")
    route_file = tmp_path / "r.json"
    code, _, _ = run(capsys, "route", str(path), "--duration", "15", "--json", str(route_file))
    assert code == 0
    code, out, _ = run(capsys, "simulate", str(route_file))
    assert code == 0 and float(out.split("arrival error")[1].split()[0]) < 1e-6


@pytest.mark.slow
def test_command_times_a_route_time_optimally_within_the_limits(tmp_path, capsys):
    """route --timing time-optimal: the shortest duration within the robot file's limits over the whole route,
    every sample within the limits, and the rotor rates alone drive 'rollplan simulate' onto the last waypoint."""
    import json

    robot = tmp_path / "robot.toml"
    robot.write_text("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2.0e-4\n"
                     "rotor_inertia_transverse = 1.2e-4\nmax_rotor_rate = 300.0\nmax_rotor_torque = 0.05\n")
    path = tmp_path / "w.csv"
    path.write_text("u_a,v_a,psi,u_o,v_o\n0,0,0,0.1,0\n0.06,0.02,0.5,,\n0.06,0.02,-0.5,0,0.2\n")
    route_file, fig = tmp_path / "r.json", tmp_path / "t.png"
    code, out, _ = run(capsys, "route", str(path), "--robot", str(robot), "--timing", "time-optimal", "--json",
                       str(route_file), "--timing-plot", str(fig))
    assert code == 0 and "timing time-optimal" in out and fig.stat().st_size > 0
    d = json.loads(route_file.read_text())
    assert d["timing"] == "time-optimal" and d["duration"] == d["minimum_duration"]
    assert max(d["segment"]) + 1 == len(d["segments"])
    assert np.abs(d["rotor_rates"]).max() <= 300.0 * (1 + 1e-6)
    assert np.abs(d["rotor_torques"]).max() <= 0.05 * (1 + 1e-6)
    code, out, _ = run(capsys, "simulate", str(route_file))
    assert code == 0 and float(out.split("arrival error")[1].split()[0]) < 1e-5


@pytest.mark.slow
def test_ctrl_c_stops_a_route_of_two_leg_searches_promptly(tmp_path):
    """SIGINT while the legs are searched (IPOPT polishes and root solves inside CasADi): exit 130 at once."""
    import signal
    import subprocess
    import sys
    import time

    rows = "\n".join(f"{1e-6 * (i % 2)},{1e-6 * i},{0.5 * (i % 2)}" for i in range(1, 30))
    path = tmp_path / "w.csv"
    path.write_text(f"u_a,v_a,psi\n0,0,0\n{rows}\n")
    # the command as a user's shell starts it: SIGINT handled by Python (a background test run ignores it); it says
    # "ready" on stderr when its first leg is done (the route's progress call), and the signal follows while the
    # second leg is searched
    code = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
            "from rollplan.cli import main; from rollplan.cli.commands import route; shown = route.report; "
            "route.report = lambda *a, **kw: (sys.stderr.write('ready\\n'), sys.stderr.flush(), shown(*a, **kw))[-1]; "
            "sys.exit(main(sys.argv[1:]))")
    p = subprocess.Popen([sys.executable, "-c", code, "route", str(path), "--k", "7.7"],
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert p.stderr.readline() == "ready\n"
    time.sleep(0.2)
    assert p.poll() is None, "the route ended before the interrupt: make it longer"
    t0 = time.perf_counter()
    p.send_signal(signal.SIGINT)
    err = p.communicate(timeout=60)[1]
    assert p.returncode == 130 and "interrupted" in err and time.perf_counter() - t0 < 5.0
