"""Root solvers of (32)-(33) chosen by name, and the shooting residual they solve.

On branch m, (32)-(33) read ``F(ab, par) = (eta(a, b) - eta_m, h(a, b) - h_m) = 0`` with
``par = (k, eta_m, h_m)``; :func:`leaf_residual` builds F in CasADi from the leaf map's closed-form turn and
Gauss-rule displacement (compiled with its Jacobian, one function per panel count). :data:`SOLVERS` holds
the solvers by name, ``"c"`` (the default: the C planner's Newton polish), ``"ipopt"`` and ``"newton"``;
:func:`polisher` gives one on the compiled residual of k: the planner's last step before the certificate,
started at an enumerated root.

The residual, the solvers' contract and options: docs/design/geometric-planner.md (the polish).
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from ... import interrupts
from ...core import compiled as _compiled_mod
from ...core.compiled import compiled_lazy
from ...core.curves import A_MAX
from . import leafmap
from .leafmap import gauss_nodes

__all__ = ["SOLVERS", "DEFAULT_ROOT_SOLVER", "SOLVER_ERROR_STATUSES", "ROOT_TOL", "step_residual", "leaf_turn",
           "leaf_displacement", "leaf_residual", "leaf_step", "polisher"]

#: Statuses that mean the solver broke (not that a start held no root).
SOLVER_ERROR_STATUSES = frozenset({"Invalid_Number_Detected", "Error_In_Step_Computation", "Internal_Error",
                                   "Insufficient_Memory", "Not_Enough_Memory", "Unrecoverable_Exception",
                                   "NonIpopt_Exception_Thrown", "Invalid_Problem_Definition", "Invalid_Option"})
#: Largest |residual of (32)-(33)| of a solver's end point that is still a candidate root.
ROOT_TOL = 1e-10
_NEWTON_NO_ROOT = "no_root_in_bracket"
_TWO_PI = 2.0 * math.pi


def step_residual(step_map: ca.Function) -> ca.Function:
    """``F(ab[2], par[3]) -> (eta - eta_m, h - h_m)`` of one step from zero by a step map
    ``(x0, ab, k, gamma) -> x_end`` (the spectral map, for the bracketing), ``par = (k, eta_m, h_m)``."""
    ab = ca.SX.sym("ab", 2)
    par = ca.SX.sym("par", 3)
    xf = step_map(ca.DM.zeros(3), ab, par[0], 0)
    return ca.Function("residual", [ab, par], [ca.vertcat(xf[2] - par[1], ca.norm_2(xf[:2]) - par[2])])


def _consts(r):
    c = ca.sqrt(1.0 - r * r)
    s = ca.sqrt(1.0 - 2.0 * r * r)
    return c, s, r * r / (c * c + s)


def leaf_turn(r, k):
    """Turn E(r, k) of the +y leaf (CasADi expression; the closed form of :func:`.leafmap.turn`)."""
    c, s, _ = _consts(r)
    return _TWO_PI * r * r / (1.0 + c) - 2.0 * _TWO_PI * k * c * r * r / (s * (1.0 + s))


def _node_kernel() -> ca.Function:
    """``(chi, cos chi, sin chi, w, rho, A, B) -> w phi'(chi) (cos, sin)(theta)``: one node of the displacement
    integral of :func:`.leafmap.displacement` (docs/design/leaf-map.md), with ``theta = A phi(chi) + B chi``,
    ``A = (1 - k) c`` and ``B = k c / s``; the leaf's constants and the nodes' cos and sin are computed once
    outside the kernel, as in :func:`.leafmap.displacement`."""
    chi, cchi, schi, w, rho, A, B = (ca.SX.sym(n) for n in ("chi", "cchi", "schi", "w", "rho", "A", "B"))
    den = 1.0 - rho * cchi
    q = den * den + (rho * schi) ** 2
    phi = chi + 2.0 * ca.atan2(rho * schi, den)
    jac = (1.0 - rho * rho) / q
    theta = A * phi + B * chi
    wj = w * jac
    return ca.Function("gp_node", [chi, cchi, schi, w, rho, A, B], [wj * ca.cos(theta), wj * ca.sin(theta)])


def leaf_displacement(r, k, panels: int):
    """Displacement ``(re, im)`` of the +y leaf of radius r (MX expressions) by the Gauss rule of
    :func:`.leafmap.gauss_nodes` with ``panels`` panels (the rule of :func:`.leafmap.displacement`)."""
    chi, w = gauss_nodes(panels)
    kernel = _node_kernel().map(chi.size, "serial")
    c, s, rho = _consts(r)
    row = lambda v: ca.DM(v).T  # noqa: E731
    re, im = kernel(row(chi), row(np.cos(chi)), row(np.sin(chi)), row(w), rho, (1.0 - k) * c, k * c / s)
    return r * ca.sum2(re), r * ca.sum2(im)


def _step_expressions(ab, k, panels: int):
    """``(Re S, Im S, eta)`` of one figure eight from zero (MX expressions; docs/design/leaf-map.md, item 4)."""
    a, b = ab[0], ab[1]
    ea, eb = leaf_turn(a, k), leaf_turn(b, k)
    ua, va = leaf_displacement(a, k, panels)
    ub, vb = leaf_displacement(b, k, panels)
    # S = d(a) + exp(-i E(a)) conj(d(b))
    cs, sn = ca.cos(ea), ca.sin(ea)
    return ua + cs * ub - sn * vb, va - sn * ub - cs * vb, ea - eb


def _leaf_residual(panels: int) -> ca.Function:
    ab = ca.MX.sym("ab", 2)
    par = ca.MX.sym("par", 3)
    su, sv, eta = _step_expressions(ab, par[0], panels)
    return ca.Function(f"gp_residual_{panels}", [ab, par],
                       [ca.vertcat(eta - par[1], ca.sqrt(su * su + sv * sv) - par[2])], ["ab", "par"], ["F"])


def _leaf_step(panels: int) -> ca.Function:
    ab = ca.MX.sym("ab", 2)
    k = ca.MX.sym("k")
    su, sv, eta = _step_expressions(ab, k, panels)
    return ca.Function(f"gp_step_{panels}", [ab, k], [ca.vertcat(su, sv, eta)], ["ab", "k"], ["step"])


_SOURCES = (Path(__file__), Path(leafmap.__file__), Path(_compiled_mod.__file__))


@lru_cache(maxsize=16)
def leaf_residual(panels: int, compile: bool = True) -> ca.Function:
    """``F(ab[2], par[3]) -> (eta(a, b) - eta_m, h(a, b) - h_m)`` on the leaf map with ``panels`` Gauss
    panels (docs/design/geometric-planner.md), compiled with its Jacobian (unless ``compile`` is false)."""
    if not compile:
        return _leaf_residual(panels)
    return compiled_lazy(f"gp_residual_{panels}", lambda: _leaf_residual(panels), f"panels={panels}", _SOURCES,
                         jacobian=True)


@lru_cache(maxsize=16)
def leaf_step(panels: int, compile: bool = True) -> ca.Function:
    """``(ab[2], k) -> (u_a, v_a, eta)`` of one figure eight (+y leaf a, then -y leaf b) from zero with gamma
    = 0, on the leaf map with ``panels`` Gauss panels (the expressions of :func:`leaf_residual`), compiled
    (unless ``compile`` is false): the planner's shift for gamma."""
    if not compile:
        return _leaf_step(panels)
    return compiled_lazy(f"gp_step_{panels}", lambda: _leaf_step(panels), f"panels={panels}", _SOURCES)


