"""Brent's method against scipy's brentq and closed forms."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rollplan.core.roots import brent

CASES = [(lambda x: x * x - 2.0, 0.0, 2.0), (math.cos, 0.0, 3.0), (lambda x: math.exp(x) - 1e3, -5.0, 20.0),
         (lambda x: (x - 0.3) ** 3, 0.0, 1.0), (lambda x: math.atan(1e6 * (x - 0.123)), -1.0, 1.0),
         (lambda x: x - 1e-300, -1.0, 1.0), (lambda x: math.sin(x) - 0.5, 0.0, 1.5)]


@pytest.mark.parametrize("i", range(len(CASES)))
def test_brent_agrees_with_scipy(i):
    f, lo, hi = CASES[i]
    x = brent(f, lo, hi, xtol=1e-15)
    ref = brentq(f, lo, hi, xtol=1e-15, rtol=4 * np.finfo(float).eps, maxiter=500)
    assert x == pytest.approx(ref, abs=2e-15 + 16 * np.finfo(float).eps * abs(ref))
    assert lo <= x <= hi


def test_closed_forms_and_errors():
    assert brent(lambda x: x * x - 2.0, 0.0, 2.0) == pytest.approx(math.sqrt(2.0), abs=1e-15)
    assert brent(lambda x: x, 0.0, 1.0) == 0.0
    with pytest.raises(ValueError, match="does not bracket"):
        brent(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="not finite"):
        brent(lambda x: float("nan"), -1.0, 1.0)
