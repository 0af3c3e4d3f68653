"""The rest-to-rest NLP with its closed-form states eliminated (rollplan.planners.collocation.rest_nlp).

Independent references: scipy's solve_ivp of ``r' = a, u' = r`` (the closed forms at the collocation points),
the midpoint and implicit Euler rules written out (degree 1), the full transcription's equations
(``Transcription.contact_nlp`` with nx = 7, every state a collocation unknown) at the reduced NLP's solution,
and DOP853 on the printed (15), (16), (20) (``references.rest_path_final``) for the corrected controls.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from conftest import recorded_fallback
from scipy.integrate import solve_ivp

from rollplan import Problem
from rollplan.planners.collocation.rest import (
    N_PAR,
    TOLERANCE,
    RestToRestPlanner,
    correct,
    naive_guess,
    rest_parameters,
)
from rollplan.planners.collocation.rest_nlp import RestTranscription
from rollplan.planners.collocation.transcription import Guess, Transcription
from rollplan.planners.geometric.maneuvers import StraightRoll

import references

K = 2.5
X0 = np.array([0.1, -0.2, 0.3, 0.25, -0.15, 0.7, -0.4])
R1 = np.array([-0.9, 1.3])
H = 0.37


@pytest.mark.parametrize("scheme", ["legendre", "radau"])
@pytest.mark.parametrize("degree", [2, 3, 4])
def test_closed_forms_are_the_motion_of_a_constant_acceleration(scheme, degree):
    """For d >= 2 the eliminated values at the collocation points and the interval's end are those of the exact
    motion ``r' = a, (u_o, v_o)' = r`` (scipy), ``a = (r1 - r0) / H``."""
    rt = RestTranscription(Transcription(4, degree, scheme, nx=7, nu=2))
    uv, rates, uv_end, a = rt.stages(X0, R1, H)
    np.testing.assert_allclose(a, (R1 - X0[5:7]) / H, rtol=1e-14)
    sol = solve_ivp(lambda t, y: np.concatenate([y[2:], a]), (0.0, H), np.concatenate([X0[3:5], X0[5:7]]),
                    method="DOP853", rtol=1e-13, atol=1e-14, dense_output=True)
    pts = np.asarray(ca.collocation_points(degree, scheme))
    for j, s in enumerate(pts):
        np.testing.assert_allclose(np.concatenate([uv[j], rates[j]]), sol.sol(s * H), rtol=0, atol=1e-12)
    np.testing.assert_allclose(uv_end, sol.y[:2, -1], rtol=0, atol=1e-12)


def test_degree_one_closed_forms_are_the_midpoint_and_implicit_euler_rules():
    """With one point the collocation is the midpoint rule (Gauss) or implicit Euler (Radau), not the exact
    quadratic: the elimination keeps the collocation's own values."""
    r0 = X0[5:7]
    uv, rates, end, _ = RestTranscription(Transcription(4, 1, "legendre", nx=7, nu=2)).stages(X0, R1, H)
    mid = (r0 + R1) / 2
    np.testing.assert_allclose(rates[0], mid, rtol=1e-14)
    np.testing.assert_allclose(uv[0], X0[3:5] + H / 2 * mid, rtol=1e-14)
    np.testing.assert_allclose(end, X0[3:5] + H * mid, rtol=1e-14)
    uv, rates, end, _ = RestTranscription(Transcription(4, 1, "radau", nx=7, nu=2)).stages(X0, R1, H)
    np.testing.assert_allclose(rates[0], R1, rtol=1e-14)
    np.testing.assert_allclose(uv[0], X0[3:5] + H * R1, rtol=1e-14)
    np.testing.assert_allclose(end, X0[3:5] + H * R1, rtol=1e-14)


