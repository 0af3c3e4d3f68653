"""C code generation: a self-contained C99 planner for the robot's microcontroller.

Every model equation comes from the symbolic model through CasADi's :class:`~casadi.CodeGenerator` (the spin
of (13), the rotor rates (11), Montana's (6)-(10), the curve ODE (28)-(30) and its RK8 step for the on-board
certificate, the time law, the spectral step map of (31), (35)); the planner (``c_templates/planner.c``)
solves (32)-(33) like :mod:`rollplan.planners.geometric`, with its own complete enumeration on a graph over the
smaller leaf radius (the numpy search uses w or sigma graphs), for ``1/2 <= k <= k_max``, and certifies every
plan on board by RK8 with step doubling. :func:`generate` writes the library, a demo and a Makefile.

What is generated, the planner, its k range and the certificate: docs/design/c-planner.md.
"""

from __future__ import annotations

import logging
import math
import os
import re
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from ..core import model
from ..core.curves import A_MAX, figure_eight
from ..core.integrate import (
    DOP853_C,
    check_heading_structure,
    heading_free_rates,
    piece_rhs,
    rk8_formula,
    rk8_step,
    spectral_leaf,
)
from ..core.rewrite import algebraic
from ..errors import InputError, NoPlanError, OutputError, check_flag, show, show_limit
from ..execution.path import curve_piece_function
from ..outputs import check_folder, write_folder
from ..planners.geometric import GeometricPhasePlanner, leafmap
from ..planners.geometric import enumerate as enumerate_
from ..planners.geometric.compiled_search import DEFAULT_K_MAX
from ..planners.geometric.enumerate import K_MONOTONE
from ..problem import K_MAX, K_MIN, MAX_STEPS, Problem
from ..result import CERTIFICATE_TOLERANCE

__all__ = [
    "DEFAULT_STEPS_PER_LEAF",
    "AUTO_STEPS_PER_LEAF",
    "DEFAULT_PREFIX",
    "MAX_STEPS_PER_LEAF",
    "MAX_PREFIX_CHARS",
    "GeneratedCode",
    "model_functions",
    "leaf_function",
    "step_functions",
    "certificate_functions",
    "motion_functions",
    "DEFAULT_K_MAX",
    "CERT_TOL",
    "FLOAT_CERT_TOL",
    "generated_functions",
    "generate",
    "auto_steps_per_leaf",
    "reference_plan",
]

log = logging.getLogger(__name__)

#: Node intervals per leaf of the generated step map (10 graded panels x degree 24): accurate to STEP_MAP_TOL
#: on the whole admissible box for k <= DEFAULT_K_MAX (results/codegen_accuracy.json).
DEFAULT_STEPS_PER_LEAF = 240
#: Node intervals per leaf that ``steps_per_leaf="auto"`` tries, in this order: the first whose step map is accurate to
#: STEP_MAP_TOL up to k_max is taken. The last is the cap (MAX_STEPS_PER_LEAF), accurate up to K_MAX
#: (240 serves k_max = 5, 320 k_max = 10, 400 k_max = 16, 480 k_max = 20, 640 k_max = 30, 2000 k_max = 100).
AUTO_STEPS_PER_LEAF = (240, 320, 400, 480, 560, 640, 800, 1000, 1200, 1600, 2000)
#: Accuracy the step map must have on ``0 < a, b <= A_MAX``, ``k <= k_max`` for :func:`generate` to accept k_max.
STEP_MAP_TOL = 1e-10
#: Tolerance of the on-board certificate: residual + error bound [R and rad] (the project's tolerance).
CERT_TOL = CERTIFICATE_TOLERANCE
#: Steps of the RK8 certificate: a panel of width w gets ceil(w (CERT_BASE + max |psi'|) / CERT_DELTA) of them.
CERT_DELTA = 1.0
CERT_BASE = 2.0
#: The certificate's error bound is |x_2N - x_N| / CERT_SAFETY (Richardson's estimate for order 8 divides by 255).
CERT_SAFETY = 16.0
#: Tolerance of the certificate of a single-precision build (``generate(real="float")``): float rounding
#: alone leaves errors of 1e-6 R, and more near A_MAX, so such plans are good to this, not to CERT_TOL.
FLOAT_CERT_TOL = 1e-4
#: Stages of the RK8 formula (:data:`rollplan.core.integrate.DOP853_C`).
RK8_STAGES = len(DOP853_C)
#: Default name prefix of the generated C symbols and files.
DEFAULT_PREFIX = "rollplan"
#: Most node intervals per leaf (the accuracy of the step map stops improving long before).
MAX_STEPS_PER_LEAF = 2000
#: Longest prefix (it starts every C symbol and file name).
MAX_PREFIX_CHARS = 64

