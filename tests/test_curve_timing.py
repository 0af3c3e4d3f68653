"""Timing and actuation of figure eights of every leaf family (rollplan.execution.path, .timing, .actuation).

References, independent of the code under test: the leaves typed in tests/references.py (the polygons' corners
by bisection, the Viviani lobe from its cylinder), arc lengths as angles between unit vectors, the contact
point (1) as printed, DOP853 on the printed (28)-(30) for where a figure eight ends, and scipy's DOP853 on the
printed (2), (6)-(10), (11) driven by the sampled rotor rates alone.
"""

from dataclasses import replace

import numpy as np
import pytest

import rollplan
from rollplan.core.paths import figure_eight_pieces
from rollplan.execution.actuation import sample_motion
from rollplan.execution.limits import Limits
from rollplan.execution.path import ContactPath
from rollplan.execution.timing import LAWS

import references

ROBOT = replace(rollplan.Robot(), max_rotor_rate=300.0, max_rotor_torque=0.05)
LIMITS = Limits.of(ROBOT)
GAMMA = 0.3


def _path(name, a, b, steps=1, gamma=GAMMA):
    return ContactPath.of_pieces(figure_eight_pieces(a, b, gamma, steps, family=name), ROBOT)


def _vertices(name, a, b, gamma=GAMMA):
    """Arc length [R] at every corner of a polygon's figure eight, its corners and the edges' great-circle normals,
    from the corners of tests/references.py rotated by gamma."""
    c, s_ = np.cos(gamma), np.sin(gamma)
    rz = np.array([[c, -s_, 0.0], [s_, c, 0.0], [0.0, 0.0, 1.0]])
    s, out, normals, edges = 0.0, [], [], []
    for size, side in ((a, 1.0), (b, -1.0)):
        corners = [rz @ c for c in references.polygon_corners(name, size, side)]
        for j, (p, q) in enumerate(zip(corners, corners[1:])):
            if j:
                out.append(s)
            s += np.arccos(np.clip(p @ q, -1.0, 1.0))
            n = np.cross(p, q)
            normals.append(n / np.linalg.norm(n))
            edges.append(s)
    return np.array(out), np.array(normals), np.array(edges)



def _rotor_drive_end(robot, t, rates):
    """The final state of ``references.rotor_drive`` for a rollplan robot."""
    keys = ("radius", "mass_total", "mass_shell", "rotor_inertia_axial", "rotor_inertia_transverse")
    return references.rotor_drive({k: getattr(robot, k) for k in keys}, t, rates, end=True)


def _speed_where(prof, s_values, iterations=200):
    """s' of a profile where s(t) first reaches each value (bisection on the nondecreasing s(t), every value at
    once)."""
    target = np.asarray(s_values, float)
    lo, hi = np.zeros(target.size), np.full(target.size, prof.duration)
    for _ in range(iterations):
        mid = 0.5 * (lo + hi)
        below = prof.evaluate(mid)[0] < target
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return prof.evaluate(hi)[1]


@pytest.mark.parametrize("name", ("triangle", pytest.param("square", marks=pytest.mark.slow)))
def test_polygon_is_great_circle_arcs_and_every_law_stops_at_every_vertex(name):
    a, b = 0.45, 0.3
    path = _path(name, a, b)
    vertices, normals, edges = _vertices(name, a, b)
    # the path's length and its corners are the polygon's: arcs between the typed corners
    assert path.length == pytest.approx(edges[-1], rel=1e-12)
    np.testing.assert_allclose(path.joints[path.corners], vertices, rtol=0, atol=1e-12)
    # the pole, where a leaf's last edge meets the next leaf's first on one great circle, is no corner
    assert not path.corners[~np.isin(np.round(path.joints, 10), np.round(vertices, 10))].any()
    # the contact path is piecewise great-circle arcs: every point of an edge on its plane
    s = np.linspace(0.0, path.length, 3001)
    points = references.contact_point(*path.evaluate(s).state[:, 3:5].T)
    edge = np.minimum(np.searchsorted(edges, s), edges.size - 1)
    assert np.abs(np.einsum("ij,ij->i", points, normals[edge])).max() < 1e-9
    for law in LAWS.values():
        prof = law.profile(path, LIMITS)
        speed = _speed_where(prof, vertices)
        peak = np.abs(prof.evaluate(np.linspace(0.0, prof.duration, 2001))[1]).max()
        assert np.abs(speed).max() < 1e-6 * peak, law.name