@pytest.mark.parametrize("scheme, degree", [("legendre", 3), ("radau", 2)])
def test_reduced_solution_solves_the_full_transcription(scheme, degree):
    """The reduced NLP's optimum, unpacked (the eliminated values by the closed forms), meets every equation of
    the full transcription (every state a collocation unknown) and its contact bound, with the same cost."""
    planner = RestToRestPlanner(8, degree, scheme)
    problem = Problem((0.5, 0.3, 0.4), k=K)
    nlp = planner.solve_nlp(problem, naive_guess(planner.transcription, *planner.boundary(problem, 0)))
    states, colloc, controls = planner.transcription.unpack(nlp.x)
    full, rows = planner.transcription.contact_nlp(planner.point, N_PAR)
    F = ca.Function("full", [full["x"], full["p"]], [full["f"], full["g"]])
    f, g = F(planner.transcription.pack(Guess(states, colloc, controls, "reduced")), rest_parameters(K, 1.0))
    g = np.asarray(g).ravel()
    assert np.abs(g[~rows]).max() < 1e-10
    assert g[rows].min() >= math.cos(planner.contact_bound) - 1e-12
    assert float(f) == pytest.approx(nlp.objective, rel=1e-13)
    np.testing.assert_allclose(states[[0, -1]], np.array(planner.boundary(problem, 0)), atol=0)
    assert np.abs(colloc[:, :, 3:5]).max() <= planner.contact_bound


@pytest.mark.slow
def test_correction_at_an_optimum_whose_end_jacobian_is_singular():
    """From the straight line, N = 8, the NLP of a straight roll reaches an optimum where the controls cannot move
    the end state in one direction (the smallest singular value of the end-state Jacobian below 1e-9 of the largest;
    IPOPT may need its fresh start there, :data:`.rest.IPOPT_RESTARTS`):
    Gauss-Newton ignores that direction instead of taking a huge step, and its controls reach the goal at rest
    (DOP853 on the printed equations)."""
    u, v = 0.3, -0.2
    problem = Problem((*StraightRoll.make(u, v, "departure").element(), u, v), k=K)
    planner = RestToRestPlanner(8, 3, cost="path_energy")
    start, final = planner.boundary(problem, 0)
    nlp = planner.solve_nlp(problem, naive_guess(planner.transcription, start, final))
    controls, _ = correct(planner.transcription.unpack(nlp.x)[2], start, final, nlp.par, "path_energy")
    y, rates = references.rest_path_final(controls, 1.0, K)
    assert np.abs(y - final[:3]).max() < TOLERANCE and np.abs(rates).max() < TOLERANCE
    assert planner.finish(nlp).residual < TOLERANCE


def test_a_failed_solve_starts_again_from_its_last_iterate(monkeypatch):
    """IPOPT stopped short of the optimum (its iteration limit) starts again from its last iterate and reaches the
    optimum of one uninterrupted solve; without the fresh start the same solve fails, and where the fresh start
    fails too the error names both statuses."""
    from rollplan.errors import SolverError
    from rollplan.planners.collocation import rest

    problem = Problem((0.5, 0.7, 0.8), k=K)
    planner = RestToRestPlanner(8, 3, cost="path_energy")
    start, final = planner.boundary(problem, 0)
    guess = naive_guess(planner.transcription, start, final)
    whole = planner.solve_nlp(problem, guess)
    short = planner.twin({"ipopt.max_iter": whole.iterations - 3})
    again = short.solve_nlp(problem, guess)
    assert again.iterations > whole.iterations - 3 and again.status in ("Solve_Succeeded", "Solved_To_Acceptable_Level")
    assert again.statuses == ("Maximum_Iterations_Exceeded", again.status) and whole.statuses == (whole.status,)
    assert np.abs(again.x - whole.x).max() < 1e-6 and again.objective == pytest.approx(whole.objective, rel=1e-9)
    assert short.finish(again).stats.details["ipopt_statuses"] == again.statuses
    monkeypatch.setattr(rest, "IPOPT_RESTARTS", 0)
    with pytest.raises(SolverError, match="Maximum_Iterations_Exceeded after"):
        short.solve_nlp(problem, guess)
    monkeypatch.undo()
    with pytest.raises(SolverError, match="Maximum_Iterations_Exceeded, then Maximum_Iterations_Exceeded after 2 "):
        planner.twin({"ipopt.max_iter": 1}).solve_nlp(problem, guess)


@pytest.mark.parametrize("status, starts", [
    ("Restoration_Failed", 2), ("Maximum_Iterations_Exceeded", 2), ("Error_In_Step_Computation", 2),
    ("Search_Direction_Becomes_Too_Small", 2), ("NonIpopt_Exception_Thrown", 1), ("User_Requested_Stop", 1),
    ("Infeasible_Problem_Detected", 1), ("Invalid_Number_Detected", 1), ("Maximum_CpuTime_Exceeded", 1)])