#: Largest |psi| [rad] the C planner accepts (its reduction modulo 2 pi is exact up to it).
PSI_MAX = 1e6


@dataclass(frozen=True)
class GeneratedCode:
    """What :func:`generate` wrote.

    Attributes
    ----------
    out : Path
        Output folder.
    prefix : str
        Prefix of the C symbols and files.
    steps_per_leaf : int
        Node intervals per leaf of the step map.
    files : tuple of Path
        Files written.
    code_bytes : int
        Size of the generated C sources and headers together [bytes].
    model_bytes : int
        Size of the CasADi-generated source ``<prefix>_model.c`` alone [bytes].
    work_doubles : int
        Static work memory of the planner [doubles].
    """

    out: Path
    prefix: str
    steps_per_leaf: int
    files: tuple
    code_bytes: int
    model_bytes: int
    work_doubles: int


# ----------------------------------------------------------------------------- functions


def model_functions(prefix: str = DEFAULT_PREFIX) -> list:
    """The model's pointwise functions, eqs. (6)-(10), (11), (13), as CasADi Functions.

    Returns
    -------
    list of casadi.Function
        ``<prefix>_omega_z(omega_xy[2], u_o, v_o, psi, k) -> omega_z`` (13);
        ``<prefix>_rotor_rates(omega[3], u_o, v_o, psi, j_xx, j_zz, j_r) -> phi_dot[2]`` (11);
        ``<prefix>_montana(omega[3], u_o, v_o, psi) -> rates[5]`` (6)-(10).
    """
    sx = ca.SX.sym
    wxy, w = sx("omega_xy", 2), sx("omega", 3)
    u_o, v_o, psi, k = sx("u_o"), sx("v_o"), sx("psi"), sx("k")
    j_xx, j_zz, j_r = sx("j_xx"), sx("j_zz"), sx("j_r")
    return [
        ca.Function(f"{prefix}_omega_z", [wxy, u_o, v_o, psi, k],
                    [model.omega_z_realizable(wxy, u_o, v_o, psi, k)],
                    ["omega_xy", "u_o", "v_o", "psi", "k"], ["omega_z"]),
        ca.Function(f"{prefix}_rotor_rates", [w, u_o, v_o, psi, j_xx, j_zz, j_r],
                    [model.rotor_rates(w, u_o, v_o, psi, j_xx, j_zz, j_r)],
                    ["omega", "u_o", "v_o", "psi", "j_xx", "j_zz", "j_r"], ["phi_dot"]),
        ca.Function(f"{prefix}_montana", [w, u_o, v_o, psi], [model.montana(w, u_o, v_o, psi)],
                    ["omega", "u_o", "v_o", "psi"], ["rates"]),
    ]


def _degree(steps_per_leaf, panels: int) -> int:
    if isinstance(steps_per_leaf, bool) or not isinstance(steps_per_leaf, (int, np.integer)) \
            or not 2 * panels <= steps_per_leaf <= MAX_STEPS_PER_LEAF or steps_per_leaf % panels:
        raise InputError(f"steps per leaf = {steps_per_leaf!r:.40} is not allowed: it must be a multiple of "
                         f"{panels} (the curve's panels) in [{2 * panels}, {MAX_STEPS_PER_LEAF}]")
    return int(steps_per_leaf) // panels


def _node_rates(curve, index: int) -> ca.Function:
    """``g(phi, r, k) -> (A, B, psi')`` along leaf ``index`` with radius ``r``, from (28)-(30).

    ``(A, B)`` are (u_a', v_a') at psi = 0 (:func:`rollplan.core.integrate.heading_free_rates`,
    which checks the structure the quadrature relies on); the leaf must depend on its own radius only.
    """
    f = piece_rhs(curve, index)
    check_heading_structure(f)
    full_p = ca.SX.sym("p", curve.n_params)
    others = [i for i in range(curve.n_params) if i != index]
    if others and ca.depends_on(f(ca.SX.sym("phi"), ca.SX.sym("x", 3), full_p, ca.SX.sym("k"), 0), full_p[others]):
        raise ValueError(f"leaf {index} depends on other parameters than its own radius")
    phi, r, k = ca.SX.sym("phi"), ca.SX.sym("r"), ca.SX.sym("k")
    params = ca.SX.zeros(curve.n_params)
    params[index] = r
    return ca.Function(f"leaf{index}_rates", [phi, r, k], [heading_free_rates(f)(phi, params, k, 0)])


