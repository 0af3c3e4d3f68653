"""Refinement of bracketed roots of (32)-(33) by a root solver chosen by name.

Every solver in :data:`SOLVERS` follows one contract: ``SOLVERS[name](residual)``
takes the residual ``F(ab[2], par[3]) -> (eta(a, b) - eta_m, h(a, b) - h_m)``
(``par = (k, eta_m, h_m)``) and returns ``solve(x0, par, lbx, ubx) -> (x, status,
iterations, ok)``: the end point, the solver's status string, its iterations,
and whether the end point is a candidate root kept inside the box ``[lbx, ubx]``.
A solve that does not converge says only that its bracket holds no root; the
statuses in :data:`SOLVER_ERROR_STATUSES` mean the solver itself broke down.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ... import interrupts
from ...core.curves import A_MAX

__all__ = ["SOLVERS", "SOLVER_ERROR_STATUSES", "ROOT_TOL", "step_residual"]

#: Statuses that mean the solver broke (not that a bracket held no root).
SOLVER_ERROR_STATUSES = frozenset({"Invalid_Number_Detected", "Error_In_Step_Computation", "Internal_Error",
                                   "Insufficient_Memory", "Not_Enough_Memory", "Unrecoverable_Exception",
                                   "NonIpopt_Exception_Thrown", "Invalid_Problem_Definition", "Invalid_Option"})
#: Largest |residual of (32)-(33)| of a solver's end point that is still a candidate root.
ROOT_TOL = 1e-10
_NEWTON_NO_ROOT = "no_root_in_bracket"


def step_residual(step_map: ca.Function) -> ca.Function:
    """``F(ab[2], par[3]) -> (eta - eta_m, h - h_m)`` of one step from zero, ``par = (k, eta_m, h_m)``."""
    ab = ca.SX.sym("ab", 2)
    par = ca.SX.sym("par", 3)
    xf = step_map(ca.DM.zeros(3), ab, par[0], 0)
    return ca.Function("residual", [ab, par], [ca.vertcat(xf[2] - par[1], ca.norm_2(xf[:2]) - par[2])])


def _ipopt_solver(residual: ca.Function):
    ab = ca.SX.sym("ab", 2)
    par = ca.SX.sym("par", 3)
    nlp = {"x": ab, "p": par, "f": 0, "g": residual(ab, par)}
    # show_eval_warnings: the Jacobian of |shift| is 0/0 where the shift of a step vanishes (targets near
    # the start point); IPOPT treats that NaN as a failed evaluation and steps back. Expected, not news.
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "show_eval_warnings": False,
            "ipopt.tol": 1e-13, "ipopt.constr_viol_tol": 1e-13, "ipopt.max_iter": 60,
            "ipopt.hessian_approximation": "limited-memory"}
    solver = ca.nlpsol("gp_ipopt", "ipopt", nlp, opts)

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        sol = interrupts.call(solver, x0=x0, p=par_value, lbx=lbx, ubx=ubx, lbg=0, ubg=0)
        st = solver.stats()
        # Where eta is steep near A_MAX IPOPT may stop short of its tolerance at a point that
        # solves (32)-(33) to rounding ("Search_Direction_Becomes_Too_Small"); such a point is a
        # candidate too: the certificate decides.
        ok = bool(st["success"]) or float(np.abs(np.array(sol["g"])).max()) < ROOT_TOL
        return np.array(sol["x"]).ravel(), st["return_status"], int(st["iter_count"]), ok

    return solve


def _newton_solver(residual: ca.Function):
    rf = ca.rootfinder("gp_newton", "newton", residual,
                       {"abstol": 1e-14, "abstolStep": 1e-16, "max_iter": 40, "error_on_fail": False,
                        "show_eval_warnings": False})  # NaN outside the admissible range is a failed solve

    def solve(x0, par_value, lbx=1e-6, ubx=A_MAX):
        x = np.array(interrupts.call(rf, x0, par_value)).ravel()
        st = rf.stats()
        ok = bool(st["success"]) and bool(np.all((x >= lbx) & (x <= ubx)))
        # Newton cannot tell a bracket without a root from a failure: both are "no root" here.
        status = st["return_status"] if ok else _NEWTON_NO_ROOT
        return x, status, int(st.get("iter_count", -1)), ok

    return solve


#: Root solvers for (32)-(33), by name (see the module docstring for the contract).
SOLVERS = {"ipopt": _ipopt_solver, "newton": _newton_solver}
