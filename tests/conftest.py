"""Shared fixtures and independent references (scipy) for the tests."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollplan.curves import figure_eight
from rollplan.geometric import GeometricPhasePlanner
from rollplan.integrate import piece_rhs


@pytest.fixture(scope="session")
def planner():
    return GeometricPhasePlanner()


@pytest.fixture(scope="session")
def scipy_trace():
    """Independent reference: DOP853 integration of (28)-(30) over the figure eight, n times."""
    curve = figure_eight()
    rhs = [piece_rhs(curve, i) for i in range(len(curve.pieces))]

    def trace(a, b, k, gamma=0.0, steps=1, x0=(0.0, 0.0, 0.0), rtol=1e-13):
        x = np.asarray(x0, float)
        for _ in range(steps):
            for f in rhs:
                sol = solve_ivp(lambda t, y: np.array(f(t, y, [a, b], k, gamma)).ravel(), (0.0, 2 * np.pi), x,
                                method="DOP853", rtol=rtol, atol=1e-15)
                x = sol.y[:, -1]
        return x

    return trace
