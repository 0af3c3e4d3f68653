"""Direct collocation of the realizable contact kinematics: the transcription, separate from the NLP solve.

``N`` equal intervals in normalized time ``tau = t / T``; on each, the state is a polynomial of degree ``d``
through the interval's start and ``d`` Legendre or Radau points, the control is constant, and the
collocation equations are those of the ``d``-stage Gauss-Legendre (order ``2d``) or Radau IIA (order
``2d - 1``) method (:func:`casadi.collocation_coeff`). Decision variables, in order: ``X_0``, then per interval
its collocation states (nx x d), its control (nu) and ``X_{i+1}``; ``nx = 5``, ``nu = 2`` by default
(``nx = 7`` for rest to rest).

Details: docs/design/collocation.md (the transcription).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ... import interrupts
from ...core import model
from ...core.integrate import rk8_formula
from ...errors import InputError, check_choice, check_whole
from ...problem import Problem
from ...result import CertifiedMotion

__all__ = ["SCHEMES", "CORRECTION_TOL", "JACOBIAN_SUBSTEPS", "Guess", "Transcription", "CollocationRun",
           "ipopt_options", "check_contact_bound", "sensitivity_step", "fixed_step", "gauss_newton", "interval_nlp",
           "interval_derivatives"]

#: Collocation point families accepted by :func:`casadi.collocation_points`.
SCHEMES = ("legendre", "radau")
#: Relative cut-off of the singular values of the end-state Jacobian in a Gauss-Newton step (:func:`gauss_newton`):
#: directions in which the controls move the end state less than this times the most are not followed.
GN_RCOND = 1e-9
#: Target of the Gauss-Newton correction of every collocation solution: largest end-condition error of the corrected
#: controls (units of R, rad).
CORRECTION_TOL = 1e-12
#: Steps per interval of the eighth-order formula (:func:`fixed_step`) that give the Jacobian of the collocation
#: planners' Newton corrections, CVODES integrating their end error (:func:`gauss_newton`, ``fallback``).
JACOBIAN_SUBSTEPS = 2


def ipopt_options(tol: float, max_iter: int) -> dict:
    """The options of every collocation NLP: IPOPT silent, tolerance ``tol`` (also on the constraints)."""
    return {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": tol,
            "ipopt.constr_viol_tol": tol, "ipopt.max_iter": max_iter, "ipopt.mu_strategy": "adaptive"}


def _scatter(block: ca.Sparsity, rows, cols, shape, nonzeros: ca.MX) -> ca.MX:
    """The sum of copies of a matrix of sparsity ``block`` with their corners at ``(rows[i], cols[i])`` in a
    matrix of ``shape``; ``nonzeros`` (MX) the copies' nonzeros, one copy after the other."""
    r, c = (np.asarray(v, int) for v in block.get_triplet())
    R = (r[None, :] + np.asarray(rows, int)[:, None]).ravel().tolist()
    C = (c[None, :] + np.asarray(cols, int)[:, None]).ravel().tolist()
    sp, where = ca.Sparsity.triplet(*shape, R, C, True)
    add = ca.DM(ca.Sparsity.triplet(sp.nnz(), len(R), list(where), list(range(len(R)))), 1.0)
    return ca.sparsity_cast(ca.mtimes(add, ca.vec(nonzeros)), sp)


def _windows(x, intervals: int, stride: int, nz: int, shared: int) -> list:
    """Each interval's slice of ``x``: its window of ``nz - shared`` entries, then the ``shared`` last entries."""
    local, n_loc = nz - shared, x.numel() - shared
    return [ca.vertcat(x[i * stride:i * stride + local], x[n_loc:]) if shared else x[i * stride:i * stride + nz]
            for i in range(intervals)]


