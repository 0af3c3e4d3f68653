"""The collocation NLPs' derivatives built interval by interval (``transcription.interval_derivatives``) against
CasADi's own derivatives of the whole NLP's expression graph: the same sparsity and the same values."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rollplan.planners.collocation.costs import N_PAR
from rollplan.planners.collocation.planner import CollocationPlanner
from rollplan.planners.collocation.rest import RestToRestPlanner
from rollplan.planners.collocation.rest_nlp import RestTranscription
from rollplan.planners.collocation.transcription import interval_derivatives

NAMES = {"grad_f": "nlp_grad_f", "jac_g": "nlp_jac_g", "hess_lag": "nlp_hess_l"}


def whole_graph_derivatives(nlp: dict) -> dict:
    """CasADi's derivative functions of the NLP ``nlp``, differentiated as one expression graph."""
    solver = ca.nlpsol("whole", "ipopt", nlp, {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes"})
    return {key: solver.get_function(name) for key, name in NAMES.items()}


def assert_same_functions(mine: dict, nlp: dict, seed: int, points: int = 3) -> None:
    """Same sparsity of every output, values equal to rounding at random points (duals and sigma random too)."""
    reference = whole_graph_derivatives(nlp)
    rng = np.random.default_rng(seed)
    nx, np_, ng = nlp["x"].numel(), nlp["p"].numel(), nlp["g"].numel()
    for key, ref in reference.items():
        f = mine[key]
        assert f.n_in() == ref.n_in() and f.n_out() == ref.n_out(), key
        for i in range(ref.n_out()):
            assert f.sparsity_out(i) == ref.sparsity_out(i), (key, i)
        for _ in range(points):
            args = [rng.normal(size=nx), rng.uniform(0.5, 2.0, size=np_), rng.normal(), rng.normal(size=ng)]
            for a, b in zip(ref.call(args[:ref.n_in()]), f.call(args[:f.n_in()])):
                a, b = np.asarray(ca.DM(a).nonzeros()), np.asarray(ca.DM(b).nonzeros())
                assert np.abs(a - b).max(initial=0.0) <= 1e-12 * max(1.0, np.abs(a).max(initial=0.0)), key


@pytest.mark.parametrize("scheme", ["legendre", "radau"])
@pytest.mark.parametrize("degree", [1, 2, 3])
def test_rest_to_rest_nlp(scheme, degree):
    planner = RestToRestPlanner(intervals=4, degree=degree, scheme=scheme)
    tr = RestTranscription(planner.transcription)
    nlp, _ = tr.contact_nlp(planner.point, N_PAR)
    assert_same_functions(tr.contact_derivatives(planner.point, N_PAR), nlp, degree)


@pytest.mark.parametrize("scheme", ["legendre", "radau"])
def test_full_transcription_nlp(scheme):
    planner = CollocationPlanner(intervals=4, degree=2, scheme=scheme)
    tr = planner.transcription
    nlp, _ = tr.contact_nlp(planner.point, N_PAR)
    assert_same_functions(tr.contact_derivatives(planner.point, N_PAR), nlp, 7)


def test_the_planners_solvers_use_them():
    """The planners' IPOPT solvers evaluate the interval-built derivatives (MX functions), not CasADi's own."""
    for planner in (RestToRestPlanner(intervals=4), CollocationPlanner(intervals=4)):
        assert planner.solver.get_function("nlp_hess_l").is_a("MXFunction")


@settings(max_examples=25, deadline=None)
@given(nz=st.integers(1, 5), ng=st.integers(1, 4), np_=st.integers(1, 3), intervals=st.integers(1, 5),
       stride=st.integers(1, 5), seed=st.integers(0, 2**31))
def test_any_overlapping_blocks(nz, ng, np_, intervals, stride, seed):
    """A random nonlinear block (products, sines, exponentials of random terms) on windows of any overlap: the
    assembled gradient, Jacobian and Hessian of the Lagrangian are those of the whole NLP's graph."""
    stride = min(stride, nz)
    rng = np.random.default_rng(seed)
    z, p = ca.SX.sym("z", nz), ca.SX.sym("p", np_)

    def term():
        i, j, k = rng.integers(nz), rng.integers(nz), rng.integers(np_)
        return rng.normal() * [ca.sin, ca.exp, ca.cos][rng.integers(3)](z[i] * p[k]) * z[j]

    g = ca.vertcat(*[sum(term() for _ in range(3)) for _ in range(ng)])
    J = sum(term() for _ in range(3)) + z[rng.integers(nz)] ** 2
    block = ca.Function("block", [z, p], [g, J])
    n_x = (intervals - 1) * stride + nz
    x = ca.SX.sym("x", n_x)
    gs, Js = zip(*(block(x[i * stride:i * stride + nz], p) for i in range(intervals)))
    nlp = {"x": x, "p": p, "f": ca.sum1(ca.vertcat(*Js)), "g": ca.vertcat(*gs)}
    assert_same_functions(interval_derivatives(block, intervals, stride), nlp, seed, points=2)
