"""The problem statement (rollplan.problem): the State type, Problem's validation (every accepted input
kept exactly, everything else refused with one InputError line naming the value) and the arrival error."""

import math
import re

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan import InputError, Robot
from rollplan.errors import show
from rollplan.problem import K_MAX, MAX_STEPS, STATE_NAMES, Problem, State, arrival_error, arrival_residual

import references

finite = st.floats(-1e12, 1e12, allow_nan=False)
not_finite = st.sampled_from([math.nan, math.inf, -math.inf])


def refuses(match, **kwargs):
    """Problem(**kwargs) raises one InputError line matching ``match``."""
    with pytest.raises(InputError, match=match) as err:
        Problem(**kwargs)
    assert "\n" not in str(err.value)
    return str(err.value)


# ----------------------------------------------------------------------------- State


def test_state_order_is_the_one_order():
    assert STATE_NAMES == ("u_a", "v_a", "psi", "u_o", "v_o") == State._fields
    s = State(1.0, 2.0, 3.0, 4.0, 5.0)
    assert (s.u_a, s.v_a, s.psi, s.u_o, s.v_o) == (1.0, 2.0, 3.0, 4.0, 5.0)
    assert s.as_dict() == {"u_a": 1.0, "v_a": 2.0, "psi": 3.0, "u_o": 4.0, "v_o": 5.0}
    assert np.array_equal(s.array(), [1.0, 2.0, 3.0, 4.0, 5.0])
    assert s.scaled(2.0) == State(2.0, 4.0, 3.0, 4.0, 5.0)   # lengths only
    assert State() == (0.0,) * 5 and State().at_pole and not s.at_pole


@settings(max_examples=100, deadline=None)
@given(st.lists(finite, min_size=5, max_size=5))
def test_state_of_five_numbers_keeps_them_exactly(values):
    for form in (values, tuple(values), np.array(values)):
        s = State.of(form)
        assert tuple(s) == tuple(float(v) for v in values)
    assert State.of(State(*values)) == State(*values)
    assert State.of(dict(zip(STATE_NAMES, values))) == State(*values)
    assert State.of(State(*values).as_dict()) == State(*values)


@settings(max_examples=50, deadline=None)
@given(st.lists(finite, min_size=3, max_size=3))
def test_state_of_three_numbers_is_at_the_pole(values):
    s = State.of(values)
    assert tuple(s) == (*values, 0.0, 0.0) and s.at_pole


@settings(max_examples=50, deadline=None)
@given(st.dictionaries(st.sampled_from(STATE_NAMES), finite))
def test_state_of_a_mapping_defaults_missing_entries_to_zero(d):
    s = State.of(d)
    assert tuple(s) == tuple(d.get(n, 0.0) for n in STATE_NAMES)


@settings(max_examples=60, deadline=None)
@given(st.lists(finite, min_size=5, max_size=5), st.integers(0, 4), not_finite, st.sampled_from(["goal", "start"]))
def test_state_of_refuses_a_non_finite_entry_naming_it(values, index, bad, name):
    values[index] = bad
    with pytest.raises(InputError, match=f"^{name} {STATE_NAMES[index]} = ") as err:
        State.of(values, name)
    assert "\n" not in str(err.value)


@settings(max_examples=30, deadline=None)
@given(st.lists(finite, max_size=8).filter(lambda v: len(v) not in (3, 5)))
def test_state_of_refuses_other_lengths(values):
    with pytest.raises(InputError, match=r"^goal = .* give \(u_a, v_a, psi\) or \(u_a, v_a, psi, u_o, v_o\)"):
        State.of(values, "goal")


@pytest.mark.parametrize("value, match", [(5, "goal = 5"), (None, "goal = None"), ({"w": 1.0}, "unknown key 'w'"),
                                          (("a", 1, 0), "goal u_a = 'a' is not allowed"),
                                          ((0, 1, [2]), "goal psi = \\[2\\] is not allowed"),
                                          ((0, 1, True), "goal psi = True is not allowed"),
                                          ("123", "goal")])
