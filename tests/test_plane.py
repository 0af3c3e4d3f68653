"""Rigid motions of the contact plane (rollplan.core.plane): angle wrapping, exact reduction,
rotation and the n-step law, against complex arithmetic, exact fractions and brute-force sums."""

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan.core.plane import n_step_gain, n_step_sum, rotate, wrap, wrap_exact

import references

finite = st.floats(allow_nan=False, allow_infinity=False)


def exact_reduction(angle: float):
    """(w, m) with angle - 2 pi m the remainder of least magnitude, w its nearest double: in exact
    fractions with 2 pi to 700 decimals (independent of rollplan's decimal reduction)."""
    two_pi = references.two_pi_fraction()
    x = Fraction(angle)
    m = round(x / two_pi)
    return float(x - m * two_pi), m   # Fraction -> float rounds correctly


# ----------------------------------------------------------------------------- wrap


@settings(max_examples=200, deadline=None)
@given(st.floats(-1e6, 1e6))
def test_wrap_lands_in_the_half_open_interval_on_the_same_heading(x):
    w = float(wrap(x))
    assert -math.pi < w <= math.pi
    assert abs(references.wrap(w - x)) < 1e-9          # the same heading
    turns = (x - w) / (2 * math.pi)
    assert abs(turns - round(turns)) < 1e-9


@pytest.mark.parametrize("x, want", [(0.0, 0.0), (math.pi, math.pi), (-math.pi, math.pi), (3 * math.pi, math.pi),
                                     (2 * math.pi, 0.0), (-0.5, -0.5), (7.0, 7.0 - 2 * math.pi)])
def test_wrap_known_values(x, want):
    assert float(wrap(x)) == pytest.approx(want, abs=4e-15)


def test_wrap_is_elementwise():
    x = np.array([[0.1, 4.0], [-4.0, 10.0]])
    assert np.allclose(wrap(x), references.wrap(x), atol=1e-14)
    assert wrap(x).shape == x.shape


# ----------------------------------------------------------------------------- wrap_exact


@pytest.mark.parametrize("x", [1e16, -1e16, 1e300, -1e300, 1e20, 2 * math.pi, -2 * math.pi, math.pi, -math.pi,
                               3 * math.pi, 1000.5, 0.8 + 2 * math.pi * 50, 5e-324, 0.0, 1.7976931348623157e308,
                               0.4, -3.1415, math.nextafter(math.pi, 4.0)])
def test_wrap_exact_is_the_exact_remainder(x):
    w, m = wrap_exact(x)
    assert (w, m) == exact_reduction(x)
    assert isinstance(m, int) and abs(w) <= math.pi


def test_wrap_exact_known_remainders():
    """The float 2 pi is 2.4e-16 below 2 pi, the float pi below pi: exact reduction keeps that."""
    two_pi = references.two_pi_fraction()
    w, m = wrap_exact(2 * math.pi)
    assert m == 1 and w == float(Fraction(2 * math.pi) - two_pi) and -2.5e-16 < w < -2.4e-16
    assert wrap_exact(-math.pi) == (-math.pi, 0) and wrap_exact(math.pi) == (math.pi, 0)
    # 1e16 = 1591549430918953 turns of 2 pi plus the remainder; float arithmetic is off by ~0.5 rad
    w, m = wrap_exact(1e16)
    assert m == 1591549430918953
    assert Fraction(10**16) - m * two_pi == pytest.approx(Fraction(w), abs=1e-16)
    assert abs(float(wrap(1e16)) - w) > 0.1


@settings(max_examples=300, deadline=None)
@given(finite)
def test_wrap_exact_any_finite_double(x):
    w, m = wrap_exact(x)
    assert (w, m) == exact_reduction(x)
    assert -math.pi <= w <= math.pi


@settings(max_examples=100, deadline=None)
@given(st.floats(-1e4, 1e4))
def test_wrap_exact_agrees_with_wrap_for_moderate_angles(x):
    w, m = wrap_exact(x)
    assert references.wrap(w - float(wrap(x))) == pytest.approx(0.0, abs=1e-11)
    assert x - 2 * math.pi * m == pytest.approx(w, abs=1e-11)


