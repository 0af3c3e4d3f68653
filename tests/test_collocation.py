"""The direct-collocation planner (rollplan.planners.collocation): realizability, goal reached, order of
convergence, the transcription's coefficients, costs, errors.

Independent references used here:

* scipy's DOP853 on ``model.contact_rhs`` (the model, not the transcription);
* Montana's (6), (7), (10) as printed in the paper, inverted for omega (``references.omega_from_rates``),
  and the realizability condition (13) from ``model.realizability_residual``;
* Gauss-Legendre quadrature nodes from numpy (not casadi) for the collocation polynomial's derivative;
* the known orders of the collocation methods: with the control constant on each interval,
  collocation at the d Gauss-Legendre points is the d-stage Gauss method (order 2d), at the d
  Radau IIA points the Radau IIA method (order 2d - 1) (Hairer, Norsett, Wanner I, Thm. II.7.9 and
  Hairer-Wanner II, Sec. IV.5): the end-of-interval error after N intervals is O(N^-p);
* the Cauchy-Schwarz identity ``L^2 <= T int |v|^2 dt`` with equality only at constant speed, and
  the mirror symmetry y -> -y of the model.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollplan import InputError, PlanResult, Problem, Robot, SolverError, State, plan
from rollplan.core import model
from rollplan.planners import solve
from rollplan.planners.collocation import COSTS, GUESSES, CollocationPlanner, Guess, Transcription, collocate
from rollplan.planners.collocation.planner import MIN_INTERVALS

import references

K = 2.5
TARGET = (0.5, 0.3, 0.4)
PROBLEM = Problem(TARGET, k=K)

_x = ca.SX.sym("x", 5)
_w = ca.SX.sym("w", 2)
_k = ca.SX.sym("k")
RHS = ca.Function("rhs", [_x, _w, _k], [model.contact_rhs(_x, _w, _k)])
_om = ca.SX.sym("om", 3)
REAL = ca.Function("real", [_om, _x, _k], [model.realizability_residual(_om, _x[3], _x[4], _x[2], _k)])


def scipy_final(controls, k, horizon=1.0):
    """End state (u_a, v_a, psi, u_o, v_o) from rest with piecewise-constant rates, by DOP853 interval by interval."""
    controls = np.asarray(controls, float)
    h = horizon / controls.shape[0]
    x = np.zeros(5)
    for w in controls:
        s = solve_ivp(lambda t, y, w=w: np.array(RHS(y, w, k)).ravel(), (0.0, h), x, method="DOP853",
                      rtol=1e-13, atol=1e-14)
        x = s.y[:, -1]
    return x


@pytest.fixture(scope="module")
def planner40():
    return CollocationPlanner(40, 3, "legendre", "path_energy")


@pytest.fixture(scope="module")
def warm40(planner40):
    return planner40.solve(PROBLEM, guess="warm")


def test_newton_correction_jacobian_by_eighth_order_steps(planner40, monkeypatch):
    """The correction's Jacobian came from CVODES's sensitivities; now from eighth-order steps (CVODES integrating
    the end error): the corrected controls are those of the correction through CVODES's sensitivities (to 1e-10)."""
    from conftest import recorded_fallback

    from rollplan.planners.collocation import planner as cp
    from rollplan.planners.collocation.transcription import CORRECTION_TOL, JACOBIAN_SUBSTEPS

    asked, used, calls, real_step, real_gn = [], [], [], cp._newton_step, cp.gauss_newton
    monkeypatch.setattr(cp, "_newton_step", lambda *a: asked.append(a) or recorded_fallback(real_step, a, used))
    monkeypatch.setattr(cp, "gauss_newton", lambda *a, **kw: calls.append(a) or real_gn(*a, **kw))
    r = planner40.solve(PROBLEM, guess="warm")
    assert (planner40.cost, True, JACOBIAN_SUBSTEPS) in asked and len(calls) == 1
    assert (planner40.cost,) in asked and not used   # CVODES's sensitivities: the fallback, never called
    _, controls, start, final, par = calls[0][:5]
    reference, _, size, first = real_gn(real_step(planner40.cost), controls, start, final, par, CORRECTION_TOL,
                                        plain=real_step(planner40.cost, False))
    assert size <= CORRECTION_TOL < first
    assert np.abs(r.solution.controls - reference).max() <= 1e-10 * np.abs(reference).max()
    assert r.residual < 1e-9