def _ipopt_solver(residual: ca.Function, near_root: bool = False):
    ab = ca.MX.sym("ab", 2)
    par = ca.MX.sym("par", 3)
    nlp = {"x": ab, "p": par, "f": 0, "g": residual(ab, par)}
    # show_eval_warnings: the Jacobian of |shift| is 0/0 where the shift of a step vanishes (targets near
    # the start point); IPOPT treats that NaN as a failed evaluation and steps back. Expected, not news.
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "show_eval_warnings": False,
            "ipopt.tol": 1e-13, "ipopt.constr_viol_tol": 1e-13, "ipopt.max_iter": 60,
            "ipopt.hessian_approximation": "limited-memory", "ipopt.print_timing_statistics": "no",
            "ipopt.print_user_options": "no", "ipopt.print_options_documentation": "no"}
    if near_root:   # a 2 x 2 problem in units of R and rad started next to its root: no scaling (which costs
        # a Jacobian evaluation per solve), a small, monotone barrier parameter, no timing records, no
        # least-squares estimate of the constraint multipliers (zero for a zero objective) and none of
        # the multipliers the solve does not return
        opts.update({"ipopt.nlp_scaling_method": "none", "ipopt.mu_strategy": "monotone", "ipopt.mu_init": 1e-6,
                     "record_time": False, "ipopt.timing_statistics": "no", "ipopt.constr_mult_init_max": 0.0,
                     "calc_lam_p": False, "calc_lam_x": False, "bound_consistency": False})
    solver = ca.nlpsol("gp_ipopt", "ipopt", nlp, opts)

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        if near_root:   # the square system without the box (checked below): from a root, no iteration
            sol = interrupts.call(solver, x0=x0, p=par_value, lbg=0, ubg=0)
        else:
            sol = interrupts.call(solver, x0=x0, p=par_value, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
        st = solver.stats()
        x = np.array(sol["x"]).ravel()
        # Where eta is steep near A_MAX IPOPT may stop short of its tolerance at a point that
        # solves (32)-(33) to rounding ("Search_Direction_Becomes_Too_Small"); such a point is a
        # candidate too: the certificate decides.
        ok = bool(st["success"]) or float(np.abs(np.array(sol["g"])).max()) < ROOT_TOL
        ok = ok and bool(np.all((x >= lbx) & (x <= ubx)))
        return x, st["return_status"], int(st["iter_count"]), ok

    return solve


def _newton_solver(residual: ca.Function, near_root: bool = False):
    rf = ca.rootfinder("gp_newton", "newton", residual,
                       {"abstol": 1e-14, "abstolStep": 1e-16, "max_iter": 40, "error_on_fail": False,
                        "show_eval_warnings": False})  # NaN outside the admissible range is a failed solve

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        x = np.array(interrupts.call(rf, x0, par_value)).ravel()
        st = rf.stats()
        ok = bool(st["success"]) and bool(np.all((x >= lbx) & (x <= ubx)))
        # Newton cannot tell a start without a root from a failure: both are "no root" here.
        status = st["return_status"] if ok else _NEWTON_NO_ROOT
        return x, status, int(st.get("iter_count", -1)), ok

    return solve


def _c_solver(residual: ca.Function, near_root: bool = False):
    """The default: Newton on the accurate leaf map, as the C planner polishes its roots. The planner's default
    path runs the C search, its polish and its certificate in one call; the paths that polish roots one by one
    here (``all_solutions``, the composed planner's legs) run the same Newton iteration on the compiled residual
    (:func:`_newton_solver`)."""
    return _newton_solver(residual, near_root)


#: Root solvers for (32)-(33), by name. Contract: ``SOLVERS[name](residual, near_root=False)`` takes a residual
#: ``F(ab[2], par[3]) -> (2,)`` (``near_root``: every start lies next to a root) and returns
#: ``solve(x0, par, lbx, ubx) -> (x, status, iterations, ok)``, ``ok`` when x is a candidate root inside
#: ``[lbx, ubx]`` (the certificate decides); docs/design/geometric-planner.md. ``"c"`` (the default,
#: :data:`DEFAULT_ROOT_SOLVER`) is the C planner's polish (Newton on the leaf map).
SOLVERS = {"c": _c_solver, "ipopt": _ipopt_solver, "newton": _newton_solver}
#: The default root solver: the C planner's search, polish and certificate in one call.
DEFAULT_ROOT_SOLVER = "c"


@lru_cache(maxsize=32)
def polisher(method: str, panels: int):
    """The solver ``method`` of :data:`SOLVERS` on the compiled leaf-map residual with ``panels`` panels
    (:func:`.leafmap.panels_for` of k); built once per process."""
    return SOLVERS[method](leaf_residual(panels), near_root=True)

