"""The step map (rollplan.core.integrate) against the independent reference (the paper's printed
(28)-(30), (35) in numpy, integrated by scipy DOP853: ``tests/references.py``), the closed form
(36), and the symmetries the planner relies on."""

import functools

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp

from rollplan.core.curves import A_MAX, Curve, Piece, figure_eight
from rollplan.core.integrate import CvodesIntegrator, piece_rhs, rk8_step, spectral_step
from rollplan.problem import Problem

import references


@pytest.fixture(scope="module")
def fmap():
    return spectral_step(figure_eight())


def sx(f, a, b, k, gamma=0.0, x0=(0, 0, 0)):
    return np.array(f(x0, [a, b], k, gamma)).ravel()


def max_error(x, ref):
    """Largest error of (u_a, v_a, psi) against the reference, psi compared as an angle."""
    e = np.asarray(x[:3], float) - ref
    e[2] = references.wrap(e[2])
    return np.abs(e).max()


CASES = [(0.3, 0.4, 2.5, 0.0), (0.6, 0.2, 5.0, 0.3), (0.533681, 0.533681, 0.0, 0.0), (0.1, 0.65, 2.5, -1.0),
         (0.69, 0.5, 10.0, 0.0), (0.68, 0.68, 10.0, 2.0), (0.05, 0.02, 1.3, 0.0), (A_MAX, A_MAX, 5.0, 0.0)]
# (a, b, k, gamma, steps): several steps, leaves at A_MAX, k from 0 to 10
MULTI = [(0.3, 0.3, 2.5, 0.1, 1), (A_MAX, A_MAX, 2.5, -1.0, 1), (A_MAX, 0.05, 10.0, 2.0, 2), (0.5, 0.2, 0.0, 0.3, 3),
         (0.12, 0.61, 5.0, -2.5, 1)]


@pytest.mark.parametrize("a,b,k,gamma", CASES)
def test_spectral_step_matches_scipy(fmap, scipy_trace, a, b, k, gamma):
    assert np.abs(sx(fmap, a, b, k, gamma) - scipy_trace(a, b, k, gamma)).max() < 1e-11


@pytest.mark.parametrize("a,b,k,gamma,steps", [pytest.param(*m, marks=pytest.mark.slow) if m[2] == 10.0 else m
                                               for m in MULTI])   # k = 10 over two steps: 0.6 s of reference
def test_spectral_steps_composed_match_scipy(fmap, scipy_trace, a, b, k, gamma, steps):
    """The one-pass spectral step map, composed over n steps, against the reference's n steps."""
    x = np.zeros(3)
    for _ in range(steps):
        x = sx(fmap, a, b, k, gamma, x)
    assert max_error(x, scipy_trace(a, b, k, gamma, steps)) < 1e-11


@pytest.mark.parametrize("a,b,k,gamma", CASES[:4])
def test_cvodes_matches_scipy(scipy_trace, a, b, k, gamma):
    _, xs = CvodesIntegrator(figure_eight(), 1e-13, 1e-14).trace([a, b], k, gamma)
    assert np.abs(xs[-1] - scipy_trace(a, b, k, gamma)).max() < 1e-11


def test_cvodes_bdf_agrees_with_adams():
    """CVODES' BDF method is still available and agrees with the default Adams method."""
    curve = figure_eight()
    bdf = CvodesIntegrator(curve, 1e-13, 1e-14, multistep="bdf")
    adams = CvodesIntegrator(curve, 1e-13, 1e-14)
    for a, b, k, gamma, steps in MULTI[:3]:
        x1 = bdf.trace([a, b], k, gamma, steps)[1][-1]
        x2 = adams.trace([a, b], k, gamma, steps)[1][-1]
        assert np.abs(x1 - x2).max() < 2e-10


@functools.cache
def _leaf_rhs(leaf):
    """rollplan's right side along a leaf of the figure eight, built once per process (6 ms each)."""
    return piece_rhs(figure_eight(), leaf)


@settings(max_examples=40, deadline=None)
@given(st.floats(0.02, A_MAX), st.floats(0.0, 2 * np.pi), st.floats(-4.0, 4.0), st.floats(0.0, 10.0),
       st.floats(-3.2, 3.2), st.sampled_from([0, 1]))