def test_only_a_stalled_solve_starts_again(status, starts):
    """IPOPT starts again only after a stall that a fresh start can change: never after an interrupt (a Ctrl-C
    that a program's own handler turned into an exception in the solver is not lost), a local infeasibility or an
    invalid number. A stand-in for IPOPT reports ``status`` at every start."""
    from rollplan.errors import SolverError

    class Failing:
        x0 = []

        def __call__(self, **args):
            self.x0.append(np.array(args["x0"]))
            return {"x": args["x0"] + 1.0, "f": 0.0}

        def stats(self):
            return {"return_status": status, "iter_count": 3, "success": False}

    planner = RestToRestPlanner(8, 3, cost="path_energy").twin()
    planner.solver = Failing()
    problem = Problem((0.5, 0.7, 0.8), k=K)
    start, final = planner.boundary(problem, 0)
    with pytest.raises(SolverError, match=", then ".join([status] * starts) + f" after {3 * starts} ") as err:
        planner.solve_nlp(problem, naive_guess(planner.transcription, start, final))
    assert err.value.status == status and len(planner.solver.x0) == starts
    if starts == 2:    # from the last iterate, not from the guess again
        assert np.array_equal(planner.solver.x0[1], planner.solver.x0[0] + 1.0)


def test_correction_jacobian_by_eighth_order_steps_gives_the_controls_of_cvodes_sensitivities(monkeypatch):
    """The Newton correction's Jacobian came from CVODES's forward sensitivities (about ten times a plain
    integration per interval); now from JACOBIAN_SUBSTEPS eighth-order steps per interval, CVODES integrating only
    the end error that decides the result. The corrected controls are those of the correction through CVODES's
    sensitivities (to 1e-10) and land on the goal at rest (DOP853 on the printed equations)."""
    from rollplan.planners.collocation import rest
    from rollplan.planners.collocation.transcription import CORRECTION_TOL, JACOBIAN_SUBSTEPS, gauss_newton
    from rollplan.studies.comparison import branch_guess

    problem = Problem((0.5, 0.3, 0.4), k=K)
    planner = RestToRestPlanner(16, 3)
    guess, m = branch_guess(problem, planner)
    nlp = planner.solve_nlp(problem, guess, 1.0, m)
    a0 = planner.transcription.unpack(nlp.x)[2]
    asked, used, real = [], [], rest._newton_step
    monkeypatch.setattr(rest, "_newton_step", lambda *a: asked.append(a) or recorded_fallback(real, a, used))
    controls, _ = correct(a0, nlp.start, nlp.final, nlp.par, planner.cost)
    # the CVODES sensitivities are only the fallback (gauss_newton's last argument), asked for but never called
    assert (planner.cost, True, JACOBIAN_SUBSTEPS) in asked and (planner.cost, True, None) in asked and not used
    reference, _, size, first = gauss_newton(real(planner.cost, True, None), a0, nlp.start, nlp.final, nlp.par,
                                             CORRECTION_TOL, 8, real(planner.cost, False, None))
    assert size <= CORRECTION_TOL < first
    assert np.abs(controls - reference).max() <= 1e-10 * np.abs(reference).max()
    y, rates = references.rest_path_final(controls, 1.0, K)
    assert np.abs(y - nlp.final[:3]).max() < TOLERANCE and np.abs(rates).max() < TOLERANCE


def test_decision_vectors_convert_both_ways():
    """``unpack`` (all intervals at once) gives each interval's closed forms (:meth:`stages`), ``pack`` inverts it,
    and the full transcription's layout (``full``, ``reduced``) round-trips exactly."""
    rt = RestTranscription(Transcription(5, 3, nx=7, nu=2))
    v = np.random.default_rng(0).normal(size=7 + 5 * rt.block)
    states, colloc, controls = rt.unpack(v, horizon=2.0)
    for i in range(5):
        uv, rates, _, a = rt.stages(states[i], states[i + 1][5:7], 2.0 / 5)
        np.testing.assert_allclose(colloc[i][:, 3:], np.hstack([uv, rates]), rtol=1e-14)
        np.testing.assert_allclose(controls[i], a, rtol=1e-14)
    np.testing.assert_array_equal(rt.pack(Guess(states, colloc, controls, "v")), v)
    np.testing.assert_array_equal(rt.reduced(rt.full(v)), v)
    assert rt.full(v).size == 7 + 5 * (7 * 3 + 2 + 7)


