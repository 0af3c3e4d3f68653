"""Time-optimal profiles (rollplan.execution.topp, .limits): closed forms, a brute-force LP, the three
solvers of the discrete problem, and the independent phase-plane integration (references.phase_plane_topp:
a different algorithm and discretisation), with and without corners."""

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import brentq, linprog

import rollplan
from rollplan import InputError
from rollplan.execution.limits import Limits, torque_bound
from rollplan.execution.path import ContactPath, PathGrid
from rollplan.execution.topp import grid_violation, solve_topp, toppra_available

import references

LIMITS = Limits(max_rotor_rate=300.0, max_rotor_torque=0.05)
#: The grid solvers, the reference, and the TOPP-RA library (IPOPT takes seconds on these grids and the
#: toppra import takes seconds: slow; toppra is skipped where it is not installed).
SOLVERS = ["numpy", "phase-plane", pytest.param("casadi", marks=pytest.mark.slow),
           pytest.param("toppra", marks=pytest.mark.slow)]


def constant_grid(lengths, n, A, B, G, corners=()):
    """A grid of pieces with constant coefficients A, B, G (each (2,), one per rotor); ``corners``: joint
    numbers (1 = between the first two pieces) where the motion must rest."""
    starts = np.concatenate([[0.0], np.cumsum(lengths)])
    counts = [max(4, round(n * ell / starts[-1])) for ell in lengths]
    s = np.concatenate([*(np.linspace(starts[j], starts[j + 1], c + 1)[:-1] for j, c in enumerate(counts)),
                        [starts[-1]]])
    joints = np.cumsum(counts)[:-1]
    rep = lambda v: np.tile(np.asarray(v, float), (s.size, 1))
    return PathGrid(s, rep(G), rep(G), rep(A), rep(A), rep(B), rep(B), joints, joints[[c - 1 for c in corners]])


def exact_size(solver):
    """Grid intervals for the closed forms that every grid meets exactly (piecewise-constant s'' with the
    switches at nodes): IPOPT's cost grows faster than the grid, and 1000 intervals test the same rows."""
    return 1000 if solver == "casadi" else 4000


def duration(grid, limits, solver):
    if solver == "phase-plane":
        return references.phase_plane_topp(grid, limits.max_rotor_rate, limits.max_rotor_torque)["duration"]
    if solver == "toppra" and not toppra_available():
        pytest.skip("toppra is not installed (pip install 'rollplan[toppra]')")
    return solve_topp(grid, limits, backend=solver).duration


@pytest.mark.parametrize("L", [0.5, 5.0])
@pytest.mark.parametrize("solver", SOLVERS)
def test_double_integrator_closed_form(L, solver):
    """B = 0, constant A and G: |s''| <= acc, s' <= v; bang-bang (short path) or bang-cruise-bang."""
    a, tau, g, rate = 0.02, 0.05, 40.0, 80.0
    acc, v = tau / a, rate / g
    expect = L / v + v / acc if v * v / acc <= L else 2 * math.sqrt(L / acc)  # with or without a cruise
    grid = constant_grid([L], exact_size(solver), [a, 0.5 * a], [0.0, 0.0], [g, 0.3 * g])
    assert duration(grid, Limits(rate, tau), solver) == pytest.approx(expect, rel=2e-4)


@pytest.mark.parametrize("solver", SOLVERS)
def test_velocity_term_closed_form(solver):
    """One row |a u + b x| <= tau (b > 0): the extremals are x = (tau/b)(1 - exp(-2bs/a)) forward and
    (tau/b)(exp(2b(L-s)/a) - 1) backward; T = int ds / sqrt(min of the two) by quad."""
    a, b, tau, L = 0.02, 0.05, 0.05, 2.0
    fwd = lambda s: tau / b * (1 - math.exp(-2 * b * s / a))
    bwd = lambda s: tau / b * (math.exp(2 * b * (L - s) / a) - 1)
    sw = brentq(lambda s: fwd(s) - bwd(s), 1e-9, L - 1e-9)
    expect = quad(lambda s: 1 / math.sqrt(fwd(s)), 0, sw, limit=200)[0] + \
        quad(lambda s: 1 / math.sqrt(bwd(s)), sw, L, limit=200)[0]
    grid = constant_grid([L], 4000, [a, 0.0], [b, 0.0], [0.0, 0.0])  # the second row is void (a = b = 0)
    assert duration(grid, Limits(None, tau), solver) == pytest.approx(expect, rel=5e-4)


@pytest.mark.parametrize("solver", SOLVERS)
def test_corners_bring_the_motion_to_rest(solver):
    """Double integrator on two pieces: through a smooth joint one bang-bang, 2 sqrt(L/acc); with a corner
    between them, a bang-bang on each piece, 2 sqrt(L1/acc) + 2 sqrt(L2/acc)."""
    a, tau = 0.02, 0.05
    acc = tau / a
    lengths = [0.7, 1.8]
    smooth = constant_grid(lengths, exact_size(solver), [a, a], [0.0, 0.0], [0.0, 0.0])
    corner = constant_grid(lengths, exact_size(solver), [a, a], [0.0, 0.0], [0.0, 0.0], corners=[1])
    lim = Limits(None, tau)
    assert duration(smooth, lim, solver) == pytest.approx(2 * math.sqrt(sum(lengths) / acc), rel=2e-4)
    expect = sum(2 * math.sqrt(ell / acc) for ell in lengths)
    if solver in ("numpy", "casadi"):   # one solve gives the duration and the profile
        prof = solve_topp(corner, lim, backend=solver)
        assert prof.duration == pytest.approx(expect, rel=2e-4)
        assert prof.x[corner.corners[0]] == 0.0 and prof.x[0] == prof.x[-1] == 0.0
    else:
        assert duration(corner, lim, solver) == pytest.approx(expect, rel=2e-4)


