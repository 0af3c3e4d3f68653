"""Geometric-phase planner: exact, dynamically realizable plans by figure eights.

Problem (Section III.B of the paper). Trace the spherical figure eight
``c(theta) = Rz(gamma) c_bar(a, b, theta)`` (31) ``n`` times so that the
contact coordinates go from zero to ``(u_a, v_a, psi) = target``, with
``u_o = v_o = 0`` at the end.

Geometry, derived from (28)-(30) (and checked in ``tests/test_geometric.py``):

* (28)-(29) are ``[u_a', v_a'] = Rot(-psi) M0 [p, q]`` and psi' does not
  depend on the state, so a step that starts at heading ``psi0`` produces the
  shift of a step from zero, ``D_bar(a, b)``, turned by ``-psi0``; it turns psi
  by ``eta(a, b)``.
* Rotating the curve by gamma about OZ conjugates the whole motion by that
  rotation: the displacement turns by ``+gamma``, psi is unchanged.
* Hence after ``n`` steps ``psi = n eta`` and the displacement is
  ``Rot(gamma) sum_{j<n} Rot(-j eta) D_bar``, of length
  ``h |sin(n eta / 2) / sin(eta / 2)|``.

So, for a branch ``m`` (psi is an angle: ``n eta = psi + 2 pi m``), solve

    eta(a, b) = (psi_des + 2 pi m) / n                                  (32)
    h(a, b)   = h_des |sin(eta / 2) / sin(n eta / 2)|                   (33)

(the paper's (33) has the fraction upside down in its first form; with
``sin(n eta/2) = 0`` and ``eta = 0 mod 2 pi`` the limit is ``h_des / n``, (34)),
then ``gamma = arg(target) - arg(sum_j Rot(-j eta) D_bar)``.

Solution branches are bracketed on a tabulated grid of the two leaves (each
leaf depends on one radius only) and refined by IPOPT on the spectral step
map (or by CasADi's Newton rootfinder). Every plan is verified by an
independent CVODES integration of all ``n`` steps; a plan whose residual
exceeds the tolerance is never returned.
"""

from __future__ import annotations

import logging
import math
import time
from collections import Counter
from dataclasses import dataclass, field, replace
from functools import lru_cache

import casadi as ca
import numpy as np

from .curves import A_MAX, figure_eight, rotated_point
from .errors import InputError, NoPlanError, SolverError, check_finite, check_range, check_whole
from .integrate import DEFAULT_NODES, CvodesIntegrator, spectral_step
from .robot import Robot
from . import model

__all__ = ["SOLVERS", "StepResult", "SolverStats", "Trajectory", "Plan", "GeometricPhasePlanner", "plan", "step"]

log = logging.getLogger(__name__)

#: Default tolerance of the verified residual (units of R and rad).
TOLERANCE = 1e-9
#: Largest number of steps a plan may have.
MAX_STEPS = 1000
#: Largest inertia ratio the planner accepts (physical robots have 1 < k < ~20).
K_MAX = 100.0
#: Solver statuses that mean the solver itself broke (not that a bracket held no root).
#: A bracket may be false (zero curves of (32) and (33) nearly touching), and a solve that
#: stops there, infeasible or out of iterations, only says that the bracket holds no root.
_SOLVER_ERROR_STATUSES = frozenset({"Invalid_Number_Detected", "Error_In_Step_Computation", "Internal_Error",
                                    "Insufficient_Memory", "Not_Enough_Memory", "Unrecoverable_Exception",
                                    "NonIpopt_Exception_Thrown", "Invalid_Problem_Definition", "Invalid_Option"})
_NEWTON_NO_ROOT = "no_root_in_bracket"
#: Largest |residual of (32)-(33)| of a solver's end point that is still a candidate root.
_ROOT_TOL = 1e-10
#: Brackets whose tables' model root lies within this many cell widths of the cell centre are
#: solved first (see :func:`_cell_start`).
_PLAUSIBLE_OFFSET = 1.5
#: Leaf tables kept per planner (one per k value).
_TABLE_CACHE = 8
#: Coarse Chebyshev degree for tabulating the leaves when bracketing branches.
_TABLE_NODES = 12