def interval_nlp(block: ca.Function, intervals: int, stride: int, shared: int = 0) -> dict:
    """The NLP ``{"x", "p", "f", "g"}`` (SX) made of intervals:

        f(x, p) = sum_i J(z_i, p),   g(x, p) = (g(z_0, p), ..., g(z_{N-1}, p)),   z_i = x[i s : i s + nz],

    ``block(z, p) -> (g, J)`` one interval's SX function, ``N = intervals``, ``s = stride`` (consecutive intervals
    share the ``nz - s`` states between them; x has ``(N - 1) s + nz`` entries). With ``shared`` > 0 the last
    ``shared`` entries of z are variables of every interval (a free final time), stored once at the end of x:
    ``z_i = (x[i s : i s + nz - shared], x[n - shared:])``."""
    nz = block.size1_in(0)
    x, p = ca.SX.sym("x", (intervals - 1) * stride + nz), ca.SX.sym("par", block.size1_in(1))
    g, J = zip(*(block(z, p) for z in _windows(x, intervals, stride, nz, shared)))
    return {"x": x, "p": p, "f": ca.sum1(ca.vertcat(*J)), "g": ca.vertcat(*g)}


def interval_derivatives(block: ca.Function, intervals: int, stride: int, shared: int = 0) -> dict:
    """The derivative functions ``{"grad_f", "jac_g", "hess_lag"}`` (options of :func:`casadi.nlpsol`) of
    :func:`interval_nlp`'s NLP of the same arguments. Each is one interval's SX derivative mapped over the
    intervals and summed where the intervals overlap (MX): the same functions as CasADi's derivatives of the whole
    NLP (the Lagrangian's Hessian, upper triangle, and the Jacobian with the same sparsity), built in a small
    fraction of the time, since the derivatives of the large expression graph are never formed."""
    z, p = ca.SX.sym("z", block.size1_in(0)), ca.SX.sym("p", block.size1_in(1))
    g, J = block(z, p)
    nz, ng = z.numel(), g.numel()
    loc = nz - shared
    sigma, lam = ca.SX.sym("sigma"), ca.SX.sym("lam", ng)
    grad, jac = ca.gradient(J, z), ca.jacobian(g, z)
    hess = ca.hessian(sigma * J + ca.dot(lam, g), z)[0]
    # each derivative in parts: the window's own variables, and the shared ones (stored at the end of x)
    cost = ca.Function("interval_cost", [z, p], [J, grad[:loc], grad[loc:]])
    rows = ca.Function("interval_rows", [z, p], [g, jac[:, :loc], jac[:, loc:]])
    second = ca.Function("interval_second", [z, p, sigma, lam],
                         [ca.triu(hess[:loc, :loc]), hess[:loc, loc:], ca.triu(hess[loc:, loc:])])
    N = intervals
    n_x = (N - 1) * stride + nz
    n_loc = n_x - shared
    x, par = ca.MX.sym("x", n_x), ca.MX.sym("p", p.numel())
    lam_f, lam_g = ca.MX.sym("lam_f"), ca.MX.sym("lam_g", N * ng)
    starts, ends, zero = np.arange(N) * stride, np.full(N, n_loc), np.zeros(N, int)
    Z = ca.horzcat(*_windows(x, N, stride, nz, shared))
    (Jv, grad_l, grad_s), (gv, jac_l, jac_s) = cost.map(N)(Z, par), rows.map(N)(Z, par)
    hess_ll, hess_ls, hess_ss = second.map(N)(Z, par, lam_f, ca.reshape(lam_g, ng, N))
    grad = _scatter(cost.sparsity_out(1), starts, zero, (n_x, 1), grad_l.nz[:])
    jac = _scatter(rows.sparsity_out(1), np.arange(N) * ng, starts, (N * ng, n_x), jac_l.nz[:])
    hess = _scatter(second.sparsity_out(0), starts, starts, (n_x, n_x), hess_ll.nz[:])
    if shared:
        grad = grad + _scatter(cost.sparsity_out(2), ends, zero, (n_x, 1), grad_s.nz[:])
        jac = jac + _scatter(rows.sparsity_out(2), np.arange(N) * ng, ends, (N * ng, n_x), jac_s.nz[:])
        hess = hess + _scatter(second.sparsity_out(1), starts, ends, (n_x, n_x), hess_ls.nz[:]) + \
            _scatter(second.sparsity_out(2), ends, ends, (n_x, n_x), hess_ss.nz[:])
    return {"grad_f": ca.Function("nlp_grad_f", [x, par], [ca.sum2(Jv), grad], ["x", "p"], ["f", "grad_f_x"]),
            "jac_g": ca.Function("nlp_jac_g", [x, par], [ca.vec(gv), jac], ["x", "p"], ["g", "jac_g_x"]),
            "hess_lag": ca.Function("nlp_hess_l", [x, par, lam_f, lam_g], [hess],
                                    ["x", "p", "lam_f", "lam_g"], ["triu_hess_gamma_x_x"])}


