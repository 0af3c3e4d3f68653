"""The method spine: the registry (a name or a class), the Method contract (check -> solve -> certificate
required), one result protocol, one meaning of ``sample(samples)``, and the methods' agreement."""

from __future__ import annotations

import inspect
import math
import warnings
from dataclasses import dataclass, replace

import numpy as np
import pytest

import rollplan
from rollplan import InputError, NoPlanError, PlanResult, Problem
from rollplan.planners import METHODS, Method, method_class, solve
from rollplan.planners.collocation import CollocationPlanner, CollocationResult
from rollplan.planners.collocation.rest import MinimumTimeMethod, RestResult, RestToRestMethod
from rollplan.planners.geometric import ComposedPlan, ComposedPlanner, GeometricPhasePlanner, Plan, Route
from rollplan.planners.geometric.maneuvers import StraightRoll
from rollplan.result import CERTIFICATE_TOLERANCE, Certificate, SolverStats
from rollplan.robot import default_robot

K = 2.5
POLE = Problem((0.5, 0.7, 0.8), k=K)
#: A goal the straight roll from the pole to the contact point (U, V) reaches: its plane element in closed form.
U, V = 0.3, -0.2
ROLL = Problem((*StraightRoll.make(U, V, "departure").element(), U, V), k=K)
#: The roll's length [R]: the great-circle angle from the south pole, whose cosine is cos(u_o) cos(v_o).
ROLL_LENGTH = math.acos(math.cos(U) * math.cos(V))


# ----------------------------------------------------------------------------- the registry

def test_the_registry_takes_a_name_a_class_or_an_instance():
    by_name = solve(POLE, "geometric")
    by_class = solve(POLE, ComposedPlanner)
    by_instance = solve(POLE, ComposedPlanner(root_solver="newton"))
    assert method_class("geometric") is METHODS["geometric"] is ComposedPlanner
    assert method_class(CollocationPlanner) is CollocationPlanner
    for p in (by_class, by_instance):
        assert (p.a, p.b, p.gamma, p.branch) == pytest.approx((by_name.a, by_name.b, by_name.gamma, by_name.branch),
                                                              abs=1e-9)
    # the method's options: steps in the method, the same plan as the problem's steps
    two = solve(POLE, "geometric", steps=2)
    assert two.steps == 2 and two.a == pytest.approx(rollplan.plan(POLE.goal[:3], steps=2, k=K).a, abs=1e-12)


@pytest.mark.parametrize("bad", ["geometric_phase", "GEOMETRIC", 3, None, dict, Plan])
def test_a_bad_method_is_one_line_naming_the_choices(bad):
    with pytest.raises(InputError) as err:
        solve(POLE, bad)
    msg = str(err.value)
    assert "\n" not in msg and msg.startswith("method = ") and all(name in msg for name in METHODS)


def test_a_bad_option_is_one_line_naming_the_allowed_ones():
    with pytest.raises(InputError) as err:
        solve(POLE, "geometric", intervals=10)
    msg = str(err.value)
    assert "\n" not in msg and "'intervals'" in msg and "'geometric'" in msg and "legs" in msg
    with pytest.raises(InputError, match="constructor"):
        solve(POLE, ComposedPlanner(), legs="two")


def test_every_registered_method_is_a_method_with_keyword_options_only():
    assert set(METHODS) == {"geometric", "collocation", "rest_to_rest", "minimum_time"}
    for name in METHODS:
        cls = METHODS[name]
        assert issubclass(cls, Method) and cls.name == name
        params = inspect.signature(cls).parameters.values()
        assert all(p.default is not p.empty for p in params), name


@dataclass
class _Loose:
    """A result whose certificate fails: what a broken method might return."""

    problem: Problem
    certificate: Certificate
    stats: SolverStats
    method: str = "loose"
    path_length: float = 0.0
    alternatives: tuple = ()


class _LooseMethod(Method):
    name = "loose"

    def _solve(self, problem):
        cert = Certificate("none", problem.goal, 1e-6, 0.0, CERTIFICATE_TOLERANCE)
        return _Loose(problem, cert, SolverStats("none", "ok", 0, 0.0))


def test_no_method_returns_a_plan_above_its_tolerance():
    """The base class requires the certificate: a method whose result misses the goal by 1e-6 > 1e-9 raises
    NoPlanError instead of returning it (through the registry too: it takes any Method subclass)."""
    with pytest.raises(NoPlanError, match="1.00e-06"):
        _LooseMethod().solve(POLE)
    with pytest.raises(NoPlanError):
        solve(POLE, _LooseMethod)
    with pytest.raises(InputError, match="rollplan.Problem"):
        _LooseMethod().solve((0.5, 0.7, 0.8))