def wrap(angle):
    """Angle wrapped to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(angle, float), 2.0 * np.pi)


def _rot(angle, vec):
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vec[0] - s * vec[1], s * vec[0] + c * vec[1]])


def n_step_sum(eta: float, steps: int) -> complex:
    """``sum_{j<n} exp(-i j eta)``: how the n shifts of a plan add up (see module doc)."""
    return complex(np.exp(-1j * eta * np.arange(steps)).sum())


@dataclass(frozen=True)
class StepResult:
    """What one trace of the figure eight does, from zero initial conditions.

    Attributes
    ----------
    a, b : float
        Leaf radii [units of R].
    k : float
        Inertia ratio.
    gamma : float
        Rotation of the figure eight about OZ [rad].
    shift : ndarray, shape (2,)
        Displacement (u_a, v_a) of the contact point [units of R].
    h : float
        Non-holonomic shift ``|shift|`` [units of R].
    eta : float
        Holonomy angle, the change of psi [rad].
    direction : float
        Direction of the shift, ``atan2(v_a, u_a)`` [rad].
    """

    a: float
    b: float
    k: float
    gamma: float
    shift: np.ndarray
    h: float
    eta: float
    direction: float


@dataclass(frozen=True)
class SolverStats:
    """Statistics of the solves behind a plan.

    Attributes
    ----------
    method : str
        Name of the root solver (``"ipopt"`` or ``"newton"``).
    status : str
        Solver return status of the chosen plan's solve.
    iterations : int
        Iterations of that solve.
    candidates : int
        Brackets found on the grid.
    solves : int
        Solves run (one per bracket refined).
    time_s : float
        Wall time of the whole plan, including verification [s].
    """

    method: str
    status: str
    iterations: int
    candidates: int
    solves: int
    time_s: float


@dataclass(frozen=True)
class Trajectory:
    """A plan sampled along the curve parameter (one step is theta in [0, 2 pi]).

    All arrays have shape (N,), ``contact`` has shape (N, 3); lengths in the
    plan's length unit, angles in rad. ``leaf`` is 0 for first half-steps and
    1 for second half-steps; ``step`` counts steps from 0.
    """

    theta: np.ndarray
    u_o: np.ndarray
    v_o: np.ndarray
    u_a: np.ndarray
    v_a: np.ndarray
    psi: np.ndarray
    contact: np.ndarray
    leaf: np.ndarray
    step: np.ndarray

    def path_length(self) -> float:
        """Length of the sampled contact path on the plane (polygonal)."""
        return float(np.hypot(np.diff(self.u_a), np.diff(self.v_a)).sum())


@dataclass(frozen=True)
class Plan:
    """A verified geometric-phase plan.

    Attributes
    ----------
    a, b : float
        Leaf radii of the figure eight [length unit of ``radius``].
    gamma : float
        Rotation of the figure eight about OZ, eq. (31) [rad].
    steps : int
        Number of traces n.
    k : float
        Inertia ratio.
    radius : float
        Sphere radius R [length unit].
    target : tuple of 3 float
        (u_a, v_a) [length unit] and psi [rad].
    branch : int
        m in ``n eta = psi + 2 pi m``.
    h : float
        Shift of one step [length unit].
    eta : float
        Holonomy angle of one step [rad].
    path_length : float
        Contact path length ``2 pi n (a + b)`` [length unit] (equal on the
        sphere and on the plane).
    final : ndarray, shape (5,)
        (u_a, v_a, psi, u_o, v_o) after n steps from an independent CVODES
        integration [length unit, rad].
    residual : float
        Euclidean norm of ``final`` minus the target (lengths divided by R,
        psi wrapped to (-pi, pi]). The (u_o, v_o) entries are those of the
        curve's end point, zero by construction of a closed curve.
    stats : SolverStats
    alternatives : tuple of Plan
        The other verified solution branches, shortest first (``all`` only).
    """

    a: float
    b: float
    gamma: float
    steps: int
    k: float
    radius: float
    target: tuple
    branch: int
    h: float
    eta: float
    path_length: float
    final: np.ndarray
    residual: float
    stats: SolverStats
    alternatives: tuple = ()
    _planner: "GeometricPhasePlanner" = field(default=None, repr=False, compare=False)

    def trajectory(self, samples_per_leaf: int = 200) -> Trajectory:
        """Sample the plan by CVODES integration (``samples_per_leaf`` points per half-step)."""
        return self._planner.trajectory(self, samples_per_leaf)


# ----------------------------------------------------------------------------- solvers


def _ipopt_solver(residual: ca.Function):
    ab = ca.SX.sym("ab", 2)
    par = ca.SX.sym("par", 3)
    nlp = {"x": ab, "p": par, "f": 0, "g": residual(ab, par)}
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes",
            "ipopt.tol": 1e-13, "ipopt.constr_viol_tol": 1e-13, "ipopt.max_iter": 60,
            "ipopt.hessian_approximation": "limited-memory"}
    solver = ca.nlpsol("gp_ipopt", "ipopt", nlp, opts)

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        sol = solver(x0=x0, p=par_value, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
        st = solver.stats()
        # Where eta is steep (|d eta/da| ~ 1e4 near A_MAX) IPOPT may stop short of its 1e-13
        # tolerance at a point that solves (32)-(33) to rounding ("Search_Direction_Becomes_Too_Small");
        # such a point is a candidate too: the CVODES verification decides.
        ok = bool(st["success"]) or float(np.abs(np.array(sol["g"])).max()) < _ROOT_TOL
        return np.array(sol["x"]).ravel(), st["return_status"], int(st["iter_count"]), ok

    return solve


def _newton_solver(residual: ca.Function):
    rf = ca.rootfinder("gp_newton", "newton", residual,
                       {"abstol": 1e-14, "abstolStep": 1e-16, "max_iter": 40, "error_on_fail": False,
                        "show_eval_warnings": False})  # NaN outside the admissible range is a failed solve

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        x = np.array(rf(x0, par_value)).ravel()
        st = rf.stats()
        ok = bool(st["success"]) and bool(np.all((x >= lbx) & (x <= ubx)))
        # Newton cannot tell a bracket without a root from a failure: both are "no root" here.
        status = st["return_status"] if ok else _NEWTON_NO_ROOT
        return x, status, int(st.get("iter_count", -1)), ok

    return solve


#: Root solvers for (32)-(33), by name: ``make(residual)`` returns
#: ``solve(x0, par, lbx, ubx) -> (x, status, iterations, ok)``, the root kept in the box.
SOLVERS = {"ipopt": _ipopt_solver, "newton": _newton_solver}


# ----------------------------------------------------------------------------- planner


class GeometricPhasePlanner:
    """Geometric-phase planner for repeated solves (problem class).

    Builds the symbolic step map once; tables of the leaves are cached per k.

    Parameters
    ----------
    method : str
        Root solver from :data:`SOLVERS`.
    nodes : int
        Chebyshev degree per panel of the spectral step map.
    tol : float
        Largest verified residual a returned plan may have.
    """

    def __init__(self, method: str = "ipopt", nodes: int = DEFAULT_NODES, tol: float = TOLERANCE) -> None:
        if method not in SOLVERS:
            raise InputError(f"method = {method!r} is not allowed: choose one of {', '.join(SOLVERS)}")
        self.method = method
        self.tol = tol
        self.curve = figure_eight()
        self.step_map = spectral_step(self.curve, nodes)
        self._leaves = [spectral_step(self.curve, _TABLE_NODES, pieces=(i,)) for i in range(2)]
        ab = ca.SX.sym("ab", 2)
        par = ca.SX.sym("par", 3)  # k, eta target, h target
        xf = self.step_map(ca.DM.zeros(3), ab, par[0], 0)
        self.residual = ca.Function("residual", [ab, par], [ca.vertcat(xf[2] - par[1], ca.norm_2(xf[:2]) - par[2])])
        self._solve = SOLVERS[method](self.residual)
        # Adams at rtol 3e-15: ~2e-11 from DOP853 on the printed (28)-(30) over 10 steps of large
        # leaves (rtol 1e-13 left 5e-10 there, too close to the 1e-9 tolerance it certifies).
        self.verifier = CvodesIntegrator(self.curve, reltol=3e-15, abstol=1e-16)
        self._verify_ints = self.verifier.integrators(1)
        self._tables: dict = {}
        self._cell_index: dict = {}

    # -- step map ------------------------------------------------------------------
    def step(self, a: float, b: float | None = None, *, k: float, gamma: float = 0.0) -> StepResult:
        """One trace of the figure eight (a, b) rotated by gamma, from zero state."""
        b = a if b is None else b
        a, b, k, gamma = _check_leaf("a", a), _check_leaf("b", b), _check_k(k), check_finite("gamma", gamma)
        x = np.array(self.step_map(ca.DM.zeros(3), ca.vertcat(a, b), k, gamma)).ravel()
        return StepResult(a, b, k, gamma, x[:2].copy(), float(np.hypot(*x[:2])), float(x[2]),
                          float(np.arctan2(x[1], x[0])))

    # -- branch bracketing ---------------------------------------------------------
    def _leaf_tables(self, k: float, fine: bool = False):
        """Leaf maps on an adaptive grid of radii (coarse; only for bracketing).

        The grid is refined until psi turns by less than 0.5 rad (0.2 rad when
        ``fine``, for finding all branches) and the shift moves by less than
        0.1 R (0.04 R) between neighbouring radii.
        """
        key = (k, fine)
        if key in self._tables:
            return self._tables[key]
        turn, move, cap = (0.2, 0.04, 2500) if fine else (0.5, 0.1, 1500)
        grid = np.linspace(0.0, A_MAX, 129)
        vals = np.zeros((7, 0))
        while grid.size:
            p = np.vstack([grid, grid])
            res = [np.array(leaf.map(grid.size)(ca.DM.zeros(3), p, k, 0)) for leaf in self._leaves]
            vals = np.hstack([vals, np.vstack([grid, res[0], res[1]])])
            vals = vals[:, np.argsort(vals[0])]
            diff = np.abs(np.diff(vals[1:], axis=1))
            coarse = (diff[[2, 5]].max(axis=0) > turn) | (diff[[0, 1, 3, 4]].max(axis=0) > move)
            if vals.shape[1] > cap:
                break
            grid = 0.5 * (vals[0, :-1] + vals[0, 1:])[coarse]
        _remember(self._tables, key, vals)
        return vals

    def _cells(self, k: float, fine: bool = False) -> dict:
        """Per-k index of the grid cells of the leaf tables (cached with the tables).

        For every cell (i, j) of the (a, b) grid: the range of eta and of h
        over its four corners, and the lower bound ``r_i + r_j`` of a + b;
        cells are sorted by their smallest eta so that the cells whose eta
        range holds a given value are found by bisection.
        """
        key = (k, fine)
        if key in self._cell_index:
            return self._cell_index[key]
        t = self._leaf_tables(k, fine)
        r, d0, eta0, d1, eta1 = t[0], t[1:3], t[3], t[4:6], t[6]
        eta = eta0[:, None] + eta1[None, :]
        shift = _rot(eta0, d0)[:, :, None] + d1[:, None, :]   # Rot(eta0) D_bar, |.| = h
        h = np.hypot(shift[0], shift[1])

        def span(z):
            lo = np.minimum(np.minimum(z[:-1, :-1], z[1:, :-1]), np.minimum(z[:-1, 1:], z[1:, 1:]))
            hi = np.maximum(np.maximum(z[:-1, :-1], z[1:, :-1]), np.maximum(z[:-1, 1:], z[1:, 1:]))
            return lo.ravel(), hi.ravel()

        emin, emax = span(eta)
        hmin, hmax = span(h)
        order = np.argsort(emin, kind="stable")
        cells = {"r": r, "n": r.size - 1, "order": order, "emin_sorted": emin[order],
                 "emin": emin, "emax": emax, "hmin": hmin, "hmax": hmax, "eta": eta, "h": h,
                 "width": float((emax - emin).max()) if emin.size else 0.0,
                 "eta_lo": float(emin.min()), "eta_hi": float(emax.max())}
        _remember(self._cell_index, key, cells)
        return cells

    def _brackets(self, k: float, h_des: float, psi: float, steps: int, fine: bool = False) -> np.ndarray:
        """Grid cells that bracket a root of (32)-(33) on some branch m.

        Returns an array with one row per (cell, m): lower bound of a + b in the
        cell, a0, b0 (cell centre), cell half-widths da, db, m, eta_m, h_m, and
        the solver's start (a_s, b_s) in the cell (see :func:`_cell_start`);
        sorted by the lower bound.

        A cell brackets branch m when ``n eta = psi + 2 pi m`` for some eta
        between its corners' smallest and largest eta, and ``h_m`` of (33)
        lies between its corners' smallest and largest h. Only the cells
        whose smallest eta lies within one cell width below ``eta_m`` are
        tested (bisection in the per-k index of :meth:`_cells`).
        """
        c = self._cells(k, fine)
        two_pi = 2 * np.pi
        m_all = np.arange(math.ceil((steps * c["eta_lo"] - psi) / two_pi) - 1,
                          math.floor((steps * c["eta_hi"] - psi) / two_pi) + 2)
        eta_all = (psi + two_pi * m_all) / steps
        h_all = _target_shift(h_des, eta_all, steps)
        keep = np.isfinite(h_all)
        m_all, eta_all, h_all = m_all[keep], eta_all[keep], h_all[keep]
        pad = 1e-9 * (1.0 + abs(c["eta_lo"]) + abs(c["eta_hi"]))
        i0 = np.searchsorted(c["emin_sorted"], eta_all - c["width"] - pad)
        i1 = np.searchsorted(c["emin_sorted"], eta_all + pad)
        count = i1 - i0
        which = np.repeat(np.arange(m_all.size), count)      # which branch each tested cell is for
        pos = np.arange(which.size) - np.repeat(np.cumsum(count) - count, count) + np.repeat(i0, count)
        cell = c["order"][pos]
        m, h_m = m_all[which], h_all[which]
        # the same tests as for the whole grid: m within [ceil, floor] of the cell's branch range
        lo = np.ceil((steps * c["emin"][cell] - psi) / two_pi)
        hi = np.floor((steps * c["emax"][cell] - psi) / two_pi)
        ok = (lo <= m) & (m <= hi) & (c["hmin"][cell] <= h_m) & (h_m <= c["hmax"][cell])
        cell, m = cell[ok], m[ok]
        r, n = c["r"], c["n"]
        ii, jj = cell // n, cell % n
        eta_m = (psi + two_pi * m) / steps
        h_m = _target_shift(h_des, eta_m, steps)
        a_s, b_s, off = _cell_start(c["eta"], c["h"], r, ii, jj, eta_m, h_m)
        out = np.column_stack([r[ii] + r[jj], 0.5 * (r[ii] + r[ii + 1]), 0.5 * (r[jj] + r[jj + 1]),
                               0.5 * (r[ii + 1] - r[ii]), 0.5 * (r[jj + 1] - r[jj]), m, eta_m, h_m, a_s, b_s, off])
        return out[np.lexsort((m, cell, out[:, 0]))]

    # -- solve -----------------------------------------------------------------------
    def solve(self, target, steps: int = 1, k: float | None = None, robot: Robot | None = None,
              radius: float | None = None, all_solutions: bool = False, branch: int | None = None) -> Plan:
        """Plan to ``target = (u_a, v_a, psi)`` in ``steps`` traces; see :func:`plan`."""
        t_start = time.perf_counter()
        k, radius = _resolve_k_radius(k, robot, radius)
        steps = _check_steps(steps)
        if len(target) != 3:
            raise InputError(f"target = {target!r} is not allowed: give (u_a, v_a, psi)")
        u_des, v_des = (check_finite(n, x) / radius for n, x in zip(("u_a", "v_a"), target[:2]))
        psi_given = check_finite("psi", target[2])
        psi_des = float(wrap(psi_given))  # psi is an angle; the branches psi + 2 pi m cover the rest
        turns = round((psi_given - psi_des) / (2 * math.pi))  # branch numbers stay relative to psi as given
        h_des = math.hypot(u_des, v_des)
        where = (f"(u_a, v_a, psi) = ({target[0]:g}, {target[1]:g}, {psi_given:g}) in {steps} step(s) "
                 f"with k = {k:g}")
        if h_des == 0.0:
            raise NoPlanError(f"no plan for {where}: the target is the start point, and rollplan plans "
                              "motions with a nonzero displacement")
        brackets = self._brackets(k, h_des, psi_des, steps, fine=all_solutions)
        if branch is not None:
            brackets = brackets[brackets[:, 5] == int(branch) + turns]
        log.info("k=%g: %d brackets", k, len(brackets))
        found: list = []      # verified plans, shortest first
        seen: list = []       # (a, b, m) of every converged root, verified or not
        rejected: list = []   # verified residuals of the roots that failed verification
        statuses: Counter = Counter()
        solves = 0
        # Brackets whose model root lies well outside the cell are mostly false (parallel zero
        # curves); the shortest plan is sought among the others first, and they are solved only
        # for all solutions or when the others give no plan.
        plausible = brackets[:, 10] <= _PLAUSIBLE_OFFSET
        passes = [brackets] if all_solutions else [brackets[plausible], brackets[~plausible]]
        for rows in passes:
            if found:
                break
            for lower, a0, b0, da, db, m, eta_m, h_m, a_s, b_s, _ in rows:
                if not all_solutions and found and found[0].a + found[0].b <= lower:
                    break  # no bracket left can hold a shorter path
                if any(sm == m and abs(sa - a0) <= da and abs(sb - b0) <= db for sa, sb, sm in seen):
                    continue  # the root in this cell is known
                # Solve within the bracketing cell widened by two cells each way: near A_MAX eta is
                # steep, and an unbounded step can jump to another root and leave this one unfound.
                box_lo = np.maximum([a0 - 3 * da, b0 - 3 * db], 1e-6)
                box_hi = np.minimum([a0 + 3 * da, b0 + 3 * db], A_MAX)
                x, status, iters, ok = self._solve([a_s, b_s], [k, eta_m, h_m], box_lo, box_hi)
                solves += 1
                statuses[str(status)] += 1
                if not ok or any(abs(x[0] - sa) < 1e-7 and abs(x[1] - sb) < 1e-7 for sa, sb, _ in seen):
                    continue
                seen.append((float(x[0]), float(x[1]), m))
                cand, residual = self._finish(x, int(m) - turns, steps, k, (u_des, v_des, psi_des), status, iters)
                if cand is None:
                    rejected.append(residual)
                    continue
                found.append(cand)
                found.sort(key=lambda p: p.a + p.b)
        elapsed = time.perf_counter() - t_start
        if not found:
            if rejected:
                raise NoPlanError(f"no verified plan for {where}: {len(rejected)} root(s) of (32)-(33) found, but "
                                  f"their verified residual (best {min(rejected):.1e}) exceeds {self.tol:.0e}; "
                                  "try more steps")
            errors = Counter({s: c for s, c in statuses.items() if s in _SOLVER_ERROR_STATUSES})
            if errors:
                status = errors.most_common(1)[0][0]
                raise SolverError(f"the root solver failed for {where} ({solves} solves from {len(brackets)} "
                                  f"brackets, {status}); try method='newton' or more steps", status)
            tried = ", ".join(f"{s} x{c}" for s, c in statuses.most_common(3))
            raise NoPlanError(f"no plan for {where}: no branch of (32)-(33) has a root with 0 < a, b <= {A_MAX} R"
                              f"{f' ({solves} bracket solves without a root: {tried})' if solves else ''}; "
                              "try more steps")
        plans = [_scaled(replace(p, stats=replace(p.stats, candidates=len(brackets), solves=solves, time_s=elapsed)),
                         radius, target, self) for p in found]
        return replace(plans[0], alternatives=tuple(plans[1:]) if all_solutions else ())

    def _finish(self, x, m, steps, k, target_r, status, iters):
        """Gamma from the geometry, then verification by CVODES: (plan or None, residual)."""
        a, b = float(x[0]), float(x[1])
        xf = np.array(self.step_map(ca.DM.zeros(3), x, k, 0)).ravel()
        eta = float(xf[2])
        total = complex(xf[0], xf[1]) * n_step_sum(eta, steps)
        gamma = float(wrap(math.atan2(target_r[1], target_r[0]) - math.atan2(total.imag, total.real)))
        final = self.verify(a, b, k, gamma, steps)
        err = np.array([final[0] - target_r[0], final[1] - target_r[1], wrap(final[2] - target_r[2]), final[3], final[4]])
        residual = float(np.linalg.norm(err))
        if residual > self.tol:
            log.warning("branch m=%d (a=%.6f, b=%.6f) rejected: verified residual %.2e > %.0e", m, a, b, residual, self.tol)
            return None, residual
        stats = SolverStats(self.method, str(status), iters, 0, 0, 0.0)
        return Plan(a, b, gamma, steps, k, 1.0, target_r, int(m), float(np.hypot(*xf[:2])), eta,
                    2 * np.pi * steps * (a + b), final, residual, stats, (), self), residual

    # -- verification and sampling --------------------------------------------------
    def verify(self, a, b, k, gamma, steps):
        """Final (u_a, v_a, psi, u_o, v_o) after ``steps`` traces, by CVODES (units of R)."""
        _, xs = self.verifier.trace([a, b], k, gamma, steps, integrators=self._verify_ints)
        end = rotated_point(self.curve.pieces[-1], 2 * np.pi, ca.DM([a, b]), gamma)
        u_o, v_o = (float(c) for c in model.contact_coordinates(end))
        return np.array([*xs[-1], u_o, v_o])

    def trajectory(self, p: Plan, samples_per_leaf: int = 200) -> Trajectory:
        """Sampled trajectory of a plan (CVODES), in the plan's units."""
        ab = [p.a / p.radius, p.b / p.radius]
        phi, xs = self.verifier.trace(ab, p.k, p.gamma, p.steps, samples_per_leaf)
        pieces = len(self.curve.pieces)
        idx = np.arange(phi.size) // samples_per_leaf
        leaf, step_no = idx % pieces, idx // pieces
        pts = np.zeros((phi.size, 3))
        for j, piece in enumerate(self.curve.pieces):
            sel = leaf == j
            ph = ca.SX.sym("ph")
            f = ca.Function("pt", [ph], [rotated_point(piece, ph, ca.DM(ab), p.gamma)]).map(int(sel.sum()))
            pts[sel] = np.array(f(phi[sel][None, :])).T
        theta = 2 * np.pi * step_no + (2 * np.pi / pieces) * (leaf + phi / (2 * np.pi))
        u_o = np.arctan2(-pts[:, 0], -pts[:, 2])
        v_o = np.arcsin(np.clip(pts[:, 1], -1, 1))
        zero = np.zeros(1)
        cat = lambda v0, v: np.concatenate([np.atleast_1d(v0), v])
        R = p.radius
        return Trajectory(cat(0.0, theta), cat(0.0, u_o), cat(0.0, v_o), cat(0.0, xs[:, 0] * R),
                          cat(0.0, xs[:, 1] * R), cat(0.0, xs[:, 2]), np.vstack([[0, 0, -R], pts * R]),
                          cat(zero, leaf).astype(int), cat(zero, step_no).astype(int))