def sensitivity_step(name: str, x, w, par, xdot, quad, jacobians: bool = True) -> ca.Function:
    """CVODES over one interval of normalized length ``h`` of ``x' = h xdot(x, w, par)`` (SX expressions) with
    the quadrature ``h quad`` and the sensitivities of the end state:
    ``(x0, p = (w, par, h)) -> (xf, qf, jac_xf_x0, jac_xf_p)``; without ``jacobians`` only
    ``(x0, p) -> (xf, qf)`` (the same integration, about ten times cheaper)."""
    h = ca.SX.sym("h")
    opts = {"abstol": 1e-13, "reltol": 1e-12, "max_num_steps": 100000}
    F = ca.integrator(name, "cvodes", {"x": x, "p": ca.vertcat(w, par, h), "ode": h * xdot, "quad": h * quad},
                      0.0, 1.0, opts)
    outputs = ["xf", "qf", "jac:xf:x0", "jac:xf:p"] if jacobians else ["xf", "qf"]
    return F.factory(name + "_step", ["x0", "p"], outputs)


def fixed_step(name: str, x, w, par, xdot, quad, substeps: int, jacobians: bool = True) -> ca.Function:
    """:func:`sensitivity_step`'s function (the same inputs and outputs) by ``substeps`` equal steps of the
    eighth-order formula of DOP853 (:func:`rollplan.core.integrate.rk8_formula`) instead of CVODES: a cheaper,
    fixed-step integration of the same ODE, its quadrature carried as an extra state."""
    h = ca.SX.sym("h")
    n = x.numel()
    rhs = ca.Function("rhs", [x, w, par, h], [ca.vertcat(h * xdot, h * quad)])
    x0 = ca.SX.sym("x0", n)
    z = ca.vertcat(x0, 0.0)
    for _ in range(substeps):
        z = rk8_formula(z, 1.0 / substeps, lambda s, zs: rhs(zs[:n], w, par, h))
    xf, qf = z[:n], z[n]
    p = ca.vertcat(w, par, h)
    outputs = {"xf": xf, "qf": qf}
    if jacobians:
        outputs.update(jac_xf_x0=ca.jacobian(xf, x0), jac_xf_p=ca.jacobian(xf, p))
    return ca.Function(name + "_step", [x0, p], list(outputs.values()), ["x0", "p"], list(outputs))