# ----------------------------------------------------------------------------- target reached


def test_target_reached_by_scipy_integration(warm40):
    r = warm40
    assert r.stats.status in ("Solve_Succeeded", "Solved_To_Acceptable_Level") and r.guess == "warm"
    xf = scipy_final(r.solution.controls, K, r.horizon)
    # scipy reaches the target (u_a, v_a, psi, u_o, v_o)
    want = np.array([TARGET[0], TARGET[1], TARGET[2] + 2 * math.pi * r.turns, 0.0, 0.0])
    assert np.linalg.norm(xf - want) < 1e-9
    # ... and agrees with the CVODES verification the result reports
    assert isinstance(r.final, State)
    assert np.allclose(r.final, xf, atol=1e-9)
    assert r.residual < 1e-9 and r.solution.max_defect < 1e-9
    assert r.trajectory.s.size >= 1000


def test_result_protocol(warm40):
    r = warm40
    assert isinstance(r, PlanResult) and r.method == "collocation" and r.problem == PROBLEM
    assert r.certificate.passed and r.certificate.method == "cvodes" and r.certificate.final == r.final
    assert r.residual == r.certificate.residual
    assert r.path_length == r.measures.path_length
    t = r.sample()
    assert t is r.trajectory and t.parameter == "t" and t.s[0] == 0 and t.s[-1] == pytest.approx(r.horizon)
    assert np.array_equal(t.state[0], np.zeros(5)) and np.array_equal(t.state[-1], r.final)
    assert r.omega.shape == (t.s.size, 3)
    assert r.stats.method == "ipopt" and r.stats.time_s > 0 and r.stats.details["guess_time_s"] > 0
    tr = r.transcription
    assert (tr.intervals, tr.degree, tr.scheme) == (40, 3, "legendre")
    assert r.solution.states.shape == (41, 5) and r.solution.controls.shape == (40, 2)
    assert r.solution.t_colloc.shape == (120,) and r.solution.states_colloc.shape == (120, 5)


def test_verification_catches_wrong_controls(planner40, warm40):
    """The residual is not vacuous: perturbed controls miss the target."""
    bad = warm40.solution.controls * 1.01
    v = planner40.verify(bad, K)
    assert np.linalg.norm(v["xf"] - warm40.solution.states[-1]) > 1e-3
    assert np.linalg.norm(scipy_final(bad, K) - v["xf"]) < 1e-9


# ----------------------------------------------------------------------------- realizability (13)


def _poly_derivatives(r):
    """d/dt of the Legendre collocation polynomial at the collocation points (numpy nodes)."""
    d, N, sol = r.transcription.degree, r.transcription.intervals, r.solution
    nodes = np.append(0.0, (np.polynomial.legendre.leggauss(d)[0] + 1) / 2)
    assert np.allclose(nodes[1:], np.sort(sol.t_colloc[:d]) / (r.horizon / N))
    V = np.vander(nodes, increasing=True)
    dV = np.array([[j * t ** (j - 1) if j else 0.0 for j in range(d + 1)] for t in nodes])
    Dm = dV @ np.linalg.inv(V)  # values at nodes -> derivative at nodes, on [0, 1]
    h = r.horizon / N
    out = []
    for i in range(N):
        X = np.vstack([sol.states[i], sol.states_colloc[i * d:(i + 1) * d]])
        out.append((Dm @ X)[1:] / h)
    return np.vstack(out)


def test_realizability_holds_along_collocation_solution(warm40):
    r = warm40
    X = r.solution.states_colloc
    om = references.omega_from_rates(X, _poly_derivatives(r))
    res = np.array([float(REAL(om[j], X[j], K)) for j in range(X.shape[0])])
    assert np.abs(res).max() < 1e-8 * max(1.0, np.abs(om).max())
    # not vacuous: the same motion violates (13) for another inertia ratio
    other = np.array([float(REAL(om[j], X[j], K + 1.0)) for j in range(X.shape[0])])
    assert np.abs(other).max() > 1e-2
    # (8)-(9): the polynomial's contact rates are the optimized controls
    rates = _poly_derivatives(r)[:, 3:5].reshape(r.transcription.intervals, r.transcription.degree, 2)
    assert np.allclose(rates, r.solution.controls[:, None, :], atol=1e-8)