def leaf_function(curve, index: int, degree: int, name: str, jacobian: bool = False) -> ca.Function:
    """One leaf of the curve by looped Chebyshev spectral integration of (28)-(30).

    ``leaf(x0[3], r, k) -> x_end[3]`` (MX, the nodes loop through ``map``).
    The panels are the piece's ``breaks``; each carries ``degree + 1`` nodes.
    With ``jacobian``, also ``d x_end / d x0`` (3x3, by CasADi's AD) and
    ``d x_end / d r`` (3x1, forward mode through the quadrature with the
    node rates' derivatives from CasADi's AD).
    """
    g = _node_rates(curve, index)
    x0, r, k = ca.MX.sym("x0", 3), ca.MX.sym("r"), ca.MX.sym("k")
    breaks = curve.pieces[index].breaks
    if not jacobian:
        x_end = spectral_leaf(g, breaks, degree, x0, r, k)
        return ca.Function(name, [x0, r, k], [x_end], ["x0", "r", "k"], ["x_end"])
    phi, rs, ks = ca.SX.sym("phi"), ca.SX.sym("r"), ca.SX.sym("k")
    val = g(phi, rs, ks)
    g_dr = ca.Function(f"{g.name()}_dr", [phi, rs, ks], [ca.cse(ca.vertcat(val, ca.jacobian(val, rs)))])
    x_end, jac_r = spectral_leaf(g_dr, breaks, degree, x0, r, k, derivative=True)
    return ca.Function(name, [x0, r, k], [x_end, ca.jacobian(x_end, x0), jac_r],
                       ["x0", "r", "k"], ["x_end", "jac_x0", "jac_r"])


def step_functions(steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX):
    """The step map of one figure-eight trace and its Jacobian, eqs. (28)-(31), (35).

    Returns
    -------
    step : casadi.Function
        ``<prefix>_step(ab[2], k) -> (shift[2], eta, direction)``: displacement
        (u_a, v_a) [R], holonomy eta [rad] and ``atan2(v_a, u_a)`` [rad] of one
        trace from zero state with gamma = 0.
    step_jac : casadi.Function
        ``<prefix>_step_jac(ab[2], k) -> (shift[2], eta, direction, jac[4x2])``
        with ``jac`` the Jacobian of ``(shift, eta, direction)`` by ``(a, b)``
        (column-major). It is assembled by the chain rule from the leaves'
        Jacobians, so each leaf is differentiated in its own radius only.
    """
    curve = figure_eight()
    degree = _degree(steps_per_leaf, len(curve.pieces[0].breaks) - 1)
    ab, k = ca.MX.sym("ab", 2), ca.MX.sym("k")
    x = ca.MX.zeros(3)
    dx = ca.MX.zeros(3, 2)   # d x / d (a, b)
    for i in range(len(curve.pieces)):
        leaf = leaf_function(curve, i, degree, f"{prefix}_leaf{i}", jacobian=True)
        x, j_x0, j_r = leaf(x, ab[i], k)
        dx = ca.mtimes(j_x0, dx)
        dx = ca.horzcat(*[dx[:, c] + (j_r if c == i else 0) for c in range(2)])
    direction = ca.atan2(x[1], x[0])
    ddir = (x[0] * dx[1, :] - x[1] * dx[0, :]) / (x[0] ** 2 + x[1] ** 2)
    names_in, names_out = ["ab", "k"], ["shift", "eta", "direction"]
    step = ca.Function(f"{prefix}_step", [ab, k], [x[:2], x[2], direction], names_in, names_out)
    step_jac = ca.Function(f"{prefix}_step_jac", [ab, k], [x[:2], x[2], direction, ca.vertcat(dx, ddir)],
                           names_in, names_out + ["jac"])
    return step, step_jac