def gauss_newton(step: ca.Function, controls, start, final, par, goal_tol: float = CORRECTION_TOL,
                 max_steps: int = 8, plain: ca.Function | None = None, fallback: ca.Function | None = None):
    """Minimum-norm Gauss-Newton correction of piecewise-constant controls so that the integrated motion ends
    at ``final``.

    ``step`` is a :func:`sensitivity_step`; the motion runs from ``start`` through the N intervals of length
    ``1 / N`` with ``controls`` (N, nu) and parameters ``par``. Each step solves ``J d = -(x(1) - final)`` for the
    least-norm ``d`` (J the nx x (N nu) Jacobian of the end state, chained from the intervals' sensitivities; its
    singular values below :data:`GN_RCOND` times the largest taken as zero, so that a nearly singular J at a
    degenerate optimum does not give a huge step) and
    sets ``controls += lambda d`` with the first of ``lambda = 1, 1/2, ..., 1/8`` that lowers the largest end
    error (a step whose integration fails counts as not lowering it), until that error is at most ``goal_tol``,
    no step lowers it, or after ``max_steps`` steps. ``plain``, a step function without jacobians, integrates
    the given controls and the trials and gives the end error and the quadrature; ``step`` then gives only the
    sensitivities, computed only where a step is taken (not for the controls that end the correction). ``plain``
    may be the same :func:`sensitivity_step` without jacobians, or another integration of the same ODE (e.g. a
    :func:`fixed_step` with more steps than the ``step`` of the Jacobian). ``fallback``, a step function with
    jacobians (e.g. CVODES's :func:`sensitivity_step` where ``step`` is a :func:`fixed_step`), goes on from the last
    controls where ``step`` stopped short of ``goal_tol``. Returns ``(controls, quadrature, end error)`` of the last
    (best) controls and the end error of the given controls (``inf`` where an integration failed).
    """
    a = np.array(controls, float)
    N, nu = a.shape
    final = np.asarray(final, float)
    nx = final.size

    def run(c, jacobians=True):
        fn = step if jacobians or plain is None else plain
        x, q, A, B = np.asarray(start, float), 0.0, [], []
        try:
            for ci in c:
                out = interrupts.call(fn, x0=x, p=np.concatenate([ci, par, [1.0 / N]]))
                x = np.array(out["xf"]).ravel()
                q += float(out["qf"])
                if fn is step:
                    A.append(np.array(out["jac_xf_x0"]))
                    B.append(np.array(out["jac_xf_p"])[:, :nu])
        except RuntimeError:      # CVODES failed (e.g. the contact point driven to the equator)
            return math.inf, x, q, A, B
        size = float(np.abs(x - final).max())
        return (size if math.isfinite(size) else math.inf), x, q, A, B

    size, x, q, A, B = run(a, False)
    first = size
    for _ in range(max_steps):
        if size <= goal_tol or not math.isfinite(size):
            break
        if not A:
            ok, _, _, A, B = run(a)
            if not math.isfinite(ok):
                break
        J, M = np.zeros((nx, nu * N)), np.eye(nx)
        for i in range(N - 1, -1, -1):
            J[:, nu * i: nu * (i + 1)] = M @ B[i]
            M = M @ A[i]
        d = np.linalg.lstsq(J, final - x, rcond=GN_RCOND)[0].reshape(N, nu)
        for lam in (1.0, 0.5, 0.25, 0.125):
            trial = run(a + lam * d, False)
            if trial[0] < size:
                a = a + lam * d
                size, x, q, A, B = trial
                break
        else:
            break
    if fallback is not None and not size <= goal_tol and math.isfinite(size):
        a, q, size, _ = gauss_newton(fallback, a, start, final, par, goal_tol, max_steps, plain)
    return a, q, size, first


def check_contact_bound(problem, contact_bound: float) -> None:
    """InputError when the start or goal contact point of ``problem`` lies beyond ``contact_bound`` [rad]
    of the south pole (polar angle from (1): ``acos(cos u_o cos v_o)``)."""
    for name in ("start", "goal"):
        state = getattr(problem, name)
        polar = math.acos(min(1.0, math.cos(state.u_o) * math.cos(state.v_o)))
        if polar > contact_bound:
            raise InputError(f"the {name} contact point lies {polar:.4g} rad from the south pole, beyond the "
                             f"collocation's contact_bound = {contact_bound:.4g} rad: raise contact_bound")


@dataclass(frozen=True)
class Guess:
    """An initial guess in units of R, normalized time on N intervals.

    Attributes
    ----------
    states : ndarray, shape (N + 1, nx)
        (u_a, v_a, psi, u_o, v_o) at the interval boundaries (and the contact rates when nx = 7).
    colloc : ndarray, shape (N, d, nx)
        The state at the collocation points.
    controls : ndarray, shape (N, nu)
        (u_o_dot, v_o_dot) on each interval [rad/s] (the contact accelerations when nx = 7).
    name : str
    """

    states: np.ndarray
    colloc: np.ndarray
    controls: np.ndarray
    name: str


