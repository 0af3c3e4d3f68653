"""One record of a motion in time: every producer returns a TimeSeries (or a result holding one), and the old
parallel records are gone."""

import ast
import collections
import functools
import math
from pathlib import Path

import numpy as np
import pytest
from conftest import package_nodes, package_tree

import rollplan
from rollplan.errors import InputError
from rollplan.measures import measure
from rollplan.problem import STATE_NAMES, State
from rollplan.timeseries import Arrival, TimeSeries

PACKAGE = Path(rollplan.__file__).parent
ROBOT = rollplan.default_robot()

#: The records that TimeSeries replaced, and the name two different classes shared.
OLD_NAMES = {"TimedMotion", "Motion", "Simulation", "PlantRun", "Execution", "PathPiece"}


@functools.lru_cache(maxsize=1)
def _trees():
    return [(path, package_tree(path)) for path in sorted(PACKAGE.rglob("*.py"))]


def test_the_old_record_names_are_gone_from_the_package():
    found = sorted(f"{path.relative_to(PACKAGE.parent)}:{node.lineno} {name}"
                   for path, _ in _trees() for node in package_nodes(path)
                   for name in [node.name if isinstance(node, ast.ClassDef) else node.id if isinstance(node, ast.Name)
                                else node.attr if isinstance(node, ast.Attribute) else
                                node.value if isinstance(node, ast.Constant) and isinstance(node.value, str) else None]
                   if name in OLD_NAMES)
    assert not found, "\n".join(found)


def test_no_two_classes_of_the_package_share_a_name():
    where = collections.defaultdict(list)
    for path, _ in _trees():
        for node in package_nodes(path):
            if isinstance(node, ast.ClassDef):
                where[node.name].append(str(path.relative_to(PACKAGE.parent)))
    assert {name: paths for name, paths in where.items() if len(paths) > 1} == {}


def test_no_other_class_records_states_in_time():
    """A class with both a time field and a state field is a parallel time-series record: only TimeSeries is one."""
    records = []
    for path, _ in _trees():
        for node in package_nodes(path):
            if isinstance(node, ast.ClassDef):
                fields = {s.target.id for s in node.body if isinstance(s, ast.AnnAssign) and
                          isinstance(s.target, ast.Name)}
                if fields & {"t", "time"} and "state" in fields:
                    records.append(node.name)
    assert records == ["TimeSeries"]


@pytest.fixture(scope="module")
def timed():
    p = rollplan.plan((0.0, 0.1, 0.3), robot=ROBOT)
    return p, rollplan.actuate(p, ROBOT, 4.0, samples=200)


def _check(series, n=None, start=None):
    assert isinstance(series, TimeSeries)
    assert series.state.shape == (len(series), 5) and (n is None or len(series) == n)
    if start is not None:
        np.testing.assert_allclose(series.state[0], start, atol=1e-15)


def test_every_producer_returns_the_one_type(timed):
    from rollplan.execution.actuation import certify_motion, motion_samples
    from rollplan.execution.feedback import execute
    from rollplan.execution.optimal_timing import optimal_timing, timed_samples
    from rollplan.execution.plants import run_rates, run_torques, simulate_rotors
    from rollplan.planners.collocation.rest import certify

    p, a = timed
    m = a.series
    _check(m, start=p.problem.start.array())
    assert m.omega.shape == (len(m), 3) and m.rotor_torques.shape == (len(m), 2) and m.segment.dtype.kind == "i"
    _check(motion_samples(a), start=m.state[0])
    _check(certify_motion(a).series, len(m), m.state[0])
    _check(simulate_rotors(ROBOT, m.time, m.rotor_rates).series, len(m))
    for run in (run_rates(ROBOT, m.time, m.rotor_rates), run_torques(ROBOT, m.time, m.rotor_torques)):
        _check(run.series, len(m))
        assert run.series.rotor_momenta.shape == (len(m), 2) and run.measured.shape == (len(m), 5)
    ex = execute(p, ROBOT, ROBOT, 1.0, closed_loop=False, samples_per_piece=50)
    _check(ex.series, start=p.problem.start.array())
    _check(timed_samples(a.path, optimal_timing(a.path, 4.0, "angular_velocity", 8)))
    roll = rollplan.Problem((0.0, ROBOT.radius / 4, 0.0, 0.0, 0.25), robot=ROBOT)   # v_o'' = +1 then -1 over 1 s
    _check(certify([[0.0, 1.0], [0.0, -1.0]], np.zeros(7), roll, 1.0, per=8), start=np.zeros(5))


def test_the_mujoco_engine_returns_the_one_type(timed):
    engine = pytest.importorskip("rollplan.execution.mujoco_engine")
    pytest.importorskip("mujoco")
    p, a = timed
    m = a.series
    run = engine.replay(engine.compile_model(engine.mjcf(ROBOT)), m.time[:20], m.rotor_torques[:20], goal=p.goal)
    _check(run.series, 20)
    assert isinstance(run, Arrival) and run.final == run.series.final


def test_arrival_in_closed_form():
    """Final (1, 2, 0.5 + 2 pi, 0, 0) m, R = 2 m, goal (1, 0, 0.5): the error is (0, 1, 0, 0, 0) in R and rad
    (lengths divided by R, psi wrapped), so both norms are 1."""

    class Run(Arrival):
        def __init__(self, series, goal):
            self.series, self.goal = series, goal

    state = np.array([[0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 2.0, 0.5 + 2 * math.pi, 0.0, 0.0]])
    run = Run(TimeSeries(np.array([0.0, 1.0]), state, radius=2.0), State(1.0, 0.0, 0.5))
    np.testing.assert_allclose(run.error, [0, 1, 0, 0, 0], atol=1e-15)
    assert run.arrival_error == pytest.approx(1.0, abs=1e-15) and run.position_error == pytest.approx(1.0, abs=1e-15)
    assert run.final == State(1.0, 2.0, 0.5 + 2 * math.pi, 0.0, 0.0)
    assert Run(run.series, None).arrival_error is None


def test_time_series_checks_its_fields_and_drops_a_time_given_twice():
    t = np.array([0.0, 1.0, 1.0, 2.0])
    with pytest.raises(InputError, match=r"TimeSeries.segment of shape \(3,\)"):
        TimeSeries(t, np.zeros((4, 5)), np.zeros(3, int))
    with pytest.raises(InputError, match=r"TimeSeries.rotor_momenta of shape \(4, 3\)"):
        TimeSeries(t, np.zeros((4, 5)), rotor_momenta=np.zeros((4, 3)))
    with pytest.raises(InputError, match="at least 2"):
        TimeSeries(np.zeros(1), np.zeros((1, 5)))
    s = TimeSeries(t, np.arange(20.0).reshape(4, 5))
    assert s.repeated_times().tolist() == [1.0] and s.distinct().tolist() == [0, 1, 3] and s.duration == 2.0
    assert s.columns() == {"t": [0.0, 1.0, 2.0], **{n: [float(j), 5.0 + j, 15.0 + j] for j, n in
                                                      enumerate(STATE_NAMES)}}
    assert s.trajectory().segment.tolist() == [0, 0, 0] and s.trajectory().parameter == "t"


def test_measure_names_the_fields_a_series_lacks():
    with pytest.raises(InputError, match="without velocity, omega, rotor_rates, rotor_torques"):
        measure(TimeSeries(np.arange(3.0), np.zeros((3, 5))))