def _cell_start(eta, h, r, ii, jj, eta_m, h_m):
    """Start of the root solve in cell (ii, jj): the root of the tables' bilinear model, linearized at
    the cell centre, clipped to the cell (the centre where the model is singular).

    ``eta``, ``h``: tabulated eta(a_i, b_j), h(a_i, b_j); returns arrays (a_s, b_s, off), where
    ``off`` is how far the unclipped model root lies from the cell centre, in cell widths
    (inf where the model is singular): a cell where the zero curves of (32) and (33) run
    parallel passes the corner-sign test but has its model root far outside.
    """
    def corners(z):
        return z[ii, jj], z[ii + 1, jj], z[ii, jj + 1], z[ii + 1, jj + 1]

    e00, e10, e01, e11 = corners(eta)
    h00, h10, h01, h11 = corners(h)
    res_e = eta_m - 0.25 * (e00 + e10 + e01 + e11)
    res_h = h_m - 0.25 * (h00 + h10 + h01 + h11)
    es, et = 0.5 * (e10 - e00 + e11 - e01), 0.5 * (e01 - e00 + e11 - e10)
    hs, ht = 0.5 * (h10 - h00 + h11 - h01), 0.5 * (h01 - h00 + h11 - h10)
    det = es * ht - et * hs
    ok = np.abs(det) > 1e-14 * (np.abs(es * ht) + np.abs(et * hs) + 1e-300)
    safe = np.where(ok, det, 1.0)
    ds = np.where(ok, (res_e * ht - et * res_h) / safe, 0.0)
    dt = np.where(ok, (es * res_h - hs * res_e) / safe, 0.0)
    s = np.clip(0.5 + ds, 0.0, 1.0)
    t = np.clip(0.5 + dt, 0.0, 1.0)
    off = np.where(ok, np.maximum(np.abs(ds), np.abs(dt)), np.inf)
    return r[ii] + s * (r[ii + 1] - r[ii]), r[jj] + t * (r[jj + 1] - r[jj]), off