@dataclass(frozen=True)
class Transcription:
    """The collocation grid and equations: N intervals, degree d, scheme.

    Parameters
    ----------
    intervals : int
        N >= 1 intervals of equal length, at most 100000.
    degree : int
        Collocation degree d in 1..9.
    scheme : str
        ``"legendre"`` (Gauss points, order 2d) or ``"radau"`` (order 2d - 1).
    nx, nu : int
        Sizes of the state and of the control (docs/design/collocation.md).
    """

    intervals: int = 100
    degree: int = 3
    scheme: str = "legendre"
    nx: int = 5
    nu: int = 2

    def __post_init__(self) -> None:
        object.__setattr__(self, "intervals", check_whole("intervals", self.intervals, 1, 100000))
        object.__setattr__(self, "degree", check_whole("degree", self.degree, 1, 9))
        object.__setattr__(self, "nx", check_whole("nx", self.nx, 1, 100))
        object.__setattr__(self, "nu", check_whole("nu", self.nu, 1, 100))
        check_choice("scheme", self.scheme, SCHEMES)

    def coefficients(self):
        """``tau`` (d + 1,) = [0, tau_1..tau_d] and :func:`casadi.collocation_coeff`'s ``C`` (d + 1, d),
        ``D`` (d + 1,), ``B`` (d,): derivatives of the Lagrange basis at the collocation points, its
        values at 1 (continuity) and the quadrature weights."""
        pts = ca.collocation_points(self.degree, self.scheme)
        C, D, B = ca.collocation_coeff(pts)
        return np.append(0.0, pts), np.array(C), np.array(D).ravel(), np.array(B).ravel()

    def interval_function(self, point: ca.Function, n_par: int) -> ca.Function:
        """Collocation equations of one interval of normalized length h.

        ``point(x, w, par) -> (xdot, L, omega)`` is the model at one point;
        returns ``G(x0[5], xc[5 x d], w[2], h, par) -> (defect[5 x d], x_end[5], J)``
        with ``defect_r = sum_j C[j, r] X_j - h T f(X_r, w)`` (T = par[1]).
        """
        d = self.degree
        _, C, D, B = self.coefficients()
        x0 = ca.SX.sym("x0", self.nx)
        xc = ca.SX.sym("xc", self.nx, d)
        w = ca.SX.sym("w", self.nu)
        h = ca.SX.sym("h")
        par = ca.SX.sym("par", n_par)
        T = par[1]
        X = [x0] + [xc[:, j] for j in range(d)]
        defects = []
        J = 0
        x_end = D[0] * x0
        for r in range(1, d + 1):
            xp = sum(C[j, r - 1] * X[j] for j in range(d + 1))
            f, L, _ = point(X[r], w, par)
            defects.append(xp - h * T * f)
            x_end = x_end + D[r] * X[r]
            J = J + B[r - 1] * L * h * T
        return ca.Function("interval", [x0, xc, w, h, par], [ca.horzcat(*defects), x_end, J],
                           ["x0", "xc", "w", "h", "par"], ["defect", "x_end", "J"])

    def interval_block(self, point: ca.Function, path: ca.Function, n_par: int) -> ca.Function:
        """``B(z, par) -> (g, J)`` of one interval: ``z = (X_i, XC_i, W_i, X_{i+1})`` (its slice of the decision
        vector), ``g`` its rows of the constraints (the collocation equations, the continuity, ``path`` at the
        d points and at the end), ``J`` its cost (:meth:`interval_function`, h = 1 / N)."""
        N, d, nx, nu = self.intervals, self.degree, self.nx, self.nu
        G = self.interval_function(point, n_par)
        z, par = ca.SX.sym("z", self._block + nx), ca.SX.sym("par", n_par)
        x0, xc, w, x1 = z[:nx], ca.reshape(z[nx:nx + nx * d], nx, d), z[nx + nx * d:nx + nx * d + nu], z[-nx:]
        defect, x_end, J = G(x0, xc, w, 1.0 / N, par)
        return ca.Function("interval_block", [z, par],
                           [ca.vertcat(ca.vec(defect), x_end - x1, path.map(d)(xc).T, path(x1)), J],
                           ["z", "par"], ["g", "J"])

    def nlp(self, point: ca.Function, path: ca.Function, n_par: int):
        """The NLP of the transcription: ``({"x", "p", "f", "g"}, path_rows)``.

        ``path(x) -> scalar`` is a path constraint imposed at every collocation
        point and interval end; ``path_rows`` (bool array over g) marks its rows,
        the others are equalities (collocation equations and continuity).
        """
        return interval_nlp(self.interval_block(point, path, n_par), self.intervals, self._block), self.path_rows()

    def path_rows(self) -> np.ndarray:
        """The rows of :meth:`nlp`'s constraints that are its path constraint (bool), interval after interval."""
        return np.concatenate([np.zeros(self.nx * self.degree + self.nx, bool), np.ones(self.degree + 1, bool)]
                              * self.intervals)

    def contact_path(self) -> ca.Function:
        """The contact bound's path function ``-z`` (the depth of the contact point (1) below the centre, the
        cosine of its polar angle) of a state whose entries 3 and 4 are u_o and v_o."""
        x = ca.SX.sym("x", self.nx)
        return ca.Function("depth", [x], [-model.contact_point(x[3], x[4])[2]])

    def contact_nlp(self, point: ca.Function, n_par: int):
        """:meth:`nlp` with the contact bound as the path constraint: ``-z >= cos(bound)`` (:meth:`contact_path`)
        at every collocation point and interval end."""
        return self.nlp(point, self.contact_path(), n_par)

    def contact_derivatives(self, point: ca.Function, n_par: int) -> dict:
        """The derivatives of :meth:`contact_nlp`'s NLP as options of :func:`casadi.nlpsol`, built interval by
        interval (:func:`interval_derivatives`)."""
        return interval_derivatives(self.interval_block(point, self.contact_path(), n_par), self.intervals,
                                    self._block)

    def contact_bounds(self, guess: Guess, start, final, contact_bound: float, path_rows):
        """``(x0, lbx, ubx, lbg, ubg)`` of the NLP of :meth:`contact_nlp`: ``start``, ``final`` fixed,
        ``|u_o|, |v_o| <= contact_bound``, the guess clipped into the bounds."""
        box = np.full(self.nx, np.inf)
        box[3:5] = contact_bound
        lbx, ubx = self.bounds(start, final, box)
        x0 = np.clip(self.pack(guess), lbx, ubx)
        lbg = np.where(path_rows, math.cos(contact_bound), 0.0)
        ubg = np.where(path_rows, np.inf, 0.0)
        return x0, lbx, ubx, lbg, ubg

    @property
    def _block(self) -> int:
        return self.nx * self.degree + self.nu + self.nx  # variables per interval after X0

    def pack(self, guess: Guess) -> np.ndarray:
        """The decision vector of a guess."""
        out = [guess.states[0]]
        for i in range(self.intervals):
            out += [guess.colloc[i].T.ravel(order="F"), guess.controls[i], guess.states[i + 1]]
        return np.concatenate(out)

    def unpack(self, v: np.ndarray):
        """``(states (N + 1, 5), colloc (N, d, 5), controls (N, 2))`` of a decision vector."""
        N, d, nx, nu = self.intervals, self.degree, self.nx, self.nu
        states, colloc, controls = np.zeros((N + 1, nx)), np.zeros((N, d, nx)), np.zeros((N, nu))
        states[0] = v[:nx]
        for i in range(N):
            blk = v[nx + i * self._block: nx + (i + 1) * self._block]
            colloc[i] = blk[: nx * d].reshape(d, nx)
            controls[i] = blk[nx * d: nx * d + nu]
            states[i + 1] = blk[nx * d + nu:]
        return states, colloc, controls

    def bounds(self, start, final, box):
        """Variable bounds: ``start`` and ``final`` fixed, every other state within ``+-box`` (nx,)."""
        N, d = self.intervals, self.degree
        box = np.asarray(box, float)
        wb = np.full(self.nu, np.inf)
        lb, ub = [np.asarray(start, float)], [np.asarray(start, float)]
        for i in range(N):
            lb += [np.tile(-box, d), -wb]
            ub += [np.tile(box, d), wb]
            last = i == N - 1
            lb.append(np.asarray(final, float) if last else -box)
            ub.append(np.asarray(final, float) if last else box)
        return np.concatenate(lb), np.concatenate(ub)

    def grid(self):
        """Normalized times of the interval starts (N,) and of the collocation points (N, d)."""
        N = self.intervals
        starts = np.arange(N) / N
        return starts, starts[:, None] + self.coefficients()[0][None, 1:] / N

    def check_guess(self, g: Guess) -> Guess:
        """``g`` if its arrays have this transcription's shapes and are finite; InputError otherwise."""
        want = {"states": (self.intervals + 1, self.nx), "colloc": (self.intervals, self.degree, self.nx),
                "controls": (self.intervals, self.nu)}
        for name, shape in want.items():
            arr = np.asarray(getattr(g, name), float)
            if arr.shape != shape or not np.all(np.isfinite(arr)):
                raise InputError(f"guess.{name} of shape {arr.shape} is not allowed: expected finite {shape}")
        return g

    def simulate(self, point: ca.Function, n_par: int, controls, par, x0=None) -> np.ndarray:
        """Solve the collocation equations interval by interval with fixed controls.

        This is the transcription used as a ``d``-stage implicit Runge-Kutta
        method (Gauss-Legendre or Radau IIA): no optimization. Returns the
        states at the interval boundaries, shape (N + 1, nx), units of R.
        """
        controls = np.asarray(controls, float)
        N, d = controls.shape[0], self.degree
        G = self.interval_function(point, n_par)
        xc = ca.SX.sym("xc", self.nx, d)
        x0s = ca.SX.sym("x0", self.nx)
        w = ca.SX.sym("w", self.nu)
        h = ca.SX.sym("h")
        p = ca.SX.sym("par", n_par)
        defect, x_end, _ = G(x0s, xc, w, h, p)
        res = ca.Function("res", [ca.vec(xc), ca.vertcat(x0s, w, h, p)], [ca.vec(defect)])
        rf = ca.rootfinder("sim", "newton", res, {"abstol": 1e-15, "abstolStep": 1e-16, "max_iter": 50,
                                                   "error_on_fail": False})
        end = ca.Function("end", [ca.vec(xc), x0s], [x_end])
        x = np.zeros(self.nx) if x0 is None else np.asarray(x0, float)
        out = [x]
        for i in range(N):
            z = interrupts.call(rf, np.tile(x, d), np.concatenate([x, controls[i], [1.0 / N], par]))
            x = np.array(end(z, x)).ravel()
            out.append(x)
        return np.array(out)


@dataclass(frozen=True)
class CollocationRun(CertifiedMotion):
    """What every collocation result holds first: the problem and how its OCP was set up.

    Attributes
    ----------
    problem : Problem
    cost : str
        Name of the cost (the planner's registry of costs).
    transcription : Transcription
        N, d, scheme.
    horizon : float
        T [s].
    turns : int
        m: psi is steered to ``goal.psi + 2 pi m``.
    guess : str
        Name of the initial guess.
    contact_bound : float
        Largest polar angle of the contact point from the south pole [rad].
    """

    method = "collocation"
    #: A collocation motion has no closed-form pieces, no legs of figure eights and no alternatives.
    pieces = ()
    legs = ()
    alternatives = ()

    problem: Problem
    cost: str
    transcription: Transcription
    horizon: float
    turns: int
    guess: str
    contact_bound: float
