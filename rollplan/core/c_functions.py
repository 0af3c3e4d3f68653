"""The model functions that the C planner calls, as CasADi Functions, and their C code.

Every model equation the C planner needs, from the symbolic model (:mod:`.model`, :mod:`.integrate`): the spin of
(13), the rotor rates (11), Montana's (6)-(10), the spectral step map of (31), (35) and its Jacobian, the curve ODE
(28)-(30) and its RK8 step for the on-board certificate, the time law along each leaf. :func:`model_code` writes
them to C with CasADi's :class:`~casadi.CodeGenerator` (in this process), :func:`to_float` turns that C into
single precision. What is generated and why: docs/design/c-planner.md.
"""

from __future__ import annotations

import os
import re
import tempfile
from pathlib import Path

import casadi as ca
import numpy as np

from ..errors import InputError, OutputError
from . import families, model
from .curves import Curve, Piece
from .integrate import (
    DOP853_C,
    check_heading_structure,
    curve_piece_function,
    heading_free_rates,
    piece_rhs,
    rk8_formula,
    rk8_step,
    spectral_leaf,
)
from .rewrite import algebraic

__all__ = [
    "PHASE",
    "POLYGON_PANELS",
    "half_angle_leaf",
    "c_curve",
    "DEFAULT_STEPS_PER_LEAF",
    "DEFAULT_PREFIX",
    "MAX_STEPS_PER_LEAF",
    "RK8_STAGES",
    "MATH_FUNCTIONS",
    "model_functions",
    "leaf_function",
    "step_functions",
    "certificate_functions",
    "motion_functions",
    "generated_functions",
    "leaf_degree",
    "model_code",
    "DM_PRECISION",
    "to_float",
]

#: Node intervals per leaf of the generated step map (10 graded panels x degree 24): accurate to 1e-10
#: (rollplan.codegen's STEP_MAP_TOL) on the whole admissible box for k <= 5 (results/codegen_accuracy.json).
DEFAULT_STEPS_PER_LEAF = 240
#: Most node intervals per leaf (the accuracy of the step map stops improving long before).
MAX_STEPS_PER_LEAF = 2000
#: Stages of the RK8 formula (:data:`rollplan.core.integrate.DOP853_C`).
RK8_STAGES = len(DOP853_C)
#: Default name prefix of the generated C symbols and files.
DEFAULT_PREFIX = "rollplan"


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


def leaf_degree(steps_per_leaf, panels: int) -> int:
    """Chebyshev degree per panel for ``steps_per_leaf`` node intervals per leaf of ``panels`` panels (InputError
    unless a multiple of them in range)."""
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


def step_functions(steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX,
                   curve: str = "circles"):
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
    curve = c_curve(curve)
    degree = leaf_degree(steps_per_leaf, len(curve.pieces[0].breaks) - 1)
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


#: The C certificate's phase of each leaf family: its generated right sides take cos and sin of ``PHASE * phi``
#: (the Viviani lobe has ``sin(phi / 2)``, a polygon leaf is one piece in the half angle: :func:`half_angle_leaf`).
PHASE = {"circles": 1.0, "viviani": 0.5, "triangle": 0.5, "square": 0.5}
#: Panels of a polygon leaf in the C planner (spread over its edges): a divisor of every automatic step-map size.
POLYGON_PANELS = 20


def half_angle_leaf(curve: str, t, a, side: float = 1.0):
    """Point (3,) of the leaf of family ``curve`` (not circles) of size ``a`` on ``side`` at the half angle
    ``t = phi / 2`` in [0, pi], written with ``cos t`` and ``sin t`` only (the C certificate's form).

    Viviani: :func:`.families.viviani_point` with ``sin phi = 2 sin t cos t``, ``sin^2(phi / 2) = sin^2 t``. A
    polygon of N edges is one piece: edge j (``cos t`` between ``cos((j + 1) pi / N)`` and ``cos(j pi / N)``) is
    the great-circle arc ``normalize((1 - w) S_j + w S_{j+1})`` between its corners
    (:func:`.families.polygon_vertices`),
    ``w = (1 - (-1)^j T_N(cos t)) / 2`` (``T_N`` Chebyshev's polynomial, ``cos(N t)``): the same edges as
    :func:`.families.figure_eight`, traced at a speed that vanishes at every corner, so the right side (28)-(30),
    linear in the speed, is zero and continuous there whichever edge a rounded ``cos t`` selects."""
    st, ct = ca.sin(t), ca.cos(t)
    if curve == "viviani":
        c = ca.sqrt(1 - a * a)
        return ca.vertcat(2 * a * a * st * ct, side * 2 * a * c * st, -(1 - 2 * a * a * st * st))
    corners = [ca.vertcat(*v) for v in ((0.0, 0.0, -1.0), *families.polygon_vertices(curve, a, side),
                                        (0.0, 0.0, -1.0))]
    n = len(corners) - 1
    cheb = {3: 4 * ct**3 - 3 * ct, 4: 8 * ct**4 - 8 * ct**2 + 1}[n]
    # the edge's corners and sign (-1)^j are chosen first, so that one edge, not every edge, is evaluated (and
    # differentiated) per point
    start, end, sign = corners[n - 1], corners[n], float((-1) ** (n - 1))
    for j in reversed(range(n - 1)):
        on = ct > np.cos((j + 1) * np.pi / n)
        start, end = ca.if_else(on, corners[j], start), ca.if_else(on, corners[j + 1], end)
        sign = ca.if_else(on, float((-1) ** j), sign)
    w = (1 - sign * cheb) / 2
    q = (1 - w) * start + w * end
    return q / ca.norm_2(q)