def certificate_functions(prefix: str = DEFAULT_PREFIX) -> list:
    """The curve ODE (28)-(30) and one RK8 step of it, per leaf, for the on-board certificate.

    Returns
    -------
    list of casadi.Function
        ``<prefix>_rhs<i>(phi, x[3], p[2], k, gamma) -> xdot[3]``: (28)-(30) along leaf ``i`` of the
        figure eight (31), (35) rotated by gamma (:func:`rollplan.core.integrate.piece_rhs`), for
        i = 0, 1; then ``<prefix>_rk8_<i>(x[3], cos_t[12], sin_t[12], h, p[2], k, cos_gamma, sin_gamma) ->
        x_next[3]``: one step from phi = t to t + h of the eighth-order Runge-Kutta formula of DOP853
        (:func:`rollplan.core.integrate.rk8_formula`) of it, given the cosine and sine of phi at its 12 stages,
        ``t + DOP853_C[s] h``, and of gamma (the right side depends on phi and gamma through them only, checked by
        :func:`algebraic`): the C certificate gets them by rotating a per-panel table, without a trigonometric call
        per stage. Last ``<prefix>_rates<i>(cos_phi, sin_phi, p[2], k, cos_gamma, sin_gamma) -> rates[2]``: the turn
        rate psi' of (30) at 0 and at k (it does not depend on the state), from which the certificate sets its steps.

    The C certificate integrates the whole n-step motion with these steps from the start state, the
    state-dependent right side as it is (no use of the heading structure the planner's leaf map
    relies on, no quadrature), so its result is independent of the planner's. The functions are written in
    :func:`algebraic` form (no trigonometric function of an inverse trigonometric result).
    """
    curve = figure_eight()
    rhs = [piece_rhs(curve, i) for i in range(len(curve.pieces))]
    named = [algebraic(ca.Function(f"{prefix}_rhs{i}", f.sx_in(), f.call(f.sx_in()), f.name_in(), f.name_out()))
             for i, f in enumerate(rhs)]
    steps = []
    for i, g0 in enumerate(named):
        g = algebraic(g0, angles=(0, 4))    # (cos phi, sin phi, x, p, k, cos gamma, sin gamma) -> xdot
        x, h, c, s = ca.SX.sym("x", 3), ca.SX.sym("h"), ca.SX.sym("cos_t", RK8_STAGES), ca.SX.sym("sin_t", RK8_STAGES)
        params = [ca.SX.sym(g.name_in(j), g.sparsity_in(j)) for j in range(3, g.n_in())]
        x_next = rk8_formula(x, h, lambda q, xs, g=g, c=c, s=s, params=params: g(c[q], s[q], xs, *params))
        steps.append(algebraic(ca.Function(f"{prefix}_rk8_{i}", [x, c, s, h, *params], [x_next],
                                           ["x", "cos_t", "sin_t", "h", *g.name_in()[3:]], ["x_next"])))
    rates = []
    for i, g0 in enumerate(named):
        phi, p, k, gamma = ca.SX.sym("phi"), ca.SX.sym("p", g0.sparsity_in(2)), ca.SX.sym("k"), ca.SX.sym("gamma")
        turn_rates = ca.vertcat(g0(phi, ca.DM.zeros(3), p, 0.0, gamma)[2], g0(phi, ca.DM.zeros(3), p, k, gamma)[2])
        rates.append(algebraic(ca.Function(f"{prefix}_rates{i}", [phi, p, k, gamma], [turn_rates],
                                           ["phi", "p", "k", "gamma"], ["rates"]), angles=(0, 3)))
    return named + steps + rates


def motion_functions(prefix: str = DEFAULT_PREFIX) -> list:
    """What the C time law needs along each leaf, per unit of the leaf's parameter phi.

    Returns
    -------
    list of casadi.Function
        ``<prefix>_piece<i>(phi, x[5], p[2], k, gamma, jxx, jzz, jr) -> (xdot[5], uv[2], g[2])`` for leaf i = 0, 1:
        d/dphi of (u_a, v_a, psi, rotor angle 1, rotor angle 2), the contact coordinates (u_o, v_o) (24)-(25)
        and the rotor rates per unit phi' (11) at psi = x[2]
        (:func:`rollplan.execution.path.curve_piece_function`, the function the Python time laws sample);
        then ``<prefix>_rk8x_<i>(x[5], t, h, p[2], k, gamma, jxx, jzz, jr) -> x_next[5]``, one RK8 step of it.
        All in :func:`algebraic` form.
    """
    curve = figure_eight()
    pieces, steps = [], []
    for i in range(len(curve.pieces)):
        f = curve_piece_function(curve, i)
        phi, x, p = ca.SX.sym("phi"), ca.SX.sym("x", 5), ca.SX.sym("p", curve.n_params)
        k, gamma, jxx, jzz, jr = (ca.SX.sym(n) for n in ("k", "gamma", "jxx", "jzz", "jr"))
        xdot, uv, _, g, _, _ = f(phi, x[2], p, gamma, k, jxx, jzz, jr)
        args, names = [phi, x, p, k, gamma, jxx, jzz, jr], ["phi", "x", "p", "k", "gamma", "jxx", "jzz", "jr"]
        piece = ca.Function(f"{prefix}_piece{i}", args, [xdot, uv, g], names, ["xdot", "uv", "g"])
        pieces.append(algebraic(piece))
        rhs = ca.Function("rhs", args, [xdot], names, ["xdot"])
        rk = rk8_step(rhs)
        steps.append(algebraic(ca.Function(f"{prefix}_rk8x_{i}", rk.sx_in(), rk.call(rk.sx_in()), rk.name_in(),
                                           rk.name_out())))
    return pieces + steps


def generated_functions(steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX) -> list:
    """Every function that :func:`generate` writes to C, in order (the symbolic twins)."""
    return [*model_functions(prefix), *step_functions(steps_per_leaf, prefix), *certificate_functions(prefix),
            *motion_functions(prefix)]


