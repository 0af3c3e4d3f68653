"""The default certificate (compiled RK8 with step doubling) against scipy's DOP853 on the printed equations."""

import inspect

import numpy as np
import pytest
import scipy.integrate._ivp.dop853_coefficients as dop

import rollplan
from rollplan.core import integrate
from rollplan.planners.geometric import GeometricPhasePlanner
from rollplan.planners.geometric.certify import CERTIFIERS, RK8Certifier
from rollplan.problem import State, arrival_residual

import references


def test_dop853_coefficients_are_scipys():
    n = dop.N_STAGES
    assert np.allclose(integrate.DOP853_C, dop.C[:n], rtol=0, atol=1e-15)
    assert np.allclose(integrate.DOP853_B, dop.B, rtol=0, atol=1e-15)
    a = np.zeros((n, n))
    for (i, j), v in integrate.DOP853_A.items():
        a[i, j] = v
    assert np.allclose(a, dop.A[:n, :n], rtol=0, atol=1e-13 * np.abs(dop.A).max())


def _error(final: State, ref) -> float:
    e = np.asarray(final[:3]) - ref
    e[2] = references.wrap(e[2])
    return float(np.linalg.norm(e))


@pytest.mark.parametrize("seed", [0, 1, 2, 3, pytest.param(4, marks=pytest.mark.slow), 5])
def test_estimate_bounds_the_true_error(seed):
    """On random plans, also at coarse step counts (large tolerances stop the doubling early), the
    estimate is at least the error against DOP853 at rtol 1e-13 (whose own error, ~1e-12, is allowed)."""
    rng = np.random.default_rng(seed)
    cert = RK8Certifier()
    a, b = rng.uniform(0.02, 0.69, 2)
    k = float(rng.choice([0.5, 1.5, 2.5, 5.0, 10.0, 20.0]))
    gamma = rng.uniform(-np.pi, np.pi)
    steps = int(rng.integers(1, 4))
    ref = references.trace(a, b, k, gamma, steps)
    for tol in (1e-9, 1e-6, 1e-3):
        final, est, n = cert.certify(a, b, k, gamma, steps, tol, start=16)
        assert est <= 0.25 * tol or n >= 2 ** 14
        assert _error(final, ref) <= est + 2e-12, (a, b, k, gamma, steps, tol, n)
    assert final.u_o == pytest.approx(0.0, abs=1e-14) and final.v_o == pytest.approx(0.0, abs=1e-14)


@pytest.mark.slow
def test_estimate_bounds_the_error_at_high_k():
    cert = RK8Certifier()
    ref = references.trace(0.69, 0.3, 30.0, 0.4, 1)
    final, est, _ = cert.certify(0.69, 0.3, 30.0, 0.4, 1)
    assert est <= 2.5e-10 and _error(final, ref) <= est + 5e-12


def test_the_certificate_rejects_a_perturbed_plan(planner):
    p = planner.solve(references_problem())
    c = p.certificate
    assert c.passed and c.method == "rk8"
    cert = RK8Certifier()
    final, est, _ = cert.certify(p.a + 1e-8, p.b, p.k, p.gamma, p.steps)
    assert arrival_residual(final, p.goal) + est > 1e-9
    shifted = p.goal._replace(u_a=p.goal.u_a + 2e-9)
    assert arrival_residual(c.final, shifted) + c.error_bound > 1e-9


def references_problem():
    from rollplan import Problem
    return Problem((0.4, -0.9, 2.0), k=2.5, steps=3)


def test_cvodes_stays_available_by_name():
    assert set(CERTIFIERS) == {"rk8", "cvodes"}
    p = GeometricPhasePlanner(certifier="cvodes").solve(references_problem())
    assert p.certificate.method == "cvodes" and p.certificate.passed and p.certificate.error_bound == 0.0
    x = references.trace(p.a, p.b, p.k, p.gamma, p.steps)
    assert _error(p.final, x) < 1e-10
    with pytest.raises(Exception, match="certifier"):
        GeometricPhasePlanner(certifier="euler")


def test_compiled_and_virtual_machine_agree():
    a, b, k, g = 0.45, 0.2, 5.0, -1.0
    f1, e1, n1 = RK8Certifier().certify(a, b, k, g, 2)
    f2, e2, n2 = RK8Certifier(compile=False).certify(a, b, k, g, 2)
    assert n1 == n2 and np.allclose(np.array(f1), np.array(f2), rtol=0, atol=1e-13)
    assert e1 == pytest.approx(e2, rel=1e-3, abs=1e-14)


@pytest.fixture(scope="module")
def written_c(tmp_path_factory):
    """The C planner as ``rollplan codegen`` writes it with its defaults: its text only, not built (conftest's
    ``generated_c`` also compiles it, which this module does not need)."""
    from rollplan import codegen

    return codegen.generate(tmp_path_factory.mktemp("c") / "planner")


def test_one_certificate_tolerance(written_c):
    """Every planner's default tolerance and the generated C planner's are the one CERTIFICATE_TOLERANCE."""
    from rollplan.codegen import c_library
    from rollplan.planners.collocation import planner as colloc
    from rollplan.planners.collocation import rest
    from rollplan.planners.geometric import certify
    from rollplan.planners.geometric import planner as geometric

    tol = rollplan.CERTIFICATE_TOLERANCE
    assert tol == 1e-9   # the project's stated tolerance (README: residuals in R and rad)
    assert geometric.TOLERANCE is tol and colloc.TOLERANCE is tol and rest.TOLERANCE is tol
    assert c_library.CERT_TOL is tol
    assert geometric.GeometricPhasePlanner().tol == tol
    assert inspect.signature(certify.initial_steps).parameters["tol"].default is tol
    header = (written_c.out / f"{written_c.prefix}.h").read_text()
    assert f"_CERT_TOL {tol!r}" in header and f"plans are certified to {tol:g}." in header
    from rollplan.planners.geometric import c_sources

    assert c_sources.CERT_TOL is tol
    config = (written_c.out / c_sources.CONFIG_HEADER).read_text()
    assert f"#define RP_CERT_TOL {tol!r}\n" in config and f"plans are certified to {tol:g}." in config