def test_realizability_along_verified_trajectory(warm40):
    """(13) on the CVODES samples, omega from Montana (6), (7), (10) with finite differences."""
    tr = warm40.trajectory
    x, t = tr.state, tr.s
    # central differences inside each interval (the controls jump at interval ends)
    per = (t.size - 1) // warm40.transcription.intervals
    idx = np.array([i for i in range(1, t.size - 1) if i % per])
    xdot = (x[idx + 1] - x[idx - 1]) / (t[idx + 1] - t[idx - 1])[:, None]
    om = references.omega_from_rates(x[idx], xdot)
    res = np.array([float(REAL(om[j], x[i], K)) for j, i in enumerate(idx)])
    assert np.abs(res).max() < 1e-3 * np.abs(om).max()  # O(dt^2) differences
    assert np.allclose(om, warm40.omega[idx], atol=1e-3 * np.abs(om).max())


# ----------------------------------------------------------------------------- order of convergence

_STEPS = np.array([[1.0, 0.5], [-0.8, 1.2], [0.3, -1.0], [-0.6, -0.4]])  # rad/s on four quarters of [0, 1]


@pytest.fixture(scope="module")
def fixed_control_reference():
    return scipy_final(_STEPS, K)


@pytest.mark.parametrize("scheme, degree, order", [("legendre", 1, 2), ("legendre", 2, 4), ("legendre", 3, 6),
                                                   ("radau", 1, 1), ("radau", 2, 3), ("radau", 3, 5)])