def test_torque_bound_against_lp():
    """The torque part of the MVC (pairwise closed form) against HiGHS: max x s.t. |A u + B x| <= tau,
    and against the bisection of the reference."""
    rng = np.random.default_rng(7)
    tau = 0.05
    for trial in range(60):
        m = 2 if trial < 40 else 4
        A = rng.normal(size=(1, m)) * 0.02
        B = rng.normal(size=(1, m)) * 0.05
        if trial % 10 == 0:
            A[0, 0] = 0.0  # a zero-inertia row
        xb = torque_bound(A, B, Limits(None, tau))[0]
        M = np.column_stack([A[0], B[0]])
        res = linprog([0.0, -1.0], A_ub=np.vstack([M, -M]), b_ub=np.full(2 * m, tau),
                      bounds=[(None, None), (0.0, 1e9)], method="highs")
        assert res.status == 0
        if np.isfinite(xb):
            assert xb == pytest.approx(res.x[1], rel=1e-9)
            assert xb == pytest.approx(references.torque_mvc(A, B, tau)[0], rel=1e-12)
        else:
            assert res.x[1] == pytest.approx(1e9)


class _Grids(dict):
    """The grids of a path by their number of intervals, each made once."""

    def __init__(self, path):
        super().__init__()
        self.path = path

    def __missing__(self, n):
        self[n] = self.path.grid(n)
        return self[n]


@pytest.fixture(scope="module")
def plan_path():
    robot = rollplan.Robot()
    return ContactPath.of_plan(rollplan.plan((0.05, 0.08, 0.5), 2, robot=robot), robot)


@pytest.fixture(scope="module")
def grids(plan_path):
    return _Grids(plan_path)


def test_grid_solvers_agree_on_a_plan(grids):
    """numpy (TOPP-RA's passes) and casadi (IPOPT: the optimum of the convex discrete problem) on one grid;
    both meet the rows of the discrete problem."""
    grid = grids[1000]
    numpy_, casadi_ = (solve_topp(grid, LIMITS, backend=b) for b in ("numpy", "casadi"))
    assert casadi_.duration == pytest.approx(numpy_.duration, rel=1e-5)
    assert casadi_.duration <= numpy_.duration * (1 + 1e-9)  # the greedy pass is not shorter than the optimum
    for prof in (numpy_, casadi_):
        viol = grid_violation(grid, prof, LIMITS)
        assert viol["torque"] < 1e-8 and viol["rate"] < 1e-8


@pytest.mark.slow
def test_toppra_agrees_on_a_plan(grids):
    """The TOPP-RA library on the same rows as the numpy passes (where toppra is installed)."""
    if not toppra_available():
        pytest.skip("toppra is not installed (pip install 'rollplan[toppra]')")
    grid = grids[2000]
    ours, lib = solve_topp(grid, LIMITS), solve_topp(grid, LIMITS, backend="toppra")
    assert lib.duration == pytest.approx(ours.duration, rel=1e-6)
    assert grid_violation(grid, lib, LIMITS)["torque"] < 1e-6


@pytest.mark.slow
def test_phase_plane_agrees_and_converges(grids):
    """The relative difference of the grid solution and the phase-plane integration falls with the grid size;
    the grid solution (feasible at its nodes) is the longer."""
    diffs = []
    for n in (1000, 3000, 9000):
        grid = grids[n]
        t_grid = solve_topp(grid, LIMITS).duration
        t_pp = references.phase_plane_topp(grid, LIMITS.max_rotor_rate, LIMITS.max_rotor_torque)["duration"]
        diffs.append((t_grid - t_pp) / t_pp)
    assert diffs[0] > diffs[1] > diffs[2] > 0
    assert diffs[2] < 3e-4


def test_bang_bang(grids):
    """On almost all of the time a torque row or the rate bound is active (to 1e-3)."""
    grid = grids[2000]
    prof = solve_topp(grid, LIMITS)
    u = prof.u[:, None]
    tq = np.maximum(np.abs(grid.A_right[:-1] * u + grid.B_right[:-1] * prof.x[:-1, None]).max(axis=1),
                    np.abs(grid.A_left[1:] * u + grid.B_left[1:] * prof.x[1:, None]).max(axis=1))
    rate = np.abs(grid.G_left[:-1]).max(axis=1) * np.sqrt(prof.x[:-1])
    util = np.maximum(tq / LIMITS.max_rotor_torque, rate / LIMITS.max_rotor_rate)
    assert np.sum(np.diff(prof.t)[util > 0.999]) / prof.duration > 0.95


def test_bad_input(plan_path):
    grid = plan_path.grid(100)
    with pytest.raises(InputError, match="max_rotor_torque"):
        solve_topp(grid, Limits(300.0, None))
    with pytest.raises(InputError, match="backend"):
        solve_topp(grid, LIMITS, backend="nope")
    with pytest.raises(InputError, match="max_rotor_rate"):
        Limits(max_rotor_rate=0.0)
    with pytest.raises(InputError, match="max_rotor_torque"):
        Limits(max_rotor_torque=float("nan"))
