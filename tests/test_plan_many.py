"""The default warm plan in one C call, and rollplan.plan_many: certified plans checked against independent
references (scipy DOP853 integration of the returned plans, the numpy enumeration of tests/reference_enumerate.py),
failures reported per target."""

import math

import numpy as np
import pytest
from conftest import one_line

import rollplan
from rollplan import InputError, NoPlanError, Problem
from rollplan.planners.geometric import compiled_search

import references
from reference_enumerate import reference_plan

TOL = rollplan.CERTIFICATE_TOLERANCE


def _random_targets(seed, count, reach=1.5):
    rng = np.random.default_rng(seed)
    return np.column_stack([rng.uniform(-reach, reach, count), rng.uniform(-reach, reach, count),
                            rng.uniform(-3.0, 3.0, count)])


def _check_certified(a, b, k, gamma, steps, target, final, residual, bound):
    """The plan reaches the target when scipy integrates it (its first figure eight by DOP853, the others by the
    symmetry of the printed equations, ``references.repeat_eight``), and its certificate is honest: the C
    integration's final state is within its error bound of scipy's."""
    x = references.repeat_eight(references.trace(a, b, k, gamma), steps)
    miss = math.hypot(x[0] - target[0], x[1] - target[1], math.remainder(x[2] - target[2], 2 * math.pi))
    assert miss <= TOL, (target, miss)
    assert residual + bound <= TOL
    assert np.abs(np.asarray(final) - x).max() <= bound + 1e-12, (target, final, x, bound)


@pytest.mark.slow
@pytest.mark.parametrize("k", [0.3, 2.5, 10.0])
def test_the_default_plan_is_certified_in_c(k):
    """rollplan.plan without options: the C search, polish and certificate in one call; the certificate's final state
    is scipy's to within its error bound, and the plan is the one IPOPT's polish and the Python RK8 certificate
    give."""
    for target, steps in [((0.0, 1.0, 0.0), 1), ((0.5, 0.3, 0.4), 2), ((1.0, -0.5, 1.0), 3), ((-0.7, 0.2, -2.5), 2)]:
        try:
            p = rollplan.plan(target, steps, k=k, legs="one")
        except NoPlanError:
            with pytest.raises(NoPlanError):
                rollplan.plan(target, steps, k=k, legs="one", root_solver="ipopt")
            continue
        assert p.stats.method == "c" and p.certificate.method == "rk8" and p.certificate.passed
        _check_certified(p.a, p.b, k, p.gamma, steps, target, p.certificate.final[:3], p.certificate.residual,
                         p.certificate.error_bound)
        q = rollplan.plan(target, steps, k=k, legs="one", root_solver="ipopt")
        assert q.stats.method == "ipopt" and q.branch == p.branch
        assert (q.a, q.b, q.gamma) == pytest.approx((p.a, p.b, p.gamma), abs=1e-12)


@pytest.mark.slow
def test_plan_many_matches_the_references():
    """Random targets at several k and n = 1..3: every "ok" plan reaches its target under scipy with an honest
    certificate, and is the shortest plan of the numpy enumeration (same branch, (a, b) to 1e-10); every target the
    enumeration finds no certified plan for is reported as failed, with no plan."""
    checked = failed = 0
    for seed, (k, steps) in enumerate([(0.3, 1), (1.0, 2), (2.5, 3), (5.0, 1), (2.5, 2)]):
        targets = _random_targets(seed, 6)
        r = rollplan.plan_many(targets, k=k, steps=steps)
        assert len(r) == 6 and set(r.status) <= set(rollplan.planners.geometric.many.STATUSES)
        for i, target in enumerate(targets):
            ref = reference_plan(target, steps, k)
            if ref is None:
                assert r.status[i] != "ok" and math.isnan(r.a[i]) and np.isnan(r.final[i]).all()
                with pytest.raises(NoPlanError):
                    r.plan(i)
                failed += 1
                continue
            assert r.status[i] == "ok", (target, steps, k)
            assert r.branch[i] == ref.branch and np.allclose([r.a[i], r.b[i]], [ref.a, ref.b], rtol=0, atol=1e-10)
            _check_certified(r.a[i], r.b[i], k, r.gamma[i], steps, target, r.final[i], r.residual[i],
                             r.error_bound[i])
            p = r.plan(i)
            assert isinstance(p, rollplan.Plan) and p.certificate.passed and (p.a, p.b) == (r.a[i], r.b[i])
            assert p.path_length == pytest.approx(2 * math.pi * steps * (p.a + p.b), rel=1e-15)
            checked += 1
    assert checked >= 20 and failed >= 1