def test_state_of_refuses_what_is_not_a_state(value, match):
    with pytest.raises(InputError, match=match):
        State.of(value, "goal")


# ----------------------------------------------------------------------------- Problem


def test_problem_defaults_and_robot():
    p = Problem((0.0, 1.0, 0.5), k=2.5)
    assert p.goal == State(0.0, 1.0, 0.5) and p.start == State() and p.k == 2.5
    assert p.radius == 1.0 and p.steps == 1 and p.robot is None and p.unit == "R"
    robot = Robot()
    q = Problem((0.0, 0.1, 0.0), robot=robot, steps=3)
    assert q.k == robot.k and q.radius == robot.radius and q.unit == "m" and q.steps == 3
    assert Problem((0.0, 0.1, 0.0), robot=robot, radius=2.0).radius == 2.0   # radius given wins
    assert Problem((0.0, 1.0, 0.0), k=1, radius=2.0).unit == "m"   # a radius without a robot is in metres
    assert isinstance(Problem((0.0, 1.0, 0.0), k=1).k, float)


@pytest.mark.parametrize("kwargs, match", [
    (dict(goal=(0, 1, 0)), "k is missing"),
    (dict(goal=(0, 1, 0), k=2.5, robot=Robot()), "either k or robot"),
    (dict(goal=(0, 1, 0), robot="robot.toml"), "robot = 'robot.toml'"),
    (dict(goal=(0, 1), k=2.5), "goal = "),
    (dict(goal=(0, 1, 0), start=(1, 2), k=2.5), "start = "),
    (dict(goal=(np.nan, 1, 0), k=2.5), "goal u_a = nan"),
    (dict(goal=(0, np.inf, 0), k=2.5), "goal v_a = inf"),
    (dict(goal=(0, 1, -np.inf), k=2.5), "goal psi = -inf"),
    (dict(goal=(0, 1, 0), start=(0, 0, 0, np.nan, 0), k=2.5), "start u_o = nan"),
    (dict(goal=(0, 1, 0), k=-1.0), "k = -1.0 is not allowed"),
    (dict(goal=(0, 1, 0), k=100.5), "k = 100.5"),
    (dict(goal=(0, 1, 0), k=1e6), "k = 1000000.0 is not allowed"),
    (dict(goal=(0, 1, 0), k=np.nan), "k = nan"),
    (dict(goal=(0, 1, 0), k=np.inf), "k = inf is not allowed: it must be a finite number"),
    (dict(goal=(0, 1, 0), k="two"), "k = 'two' is not allowed"),
    (dict(goal=(0, 1, 0), k=2.5, radius=0.0), "radius = 0.0 is not allowed"),
    (dict(goal=(0, 1, 0), k=2.5, radius=-2.0), "radius = -2"),
    (dict(goal=(0, 1, 0), k=2.5, radius=np.inf), "radius = inf"),
    (dict(goal=(0, 1, 0), k=2.5, steps=0), "steps = 0 is not allowed"),
    (dict(goal=(0, 1, 0), k=2.5, steps=1001), "steps = 1001"),
    (dict(goal=(0, 1, 0), k=2.5, steps=2.5), "steps = 2.5"),
    (dict(goal=(0, 1, 0), k=2.5, steps=2.0), "steps = 2.0"),
    (dict(goal=(0, 1, 0), k=2.5, steps="2"), "steps = '2'"),
    (dict(goal=(0, 1, 0), k=2.5, steps=True), "steps = True"),
])
def test_problem_refuses_bad_input_in_one_line_naming_the_value(kwargs, match):
    refuses(match, **kwargs)


@settings(max_examples=100, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False).filter(lambda k: not 0.0 <= k <= K_MAX))
def test_k_outside_0_100_is_refused(k):
    msg = refuses(f"^k = {re.escape(repr(k))} is not allowed", goal=(0, 1, 0), k=k)
    assert f"[0, {K_MAX:g}]" in msg