def _target_shift(h_des, eta_m, steps):
    """Shift one step must produce on branches eta_m, from (33)-(34); nan if unreachable.

    Where ``sin(n eta / 2) = 0`` the n shifts cancel, unless also
    ``sin(eta / 2) = 0``: then they add up, ``h = h_des / n`` (34).
    """
    eta_m = np.asarray(eta_m, float)
    num, den = np.sin(eta_m / 2), np.sin(steps * eta_m / 2)
    singular = np.abs(den) < 1e-12
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where(singular, np.where(np.abs(num) < 1e-12, 1.0 / steps, np.nan), np.abs(num / den))
    return h_des * ratio


def _scaled(p: Plan, radius: float, target, planner) -> Plan:
    final = p.final.copy()
    final[:2] *= radius
    return replace(p, a=p.a * radius, b=p.b * radius, h=p.h * radius, path_length=p.path_length * radius,
                   radius=radius, final=final, target=(float(target[0]), float(target[1]), float(target[2])),
                   _planner=planner)


def _remember(cache: dict, key, value, size: int = _TABLE_CACHE) -> None:
    """Store ``value`` in a small cache, dropping the oldest entry beyond ``size``."""
    cache[key] = value
    while len(cache) > size:
        cache.pop(next(iter(cache)))


def _check_k(k) -> float:
    return check_range("k", k, 0.0, K_MAX)