def rk8_trace(ab, k: float, gamma: float = 0.0, delta: float = 0.1, x0=(0.0, 0.0, 0.0)) -> np.ndarray:
    """(u_a, v_a, psi) after one trace of the figure eight by fixed RK8 steps, as the C certificate does it.

    Each panel of a leaf gets ``ceil(w (CERT_BASE + max |psi'|) / delta)`` equal steps (``max |psi'|`` over five
    points of the panel; psi' of (30) does not depend on the state). The C certificate uses
    ``delta = CERT_DELTA`` and step doubling; :func:`generate` uses a small ``delta`` to check the step map.
    """
    curve = figure_eight()
    x = np.asarray(x0, float)
    p = np.asarray(ab, float)
    for i, piece in enumerate(curve.pieces):
        f = piece_rhs(curve, i)
        step = rk8_step(f)
        for b0, b1 in zip(piece.breaks[:-1], piece.breaks[1:]):
            w = b1 - b0
            rate = max(abs(float(f(b0 + q * w / 4, ca.DM.zeros(3), p, k, gamma)[2])) for q in range(5))
            n = int(np.ceil(w * (CERT_BASE + rate) / delta))
            phis = b0 + np.arange(n) * (w / n)
            xs = step.mapaccum(n)(x, phis.reshape(1, -1), w / n, p, k, gamma)
            x = np.array(xs[:, -1]).ravel()
    return x


def _valid_k_max(k_max) -> float:
    if isinstance(k_max, bool) or not isinstance(k_max, (int, float, np.integer, np.floating)) \
            or not K_MONOTONE <= float(k_max) <= K_MAX:
        raise InputError(f"k_max = {k_max!r} is not allowed: it must be a number in [{K_MONOTONE:g}, {K_MAX:g}]")
    return float(k_max)


#: The corners of the admissible box where the step map is checked (its error peaks near A_MAX).
_CHECK_LEAVES = ((A_MAX, A_MAX), (A_MAX, 0.05), (0.05, A_MAX))


@lru_cache(maxsize=32)
def _fine_trace(ab: tuple, k: float) -> tuple:
    return tuple(rk8_trace(ab, k))


def _step_map_error(k_max: float, step: ca.Function) -> float:
    """Largest error of the step map ``step`` against fine RK8 traces (:func:`rk8_trace`) at the corners of the
    admissible box, ``a, b in {0.05, A_MAX}``, for ``k in {0, k_max / 2, k_max}``."""
    worst = 0.0
    for k in (0.0, 0.5 * k_max, k_max):
        for ab in _CHECK_LEAVES:
            shift, eta, _ = (np.array(v).ravel() for v in step(ab, k))
            worst = max(worst, float(np.max(np.abs(np.concatenate([shift, eta]) - np.array(_fine_trace(ab, k))))))
    return worst


def _check_k_max(k_max, steps_per_leaf: int, step: ca.Function) -> float:
    """``k_max`` as a float if the step map is accurate to STEP_MAP_TOL up to it; InputError otherwise.

    The step map's error grows with k and with the leaf radii (the turn rate psi' peaks as the leaf
    nears the singular equator); it is measured by :func:`_step_map_error`.
    """
    k_max = _valid_k_max(k_max)
    worst = _step_map_error(k_max, step)
    if not worst <= STEP_MAP_TOL:
        raise InputError(f"k_max = {k_max:g} is not allowed with {steps_per_leaf} steps per leaf: the step map "
                         f"is off by {worst:.1e} (more than {STEP_MAP_TOL:g}) near A_MAX; give more steps per leaf "
                         f"(auto: the smallest that serves it) or a smaller k_max")
    return k_max


def auto_steps_per_leaf(k_max) -> int:
    """The smallest of :data:`AUTO_STEPS_PER_LEAF` whose step map is accurate to STEP_MAP_TOL up to ``k_max`` (the
    check of :func:`_check_k_max`); InputError naming the cap when none is."""
    k_max = _valid_k_max(k_max)
    worst = math.inf
    for steps_per_leaf in AUTO_STEPS_PER_LEAF:
        worst = _step_map_error(k_max, step_functions(steps_per_leaf)[0])
        if worst <= STEP_MAP_TOL:
            return steps_per_leaf
    raise InputError(f"k_max = {k_max:g} is not allowed: even the largest automatic size, {AUTO_STEPS_PER_LEAF[-1]} "
                     f"steps per leaf, leaves the step map off by {worst:.1e} (more than {STEP_MAP_TOL:g}) near "
                     f"A_MAX; give a smaller k_max")


