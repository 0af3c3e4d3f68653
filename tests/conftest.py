"""Shared fixtures and the independent reference for the tests.

``scipy_trace`` is the paper's printed (28)-(30), (35) and Rz(gamma) (31), typed in
numpy in ``tests/printed_rhs.py`` and integrated by scipy's DOP853: it shares no code
with rollplan (not its model, curves or integrators). That rollplan's symbolic model
agrees with the printed equations is tested on its own in ``tests/test_integrate.py``.
"""

import pytest

import printed_rhs
from rollplan.geometric import GeometricPhasePlanner


@pytest.fixture(scope="session")
def planner():
    return GeometricPhasePlanner()


@pytest.fixture(scope="session")
def scipy_trace():
    """Independent reference: (u_a, v_a, psi) after ``steps`` figure eights (a, b) rotated by gamma,
    from zero, by DOP853 on the printed (28)-(30), (35) (units of R, rad)."""
    return printed_rhs.trace
