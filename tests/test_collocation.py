"""Direct collocation: realizability, target reached, order of convergence, errors.

Independent references used here:

* scipy's DOP853 on ``model.contact_rhs`` (the model, not the transcription);
* Montana's (6), (7), (10) as printed in the paper, inverted by hand for omega,
  and the realizability condition (13) from ``model.realizability_residual``;
* Gauss-Legendre quadrature nodes from numpy (not casadi) for the collocation
  polynomial's derivative;
* the known orders of the collocation methods: with the control constant on
  each interval, collocation at the d Gauss-Legendre points is the d-stage
  Gauss method (order 2d), at the d Radau IIA points the Radau IIA method
  (order 2d - 1) (Hairer, Norsett, Wanner I, Thm. II.7.9 and Hairer-Wanner II,
  Sec. IV.5): the end-of-interval error after N intervals is O(N^-p);
* the Cauchy-Schwarz identity ``L^2 <= T int |v|^2 dt`` with equality only at
  constant speed, and the mirror symmetry y -> -y of the model.
"""

from __future__ import annotations

import math

import casadi as ca
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from rollplan import InputError, Robot, SolverError, model, plan
from rollplan.collocation import COSTS, CollocationPlanner, collocate, collocation_coefficients

K = 2.5
TARGET = (0.5, 0.3, 0.4)

_x = ca.SX.sym("x", 5)
_w = ca.SX.sym("w", 2)
_k = ca.SX.sym("k")
RHS = ca.Function("rhs", [_x, _w, _k], [model.contact_rhs(_x, _w, _k)])
_om = ca.SX.sym("om", 3)
REAL = ca.Function("real", [_om, _x, _k], [model.realizability_residual(_om, _x[2], _x[3], _x[4], _k)])


def scipy_final(controls, k, horizon=1.0):
    """End state from rest with piecewise-constant rates, by DOP853 interval by interval."""
    controls = np.asarray(controls, float)
    h = horizon / controls.shape[0]
    x = np.zeros(5)
    for w in controls:
        s = solve_ivp(lambda t, y: np.array(RHS(y, w, k)).ravel(), (0.0, h), x, method="DOP853",
                      rtol=1e-13, atol=1e-14)
        x = s.y[:, -1]
    return x


@pytest.fixture(scope="module")
def planner40():
    return CollocationPlanner(40, 3, "legendre", "path_length")


@pytest.fixture(scope="module")
def warm40(planner40):
    return planner40.solve(TARGET, k=K, guess="warm")


# ----------------------------------------------------------------------------- target reached


def test_target_reached_by_scipy_integration(warm40):
    r = warm40
    assert r.stats.success and r.guess == "warm"
    xf = scipy_final(r.controls, K, r.horizon)
    # scipy reaches the target (u_a, v_a, u_o, v_o, psi)
    want = np.array([TARGET[0], TARGET[1], 0.0, 0.0, TARGET[2] + 2 * math.pi * r.turns])
    assert np.linalg.norm(xf - want) < 1e-7
    # ... and agrees with the CVODES verification the result reports
    assert np.allclose(r.final, [xf[0], xf[1], xf[4], xf[2], xf[3]], atol=1e-9)
    assert r.residual < 1e-7 and r.max_defect < 1e-9
    assert r.trajectory.t.size >= 1000


def test_verification_catches_wrong_controls(planner40, warm40):
    """The residual is not vacuous: perturbed controls miss the target."""
    bad = warm40.controls * 1.01
    v = planner40.verify(bad, K)
    assert np.linalg.norm(v["xf"] - warm40.states[-1]) > 1e-3
    assert np.linalg.norm(scipy_final(bad, K) - v["xf"]) < 1e-9


# ----------------------------------------------------------------------------- realizability (13)


def _poly_derivatives(r):
    """d/dt of the Legendre collocation polynomial at the collocation points (numpy nodes)."""
    d = r.degree
    nodes = np.append(0.0, (np.polynomial.legendre.leggauss(d)[0] + 1) / 2)
    assert np.allclose(nodes[1:], np.sort(r.t_colloc[:d]) / (r.horizon / r.intervals))
    V = np.vander(nodes, increasing=True)
    dV = np.array([[j * t ** (j - 1) if j else 0.0 for j in range(d + 1)] for t in nodes])
    Dm = dV @ np.linalg.inv(V)  # values at nodes -> derivative at nodes, on [0, 1]
    h = r.horizon / r.intervals
    out = []
    for i in range(r.intervals):
        X = np.vstack([r.states[i], r.states_colloc[i * d:(i + 1) * d]])
        out.append((Dm @ X)[1:] / h)
    return np.vstack(out)