# ----------------------------------------------------------------------------- rotate


@settings(max_examples=100, deadline=None)
@given(st.floats(-10.0, 10.0), st.floats(-5.0, 5.0), st.floats(-5.0, 5.0))
def test_rotate_is_complex_multiplication(angle, x, y):
    z = complex(x, y) * np.exp(1j * angle)
    assert np.allclose(rotate(angle, np.array([x, y])), [z.real, z.imag], atol=1e-13)


def test_rotate_broadcasts_over_vectors_and_angles():
    rng = np.random.default_rng(7)
    vec = rng.normal(size=(2, 9))
    ang = rng.uniform(-4, 4, 9)
    z = (vec[0] + 1j * vec[1]) * np.exp(1j * ang)
    out = rotate(ang, vec)
    assert out.shape == (2, 9)
    assert np.allclose(out, [z.real, z.imag], atol=1e-14)
    assert np.allclose(np.hypot(*out), np.hypot(*vec), atol=1e-14)   # a rotation keeps lengths


# ----------------------------------------------------------------------------- the n-step law


def brute_n_steps(shift, eta, steps):
    """Displacement of n steps composed one by one: each step from heading psi shifts by the first
    step's shift turned by -psi and turns psi by eta (the structure of (28)-(30))."""
    pos, psi = np.zeros(2), 0.0
    for _ in range(steps):
        c, s = math.cos(-psi), math.sin(-psi)
        pos = pos + [c * shift[0] - s * shift[1], s * shift[0] + c * shift[1]]
        psi += eta
    return pos


@settings(max_examples=100, deadline=None)
@given(st.floats(-7.0, 7.0), st.integers(1, 40), st.floats(-2.0, 2.0), st.floats(-2.0, 2.0))
def test_n_step_sum_is_the_composed_displacement(eta, steps, u, v):
    total = complex(u, v) * n_step_sum(eta, steps)
    assert np.allclose([total.real, total.imag], brute_n_steps((u, v), eta, steps), atol=1e-11)


@settings(max_examples=100, deadline=None)
@given(st.floats(-7.0, 7.0), st.integers(1, 40))
def test_n_step_gain_is_the_length_of_the_composed_displacement(eta, steps):
    d = brute_n_steps((1.0, 0.0), eta, steps)
    assert float(n_step_gain(eta, steps)) == pytest.approx(np.hypot(*d), abs=1e-10)
    assert float(n_step_gain(eta, steps)) == pytest.approx(references.n_step_gain(eta, steps), abs=1e-10)


@pytest.mark.parametrize("eta", [0.0, 2 * math.pi, -2 * math.pi, 4 * math.pi])
@pytest.mark.parametrize("steps", [1, 2, 7])
def test_n_step_gain_limit_34(eta, steps):
    """sin(eta / 2) = 0: every step shifts the same way, the gain is n (34)."""
    assert float(n_step_gain(eta, steps)) == steps
    assert np.hypot(*brute_n_steps((1.0, 0.0), eta, steps)) == pytest.approx(steps, abs=1e-12)


def test_n_step_gain_zero_where_the_steps_cancel():
    """sin(n eta / 2) = 0, sin(eta / 2) != 0: n steps come back to the start."""
    for steps in (2, 3, 5):
        eta = 2 * math.pi / steps
        assert float(n_step_gain(eta, steps)) == pytest.approx(0.0, abs=1e-14)
        assert np.hypot(*brute_n_steps((1.0, 0.0), eta, steps)) == pytest.approx(0.0, abs=1e-14)


def test_n_step_gain_is_elementwise():
    eta = np.array([0.0, 0.3, 1.0, 2 * math.pi])
    assert np.allclose(n_step_gain(eta, 3), [references.n_step_gain(e, 3) for e in eta], atol=1e-14)