# ----------------------------------------------------------------------------- every method, one protocol

_CASES = {
    "geometric": (POLE, {}),
    "collocation": (POLE, {"intervals": 10}),
    "rest_to_rest": (ROLL, {"intervals": 8, "cost": "path_energy"}),
    "minimum_time": (Problem((*np.multiply(ROLL.goal[:2], default_robot().radius), *ROLL.goal[2:]),
                             robot=replace(default_robot(), max_rotor_rate=300.0, max_rotor_torque=0.05)),
                     {"intervals": 8}),
}


@pytest.fixture(scope="module")
def results():
    return {}


def _result(results, name):
    if name not in results:
        problem, options = _CASES[name]
        results[name] = solve(problem, name, **options)
    return results[name]


@pytest.mark.parametrize("name", [
    "geometric", "collocation", "rest_to_rest",
    pytest.param("minimum_time", marks=pytest.mark.slow),
])
def test_every_method_returns_a_certified_plan_result(results, name):
    """Each registered method on a small problem: a PlanResult named by the method, its certificate passed
    within CERTIFICATE_TOLERANCE, its final state on the problem's goal, and samples from start to goal."""
    problem = _CASES[name][0]
    r = _result(results, name)
    assert isinstance(r, PlanResult) and r.method == name and r.problem.goal == problem.goal
    c = r.certificate
    assert c.passed and c.residual + c.error_bound <= CERTIFICATE_TOLERANCE and c.tolerance <= CERTIFICATE_TOLERANCE
    assert problem.residual(r.final) <= CERTIFICATE_TOLERANCE   # measured here against the goal as stated
    assert isinstance(r.pieces, tuple) and isinstance(r.legs, tuple) and r.alternatives == ()
    traj = r.sample(57)
    assert traj.s.size == traj.state.shape[0] == traj.segment.size == 57
    assert np.allclose(traj.state[0], problem.start, atol=1e-12)
    assert problem.residual(traj.state[-1]) <= 1e-8


@pytest.mark.slow
def test_minimum_time_returns_a_result_not_a_tuple(results):
    r = _result(results, "minimum_time")
    assert isinstance(r, RestResult) and r.duration == r.horizon > 0
    assert r.sample().s[-1] == pytest.approx(r.duration, rel=1e-12)
    robot = _CASES["minimum_time"][0].robot
    assert np.abs(r.motion.rotor_rates).max() <= robot.max_rotor_rate
    assert np.abs(r.motion.rotor_torques).max() <= robot.max_rotor_torque


def test_the_one_leg_plan_has_the_surface_of_a_composed_plan():
    p = solve(POLE, "geometric")
    c = solve(Problem(POLE.goal, start=(0.0, 0.0, 0.0, 0.1, 0.0), k=K), "geometric")
    assert isinstance(p, Plan) and isinstance(c, ComposedPlan)
    assert p.legs == (p,) and p.mode == "one" and [q.kind for q in p.pieces] == ["leaf", "leaf"]
    assert sum(q.length for q in p.pieces) * p.radius == pytest.approx(p.path_length, rel=1e-14)
    assert c.mode == "one" and len(c.legs) == 1 and c.pieces[0].kind == "approach"


# ----------------------------------------------------------------------------- sample(samples)

@pytest.mark.parametrize("samples", [5, 10, 101, 1000])
def test_sample_counts_the_samples_in_all_for_a_plan(samples):
    """samples in all: the start, then the leaves' samples, the first leaves one more when they do not divide
    evenly; each leaf's last sample at its end (theta = pi per leaf)."""
    p = rollplan.plan((0.3, -0.2, 0.5), steps=2, k=K)
    t = p.sample(samples)
    assert t.s.size == t.state.shape[0] == samples
    assert t.s[0] == 0.0 and t.s[-1] == pytest.approx(4 * np.pi, abs=1e-12) and np.all(np.diff(t.s) > 0)
    counts = np.bincount(t.segment[1:], minlength=4)
    assert counts.sum() == samples - 1 and counts.max() - counts.min() <= 1 and np.all(np.diff(counts) <= 0)
    ends = [t.s[1:][t.segment[1:] == j][-1] for j in range(4)]
    assert ends == pytest.approx(np.pi * np.arange(1, 5), abs=1e-12)
    with pytest.raises(InputError, match="samples"):
        p.sample(4)   # fewer than one per leaf