def test_symbolic_rhs_matches_printed_rhs(a, phi, psi, k, gamma, leaf):
    """rollplan's symbolic (28)-(30) along the rotated circles (model.curve_rhs, circle_point,
    rotated_point) equals the printed equations typed in numpy, pointwise."""
    f = _leaf_rhs(leaf)
    ours = np.array(f(phi, [0.2, -0.1, psi], [a, a], k, gamma)).ravel()
    ref = references.rhs(phi, np.array([0.2, -0.1, psi]), a, 1.0 if leaf == 0 else -1.0, k, gamma)
    assert np.allclose(ours, ref, rtol=1e-12, atol=1e-12 * (1 + np.abs(ref).max()))


@pytest.mark.parametrize("a,b,k,gamma", [pytest.param(0.3, 0.4, 2.5, 0.0, marks=pytest.mark.slow),
                                         (0.1, 0.65, 2.5, -1.0),
                                         pytest.param(0.68, 0.68, 10.0, 2.0, marks=pytest.mark.slow)])
def test_symbolic_rhs_integrates_like_printed_rhs(a, b, k, gamma):
    """Integrating rollplan's symbolic right side by the same DOP853 gives the printed reference's step (a
    Python call per evaluation: the unit tier keeps the case with unequal leaves and a turn gamma)."""
    curve = figure_eight()
    x = np.zeros(3)
    for i in range(2):
        f = piece_rhs(curve, i)
        x = solve_ivp(lambda t, y, f=f: np.array(f(t, y, [a, b], k, gamma)).ravel(), (0.0, 2 * np.pi), x,
                      method="DOP853", rtol=1e-13, atol=1e-14).y[:, -1]
    assert np.abs(x - references.trace(a, b, k, gamma)).max() < 1e-11


@settings(max_examples=25, deadline=None)
@given(st.floats(0.02, A_MAX))
def test_pure_rolling_matches_closed_form_36(fmap, a):
    x = sx(fmap, a, a, 0.0)
    assert np.hypot(x[0], x[1]) == pytest.approx(abs(references.shift_36(a)), abs=1e-11)
    assert abs(x[2]) < 1e-12  # no net turn


@settings(max_examples=25, deadline=None)
@given(st.floats(0.02, A_MAX), st.floats(0.0, 10.0))
def test_symmetric_figure_eight_has_no_holonomy(fmap, a, k):
    """Mirror symmetry y -> -y of (28)-(30) maps psi to -psi, so eta(a, a) = 0."""
    assert abs(sx(fmap, a, a, k)[2]) < 1e-10 * (1 + k)


@pytest.fixture(scope="module")
def leaf_maps():
    """The step maps of leaf a alone and of leaf b alone of the figure eight."""
    c = figure_eight()
    return spectral_step(c, pieces=(0,)), spectral_step(c, pieces=(1,))


@settings(max_examples=25, deadline=None)
@given(st.floats(0.02, A_MAX), st.floats(0.0, 8.0))
def test_mirror_leaf(leaf_maps, a, k):
    """Leaf b alone is the mirror image of leaf a: (u, v, psi) -> (u, -v, -psi)."""
    first = np.array(leaf_maps[0]([0, 0, 0], [a, a], k, 0)).ravel()
    second = np.array(leaf_maps[1]([0, 0, 0], [a, a], k, 0)).ravel()
    assert np.allclose(second, first * [1, -1, -1], atol=1e-11 * (1 + abs(first[2])))


@settings(max_examples=25, deadline=None)
@given(st.floats(0.05, 0.65), st.floats(0.05, 0.65), st.floats(0.0, 8.0), st.floats(-3.0, 3.0))
def test_gamma_turns_the_displacement(fmap, a, b, k, gamma):
    """Rotating the curve about OZ by gamma turns the displacement by +gamma, psi unchanged."""
    x0, xg = sx(fmap, a, b, k), sx(fmap, a, b, k, gamma)
    assert np.allclose(xg[:2], references.rotate(gamma, x0[:2]), atol=1e-11)
    assert xg[2] == pytest.approx(x0[2], abs=1e-10)


@settings(max_examples=25, deadline=None)
@given(st.floats(0.05, 0.65), st.floats(0.05, 0.65), st.floats(0.0, 8.0), st.floats(-3.0, 3.0))
def test_initial_heading_turns_the_shift(fmap, a, b, k, psi0):
    """(28)-(29) rotate with psi: a step from heading psi0 gives the shift turned by -psi0."""
    x0, xp = sx(fmap, a, b, k), sx(fmap, a, b, k, 0.0, (0.3, -0.2, psi0))
    assert np.allclose(xp[:2] - [0.3, -0.2], references.rotate(-psi0, x0[:2]), atol=1e-11)
    assert xp[2] - psi0 == pytest.approx(x0[2], abs=1e-10)