def _test_ode():
    """x1' = w - x2, x2' = x1^2 + x1 x2 (nonlinear: a single step of the eighth-order formula over an interval of
    1/2 misses the end by far more than 1e-10), the quadrature x1^2."""
    x, w, par = ca.SX.sym("x", 2), ca.SX.sym("w", 1), ca.SX.sym("par", 1)
    return x, w, par, ca.vertcat(w - x[1], x[0] ** 2 + x[0] * x[1]), x[0] ** 2


def _scipy_end(controls, x0):
    """End state and quadrature of :func:`_test_ode` by DOP853 (rtol 1e-13), interval by interval on [0, 1]."""
    def rhs(t, z, wi):
        return [wi - z[1], z[0] ** 2 + z[0] * z[1], z[0] ** 2]

    z, n = np.r_[x0, 0.0], len(controls)
    for j, wi in enumerate(np.ravel(controls)):
        z = solve_ivp(rhs, (j / n, (j + 1) / n), z, method="DOP853", rtol=1e-13, atol=1e-14, args=(wi,)).y[:, -1]
    return z[:2], z[2]


def test_fixed_step_integrates_like_dop853_and_differentiates_its_own_end():
    """``fixed_step`` has the inputs and outputs of ``sensitivity_step``: its end and quadrature converge to DOP853's
    (order 8: 16 steps per interval to 1e-12), its Jacobians are those of its end (central differences)."""
    from rollplan.planners.collocation.transcription import fixed_step

    x, w, par, xdot, quad = _test_ode()
    x0, wi, h = np.array([0.3, -0.2]), 0.7, 0.5
    xe, qe = _scipy_end([wi], x0)
    fine, coarse = fixed_step("t", x, w, par, xdot, quad, 16), fixed_step("t", x, w, par, xdot, quad, 1, False)
    p = np.array([wi, 0.0, 1.0])
    out = fine(x0=x0, p=p)
    assert np.abs(np.array(out["xf"]).ravel() - xe).max() <= 1e-12 and abs(float(out["qf"]) - qe) <= 1e-12
    assert set(coarse.name_out()) == {"xf", "qf"}
    assert np.abs(np.array(coarse(x0=x0, p=p)["xf"]).ravel() - xe).max() > 1e-10
    plain = fixed_step("t", x, w, par, xdot, quad, 16, False)
    p = np.array([wi, 0.0, h])
    jx, jp = np.array(out["jac_xf_x0"]), np.array(fine(x0=x0, p=p)["jac_xf_p"])
    eps = 1e-6
    for i in range(2):
        d = np.eye(2)[i] * eps
        fd = (np.array(plain(x0=x0 + d, p=np.array([wi, 0.0, 1.0]))["xf"]) -
              np.array(plain(x0=x0 - d, p=np.array([wi, 0.0, 1.0]))["xf"])).ravel() / (2 * eps)
        np.testing.assert_allclose(jx[:, i], fd, atol=1e-8)
    fd = (np.array(plain(x0=x0, p=p + [eps, 0, 0])["xf"]) - np.array(plain(x0=x0, p=p - [eps, 0, 0])["xf"])).ravel()
    np.testing.assert_allclose(jp[:, 0], fd / (2 * eps), atol=1e-8)


def test_gauss_newton_meets_the_goal_of_its_plain_integration_with_a_coarser_jacobian():
    """With ``plain`` a finer integration than ``step`` (here CVODES, and one step of the eighth-order formula per
    interval for the sensitivities), the end error and the quadrature are the plain integration's: the corrected
    controls reach the goal by DOP853, though the coarse integration of those controls misses it."""
    from rollplan.planners.collocation.transcription import fixed_step, gauss_newton, sensitivity_step

    x, w, par, xdot, quad = _test_ode()
    coarse = fixed_step("gn", x, w, par, xdot, quad, 1)
    plain = sensitivity_step("gn", x, w, par, xdot, quad, False)
    N, x0, final = 2, np.array([0.3, -0.2]), np.array([0.9, 0.4])
    a, q, size, first = gauss_newton(coarse, np.zeros((N, 1)), x0, final, np.zeros(1), 1e-12, 8, plain)
    end, quadrature = _scipy_end(a, x0)
    assert first > 0.1 and size <= 1e-12
    assert np.abs(end - final).max() <= 1e-10 and abs(q - quadrature) <= 1e-10
    y = x0
    for ai in a:
        y = np.array(coarse(x0=y, p=np.array([ai[0], 0.0, 1.0 / N]))["xf"]).ravel()
    assert np.abs(y - final).max() > 1e-9