def _omega_from_montana(x, xdot):
    """Invert (6), (7), (10) for omega: wy = u_a', wx = -v_a', wz = -psi' - roll tan(v_o) (R = 1)."""
    wy, wx = xdot[:, 0], -xdot[:, 1]
    psi, v_o = x[:, 4], x[:, 3]
    roll = wx * np.sin(psi) + wy * np.cos(psi)
    return np.column_stack([wx, wy, -xdot[:, 4] - roll * np.tan(v_o)])


def test_realizability_holds_along_collocation_solution(warm40):
    r = warm40
    X = r.states_colloc
    om = _omega_from_montana(X, _poly_derivatives(r))
    res = np.array([float(REAL(om[j], X[j], K)) for j in range(X.shape[0])])
    assert np.abs(res).max() < 1e-8 * max(1.0, np.abs(om).max())
    # not vacuous: the same motion violates (13) for another inertia ratio
    other = np.array([float(REAL(om[j], X[j], K + 1.0)) for j in range(X.shape[0])])
    assert np.abs(other).max() > 1e-2
    # (8)-(9): the polynomial's contact rates are the optimized controls
    rates = _poly_derivatives(r)[:, 2:4].reshape(r.intervals, r.degree, 2)
    assert np.allclose(rates, r.controls[:, None, :], atol=1e-8)


def test_realizability_along_verified_trajectory(warm40):
    """(13) on the CVODES samples, omega from Montana (6), (7), (10) with finite differences."""
    tr = warm40.trajectory
    x = np.column_stack([tr.u_a, tr.v_a, tr.u_o, tr.v_o, tr.psi])
    t = tr.t
    # central differences inside each interval (the controls jump at interval ends)
    per = (t.size - 1) // warm40.intervals
    idx = np.array([i for i in range(1, t.size - 1) if i % per])
    xdot = (x[idx + 1] - x[idx - 1]) / (t[idx + 1] - t[idx - 1])[:, None]
    om = _omega_from_montana(x[idx], xdot)
    res = np.array([float(REAL(om[j], x[i], K)) for j, i in enumerate(idx)])
    assert np.abs(res).max() < 1e-3 * np.abs(om).max()  # O(dt^2) differences
    assert np.allclose(om, tr.omega[idx], atol=1e-3 * np.abs(om).max())


# ----------------------------------------------------------------------------- order of convergence

_STEPS = np.array([[1.0, 0.5], [-0.8, 1.2], [0.3, -1.0], [-0.6, -0.4]])  # rad/s on four quarters of [0, 1]


@pytest.fixture(scope="module")
def fixed_control_reference():
    return scipy_final(_STEPS, K)


@pytest.mark.parametrize("scheme, degree, order", [("legendre", 1, 2), ("legendre", 2, 4), ("legendre", 3, 6),
                                                   ("radau", 1, 1), ("radau", 2, 3), ("radau", 3, 5)])