def test_collocation_order_with_fixed_controls(scheme, degree, order, fixed_control_reference):
    """The transcription's collocation equations converge at order 2d (Legendre) / 2d - 1 (Radau)."""
    P = CollocationPlanner(MIN_INTERVALS, degree, scheme, "angular_velocity")
    Ns = [4, 8, 16, 32] if order >= 5 else [8, 16, 32, 64]
    err = np.array([np.linalg.norm(P.simulate(np.repeat(_STEPS, N // 4, axis=0), K)[-1] - fixed_control_reference)
                    for N in Ns])
    slope = -np.polyfit(np.log(Ns), np.log(err), 1)[0]
    assert abs(slope - order) < 0.3, (err, slope)


@pytest.mark.slow
@pytest.mark.parametrize("scheme, degree, order", [("legendre", 1, 2), ("radau", 2, 3)])
def test_verified_residual_of_optimal_solutions_shrinks_at_order(scheme, degree, order):
    """The end error of optimal solutions before the Newton correction (controls re-optimized at each N, integrated
    by CVODES) follows the same order; after it the residual is below the tolerance."""
    Ns = [20, 40, 80]
    runs = [CollocationPlanner(N, degree, scheme, "path_energy").solve(PROBLEM) for N in Ns]
    assert max(r.residual for r in runs) < 1e-9
    res = np.array([r.stats.details["uncorrected_error"] for r in runs])
    slope = -np.polyfit(np.log(Ns), np.log(res), 1)[0]
    assert abs(slope - order) < 0.4, (res, slope)


@pytest.mark.parametrize("scheme", ["legendre", "radau"])
def test_coefficients_integrate_and_differentiate_polynomials(scheme):
    """casadi.collocation_coeff's C, D, B: the interpolant of tau^p through [0, tau_1..tau_d] has the
    derivative p tau^(p-1) at the collocation points (C), the value 1 at tau = 1 (D), and the
    quadrature on the collocation points integrates it to 1 / (p + 1) (B), exactly for p <= d."""
    tau, C, D, B = Transcription(5, 3, scheme).coefficients()
    assert tau.shape == (4,) and C.shape == (4, 3) and D.shape == (4,) and B.shape == (3,)
    assert tau[0] == 0.0 and np.all(np.diff(tau) > 0) and tau[-1] <= 1.0
    for p in range(4):  # exact for degree <= 3 on 4 nodes
        vals = tau ** p
        assert np.isclose(vals @ D, 1.0)
        assert np.isclose(vals[1:] @ B, 1.0 / (p + 1))
        assert np.allclose(vals @ C, p * tau[1:] ** (p - 1) if p else 0.0)


# ----------------------------------------------------------------------------- costs


def test_path_length_cost_gives_constant_speed_shortest_path(warm40):
    """Energy form: L^2 <= T int |v|^2, equality only at constant speed; shorter than the figure eight."""
    r = warm40
    assert r.path_length == pytest.approx(math.sqrt(r.horizon * r.solution.objective), rel=1e-3)
    p = plan(TARGET, 1, k=K)
    assert r.path_length < p.path_length


@pytest.mark.slow
def test_mirror_symmetry_of_optimal_cost(planner40, warm40):
    """y -> -y maps the model onto itself with psi -> -psi: the optimum of the mirrored target is equal."""
    m = planner40.solve(Problem((TARGET[0], -TARGET[1], -TARGET[2]), k=K), guess="warm")
    assert m.solution.objective == pytest.approx(warm40.solution.objective, rel=1e-6)
    mirror = np.array([1.0, -1.0, -1.0, 1.0, -1.0])   # (u_a, v_a, psi, u_o, v_o)
    assert np.allclose(m.solution.states * mirror, warm40.solution.states, atol=1e-5)


def test_rotor_effort_equals_quadrature_of_rotor_rates():
    robot = Robot()
    r = collocate((0.05, 0.03, 0.4), robot=robot, cost="rotor_effort", intervals=12)
    assert r.problem.radius == robot.radius and r.residual < 1e-6
    # the verified rotor effort matches the transcription's objective (same functional, different quadrature)
    assert r.measures.rotor_effort == pytest.approx(r.solution.objective, rel=1e-4)
    # rotor rates from (11) along the verified motion: |phi_dot| >= Jxx |omega| / J_r * ... > 0
    assert r.measures.rotor_effort > 0 and r.measures.effort > 0


def test_costs_registry():
    assert {"path_energy", "angular_velocity", "rotor_effort"} <= set(COSTS)
    assert COSTS["rotor_effort"].needs_robot


def test_energy_form_of_the_path_length_has_its_own_name():
    """"path_length" is int |v| dt in rollplan.measures but was int |v|^2 dt here: the energy form is now
    "path_energy", and the old key still gives it, with a DeprecationWarning."""
    from rollplan.execution.optimal_timing import TIMING_COSTS
    from rollplan.measures import COSTS as MEASURED
    from rollplan.planners.collocation.rest import REST_COSTS

    assert "path_length" in MEASURED and "path_length" not in COSTS
    assert "path_length" not in REST_COSTS and "path_length" not in TIMING_COSTS
    x, w, xdot, omega, par = (ca.SX.sym(n, m) for n, m in (("x", 5), ("w", 2), ("xd", 5), ("om", 3), ("p", 6)))
    energy = ca.Function("L", [xdot], [COSTS["path_energy"].integrand(x, w, xdot, omega, par)])
    assert float(energy([0.3, -0.4, 0, 0, 0])) == pytest.approx(0.25, rel=1e-15)   # |v|^2, not |v|
    with pytest.warns(DeprecationWarning, match="path_energy"):
        planner = CollocationPlanner(4, 1, cost="path_length")
    assert planner.cost is COSTS["path_energy"]


# ----------------------------------------------------------------------------- errors


def test_failed_solve_raises_solver_error_with_status():
    P = CollocationPlanner(20, 2, "legendre", "path_energy", max_iter=2)
    with pytest.raises(SolverError) as exc:
        P.solve(PROBLEM, guess="naive")
    assert exc.value.status == "Maximum_Iterations_Exceeded"
    assert "hint" in str(exc.value) and "Maximum_Iterations_Exceeded" in str(exc.value)


@pytest.mark.parametrize("kwargs, word", [
    ({"scheme": "gauss"}, "scheme"), ({"degree": 0}, "degree"), ({"intervals": 0}, "intervals"),
    ({"cost": "fuel"}, "cost"), ({"degree": 2.5}, "degree"), ({"contact_bound": 2.0}, "contact_bound"),
])
def test_bad_planner_input(kwargs, word):
    with pytest.raises(InputError, match=word):
        CollocationPlanner(**{"intervals": 4, **kwargs})


def test_bad_solve_input(planner40):
    with pytest.raises(InputError, match="needs robot"):
        CollocationPlanner(4, 1, cost="rotor_effort").solve(PROBLEM)
    with pytest.raises(InputError, match="horizon"):
        planner40.solve(PROBLEM, horizon=0.0)
    with pytest.raises(InputError, match="guess"):
        planner40.solve(PROBLEM, guess="random")
    with pytest.raises(InputError, match="psi"):
        planner40.solve(Problem((0.1, 0.2, float("nan")), k=K))
    with pytest.raises(InputError, match="k"):
        planner40.solve(Problem(TARGET, k=-1.0))
    with pytest.raises(InputError, match="problem"):
        planner40.solve(TARGET)
    g = Guess(np.zeros((11, 5)), np.zeros((10, 3, 5)), np.zeros((10, 2)), "naive")   # a guess for N = 10
    with pytest.raises(InputError, match="guess.states"):
        planner40.solve_from(PROBLEM, g)


@pytest.mark.slow
def test_explicit_guess_object_is_used(planner40, warm40):
    """A Guess built from a previous solution converges faster to the same optimum."""
    r = warm40
    N, d = r.transcription.intervals, r.transcription.degree
    g = Guess(r.solution.states, r.solution.states_colloc.reshape(N, d, 5), r.solution.controls, "previous")
    again = planner40.solve_from(PROBLEM, g, turns=r.turns)
    assert again.guess == "previous" and again.stats.iterations < r.stats.iterations
    assert again.solution.objective == pytest.approx(r.solution.objective, rel=1e-9)


@pytest.mark.slow
def test_collocate_keywords_and_warm_start_plan(warm40):
    """collocate() states the problem by keywords; warm_start= passes the geometric-phase plan it follows,
    and planners.solve(problem, "collocation") is the same solve."""
    p = plan(TARGET, 1, k=K)
    r = collocate(TARGET, k=K, intervals=40, warm_start=p)
    assert r.guess == "warm" and r.turns == p.branch
    assert r.solution.objective == pytest.approx(warm40.solution.objective, rel=1e-9)
    q = solve(PROBLEM, "collocation", intervals=40)
    assert q.solution.objective == pytest.approx(warm40.solution.objective, rel=1e-9)


@pytest.mark.slow
def test_naive_guess_is_a_singular_point_and_fails_with_a_hint():
    """At rest on the south pole the linearized kinematics are not controllable: the equality
    Jacobian loses rank, and IPOPT fails from the naive guess for a psi = 0 target (see comparison.md)."""
    P = CollocationPlanner(10, 3, "legendre", "path_energy")
    tr, c = P.transcription, P.contact_bound
    problem = Problem((0.3, 0.0, 0.0), k=K)
    start, final = np.zeros(5), np.array([0.3, 0.0, 0.0, 0.0, 0.0])
    x0 = tr.pack(GUESSES["naive"](P, problem, start, final, 1.0, None))
    lbx, ubx = tr.bounds(start, final, [np.inf, np.inf, np.inf, c, c])
    par = P.parameters(K, 1.0, 0.0, None)
    J = np.array(P.solver.get_function("nlp_jac_g")(x0, par)[1])
    Je = J[~P.path_rows][:, lbx != ubx]
    assert np.linalg.matrix_rank(Je) < Je.shape[0]
    # the warm start is not singular
    xw = tr.pack(GUESSES["warm"](P, problem, start, final, 1.0, plan((0.3, 0.0, 0.0), 1, k=K)))
    Jw = np.array(P.solver.get_function("nlp_jac_g")(np.clip(xw, lbx, ubx), par)[1])
    assert np.linalg.matrix_rank(Jw[~P.path_rows][:, lbx != ubx]) == Je.shape[0]
    with pytest.raises(SolverError) as exc:
        P.solve(problem, guess="naive")
    assert exc.value.status in ("Infeasible_Problem_Detected", "Restoration_Failed")
    assert "controllable" in str(exc.value)