def reference_plan(target, steps: int, k: float, near=None, branch: int | None = None):
    """The Python planner's certified plan for the same target, for cross-checking the C planner.

    :class:`rollplan.planners.geometric.GeometricPhasePlanner` on ``Problem(target, k, steps)``: the shortest
    plan over all branches (the C planner's default), or on ``branch`` only; with ``near = (a, b)`` the plan
    of all certified ones closest to it. None if there is none. The planner runs its numpy search, not the
    compiled C search it would otherwise call: the comparison is between two implementations.
    """
    problem = Problem(tuple(float(x) for x in target), k=k, steps=steps)
    try:
        best = GeometricPhasePlanner(compiled_search=False).solve(problem, all_solutions=near is not None,
                                                                  branch=branch)
    except NoPlanError:
        return None
    if near is None:
        return best
    return min((best,) + best.alternatives, key=lambda q: (max(abs(q.a - near[0]), abs(q.b - near[1])), q.a + q.b))


# ----------------------------------------------------------------------------- C sources

_PRAGMA = """/* Generated by rollplan.codegen from the symbolic model with CasADi's CodeGenerator. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
"""


_COMMENT_OR_STRING = re.compile(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\])*"', re.S)
_LITERAL = re.compile(r"(?<![\w.])((?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
_MATH = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "pow", "sqrt",
         "hypot", "fabs", "floor", "ceil", "fmod", "fmin", "fmax", "copysign")
_MATH_CALL = re.compile(r"(?<![\w.])(" + "|".join(_MATH) + r")(\s*\()")


def _to_float(code: str) -> str:
    """C code with every floating literal suffixed ``f`` and the double math functions by their float names.

    CasADi's CodeGenerator with ``casadi_real = float`` changes the typedef only: it still writes double
    literals and ``sin``, ``sqrt`` ..., which promote every expression to double (software double on a
    single-precision FPU). Comments and string literals are left alone. (``<tgmath.h>`` would do this,
    but newlib's does not compile with GCC.) The Makefile's ``-Wdouble-promotion -Werror`` and
    ``make check-static`` check that nothing double is left.
    """
    out, i = [], 0
    for m in _COMMENT_OR_STRING.finditer(code):
        out.append(_MATH_CALL.sub(r"\1f\2", _LITERAL.sub(r"\1f", code[i:m.start()])))
        out.append(m.group(0))
        i = m.end()
    out.append(_MATH_CALL.sub(r"\1f\2", _LITERAL.sub(r"\1f", code[i:])))
    return "".join(out)


def _check_real(real) -> str:
    if real not in ("double", "float"):
        raise InputError(f"real = {real!r} is not allowed: it must be 'double' or 'float'")
    return real


def _check_prefix(prefix) -> str:
    if not isinstance(prefix, str) or not prefix.isidentifier() or not prefix.isascii() or prefix.startswith("_") \
            or len(prefix) > MAX_PREFIX_CHARS:
        raise InputError(f"prefix = {show(prefix)} is not allowed: it must be a C identifier (letters, digits, _) "
                         f"of at most {MAX_PREFIX_CHARS} characters")
    return prefix


#: Files for the microcontroller builds (QEMU's mps2-an500 and mps2-an386 boards), copied into the output.
#: What the generated Makefile builds in its folder (its ``clean`` target removes them).
_BUILD_PRODUCTS = ("plan_demo", "plan_demo.o", "@PREFIX@_planner.o", "@PREFIX@_model.o", "lib@PREFIX@.a",
                   "lib@PREFIX@.so", "build")
_EMBEDDED = ("startup.c", "mps2-common.ld", "mps2-an500.ld", "mps2-an386.ld", "planner_only.c", "stack_bound.py")


#: 2 pi to 50 digits.
_TWO_PI_DIGITS = "6.2831853071795864769252867665590057683943387987502"


def _two_pi_parts() -> dict:
    """2 pi as TWO_PI_1 + TWO_PI_2 + TWO_PI_3, the first two with 32 significant bits, so that m * TWO_PI_1 and
    m * TWO_PI_2 are exact for |m| < 2^21 (Cody and Waite's argument reduction, used by the C planner)."""
    from fractions import Fraction

    parts, rest = [], Fraction(_TWO_PI_DIGITS)
    for _ in range(2):
        e = math.frexp(float(rest))[1]
        part = Fraction(math.floor(rest * 2 ** (32 - e)), 2 ** (32 - e))
        parts.append(float(part))
        rest -= part
    parts.append(float(rest))
    return {f"@TWO_PI_{i + 1}@": repr(p) for i, p in enumerate(parts)}


