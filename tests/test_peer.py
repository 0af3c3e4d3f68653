"""The peer of the rest-to-rest collocation (rollplan.studies.comparison_peer): the same OCP transcribed by
rockit (an independent implementation of direct collocation on CasADi) must have the same optimum.

rockit is in the test extra: these tests run in CI (a skipped peer would leave the 1e-6 agreement unchecked).
"""

from __future__ import annotations

import functools
import sys

import numpy as np
import pytest

from rollplan import Problem
from rollplan.errors import InputError, SolverError
from rollplan.planners.collocation.rest import RestToRestPlanner, naive_guess
from rollplan.studies.comparison_peer import peer_rest_to_rest, rockit_solve

import references

K = 2.5


@functools.cache
def _comparison(scheme, degree):
    """The peer comparison of the rest-to-rest problem of these tests, 8 intervals (a transcription that differs
    from rockit's differs at any size), each side solved twice (the optimum is the first solve's, corrected and
    certified): made once per process for the tests that read it."""
    return peer_rest_to_rest(Problem((-0.4, 0.4, 1.0), k=K), "naive", intervals=8, degree=degree, scheme=scheme,
                             repeats=1)


@pytest.mark.slow   # rockit's import alone costs ~0.9 s of CPU
@pytest.mark.parametrize("scheme, degree", [("legendre", 3), ("radau", 4)])
def test_rockit_and_rollplan_have_the_same_optimum(scheme, degree):
    """Same OCP, same transcription class, same guess: the optima agree to 1e-6 (relative), the controls too,
    and rockit's controls (Newton-corrected), integrated by scipy's DOP853 on the printed (15), (16), (20),
    reach the goal at rest."""
    c = _comparison(scheme, degree)
    assert c.relative_difference < 1e-6
    assert c.control_difference < 1e-4
    # the peer's controls, Newton-corrected, are its own certified plan: integrated by DOP853 on the printed
    # equations they end at the goal, at rest, within the project's tolerance
    assert c.peer.residual < 1e-9 and c.residual < 1e-9
    y, rates = references.rest_path_final(c.peer.controls, 1.0, K)
    assert np.abs(y - np.array([-0.4, 0.4, 1.0])).max() < 1e-9 and np.abs(rates).max() < 1e-9


def test_peer_bad_input_and_missing_rockit(monkeypatch):
    problem = Problem((-0.4, 0.4, 1.0), k=K)
    with pytest.raises(InputError, match="guess"):
        peer_rest_to_rest(problem, "warm")
    planner = RestToRestPlanner(4, 1)
    guess = naive_guess(planner.transcription, *planner.boundary(problem, 0))
    with pytest.raises(InputError, match="horizon"):
        rockit_solve(planner, problem, guess, horizon=float("nan"))
    monkeypatch.setitem(sys.modules, "rockit", None)
    with pytest.raises(InputError, match="rockit-meco"):
        rockit_solve(planner, problem, guess)


@pytest.mark.slow
def test_rockit_gets_the_planners_ipopt_options(monkeypatch):
    """The peer is timed like for like: rockit's IPOPT receives exactly the options of rollplan's solver
    (including its MUMPS ordering and its iteration limit), expanded to SX like rollplan's NLP. The smallest
    transcription, stopped after one iteration: the options are given before the solve."""
    import rockit

    seen, real = [], rockit.Ocp.solver
    monkeypatch.setattr(rockit.Ocp, "solver", lambda self, name, opts=None, *a, **kw:
                        seen.append((name, dict(opts or {}))) or real(self, name, opts, *a, **kw))
    planner = RestToRestPlanner(4, 1, max_iter=1)
    problem = Problem((-0.4, 0.4, 1.0), k=K)
    guess = naive_guess(planner.transcription, *planner.boundary(problem, 0))
    with pytest.raises(SolverError, match="rockit/IPOPT did not solve"):    # IPOPT stopped after one iteration
        rockit_solve(planner, problem, guess)
    assert planner.ipopt_options["ipopt.max_iter"] == 1
    assert seen == [("ipopt", {**planner.ipopt_options, "expand": True})]
    assert planner.ipopt_options["ipopt.mumps_pivot_order"] == 0


@pytest.mark.slow
def test_peer_times_both_solves_in_cpu_time_too():
    """On a loaded machine the wall times of one run swing by 2x and their ratio with them: the comparison now
    measures the CPU time of every timed solve of both sides as well (the process's time: rockit's Python
    bookkeeping counts, rollplan's correction does not, as in the wall times)."""
    c = _comparison("legendre", 3)
    assert len(c.solve_cpu_s) == 2 and len(c.peer.solve_cpu_s) == 1 and len(c.solve_s) == 2
    row = c.row()
    assert 0.0 < row["solve_cpu_median_s"] < float("inf") and 0.0 < row["peer_solve_cpu_median_s"] < float("inf")
    assert c.relative_difference < 1e-6