def _check_leaf(name, value) -> float:
    return check_range(name, value, 0.0, A_MAX, low_open=True)


def _check_steps(steps) -> int:
    return check_whole("steps", steps, 1, MAX_STEPS)


def _resolve_k_radius(k, robot, radius):
    if robot is not None and k is not None:
        raise InputError("give either k or robot, not both")
    if robot is None and k is None:
        raise InputError("k is missing: give k (>= 0) or a robot")
    if robot is not None:
        k = robot.k
        radius = robot.radius if radius is None else radius
    k = _check_k(k)
    radius = 1.0 if radius is None else check_range("radius", radius, 0.0, None, low_open=True)
    return k, radius


@lru_cache(maxsize=4)
def _planner(method: str) -> GeometricPhasePlanner:
    return GeometricPhasePlanner(method)


def plan(target, steps: int = 1, k: float | None = None, robot: Robot | None = None, radius: float | None = None,
         all_solutions: bool = False, method: str = "ipopt", branch: int | None = None) -> Plan:
    """Plan an exact, dynamically realizable motion by tracing a figure eight n times.

    Solves (32)-(33) for the leaf radii (a, b) on every branch
    ``n eta = psi + 2 pi m`` and the rotation gamma of (31), so that ``steps``
    traces bring the robot from rest at the origin to ``target``.

    Parameters
    ----------
    target : (u_a, v_a, psi)
        Final contact point on the plane [length unit of ``radius``] and
        contact angle [rad].
    steps : int
        Number of traces n >= 1.
    k : float, optional
        Inertia ratio (14), k >= 0 (k = 0 is pure rolling). Or give ``robot``.
    robot : Robot, optional
        Robot parameters; sets k and, unless given, the radius.
    radius : float, optional
        Sphere radius R (default 1, or the robot's).
    all_solutions : bool
        Also return the other verified branches in ``Plan.alternatives``.
    method : str
        Root solver name from :data:`SOLVERS`.
    branch : int, optional
        Only the branch m of ``n eta = psi + 2 pi m`` (psi as given).

    Returns
    -------
    Plan
        The verified plan with the shortest contact path.

    Raises
    ------
    InputError
        Bad input.
    NoPlanError
        No verified plan exists in the admissible range ``0 < a, b <= A_MAX R``.
    SolverError
        The root solver broke down (an internal IPOPT error; carries its status). A bracket
        whose solve does not converge is taken to hold no root.
    """
    return _planner(method).solve(target, steps, k, robot, radius, all_solutions, branch)


def step(a: float, b: float | None = None, *, k: float, gamma: float = 0.0) -> StepResult:
    """What one figure eight does: shift h(a, b), holonomy eta(a, b), eqs. (28)-(31)."""
    return _planner("ipopt").step(a, b, k=k, gamma=gamma)