def test_plan_many_reports_failures_per_target():
    """Unreachable targets (too far for one figure eight per step, the start point itself) fail alone: the
    targets around them are planned, the failures carry no plan."""
    targets = [(0.5, 0.3, 0.4), (30.0, 0.0, 0.0), (0.0, 0.0, 1.0), (0.2, 0.2, -0.3)]
    r = rollplan.plan_many(targets, k=2.5, steps=1)
    assert list(r.status) == ["ok", "no plan", "no plan", "ok"]
    assert list(r.ok) == [True, False, False, True]
    assert np.isnan(r.a[1:3]).all() and np.isnan(r.final[1:3]).all() and (r.branch[1:3] == 0).all()
    for i in (0, 3):
        _check_certified(r.a[i], r.b[i], 2.5, r.gamma[i], 1, targets[i], r.final[i], r.residual[i], r.error_bound[i])
    assert r.plans()[1] is None and r.plans()[0].a == r.a[0]


def test_plan_many_units_and_wrapped_psi():
    """Lengths in the robot's unit (radius R) and psi beyond pi: the same plans as rollplan.plan."""
    targets = [(0.05, 0.03, 0.4 + 4 * math.pi), (0.1, -0.05, -7.0)]
    r = rollplan.plan_many(targets, k=2.5, steps=2, radius=0.1)
    for i, target in enumerate(targets):
        p = rollplan.plan(target, 2, k=2.5, radius=0.1)
        assert r.status[i] == "ok" and r.branch[i] == p.branch
        assert (r.a[i], r.b[i], r.gamma[i]) == pytest.approx((p.a, p.b, p.gamma), abs=1e-13)
        assert r.plan(i).problem == Problem(target, k=2.5, radius=0.1, steps=2)
    far = rollplan.plan_many([(0.5, 0.3, -1e300), (0.5, 0.3, 0.4)], k=2.5)   # a branch beyond int64: exact
    assert far.branch[0] == rollplan.plan((0.5, 0.3, -1e300), k=2.5).branch and far.branch[1] == 0


def test_plan_many_uses_many_targets_per_call(monkeypatch):
    """The targets go to the C planner many per call, not one call each."""
    calls = []
    real = compiled_search.certified_plans

    def counting(targets, *args, **kwargs):
        calls.append(len(targets))
        return real(targets, *args, **kwargs)

    monkeypatch.setattr("rollplan.planners.geometric.many.certified_plans", counting)
    done = []
    r = rollplan.plan_many(_random_targets(7, 600), k=2.5, steps=1, progress=lambda d, n: done.append((d, n)))
    assert calls == [600] and done == [(256, 600), (512, 600), (600, 600)] and r.ok.sum() >= 500


@pytest.mark.parametrize("kwargs, name", [
    (dict(targets=[(0.1, 0.2)]), "targets"), (dict(targets=[(0.1, math.nan, 0.0)]), "targets[0]"),
    (dict(targets="abc"), "targets"), (dict(targets=[(0.1, 0.2, 0.0)], k=-1.0), "k"),
    (dict(targets=[(0.1, 0.2, 0.0)], steps=0), "steps"), (dict(targets=[(0.1, 0.2, 0.0)], radius=0.0), "radius"),
])
def test_plan_many_bad_input_is_one_clear_line(kwargs, name):
    kwargs.setdefault("k", 2.5)
    with pytest.raises(InputError) as err:
        rollplan.plan_many(**kwargs)
    assert one_line(str(err.value)) and name in str(err.value)


@pytest.mark.slow
def test_another_tolerance_or_certifier_takes_the_python_path():
    """The C certificate applies 1e-9: a planner with a tighter tolerance, or the CVODES certifier, certifies in Python
    (its own tolerance met), and the plan is the same root."""
    problem = Problem((0.5, 0.3, 0.4), k=2.5, steps=2)
    default = rollplan.GeometricPhasePlanner().solve(problem)
    for planner in (rollplan.GeometricPhasePlanner(tol=1e-11), rollplan.GeometricPhasePlanner(certifier="cvodes")):
        p = planner.solve(problem)
        assert p.certificate.tolerance == planner.tol and p.certificate.passed
        assert p.certificate.method == planner.certifier.name and p.stats.status != "ok"
        assert (p.a, p.b, p.branch) == (pytest.approx(default.a, abs=1e-12), pytest.approx(default.b, abs=1e-12),
                                        default.branch)
