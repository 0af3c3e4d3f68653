"""rollplan's not-a-knot cubic spline against scipy's CubicSpline (the same interpolant)."""

import numpy as np
import pytest
from scipy.interpolate import CubicSpline as Reference

from rollplan.core.spline import CubicSpline
from rollplan.errors import InputError


@pytest.mark.parametrize("n", [2, 3, 4, 5, 17, 400])
@pytest.mark.parametrize("cols", [(), (3,), (2, 2)])
def test_matches_scipy(n, cols):
    rng = np.random.default_rng(n)
    x = np.cumsum(rng.uniform(0.1, 1.0, n))
    y = rng.normal(size=(n, *cols))
    q = np.concatenate([np.linspace(x[0] - 0.3, x[-1] + 0.3, 301), x])
    ours, ref = CubicSpline(x, y, axis=0), Reference(x, y, axis=0)
    scale = 1.0 + np.abs(y).max()
    assert ours(q).shape == ref(q).shape
    assert np.abs(ours(q) - ref(q)).max() < 1e-11 * scale
    assert np.abs(ours(q, 1) - ref(q, 1)).max() < 1e-10 * scale
    assert np.abs(ours.antiderivative()(q) - ref.antiderivative()(q)).max() < 1e-10 * scale * (x[-1] - x[0] + 1)


def test_reproduces_cubics_and_refuses_bad_input():
    x = np.linspace(0.0, 2.0, 9)
    s = CubicSpline(x, x**3 - x)
    q = np.linspace(0.0, 2.0, 50)
    assert np.abs(s(q) - (q**3 - q)).max() < 1e-12 and np.abs(s(q, 1) - (3 * q**2 - 1)).max() < 1e-11
    assert np.abs(s.antiderivative()(q) - (q**4 / 4 - q**2 / 2)).max() < 1e-12
    for bad in ((np.array([0.0, 0.0, 1.0]), np.zeros(3)), (np.array([0.0]), np.zeros(1)), (x, np.zeros(3))):
        with pytest.raises(InputError):
            CubicSpline(*bad)