def test_collocation_order_with_fixed_controls(scheme, degree, order, fixed_control_reference):
    """The transcription's collocation equations converge at order 2d (Legendre) / 2d - 1 (Radau)."""
    P = CollocationPlanner(1, degree, scheme, "angular_velocity")
    Ns = [4, 8, 16, 32] if order >= 5 else [8, 16, 32, 64]
    err = np.array([np.linalg.norm(P.simulate(np.repeat(_STEPS, N // 4, axis=0), K)[-1] - fixed_control_reference)
                    for N in Ns])
    slope = -np.polyfit(np.log(Ns), np.log(err), 1)[0]
    assert abs(slope - order) < 0.3, (err, slope)


@pytest.mark.slow
@pytest.mark.parametrize("scheme, degree, order", [("legendre", 1, 2), ("radau", 2, 3)])
def test_verified_residual_of_optimal_solutions_shrinks_at_order(scheme, degree, order):
    """The verified residual of optimal solutions (controls re-optimized at each N) follows the same order."""
    Ns = [20, 40, 80]
    res = np.array([CollocationPlanner(N, degree, scheme, "path_length", verify_tol=None).solve(TARGET, k=K).residual for N in Ns])
    slope = -np.polyfit(np.log(Ns), np.log(res), 1)[0]
    assert abs(slope - order) < 0.4, (res, slope)


def test_coefficients_integrate_and_differentiate_polynomials():
    for scheme in ("legendre", "radau"):
        tau, C, D, B = collocation_coefficients(3, scheme)
        for p in range(4):  # exact for degree <= 3 on 4 nodes
            vals = tau ** p
            assert np.isclose(vals @ D, 1.0)
            assert np.isclose(vals @ B, 1.0 / (p + 1))
            assert np.allclose(vals @ C, p * tau ** (p - 1) if p else 0.0)


# ----------------------------------------------------------------------------- costs


def test_path_length_cost_gives_constant_speed_shortest_path(warm40):
    """Energy form: L^2 <= T int |v|^2, equality only at constant speed; shorter than the figure eight."""
    r = warm40
    assert r.path_length == pytest.approx(math.sqrt(r.horizon * r.objective), rel=1e-3)
    p = plan(TARGET, 1, k=K)
    assert r.path_length < p.path_length


def test_mirror_symmetry_of_optimal_cost(planner40, warm40):
    """y -> -y maps the model onto itself with psi -> -psi: the optimum of the mirrored target is equal."""
    m = planner40.solve((TARGET[0], -TARGET[1], -TARGET[2]), k=K, guess="warm")
    assert m.objective == pytest.approx(warm40.objective, rel=1e-6)
    mirror = np.array([1.0, -1.0, 1.0, -1.0, -1.0])
    assert np.allclose(m.states * mirror, warm40.states, atol=1e-5)


def test_rotor_effort_equals_quadrature_of_rotor_rates():
    robot = Robot()
    r = collocate((0.05, 0.03, 0.4), robot=robot, cost="rotor_effort", intervals=30)
    assert r.radius == robot.radius and r.residual < 1e-6
    # the verified rotor effort matches the transcription's objective (same functional, different quadrature)
    assert r.rotor_effort == pytest.approx(r.objective, rel=1e-4)
    # rotor rates from (11) along the verified motion: |phi_dot| >= Jxx |omega| / J_r * ... > 0
    assert r.rotor_effort > 0 and r.effort > 0


def test_costs_registry():
    assert {"path_length", "angular_velocity", "rotor_effort"} <= set(COSTS)
    assert COSTS["rotor_effort"].needs_robot


# ----------------------------------------------------------------------------- errors


def test_failed_solve_raises_solver_error_with_status():
    P = CollocationPlanner(20, 2, "legendre", "path_length", max_iter=2)
    with pytest.raises(SolverError) as exc:
        P.solve(TARGET, k=K, guess="naive")
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
        CollocationPlanner(4, 1, cost="rotor_effort").solve(TARGET, k=K)
    with pytest.raises(InputError, match="horizon"):
        planner40.solve(TARGET, k=K, horizon=0.0)
    with pytest.raises(InputError, match="guess"):
        planner40.solve(TARGET, k=K, guess="random")
    with pytest.raises(InputError, match="psi"):
        planner40.solve((0.1, 0.2, float("nan")), k=K)
    with pytest.raises(InputError, match="k"):
        planner40.solve(TARGET, k=-1.0)
    g = CollocationPlanner(10, 3).naive_guess(np.zeros(5))
    with pytest.raises(InputError, match="guess.states"):
        planner40.solve(TARGET, k=K, guess=g)


def test_explicit_guess_object_is_used(planner40, warm40):
    """A Guess built from a previous solution converges faster to the same optimum."""
    from rollplan.collocation import Guess

    r = warm40
    d = r.degree
    g = Guess(r.states, r.states_colloc.reshape(r.intervals, d, 5), r.controls, "previous")
    again = planner40.solve(TARGET, k=K, guess=g, turns=r.turns)
    assert again.guess == "previous" and again.stats.iterations < r.stats.iterations
    assert again.objective == pytest.approx(r.objective, rel=1e-9)


def test_naive_guess_is_a_singular_point_and_fails_with_a_hint():
    """At rest on the south pole the linearized kinematics are not controllable: the equality
    Jacobian loses rank, and IPOPT fails from the naive guess for a psi = 0 target (see comparison.md)."""
    P = CollocationPlanner(10, 3, "legendre", "path_length")
    final = np.array([0.3, 0.0, 0.0, 0.0, 0.0])
    x0 = P._pack(P.naive_guess(final))
    lbx, ubx = P._bounds(final)
    J = np.array(P.solver.get_function("nlp_jac_g")(x0, P._par(K, 1.0, 0.0, None))[1])
    Je = J[~P._path_rows][:, lbx != ubx]
    assert np.linalg.matrix_rank(Je) < Je.shape[0]
    # the warm start is not singular
    xw = P._pack(P.warm_guess(plan((0.3, 0.0, 0.0), 1, k=K), 1.0))
    Jw = np.array(P.solver.get_function("nlp_jac_g")(np.clip(xw, lbx, ubx), P._par(K, 1.0, 0.0, None))[1])
    assert np.linalg.matrix_rank(Jw[~P._path_rows][:, lbx != ubx]) == Je.shape[0]
    with pytest.raises(SolverError) as exc:
        P.solve((0.3, 0.0, 0.0), k=K, guess="naive")
    assert exc.value.status in ("Infeasible_Problem_Detected", "Restoration_Failed")
    assert "controllable" in str(exc.value)