@settings(max_examples=100, deadline=None)
@given(st.floats(0.0, K_MAX))
def test_k_within_0_100_is_kept_exactly(k):
    assert Problem((0, 1, 0), k=k).k == k


@settings(max_examples=100, deadline=None)
@given(st.integers().filter(lambda n: not 1 <= n <= MAX_STEPS))
def test_steps_outside_1_1000_are_refused(n):
    refuses(f"^steps = {re.escape(show(n))} is not allowed: it must be a whole number in \\[1, {MAX_STEPS}\\]",
            goal=(0, 1, 0), k=1, steps=n)   # show: a value longer than a message shows is cut, with an ellipsis


@settings(max_examples=50, deadline=None)
@given(st.integers(1, MAX_STEPS), st.sampled_from([int, np.int64, np.int32]))
def test_steps_within_1_1000_are_accepted_as_int(n, kind):
    steps = Problem((0, 1, 0), k=1, steps=kind(n)).steps
    assert steps == n and type(steps) is int


@settings(max_examples=50, deadline=None)
@given(st.floats(allow_nan=False, allow_infinity=False).filter(lambda r: r <= 0))
def test_radius_must_be_positive(r):
    refuses("^radius = ", goal=(0, 1, 0), k=1, radius=r)


@settings(max_examples=50, deadline=None)
@given(st.floats(1e-6, 1e6))
def test_scaled_divides_lengths_by_the_radius(r):
    p = Problem((3.0, -4.0, 0.5, 0.1, 0.2), k=1, radius=r)
    s = p.scaled(p.goal)
    assert (s.u_a, s.v_a) == pytest.approx((3.0 / r, -4.0 / r), rel=1e-15)
    assert (s.psi, s.u_o, s.v_o) == (0.5, 0.1, 0.2)


def test_describe_is_one_line():
    text = Problem((0.5, 0.3, 1.0, 0.1, 0.0), start=(0.1, 0, 0), k=2.5, steps=3).describe()
    assert "\n" not in text and "k = 2.5" in text and "3 step(s)" in text and "(u_o, v_o)" in text


# ----------------------------------------------------------------------------- arrival error


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-10, 10), min_size=5, max_size=5), st.lists(st.floats(-1, 1), min_size=5, max_size=5),
       st.integers(-5, 5), st.floats(0.01, 10.0))
def test_arrival_error_wraps_psi_and_scales_lengths(goal, delta, turns, radius):
    final = np.array(goal) + delta
    final[2] += 2 * math.pi * turns
    err = arrival_error(final, goal, radius)
    want = [delta[0] / radius, delta[1] / radius, references.wrap(final[2] - goal[2]), delta[3], delta[4]]
    assert np.allclose(err, want, atol=1e-12 * (1 + abs(turns) + max(map(abs, goal))))
    assert arrival_residual(final, goal, radius) == pytest.approx(np.linalg.norm(err), rel=1e-15)
    inside = np.r_[goal[:3], 0.0, 0.0]   # a Problem's contact points lie in its region (problem.check_contact)
    moved = final - np.r_[0.0, 0.0, 0.0, goal[3:]]
    assert Problem(inside, k=1, radius=radius).residual(moved) == pytest.approx(np.linalg.norm(err), rel=1e-15)


def test_arrival_error_psi_is_an_angle():
    """psi = pi and psi = -pi are one heading: no error; a full turn is no error either."""
    assert arrival_residual(State(0, 0, math.pi), State(0, 0, -math.pi)) < 1e-15
    assert arrival_residual(State(1, 2, 0.3 + 4 * math.pi), State(1, 2, 0.3)) < 1e-14
    assert arrival_error(State(0, 0, 0.1), State(0, 0, 2 * math.pi - 0.1))[2] == pytest.approx(0.2, abs=1e-15)