def test_rotation_structure_of_curve_ode():
    """(28)-(29) are Rot(-psi) applied to their value at psi = 0, and psi' has no psi (the spectral
    quadrature and the generated C loop rely on it)."""
    f = piece_rhs(figure_eight(), 1)
    rng = np.random.default_rng(4)
    for _ in range(10):
        phi, a, b = rng.uniform(0, 2 * np.pi), *rng.uniform(0.05, A_MAX, 2)
        k, psi = rng.uniform(0, 8), rng.uniform(-9, 9)
        at0 = np.array(f(phi, [0, 0, 0], [a, b], k, 0)).ravel()
        at = np.array(f(phi, [0.3, -0.2, psi], [a, b], k, 0)).ravel()
        c, s = np.cos(psi), np.sin(psi)
        np.testing.assert_allclose(at, [c * at0[0] + s * at0[1], -s * at0[0] + c * at0[1], at0[2]], atol=1e-12)


@pytest.fixture(scope="module")
def fmap_jacobian(fmap):
    """d(step)/d(a, b) of ``fmap`` from the origin, gamma = 0, as a function of (a, b) and k: built once (building
    it for each k took most of the test's time)."""
    ab, k = ca.MX.sym("ab", 2), ca.MX.sym("k")
    return ca.Function("J", [ab, k], [ca.jacobian(fmap(ca.DM.zeros(3), ab, k, 0), ab)])


@settings(max_examples=15, deadline=None)
@given(st.floats(0.02, 0.68), st.floats(0.02, 0.68), st.floats(0.0, 5.0), st.sampled_from([0, 1, 2]))
def test_step_map_jacobian_matches_finite_differences(fmap, fmap_jacobian, a, b, k, row):
    j = np.array(fmap_jacobian([a, b], k))
    eps = 1e-6
    for col, (da, db) in enumerate([(eps, 0), (0, eps)]):
        fd = (sx(fmap, a + da, b + db, k) - sx(fmap, a - da, b - db, k)) / (2 * eps)
        assert j[row, col] == pytest.approx(fd[row], rel=1e-5, abs=1e-6)


def test_contact_path_length_is_the_curve_length(planner):
    """Rolling: the planar contact path is as long as the spherical one, 2 pi (a + b), for any k."""
    p = planner.solve(Problem((0.0, 1.0, 0.0), k=2.5))
    traj = p.sample(1 + 2 * 4000)
    assert traj.path_length() == pytest.approx(2 * np.pi * (p.a + p.b), rel=1e-6)
    sphere = np.linalg.norm(np.diff(traj.contact, axis=0), axis=1).sum()
    assert sphere == pytest.approx(traj.path_length(), rel=1e-6)


@pytest.mark.parametrize("params, k", [((0.5, 0.3), 2.5), pytest.param((0.8, -0.4), 6.0, marks=pytest.mark.slow)])
def test_pluggable_curve_matches_scipy(params, k):
    """Any closed curve through the south pole: a lemniscate-like curve, one piece."""

    def lemniscate(phi, p):
        v = ca.vertcat(p[0] * ca.sin(phi), p[1] * ca.sin(2 * phi), -1)
        return v / ca.norm_2(v)

    curve = Curve((Piece(lemniscate),), ("alpha", "beta"))
    f = piece_rhs(curve, 0)
    spectral = np.array(spectral_step(curve)([0, 0, 0], params, k, 0.4)).ravel()
    ref = solve_ivp(lambda t, y: np.array(f(t, y, params, k, 0.4)).ravel(), (0, 2 * np.pi),
                    [0, 0, 0], method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
    assert np.abs(spectral - ref).max() < 1e-10
    assert np.hypot(*spectral[:2]) > 1e-3  # it does move the robot


def test_rk8_step_has_order_eight():
    """Fixed-step RK8 on x' = x cos t (closed form exp(sin t)): the error falls 2^8-fold per halving."""
    t, x, c = ca.SX.sym("t"), ca.SX.sym("x"), ca.SX.sym("c")
    step = rk8_step(ca.Function("f", [t, x, c], [c * x * ca.cos(t)]))
    errors = []
    for n in (4, 8, 16):
        y = 1.0
        for i in range(n):
            y = float(step(y, i * 2.0 / n, 2.0 / n, 1.0))
        errors.append(abs(y - np.exp(np.sin(2.0))))
    assert 2**7.5 < errors[0] / errors[1] < 2**8.5 and 2**7.5 < errors[1] / errors[2] < 2**8.5