def _lobe_tangent(a, side, phi):
    """Unit tangent of the Viviani lobe of tests/references.py at phi, by a central difference."""
    h = 1e-6
    d = (references.viviani(a, side)(phi + h)[0] - references.viviani(a, side)(phi - h)[0]) / (2 * h)
    return d / np.linalg.norm(d)


@pytest.mark.parametrize("a, b", ((0.4, 0.4), (0.4, 0.3)))
def test_viviani_joint_is_a_corner_only_for_unequal_lobes(a, b):
    """The lobes' tangents at the double point from the parametrisation: lobe a ends along lobe b's start iff
    a = b; the path's corners agree, and at a = b a non-stop passage keeps the torques continuous."""
    turn = np.arccos(np.clip(_lobe_tangent(a, 1.0, 2 * np.pi) @ _lobe_tangent(b, -1.0, 0.0), -1, 1))
    back = np.arccos(np.clip(_lobe_tangent(b, -1.0, 2 * np.pi) @ _lobe_tangent(a, 1.0, 0.0), -1, 1))
    assert turn == pytest.approx(abs(np.arcsin(a) - np.arcsin(b)), abs=1e-6)
    assert back == pytest.approx(turn, abs=1e-6)
    path = _path("viviani", a, b, steps=2)
    assert path.corners.tolist() == [turn > 1e-3] * 3
    assert path.nonstop_continuous == (turn < 1e-3)


def _largest_sample_step(name, a, b, law="nonstop-min-jerk"):
    """The largest change of the torques between neighbouring samples of a timed motion, over their peak."""
    path = _path(name, a, b, steps=2)
    m = sample_motion(path, LAWS[law].profile(path, LIMITS), 40001)
    tq = m.series.rotor_torques
    return np.abs(np.diff(tq, axis=0)).max() / np.abs(tq).max()


@pytest.mark.slow
def test_nonstop_torques_continuous_on_a_viviani_eight_not_on_circles():
    """Sampled densely, the non-stop torques of the Viviani eight (a = b) change by little between samples;
    those of the circles step at every pole (their curvature flips sign there)."""
    viviani, circles = _largest_sample_step("viviani", 0.4, 0.4), _largest_sample_step("circles", 0.4, 0.4)
    assert viviani < 2e-3 and circles > 0.05
    assert not _path("circles", 0.4, 0.4).nonstop_continuous
    assert not _path("triangle", 0.4, 0.4).nonstop_continuous


FAMILY_CASES = (("circles", 0.35, 0.25), ("viviani", 0.4, 0.4), ("viviani", 0.45, 0.3), ("triangle", 0.4, 0.3),
                ("square", 0.3, 0.4))


@pytest.mark.slow
@pytest.mark.parametrize("name, a, b, law", [(*case, "min-jerk") for case in FAMILY_CASES]
                         + [("triangle", 0.4, 0.3, "time-optimal")])
def test_rotor_rates_of_every_family_drive_the_printed_equations_to_the_end(name, a, b, law):
    """Two figure eights timed by a law: their sampled rotor rates alone, replayed by scipy (DOP853 on the printed
    (2), (6)-(10), (11), not-a-knot spline: :func:`_rotor_drive_end`), end where DOP853 on the printed (28)-(30)
    along the typed leaves ends (1e-6 R and rad)."""
    steps = 2
    path = _path(name, a, b, steps=steps)
    prof = LAWS[law].profile(path, LIMITS)
    m = sample_motion(path, prof, 4, per_piece=LAWS[law].samples_per_piece)
    end = np.zeros(3)
    for _ in range(steps):
        end = references.family_trace(name, a, b, ROBOT.k, GAMMA, end)
    final = _rotor_drive_end(ROBOT, m.series.time, m.series.rotor_rates)
    R = ROBOT.radius
    assert np.hypot(final[0] / R - end[0], final[1] / R - end[1]) < 1e-6
    assert abs(references.wrap(final[2] - end[2])) < 1e-6
    assert np.abs(final[3:]).max() < 1e-6


@pytest.mark.parametrize("name, a, b", (pytest.param("triangle", 0.4, 0.3, marks=pytest.mark.slow),
                                        ("viviani", 0.4, 0.3)))