def test_samples_per_leaf_is_the_old_name_of_a_count_per_leaf():
    p = rollplan.plan((0.3, -0.2, 0.5), steps=2, k=K)
    with pytest.warns(DeprecationWarning, match="samples_per_leaf"):
        old = p.sample(samples_per_leaf=30)
    new = p.sample(1 + 4 * 30)
    assert np.array_equal(old.s, new.s) and np.array_equal(old.state, new.state)


def test_sample_counts_the_samples_in_all_for_every_result_type(results):
    composed = solve(Problem(POLE.goal, start=(0.0, 0.0, 0.0, 0.1, 0.0), k=K), "geometric")
    route = rollplan.plan_route([(0, 0, 0), (0.5, 0.0, 0.0), (0.5, 0.5, 0.3)], k=K)
    coll = _result(results, "collocation")
    rest = _result(results, "rest_to_rest")
    assert isinstance(composed, ComposedPlan) and isinstance(route, Route)
    assert isinstance(coll, CollocationResult) and isinstance(rest, RestResult)
    for r in (composed, route, coll, rest):
        certified = r.sample()
        for n in (certified.s.size // 3, certified.s.size + 17, 3 * certified.s.size):
            t = r.sample(n)
            assert t.s.size == t.state.shape[0] == n, (type(r).__name__, n)
            assert t.s[0] == certified.s[0] and t.s[-1] == pytest.approx(certified.s[-1], rel=1e-12)
            assert np.all(np.diff(t.s) >= 0)
            assert np.allclose(t.state[[0, -1]], certified.state[[0, -1]], atol=1e-9)


# ----------------------------------------------------------------------------- distinct names

def test_root_solver_has_its_own_name_and_the_old_one_still_works():
    new = rollplan.plan((0.5, 0.7, 0.8), k=K, root_solver="newton")
    with pytest.warns(DeprecationWarning, match="root_solver"):
        old = rollplan.plan((0.5, 0.7, 0.8), k=K, method="newton")
    assert (old.a, old.b, old.gamma) == (new.a, new.b, new.gamma)
    assert new.stats.method == "newton" and new.method == "geometric"
    with pytest.raises(InputError, match="root_solver only"):
        rollplan.plan((0.5, 0.7, 0.8), k=K, method="newton", root_solver="ipopt")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert GeometricPhasePlanner(root_solver="newton").root_solver == "newton"
        assert ComposedPlanner(root_solver="newton").root_solver == "newton"
    with pytest.raises(InputError, match="root_solver"):
        ComposedPlanner(root_solver="bogus")


def test_the_rest_to_rest_methods_share_their_nlp():
    """A method is cheap to make: the NLP is built once per set of NLP options, whatever the per-solve ones."""
    a = RestToRestMethod(intervals=8, horizon=1.0, turns=0)
    b = RestToRestMethod(intervals=8, horizon=2.0, turns=1)
    assert a.planner is b.planner and RestToRestMethod(intervals=4).planner is not a.planner
    with pytest.raises(InputError, match="guess"):
        solve(ROLL, "rest_to_rest", intervals=8, guess="warm")
    with pytest.raises(InputError, match="max_rotor_rate"):
        MinimumTimeMethod(intervals=4).solve(ROLL)


# ----------------------------------------------------------------------------- the methods agree

@pytest.mark.slow
def test_geometric_and_collocation_agree_on_a_straight_roll():
    """From rest at the pole to the state the straight roll reaches, the shortest contact path is the roll:
    the geometric method plans it in closed form, and the collocation minimising int |v|^2 dt (whose minimizers
    are the shortest paths at constant speed) converges to it from a straight-line guess. Both lengths against
    the closed form (the great-circle angle arccos(cos u_o cos v_o)); the collocation never shorter, and its
    motion approaching the roll at second order in the interval length (piecewise-constant contact rates)."""
    g = solve(ROLL, "geometric")
    assert g.mode == "rolls" and g.path_length == pytest.approx(ROLL_LENGTH, rel=1e-12)
    ref = g.sample(201)
    dev, excess = {}, {}
    for n in (10, 20):
        c = solve(ROLL, "collocation", intervals=n, guess="naive", cost="path_energy")
        excess[n] = c.path_length - ROLL_LENGTH
        t = c.sample(201)   # uniform in time; the roll's samples are uniform in its arc length: constant speed
        dev[n] = np.abs(t.state - ref.state).max()
    assert 0.0 <= excess[20] < excess[10] and excess[20] < 1e-6 * ROLL_LENGTH
    assert dev[20] < 1e-5 and 3.0 < dev[10] / dev[20] < 5.0   # second order: 4 when the intervals halve
