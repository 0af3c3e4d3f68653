"""The shooting residual in CasADi against the numpy leaf map, and the solvers of (32)-(33) by name."""

import numpy as np
import pytest

import rollplan
from rollplan.planners.geometric import leafmap, refine

import references


@pytest.mark.parametrize("k", [0.0, 0.3, 2.5, 12.0, 29.0, 60.0, 100.0])
def test_casadi_residual_is_the_leaf_map(k):
    """One definition in CasADi, one in numpy (the enumeration's): the same turn and shift."""
    rng = np.random.default_rng(int(k * 10))
    panels = leafmap.panels_for(k)
    f = refine.leaf_residual(panels)
    for a, b in [(leafmap.A_MAX, leafmap.A_MAX), (1e-4, 0.69), *rng.uniform(0.01, 0.69, (4, 2))]:
        shift, eta = leafmap.step_values(a, b, k)
        res = np.array(f([a, b], [k, 0.0, 0.0])).ravel()
        assert res[0] == pytest.approx(eta[0], abs=1e-12 * (1 + abs(eta[0])))
        assert res[1] == pytest.approx(abs(shift[0]), abs=1e-12)


@pytest.mark.parametrize("k", [2.5, 29.0])
def test_casadi_step_is_the_leaf_map(k):
    """The planner's compiled shift and turn of one step (for gamma) against the numpy leaf map."""
    f = refine.leaf_step(leafmap.panels_for(k))
    for a, b in [(leafmap.A_MAX, 0.05), (0.31, 0.17), (1e-4, 0.69)]:
        shift, eta = leafmap.step_values(a, b, k)
        u, v, e = np.array(f([a, b], k)).ravel()
        assert abs(complex(u, v) - shift[0]) < 1e-12 and e == pytest.approx(eta[0], abs=1e-12 * (1 + abs(eta[0])))


def test_residual_against_dop853():
    a, b, k = 0.62, 0.15, 20.0
    ref = references.trace(a, b, k)
    res = np.array(refine.leaf_residual(leafmap.panels_for(k))([a, b], [k, 0.0, 0.0])).ravel()
    assert res[0] == pytest.approx(ref[2], abs=1e-10) and res[1] == pytest.approx(np.hypot(ref[0], ref[1]), abs=1e-10)


def test_compiled_and_virtual_machine_jacobians_agree():
    import casadi as ca

    x = ca.MX.sym("x", 2)
    par = [5.0, 0.1, 0.3]
    jc = ca.Function("j", [x], [ca.jacobian(refine.leaf_residual(2)(x, par), x)])([0.4, 0.3])
    jv = ca.Function("j", [x], [ca.jacobian(refine.leaf_residual(2, compile=False)(x, par), x)])([0.4, 0.3])
    assert np.allclose(np.array(jc), np.array(jv), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("method", sorted(refine.SOLVERS))
def test_solvers_follow_the_contract_from_a_nearby_start(method):
    a, b, k = 0.35, 0.22, 2.5
    shift, eta = leafmap.step_values(a, b, k)
    solve = refine.polisher(method, leafmap.panels_for(k))
    x, status, iters, ok = solve([a + 1e-4, b - 1e-4], [k, eta[0], abs(shift[0])], 1e-6, leafmap.A_MAX)
    assert ok and isinstance(status, str) and iters >= 1
    assert np.abs(x - [a, b]).max() < 1e-12


@pytest.mark.parametrize("method", ["ipopt", "newton"])
def test_plans_record_the_polish(method):
    p = rollplan.plan((1, -0.5, 1), steps=3, k=2.5, root_solver=method)
    assert p.stats.method == method and p.certificate.passed
    assert p.stats.status in ("Solve_Succeeded", "success") and 0 <= p.stats.iterations <= 3
    ref = references.trace(p.a, p.b, p.k, p.gamma, p.steps)
    assert np.linalg.norm([ref[0] - 1, ref[1] + 0.5, references.wrap(ref[2] - 1)]) < 1e-9