def test_optimal_timing_rests_at_corners_and_nears_the_cauchy_schwarz_bound(name, a, b):
    """The int|omega|^2-optimal rest-to-rest timing of a path with corners (it refused them before): at rest at
    every corner (the typed polygon's vertices; the Viviani eight's unequal lobes), and its cost, measured on the
    exact path, between the bound (int |W| ds)^2 / T of every timing and 3 % above it (N = 300)."""
    from rollplan.execution.optimal_timing import optimal_timing, timed_samples, timing_bound
    from rollplan.measures import measure

    path = _path(name, a, b)
    prof = optimal_timing(path, 2.0, "angular_velocity", 300)
    corners = _vertices(name, a, b)[0] if name == "triangle" else path.joints
    peak = np.abs(prof.evaluate(np.linspace(0.0, 2.0, 2001))[1]).max()
    assert np.abs(_speed_where(prof, corners)).max() < 1e-6 * peak   # sqrt(2 s'' ds) of the bisection
    cost = measure(timed_samples(path, prof))["angular_velocity"]
    bound = timing_bound(path, 2.0, "angular_velocity")
    assert bound <= cost <= 1.03 * bound


@pytest.mark.slow
def test_a_viviani_plan_runs_nonstop_and_its_rates_land_on_the_goal():
    """A plan of the public planner with curve viviani and psi = 0 (equal lobes): timed by nonstop-min-jerk its
    torques never step (no listed break), and its rotor rates alone, replayed by scipy on the printed equations,
    land on the plan's goal (1e-6 R)."""
    from rollplan.execution.actuation import actuate, torque_breaks

    p = rollplan.plan((0.0, 0.08, 0.0), 1, robot=ROBOT, curve="viviani")
    assert p.curve == "viviani" and p.a == pytest.approx(p.b, rel=1e-9)
    m = actuate(p, ROBOT, None, 4, "nonstop-min-jerk")
    assert torque_breaks(m)[0].size == 0 and m.rest_indices.tolist() == [0, m.series.time.size - 1]
    final = _rotor_drive_end(ROBOT, m.series.time, m.series.rotor_rates)
    g, R = p.goal, ROBOT.radius
    assert np.hypot(final[0] - g.u_a, final[1] - g.v_a) / R < 1e-6 and abs(references.wrap(final[2] - g.psi)) < 1e-6


@pytest.mark.slow
def test_time_optimal_torques_at_a_corner_are_measured_on_the_side_the_robot_is_on():
    """At rest on a corner s is flat, so times just after the rest had s at the corner to rounding and were measured
    with the piece before's A (which jumps there) times the s'' of the piece after: unit_peaks reported 19 % over
    the torque limit on this Viviani eight of unequal lobes. Brute force: the torques a moment (1e-7 s) before and
    after each rest, each with its own side's coefficients, stay within the limit; so do unit_peaks and the
    sampled motion's torques."""
    from rollplan.execution.timing import unit_peaks

    robot = replace(rollplan.Robot(radius=0.1, mass_total=0.466, mass_shell=0.4, rotor_inertia_axial=2e-4,
                                   rotor_inertia_transverse=1.2e-4), max_rotor_rate=300.0, max_rotor_torque=0.05)
    path = ContactPath.of_pieces(figure_eight_pieces(0.5970596258653416, 0.24846765587697633, 0.4369411340147731, 2,
                                                     family="viviani"), robot)
    assert path.corners.all()
    prof = LAWS["time-optimal"].profile(path, Limits.of(robot))
    limit = robot.max_rotor_torque
    for sj in path.joints:
        lo, hi = 0.0, prof.duration
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if prof.evaluate(mid)[0][0] < sj else (lo, mid)
        for dt, side in ((-1e-7, "left"), (1e-7, "right")):
            s, sd, sdd = prof.evaluate(hi + dt)
            _, A, B = path.coefficients(s, side)
            assert np.abs(A * sdd[:, None] + B * sd[:, None] ** 2).max() <= limit * (1 + 1e-4)
    assert unit_peaks(path, prof)[1] <= limit * (1 + 1e-4)
    m = sample_motion(path, prof, 4, per_piece=LAWS["time-optimal"].samples_per_piece)
    assert np.abs(m.series.rotor_torques).max() <= limit * (1 + 1e-4)