def _enumeration_constants(k_max: float) -> dict:
    """The constants of :mod:`rollplan.planners.geometric.leafmap` and :mod:`~rollplan.planners.geometric.enumerate`
    the C planner uses, and the sizes of its static tables for ``k <= k_max``."""
    if leafmap.ORDER % 2:
        raise ValueError("the C leaf map evaluates the nodes chi < pi only (symmetry): it needs an even ORDER")
    x, w = np.polynomial.legendre.leggauss(leafmap.ORDER)
    buckets = [(kk, p) for kk, p in leafmap.BUCKETS if kk < k_max] + [next((kk, p) for kk, p in leafmap.BUCKETS
                                                                           if kk >= k_max)]
    # the table's radii (enumerate.table_radii): their number grows with k for k >= 1/2 (E is monotone, its
    # steps grow with k); the cell of the last radius is one more
    ntable = 1 + max(enumerate_.table_radii(kk, enumerate_.TABLE_STEP, enumerate_.TABLE_PHASE,
                                            enumerate_.TABLE_INV_S).size for kk in (K_MIN, K_MONOTONE, k_max))
    if ntable >= 2 ** 16:
        raise ValueError(f"the rho table at k_max = {k_max:g} needs {ntable} radii: its buckets hold 16-bit indices")
    return {
        "@ORDER@": str(leafmap.ORDER),
        "@GAUSS_X@": ", ".join(repr(float(v)) for v in x),
        "@GAUSS_W@": ", ".join(repr(float(v)) for v in w),
        "@NBUCKET@": str(len(buckets)),
        "@BUCKET_K@": ", ".join(repr(float(kk)) for kk, _ in buckets),
        "@BUCKET_P@": ", ".join(str(p) for _, p in buckets),
        "@MAX_PANELS@": str(buckets[-1][1]),
        "@PHASE_STEP@": repr(enumerate_.PHASE_STEP),
        "@X_STEP@": repr(enumerate_.X_STEP),
        "@SIGMA_STEP@": repr(enumerate_.SIGMA_STEP),
        "@K_MONOTONE@": repr(float(enumerate_.K_MONOTONE)),
        "@HERMITE_REL@": repr(enumerate_.HERMITE_REL),
        "@POLISH_STEP@": repr(enumerate_.POLISH_STEP),
        "@POLISH_BRACKET@": repr(enumerate_.POLISH_BRACKET),
        "@NOT_A_ROOT@": repr(enumerate_.NOT_A_ROOT),
        "@SAFETY@": repr(enumerate_.SAFETY),
        "@MIN_WIDTH@": repr(enumerate_.MIN_WIDTH),
        "@TABLE_PHASE@": repr(enumerate_.TABLE_PHASE),
        "@TABLE_STEP@": repr(enumerate_.TABLE_STEP),
        "@TABLE_INV_S@": repr(enumerate_.TABLE_INV_S),
        "@NTABLE@": str(ntable),
    }


def _template(name: str) -> str:
    return (Path(__file__).with_name("c_templates") / name).read_text()


