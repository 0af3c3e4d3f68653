"""The peer of the rest-to-rest collocation (rollplan.studies.comparison_peer): the same OCP transcribed by
rockit (an independent implementation of direct collocation on CasADi) must have the same optimum.

rockit is in the test extra: these tests run in CI (a skipped peer would leave the 1e-6 agreement unchecked).
"""

from __future__ import annotations

import sys

import numpy as np
import pytest

from rollplan import Problem
from rollplan.errors import InputError, SolverError
from rollplan.planners.collocation.rest import RestToRestPlanner, naive_guess
from rollplan.studies.comparison_peer import peer_rest_to_rest, rockit_solve

import references

K = 2.5


@pytest.mark.parametrize("scheme, degree", [("legendre", 3), ("radau", 4)])
def test_rockit_and_rollplan_have_the_same_optimum(scheme, degree):
    """Same OCP, same transcription class, same guess: the optima agree to 1e-6 (relative), the controls too,
    and rockit's controls, integrated by scipy's DOP853 on the printed (15), (16), (20), reach the goal."""
    problem = Problem((-0.4, 0.4, 1.0), k=K)
    c = peer_rest_to_rest(problem, "naive", intervals=16, degree=degree, scheme=scheme, repeats=0)
    assert c.relative_difference < 1e-6
    assert c.control_difference < 1e-4
    assert c.peer.residual < 1e-6 and c.residual < 1e-6
    # the peer's optimum is its own: its contact path, integrated independently, ends at the goal
    acc = c.peer.controls
    T, N = 1.0, acc.shape[0]
    h = T / N

    def path(t):   # u_o, v_o and rates of the piecewise-constant accelerations, from rest at the origin
        i = min(int(t / h), N - 1)
        pos, vel = np.zeros(2), np.zeros(2)
        for j in range(i):
            pos, vel = pos + vel * h + acc[j] * h ** 2 / 2, vel + acc[j] * h
        s = t - i * h
        return (*(pos + vel * s + acc[i] * s ** 2 / 2), *(vel + acc[i] * s))

    y = np.zeros(3)
    for i in range(N):
        y = references.integrate_contact_path(path, y, (i * h, (i + 1) * h), K).y[:, -1]
    assert np.abs(y - np.array([-0.4, 0.4, 1.0])).max() < 1e-5


def test_peer_bad_input_and_missing_rockit(monkeypatch):
    problem = Problem((-0.4, 0.4, 1.0), k=K)
    with pytest.raises(InputError, match="guess"):
        peer_rest_to_rest(problem, "warm")
    planner = RestToRestPlanner(4, 1)
    guess = naive_guess(planner.transcription, *planner.boundary(problem, 0))
    with pytest.raises(InputError, match="horizon"):
        rockit_solve(planner, problem, guess, horizon=float("nan"))
    with pytest.raises(SolverError, match="rockit/IPOPT did not solve"):    # IPOPT stopped after one iteration
        rockit_solve(RestToRestPlanner(4, 1, max_iter=1), problem, guess)
    monkeypatch.setitem(sys.modules, "rockit", None)
    with pytest.raises(InputError, match="rockit-meco"):
        rockit_solve(planner, problem, guess)
