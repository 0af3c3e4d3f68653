"""Figure eights at any base point (rollplan.planners.geometric.basepoint, ComposedPlanner(base="any")): the
structure claims of docs/design/basepoint.md against scipy's DOP853 on the printed (15), (16), (20) along the
contact path (tests/references.py: based_circle_path, based_eight, geodesic), and the plans certified by the
same independent integration."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import dblquad

from rollplan import InputError, Problem
from rollplan.core.paths import CurvePiece, PathIntegrator
from rollplan.planners.geometric.basepoint import (
    POLAR_MAX,
    along,
    arc_element,
    arc_piece,
    beside,
    leaf_bound,
    polar_distance,
    solve_leg,
    step_element,
)
from rollplan.planners.geometric.composed import ComposedPlanner

import references as ref

TOL = 1e-9


def chart_frame(c):
    """Plane axes at psi = 0 at the contact point c, as tangent vectors: (15), (16) give u_a' = -cos v u_o'
    (along -c_u) and v_a' = v_o' (along c_v), c_u and c_v of (26) normalised."""
    x, y, z = c
    s = math.sqrt(1 - y * y)
    return -np.array([z, 0.0, -x]) / s, np.array([-x * y / s, s, -y * z / s])


def gauge_angle(sigma, beta, gamma):
    """Angle from the chart frame at Rz(gamma) c0 to the chart frame at c0 turned by Rz(gamma)."""
    c0 = ref._unit_polar(sigma, beta)
    ex0 = ref._rz(gamma) @ chart_frame(c0)[0]
    ex1, ey1 = chart_frame(ref._rz(gamma) @ c0)
    return math.atan2(ex0 @ ey1, ex0 @ ex1)


@pytest.mark.parametrize("a, b, sigma, orientation, beta, k", [
    (0.3, 0.2, 0.6, 0.4, 0.3, 2.5), (0.12, 0.25, 0.9, -2.0, -1.7, 6.0), (0.4, 0.35, 0.3, 2.9, 2.2, 1.5)])
def test_based_eight_matches_printed_equations(a, b, sigma, orientation, beta, k):
    expect = ref.based_eight(a, b, sigma, orientation, beta, k)
    assert np.allclose(step_element(a, b, (sigma, beta), orientation, k), expect, atol=TOL, rtol=0)
    pieces = [CurvePiece("based_figure_eight", i, (a, b, sigma, orientation), beta) for i in (0, 1)]
    ends = PathIntegrator().ends(pieces, np.zeros(5), k)
    assert np.allclose(ends[-1][:3], expect, atol=TOL, rtol=0)
    assert np.allclose(ends[-1][3:], ref.polar_contact(sigma, beta), atol=1e-12)   # back at the base point
    assert math.isclose(sum(p.length for p in pieces), 2 * math.pi * (a + b))


def test_arc_matches_printed_equations_and_its_length():
    p, q, k = (0.5, 0.3), (0.7, -2.0), 3.0
    e0, e1 = ref._unit_polar(*p), ref._unit_polar(*q)
    piece = arc_piece(p, q, "approach")
    assert math.isclose(piece.length, math.acos(e0 @ e1), rel_tol=1e-12)
    assert math.isclose(polar_distance(p, q), math.acos(e0 @ e1), rel_tol=1e-12)
    expect = ref.composed_final([piece], np.r_[0.0, 0.0, 0.0, ref.polar_contact(*p)], k)
    assert np.allclose(arc_element(piece, k), expect[:3], atol=TOL, rtol=0)
    assert np.allclose(expect[3:], ref.polar_contact(*q), atol=1e-12)
    mid = along(p, q, 0.5)
    assert math.isclose(polar_distance(p, mid), 0.5 * polar_distance(p, q), rel_tol=1e-12)
    assert math.isclose(polar_distance(mid, q), 0.5 * polar_distance(p, q), rel_tol=1e-12)
    assert arc_piece(p, p, "approach") is None


def test_offset_base_points_lie_off_the_arc_by_the_offset():
    p, q = (0.5, 0.3), (0.7, -2.0)
    mid = along(p, q, 0.5)
    for d in (-0.6, 0.3):
        b = beside(p, q, 0.5, d)
        assert math.isclose(polar_distance(mid, b), abs(d), rel_tol=1e-12)
        assert math.isclose(polar_distance(p, b), polar_distance(q, b), rel_tol=1e-12)   # on the bisector
    assert beside(p, q, 0.25, 0.0) == along(p, q, 0.25)


def test_pole_limit_reproduces_the_pole_figure_eight():
    a, b, orientation, beta, k = 0.3, 0.2, 0.4, 0.3, 2.5
    pole = ref.trace(a, b, k, beta + orientation)   # the pole figure eight rotated by gamma = beta + orientation
    assert np.allclose(ref.based_eight(a, b, 0.0, orientation, beta, k), pole, atol=1e-11, rtol=0)
    errors = []
    for sigma in (1e-4, 1e-3, 1e-2):
        e = ref.based_eight(a, b, sigma, orientation, beta, k)
        errors.append([abs(e[2] - pole[2]), abs(math.hypot(*e[:2]) - math.hypot(*pole[:2]))])
    errors = np.array(errors)
    # turn and shift converge to the pole's at first order in sigma
    assert np.all(errors[:-1] < 0.2 * errors[1:])
    assert np.all(errors[1:] < 20 * errors[:-1])
    assert errors[0].max() < 1e-3


@pytest.mark.parametrize("a, b, orientation", [(0.3, 0.2, 0.4), (0.15, 0.25, -1.0)])
def test_rotation_about_oz_survives_with_a_gauge_turn(a, b, orientation):
    sigma, beta, gamma, k = 0.6, 0.3, 1.1, 2.5
    e0 = ref.based_eight(a, b, sigma, orientation, beta, k)
    e1 = ref.based_eight(a, b, sigma, orientation, beta + gamma, k)
    assert math.isclose(e1[2], e0[2], abs_tol=1e-10)                                   # the turn
    turned = ref.rotate(gauge_angle(sigma, beta, gamma), e0[:2])
    assert np.allclose(e1[:2], turned, atol=1e-10, rtol=0)     # the shift, turned by the base point's gauge angle
    assert math.isclose(gauge_angle(1e-9, beta, gamma), gamma, abs_tol=1e-8)          # at the pole: gamma


def test_rotation_about_the_base_is_no_symmetry_off_the_pole():
    a, b, k = 0.3, 0.2, 2.5
    at_pole = [ref.based_eight(a, b, 0.0, o, 0.0, k) for o in (0.0, 1.0, 2.0)]
    assert np.ptp([e[2] for e in at_pole]) < 1e-10
    assert np.ptp([math.hypot(*e[:2]) for e in at_pole]) < 1e-10
    off = [ref.based_eight(a, b, 0.6, o, 0.0, k) for o in (0.0, 1.0, 2.0)]
    assert np.ptp([e[2] for e in off]) > 0.1
    assert np.ptp([math.hypot(*e[:2]) for e in off]) > 0.1


def test_mirror_in_the_meridian_plane_flips_turn_and_lateral_shift():
    a, b, sigma, orientation, k = 0.3, 0.2, 0.6, 0.4, 2.5
    e = ref.based_eight(a, b, sigma, orientation, 0.0, k)
    m = ref.based_eight(a, b, sigma, orientation, 0.0, k, mirror=True)
    assert np.allclose(m, [e[0], -e[1], -e[2]], atol=1e-10, rtol=0)


@pytest.mark.parametrize("a, sigma, orientation, beta, k", [(0.3, 0.5, 0.7, 0.2, 2.5), (0.2, 0.9, -1.3, 2.0, 6.0)])
def test_turn_of_a_leaf_is_the_integral_of_the_curvature_density(a, sigma, orientation, beta, k):
    """The turn of one closed leaf is the integral over its cap of k / n3z^2 + k - 1 (n3z = -z), by Stokes."""
    end = ref.integrate_contact_path(ref.based_circle_path(a, 1.0, sigma, orientation, beta), np.zeros(3),
                                     (0.0, 2 * np.pi), k).y[:, -1]
    m = ref._rz(beta) @ ref._ry(-sigma) @ ref._rz(orientation)
    centre = m @ np.array([0.0, a, -math.sqrt(1 - a * a)])
    e1 = np.cross(centre, [1.0, 0.0, 0.0])
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(centre, e1)

    def density(t, r):
        z = (math.cos(r) * centre + math.sin(r) * (math.cos(t) * e1 + math.sin(t) * e2))[2]
        return (k / z**2 + k - 1) * math.sin(r)

    total, _ = dblquad(density, 0.0, math.asin(a), 0.0, 2 * math.pi, epsabs=1e-12, epsrel=1e-12)
    assert math.isclose(abs(end[2]), total, rel_tol=1e-8)


def test_leaf_bound_keeps_leaves_inside_the_polar_limit():
    for sigma in (0.0, 0.5, 1.0, 1.4):
        a = leaf_bound(sigma)
        assert sigma + 2 * math.asin(a) <= POLAR_MAX + 1e-12


@pytest.mark.slow
def test_local_solve_reaches_a_target_by_the_printed_equations():
    """(The first local solve of a process builds its NLP: about 1 s of CPU; later solves take milliseconds.)"""
    base, k = (0.5, 0.8), 3.0
    target = ref.based_eight(0.25, 0.18, base[0], 1.2, base[1], k)   # a reachable target
    leg = solve_leg(target, base, k, 1, [(0.2, 0.2, o) for o in (0.0, 1.5, 3.0, -1.5)])
    assert leg is not None
    got = ref.based_eight(leg.a, leg.b, base[0], leg.orientation, base[1], k)
    assert np.allclose(got[:2], target[:2], atol=TOL, rtol=0)
    assert math.isclose(float(ref.wrap(got[2] - target[2])), 0.0, abs_tol=TOL)
    assert max(leg.a, leg.b) <= leaf_bound(base[0])
    assert leg.guarantee == "best of starts"


def test_base_option_is_checked():
    with pytest.raises(InputError, match="base"):
        ComposedPlanner(base="middle")


def random_pair(rng):
    """Start and goal with contact points up to 60 degrees from the pole."""
    out = []
    for _ in range(2):
        u, v = ref.polar_contact(rng.uniform(0.0, math.radians(60)), rng.uniform(-math.pi, math.pi))
        out.append((*rng.uniform(-1, 1, 2), rng.uniform(-math.pi, math.pi), u, v))
    return out


def certified_by_reference(plan, problem):
    final = ref.composed_final(plan.pieces, np.asarray(problem.start, float), problem.k)
    goal = np.asarray(problem.goal, float)
    assert np.allclose(final[[0, 1, 3, 4]], goal[[0, 1, 3, 4]], atol=TOL, rtol=0)
    assert math.isclose(float(ref.wrap(final[2] - goal[2])), 0.0, abs_tol=TOL)


@pytest.mark.slow
def test_readme_example_shorter_than_the_pole_plan_and_certified():
    problem = Problem((0.8, 0.2, 1.0, -0.4, 0.4), start=(0.0, 0.0, 0.0, 0.5, -0.3), k=2.5)
    pole = ComposedPlanner().solve(problem)
    based = ComposedPlanner(base="any").solve(problem)
    assert based.mode == "based" and based.path_length < pole.path_length
    assert based.certificate.residual <= TOL
    certified_by_reference(based, problem)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_any_base_is_never_longer_than_the_pole_plan(seed):
    rng = np.random.default_rng(seed)
    start, goal = random_pair(rng)
    problem = Problem(goal, start=start, k=float(rng.uniform(1.5, 8.0)))
    pole = ComposedPlanner().solve(problem)
    based = ComposedPlanner(base="any").solve(problem)
    assert based.path_length <= pole.path_length
    assert based.certificate.residual <= TOL
    certified_by_reference(based, problem)


@pytest.mark.slow
def test_cli_plan_base_any(capsys, tmp_path):
    from types import SimpleNamespace

    from conftest import run

    argv = ["plan", "--from", "0.3", "-0.2", "0.5", "-0.3", "0.2", "--to", "-0.5", "0.6", "--psi", "-0.7",
            "--contact", "0.35", "0.25", "--k", "4", "--polish", "off"]
    lengths = {}
    for base in ("pole", "any"):
        out = tmp_path / f"{base}.json"
        code, text, err = run(capsys, *argv, "--base", base, "--json", str(out))
        assert code == 0, err
        d = json.loads(out.read_text())
        lengths[base] = d["path_length"]
    assert d["mode"] == "based" and "base point" in text and d["base"]["guarantee"] in ("best of starts", "local")
    assert "screened by the pole search" in text and "not a complete search" in text
    assert lengths["any"] < lengths["pole"]
    pieces = [SimpleNamespace(**{n: s[n] for n in ("curve", "index", "params", "gamma")}) for s in d["segments"]]
    final = ref.composed_final(pieces, np.array([0.3, -0.2, 0.5, -0.3, 0.2]), 4.0)
    assert np.allclose(final, [-0.5, 0.6, -0.7, 0.35, 0.25], atol=TOL, rtol=0)