def generate(out, steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX,
             k_max: float = DEFAULT_K_MAX, real: str = "double", overwrite: bool = False) -> GeneratedCode:
    """Write the C99 library, ``plan_demo.c`` and a ``Makefile`` into folder ``out``.

    Parameters
    ----------
    out : path
        Output folder (created if missing; its parent must exist). It appears whole or not at all; an
        existing folder must hold only files that ``generate`` wrote there (and the products of their
        Makefile), else it is refused unless ``overwrite`` (:func:`rollplan.outputs.write_folder`).
    steps_per_leaf : int or "auto"
        Node intervals per leaf of the step map (a multiple of the 10 panels); ``"auto"``: the smallest of
        :data:`AUTO_STEPS_PER_LEAF` accurate up to ``k_max`` (:func:`auto_steps_per_leaf`).
    prefix : str
        Prefix of the C symbols and file names.
    k_max : float
        Largest inertia ratio the generated planner accepts (status 2 above it); refused unless the
        step map is accurate to STEP_MAP_TOL up to it (:func:`_check_k_max`).
    real : {"double", "float"}
        C type of every number (``casadi_real``). ``"float"`` is for single-precision FPUs (Cortex-M4F):
        no double operation is left, and plans are certified to FLOAT_CERT_TOL, not CERT_TOL.
    overwrite : bool
        Write into an existing folder that holds other files too, replacing those of the names written
        (the others are kept).

    Returns
    -------
    GeneratedCode
    """
    prefix = _check_prefix(prefix)
    real = _check_real(real)
    out = check_folder(out, overwrite=check_flag("overwrite", overwrite))   # refused before any work
    if isinstance(steps_per_leaf, str) and steps_per_leaf == "auto":
        steps_per_leaf = auto_steps_per_leaf(k_max)                     # refused before anything is written
    _degree(steps_per_leaf, len(figure_eight().pieces[0].breaks) - 1)   # refused before anything is written
    funcs = generated_functions(steps_per_leaf, prefix)
    step = funcs[3]
    k_max = _check_k_max(k_max, steps_per_leaf, step)                  # refused before anything is written
    curve = figure_eight()
    breaks = curve.pieces[0].breaks
    if any(tuple(piece.breaks) != tuple(breaks) for piece in curve.pieces):
        raise ValueError("the C certificate assumes the leaves share their panels")
    lib = f"{prefix}_model"
    cg = ca.CodeGenerator(f"{lib}.c", {"with_header": True, "casadi_real": real})
    for f in funcs:
        cg.add(f)
    try:
        with tempfile.TemporaryDirectory() as tmp:
            cg.generate(tmp + os.sep)
            model_c = _PRAGMA + (Path(tmp) / f"{lib}.c").read_text()
            model_h = (Path(tmp) / f"{lib}.h").read_text()
    except (OSError, RuntimeError) as exc:
        raise OutputError(f"CasADi's generated code cannot be written to a temporary folder ({tempfile.gettempdir()}): "
                          f"{str(exc).splitlines()[-1][:100]}") from None
    sizes = {name: max(int(getattr(f, name)()) for f in funcs[3:])
             for name in ("sz_arg", "sz_res", "sz_iw", "sz_w")}
    subs = {
        "@PREFIX@": prefix,
        "@PREFIX_UPPER@": prefix.upper(),
        "@SZ_ARG@": str(sizes["sz_arg"]),
        "@SZ_RES@": str(sizes["sz_res"]),
        "@SZ_IW@": str(max(sizes["sz_iw"], 1)),
        "@SZ_W@": str(max(sizes["sz_w"], 1)),
        "@A_MAX@": repr(float(A_MAX)),
        "@K_MIN@": repr(float(K_MIN)),
        "@PSI_MAX@": repr(PSI_MAX),
        **_two_pi_parts(),
        **_enumeration_constants(k_max),
        "@STEPS_PER_LEAF@": str(int(steps_per_leaf)),
        "@REAL@": real,
        "@K_MAX@": repr(k_max),
        "@MAX_STEPS@": show_limit(MAX_STEPS),
        "@CERT_TOL@": repr(CERT_TOL if real == "double" else FLOAT_CERT_TOL),
        "@REAL_TINY@": "DBL_MIN" if real == "double" else "FLT_MIN",
        "@REAL_EPS@": "DBL_EPSILON" if real == "double" else "FLT_EPSILON",
        "@REAL_MAX@": "DBL_MAX" if real == "double" else "FLT_MAX",
        "@ACCURACY@": f"plans are certified to {CERT_TOL:g}." if real == "double" else
                      f"single precision: plans are certified to {FLOAT_CERT_TOL:g} (R and rad) only.",
        "@CERT_DELTA@": repr(CERT_DELTA),
        "@CERT_BASE@": repr(CERT_BASE),
        "@CERT_SAFETY@": repr(CERT_SAFETY),
        "@NPANEL@": str(len(breaks) - 1),
        "@RK8_STAGES@": str(RK8_STAGES),
        "@RK8_C@": ", ".join(repr(float(c)) for c in DOP853_C),
        "@BREAKS@": ", ".join(repr(float(b)) for b in breaks),
        "@QEMU_TOL@": "1e-12" if real == "double" else "1e-5",
        "@M4F_EXTRA@": "" if real == "double" else "-Wdouble-promotion",
    }

    def fill(text: str) -> str:
        for key, value in subs.items():
            text = text.replace(key, value)
        return text

    if real == "float":
        model_c = _to_float(model_c)
    glue = {name: fill(_template(template)) for name, template in
            ((f"{prefix}.h", "planner.h"), (f"{prefix}_planner.c", "planner.c"))}
    if real == "float":
        glue = {name: _to_float(text) for name, text in glue.items()}
    files = {
        f"{lib}.c": model_c,
        f"{lib}.h": model_h,
        **glue,
        "plan_demo.c": fill(_template("plan_demo.c")),
        "Makefile": fill(_template("Makefile")),
        **{name: fill(_template(name)) for name in _EMBEDDED},
    }
    products = [name.replace("@PREFIX@", prefix) for name in _BUILD_PRODUCTS]
    write_folder(out, {name: text.encode() for name, text in files.items()}, overwrite=overwrite, products=products)
    written = [out / name for name in files]
    code_bytes = sum(len(t.encode()) for n, t in files.items() if n.endswith((".c", ".h")))
    work = sizes["sz_w"]
    log.info("wrote %s: %d bytes of C, %d doubles of work memory", out, code_bytes, work)
    return GeneratedCode(out, prefix, int(steps_per_leaf), tuple(written), code_bytes, len(model_c.encode()), work)