def c_curve(curve: str):
    """The figure eight of family ``curve`` as the C planner integrates it, one piece per leaf (parameters
    ``(a, b)``, phi in [0, 2 pi]): the circles' and the Viviani lobes' of :func:`.families.figure_eight`; a polygon's
    edges as one piece (:func:`half_angle_leaf` at ``t = phi / 2``), :data:`POLYGON_PANELS` panels spread over the
    edges, graded towards the corners."""
    if curve in ("circles", "viviani"):
        return families.figure_eight(curve)
    edges = families.pieces_per_leaf(curve)
    breaks = [0.0]
    for j in range(edges):
        panels = POLYGON_PANELS // edges + (j < POLYGON_PANELS % edges)
        tau = 0.5 * (1 - np.cos(np.pi * np.arange(1, panels + 1) / panels))
        breaks += list(2 * (j + tau) * np.pi / edges)
    breaks[-1] = 2 * np.pi

    def leaf(index, side):
        return Piece(lambda phi, p: half_angle_leaf(curve, phi / 2, p[index], side), tuple(breaks),
                              lambda p: families.leaf_length(curve, float(np.atleast_1d(p)[index])))

    return Curve(pieces=(leaf(0, 1.0), leaf(1, -1.0)), param_names=("a", "b"))


def _half_angle_rhs(curve, index: int) -> ca.Function:
    """(28)-(30) along leaf ``index`` of the figure eight of family ``curve`` per unit phi, as a function of the
    half angle ``t = phi / 2`` (:func:`half_angle_leaf`): its rates in t halved."""
    t, params, k, gamma, x = ca.SX.sym("phi"), ca.SX.sym("p", 2), ca.SX.sym("k"), ca.SX.sym("gamma"), ca.SX.sym("x", 3)
    point = model.rot_z(gamma) @ half_angle_leaf(curve, t, params[index], (1.0, -1.0)[index])
    rhs, psi = model.curve_rhs(point, t, k)
    rhs = 0.5 * ca.substitute(rhs, psi, x[2])
    return ca.Function(f"rhs{index}", [t, x, params, k, gamma], [rhs], ["phi", "x", "p", "k", "gamma"], ["xdot"])


def certificate_functions(prefix: str = DEFAULT_PREFIX, curve: str = "circles") -> list:
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
    rhs = [_half_angle_rhs(curve, i) if PHASE[curve] != 1.0 else piece_rhs(families.figure_eight(curve), i)
           for i in range(2)]
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


def motion_functions(prefix: str = DEFAULT_PREFIX, curve: str = "circles") -> list:
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
    curve = c_curve(curve)
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


def generated_functions(steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX,
                        curve: str = "circles") -> list:
    """Every function that :func:`generate` writes to C, in order (the symbolic twins), along the figure eight of
    the leaf family ``curve`` (:data:`rollplan.core.families.FAMILIES`; one piece per leaf: circles, viviani)."""
    return [*model_functions(prefix), *step_functions(steps_per_leaf, prefix, curve),
            *certificate_functions(prefix, curve), *motion_functions(prefix, curve)]



# ----------------------------------------------------------------------------- C code

_PRAGMA = """/* Generated by rollplan from the symbolic model with CasADi's CodeGenerator. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
"""


#: CasADi's print precision of constant matrices (``DM``) in a fresh process, at which :func:`model_code` writes:
#: the generated C prints such matrices in its comments at the process's precision, which other libraries change
#: for the whole process (rockit sets 14 digits).
DM_PRECISION = 6


def model_code(functions, prefix: str = DEFAULT_PREFIX, real: str = "double") -> tuple:
    """``(source, header)``: the C text of ``functions`` in the library ``<prefix>_model`` (CasADi's
    CodeGenerator, ``casadi_real`` = ``real``; the source in :func:`to_float` form for ``"float"``), the same
    whatever the process ran before (written at :data:`DM_PRECISION`, the caller's precision restored after)."""
    lib = f"{prefix}_model"
    before = ca.DM.get_precision()
    ca.DM.set_precision(DM_PRECISION)     # the comments are written as the functions are added
    try:
        cg = ca.CodeGenerator(f"{lib}.c", {"with_header": True, "casadi_real": real})
        for f in functions:
            cg.add(f)
        with tempfile.TemporaryDirectory() as tmp:
            cg.generate(tmp + os.sep)
            source = _PRAGMA + (Path(tmp) / f"{lib}.c").read_text()
            header = (Path(tmp) / f"{lib}.h").read_text()
    except (OSError, RuntimeError) as exc:
        raise OutputError(f"CasADi's generated code cannot be written to a temporary folder ({tempfile.gettempdir()}): "
                          f"{str(exc).splitlines()[-1][:100]}") from None
    finally:
        ca.DM.set_precision(before)
    return (to_float(source) if real == "float" else source), header


_COMMENT_OR_STRING = re.compile(r'/\*.*?\*/|//[^\n]*|"(?:\\.|[^"\\])*"', re.S)
_LITERAL = re.compile(r"(?<![\w.])((?:\d+\.\d*|\.\d+)(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
#: The C math functions of double that :func:`to_float` renames (their float names end in ``f``).
MATH_FUNCTIONS = ("sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "log", "pow",
                  "sqrt", "hypot", "fabs", "floor", "ceil", "fmod", "fmin", "fmax", "copysign")
_MATH_CALL = re.compile(r"(?<![\w.])(" + "|".join(MATH_FUNCTIONS) + r")(\s*\()")


def to_float(code: str) -> str:
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

