"""The references' scalar right sides (tests/references.py) against their array forms: a spline evaluated by
Horner on its piece is scipy's own evaluation, and the rotor-driven right side is Montana's (6)-(10) with omega
from (11) and n_1, n_2 the columns of (2) composed from elementary rotations."""

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.interpolate import CubicSpline

import references

angle = st.floats(-1.4, 1.4)


@settings(max_examples=30, deadline=None)
@given(st.integers(3, 30), st.integers(1, 3), st.integers(0, 2**32 - 1))
def test_scalar_spline_is_scipys_spline(n, m, seed):
    """Values and first derivatives at and between the knots, and outside them (scipy extrapolates the end pieces)."""
    rng = np.random.default_rng(seed)
    x = np.cumsum(rng.uniform(0.01, 1.0, n))
    y = rng.normal(size=(n, m)) if m > 1 else rng.normal(size=n)
    spline = CubicSpline(x, y, bc_type="not-a-knot")
    f, fd = references.scalar_spline(spline), references.scalar_spline(spline, derivative=True)
    span = x[-1] - x[0]
    for p in np.r_[x, rng.uniform(x[0] - 0.2 * span, x[-1] + 0.2 * span, 50)]:
        want, dwant = np.atleast_1d(spline(p)), np.atleast_1d(spline(p, 1))
        scale = 1 + np.abs(want).max() + np.abs(dwant).max()
        assert np.abs(np.array(f(p)) - want).max() < 1e-12 * scale
        value, slope = fd(p)
        assert np.array_equal(value, f(p)) and np.abs(np.array(slope) - dwant).max() < 1e-12 * scale


@settings(max_examples=60, deadline=None)
@given(angle, angle, st.floats(-3.2, 3.2), st.floats(-50, 50), st.floats(-50, 50),
       st.floats(0.5, 3.0), st.floats(0.1, 3.0), st.floats(1e-3, 0.5), st.floats(0.05, 2.0))
def test_rotor_driven_rhs_is_montana_with_omega_from_11(u, v, psi, r1, r2, j_zz, extra, j_r, radius):
    """``Jc omega = -J_r (n_1 phi_1' + n_2 phi_2')`` with n_1, n_2 the columns of :func:`references.orientation`
    (elementary rotations), then :func:`references.montana`."""
    j_xx = j_zz + extra
    f = references.rotor_driven_rhs(j_xx, j_zz, j_r, radius, lambda t: (r1, r2))
    rot = references.orientation(u, v, psi)
    omega = -j_r * (rot[:, 0] * r1 + rot[:, 1] * r2) / np.array([j_xx, j_xx, j_zz])
    want = references.montana(omega, u, v, psi, radius)
    got = f(0.0, np.array([0.3, -0.2, psi, u, v]))
    assert np.abs(got - want).max() <= 1e-12 * (1 + np.abs(want).max())


def test_end_only_integrations_end_where_the_sampled_ones_do():
    """``end=True`` of :func:`references.rotor_drive` and :func:`references.replay`: the last sample of the full
    integration (the same DOP853 steps: t_eval does not change them)."""
    t = np.linspace(0.0, 2.0, 201)
    rates = np.column_stack([np.sin(3 * t), 0.5 * np.cos(2 * t) * t])
    robot = {"radius": 0.1, "mass_total": 2.0, "mass_shell": 0.5, "rotor_inertia_axial": 1e-3,
             "rotor_inertia_transverse": 5e-4}
    full = references.rotor_drive(robot, t, rates)
    assert np.abs(full[-1]).max() > 1e-2
    assert np.abs(references.rotor_drive(robot, t, rates, end=True) - full[-1]).max() < 1e-14
    s = np.linspace(0.0, 2 * np.pi, 61)
    u, v = 0.3 * np.sin(s), 0.2 * np.sin(2 * s)
    segment = (s > np.pi).astype(int)
    full = references.replay(u, v, segment, np.zeros(3), 2.5)
    assert np.abs(full[-1]).max() > 1e-2
    assert np.abs(references.replay(u, v, segment, np.zeros(3), 2.5, end=True) - full[-1]).max() < 1e-14


def test_repeated_eights_from_their_symmetry_are_the_eights_integrated_in_turn():
    """references.repeat_eight (n figure eights from the end of one and the symmetry of (28)-(30)) against n figure
    eights integrated one after another by DOP853 from each one's end, for the circles and a polygon family."""
    for name, a, b, k, gamma, steps in (("circles", 0.3, 0.2, 2.5, 0.4, 3), ("triangle", 0.35, 0.25, 6.0, -0.7, 2)):
        if name == "circles":
            one, x = references.trace(a, b, k, gamma), references.trace(a, b, k, gamma, steps=steps)
        else:
            one = x = references.family_trace(name, a, b, k, gamma)
            for _ in range(steps - 1):
                x = references.family_trace(name, a, b, k, gamma, x)
        assert np.abs(references.repeat_eight(one, steps) - x).max() < 1e-11, (name, x)
