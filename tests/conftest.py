"""Shared fixtures; makes ``tests/references.py`` importable as ``references``.

``references`` holds the independent references of the tests: the paper's printed equations and
closed forms in numpy, and the printed (28)-(30), (35), (31) integrated by scipy's DOP853
(``references.trace``). It shares no code with rollplan (not its model, curves or integrators).
That rollplan's symbolic model agrees with the printed equations is tested on its own in
``tests/test_model.py`` and ``tests/test_integrate.py``.
"""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rollplan  # noqa: E402
from rollplan.planners.geometric import GeometricPhasePlanner  # noqa: E402

import references  # noqa: E402


@pytest.fixture(scope="session")
def planner():
    """One geometric-phase planner for the whole session (step map and leaf tables built once)."""
    return GeometricPhasePlanner()


@pytest.fixture(scope="session")
def scipy_trace():
    """Independent reference: (u_a, v_a, psi) after ``steps`` figure eights (a, b) rotated by gamma,
    from zero, by DOP853 on the printed (28)-(30), (35) (units of R, rad)."""
    return references.trace


@pytest.fixture(scope="session")
def asym_plan():
    """A plan for the default robot with a != b (psi = 0.5), two steps: four leaves, three poles between them."""
    return rollplan.plan((0.05, 0.08, 0.5), 2, robot=rollplan.Robot())
