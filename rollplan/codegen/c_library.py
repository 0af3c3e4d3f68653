"""C code generation: a self-contained C99 planner for the robot's microcontroller.

Everything numerical in the generated library comes from the symbolic model
through CasADi's :class:`~casadi.CodeGenerator`; no equation is typed twice:

* the realizability condition (13) solved for the spin ``omega_z``
  (:func:`rollplan.core.model.omega_z_realizable`);
* the rotor-rate map (11) (:func:`rollplan.core.model.rotor_rates`);
* Montana's contact kinematics (6)-(10) (:func:`rollplan.core.model.montana`);
* the step map ``(a, b, k) -> (shift, eta, direction)`` of one trace of the
  figure eight (31), (35), integrated along the curve ODE (28)-(30)
  (:func:`rollplan.core.integrate.piece_rhs`), and its Jacobian;
* a coarse table of the two leaves on a fixed grid of radii, used only to
  bracket the root of (32)-(33) on branch ``m = 0``.

The step map is the Chebyshev spectral quadrature of :mod:`rollplan.core.integrate`
(:func:`~rollplan.core.integrate.spectral_leaf`), written with loops: each leaf is integrated over the
curve's 10 graded panels
(its fixed steps), each panel on ``degree + 1`` Chebyshev points. Along a
curve psi' in (30) does not depend on the state, and (28)-(29) are
``[u_a', v_a'] = Rot(-psi) [A, B]`` with ``(A, B)`` their value at psi = 0
(checked when the function is built). So one ``map`` over the nodes evaluates
``(A, B, psi')`` and their derivatives by the leaf radius, a cumulative
Chebyshev integration gives psi at the nodes, and weighted sums give
``(u_a, v_a)``. The generated C loops over the nodes instead of unrolling
them. The Jacobian by (a, b) is assembled by the chain rule from the leaves'
derivatives.

``steps_per_leaf`` counts node intervals per leaf: panels x degree. The
default, :data:`DEFAULT_STEPS_PER_LEAF`, was chosen from the measured error of
the generated step map against steps per leaf over the admissible range
(``scripts/bench_codegen.py --accuracy`` writes ``results/codegen_accuracy.json``);
larger k needs more steps per leaf.

The planner (hand-written C glue, not model equations) solves, for branch
``m = 0``,

    eta(a, b) = psi / n                                                 (32)
    h(a, b)   = h_des |sin(eta / 2) / sin(n eta / 2)|   (h_des / n if psi = 0)   (33)

by a damped Newton iteration (backtracking on the residual norm, iterates kept
in ``(0, A_MAX]``) on the generated step map and its Jacobian. It starts in the
bracketing cells of the leaf table in order of their smallest ``a + b`` (as the
Python planner orders its brackets), from the targets interpolated linearly in
the cell, then sets ``gamma = atan2(v, u) - arg(sum_{j<n} exp(-i j eta) shift)``
(see :mod:`rollplan.planners.geometric`). The table depends on k only and is kept for
the last k. Static memory only, a bounded number of iterations, and a status
code (0 ok, 2 bad input, 3 no bracket, 4 no convergence).
"""

from __future__ import annotations

import logging
import os
import tempfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from ..core import model
from ..core.curves import A_MAX, figure_eight
from ..core.integrate import check_heading_structure, heading_free_rates, piece_rhs, spectral_leaf
from ..errors import InputError, NoPlanError
from ..io import write_atomic
from ..planners.geometric import plan as gp_plan

__all__ = [
    "DEFAULT_STEPS_PER_LEAF",
    "DEFAULT_PREFIX",
    "TABLE_RADII",
    "TABLE_STEPS_PER_LEAF",
    "GeneratedCode",
    "model_functions",
    "leaf_function",
    "step_functions",
    "table_function",
    "generated_functions",
    "generate",
    "reference_plan",
]

log = logging.getLogger(__name__)

#: Node intervals per leaf of the generated step map (10 graded panels x degree 20).
DEFAULT_STEPS_PER_LEAF = 200
#: Node intervals per leaf of the coarse bracketing table (10 panels x degree 4).
TABLE_STEPS_PER_LEAF = 40
#: Radii of the bracketing table on (0, A_MAX], graded towards A_MAX (see :func:`table_radii`).
TABLE_RADII = 64
#: Inertia ratio for which the table's radii equidistribute the turn of psi.
_TABLE_K = 2.5
#: Default name prefix of the generated C symbols and files.
DEFAULT_PREFIX = "rollplan"

# Planner constants (written into the C code).
_MAX_ITER = 25
_MAX_CELLS = 12
_TOL = 1e-13
_A_MIN = 1e-6


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
            or steps_per_leaf < 2 * panels or steps_per_leaf % panels:
        raise InputError(f"steps per leaf = {steps_per_leaf!r} is not allowed: it must be a multiple of "
                         f"{panels} (the curve's panels), at least {2 * panels}")
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


@lru_cache(maxsize=4)
def table_radii(count: int = TABLE_RADII) -> np.ndarray:
    """Radii of the bracketing table, graded towards A_MAX.

    A quarter of the cells are spread evenly over (0, A_MAX], three quarters
    follow the turn of psi over the first leaf for k = 2.5, which grows steeply
    towards the singular radius R/sqrt(2) (and with it the density of roots of
    (32)-(33)): the radii equidistribute ``1/A_MAX + 3 |d eta_0/d r| / TV(eta_0)``.
    """
    curve = figure_eight()
    leaf = leaf_function(curve, 0, 8, "grading")
    fine = np.linspace(0.0, A_MAX, 801)
    eta = np.array(leaf.map(fine.size)(ca.DM.zeros(3), ca.DM(fine).T, _TABLE_K))[2]
    turn = np.abs(np.diff(eta))
    monitor = np.concatenate([[0.0], np.cumsum(np.diff(fine) / A_MAX + 3.0 * turn / turn.sum())])
    radii = np.interp(np.linspace(0.0, monitor[-1], count + 1)[1:], monitor, fine)
    radii[-1] = A_MAX
    return radii


def table_function(prefix: str = DEFAULT_PREFIX, steps_per_leaf: int = TABLE_STEPS_PER_LEAF,
                   count: int = TABLE_RADII) -> ca.Function:
    """Coarse leaf maps on the fixed radii grid, for bracketing only.

    ``<prefix>_leaf_table(k) -> (leaf0[3 x count], leaf1[3 x count])``: columns
    are (u_a, v_a, psi) at the end of each leaf traced alone from zero state.
    The second leaf is the mirror image (y -> -y) of the first, so its table is
    ``diag(1, -1, -1)`` times the first one's; this is checked here against a
    direct integration of the second leaf (and in ``tests/test_codegen.py``).
    """
    curve = figure_eight()
    degree = _degree(steps_per_leaf, len(curve.pieces[0].breaks) - 1)
    k = ca.MX.sym("k")
    radii = table_radii(count)
    leaves = [leaf_function(curve, i, degree, f"{prefix}_tleaf{i}") for i in range(2)]
    mirror = ca.DM([1.0, -1.0, -1.0])
    for r, kk in ((radii[3], 2.5), (radii[-1], 5.0)):
        first, second = (np.array(f(ca.DM.zeros(3), r, kk)).ravel() for f in leaves)
        if not np.allclose(second, np.array(mirror).ravel() * first, rtol=1e-10, atol=1e-12):
            raise ValueError("the second leaf is not the mirror image of the first")
    leaf0 = leaves[0].map(count, "serial")(ca.DM.zeros(3, 1), ca.DM(radii).T, k)
    leaf1 = ca.repmat(mirror, 1, count) * leaf0
    return ca.Function(f"{prefix}_leaf_table", [k], [leaf0, leaf1], ["k"], ["leaf0", "leaf1"])


def generated_functions(steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX) -> list:
    """Every function that :func:`generate` writes to C, in order (the symbolic twins)."""
    return [*model_functions(prefix), *step_functions(steps_per_leaf, prefix), table_function(prefix)]


def reference_plan(target, steps: int, k: float, near=None):
    """The Python planner's verified plan on branch m = 0, for cross-checking the C planner.

    Solves (32)-(33) with ``m = 0`` by :mod:`rollplan.planners.geometric` (IPOPT on the
    spectral step map, CVODES verification). Returns the shortest such plan,
    or with ``near = (a, b)`` the one closest to it; None if there is none.
    Uses :func:`rollplan.planners.geometric.plan` restricted to ``branch=0`` (all of its
    roots when ``near`` is given).
    """
    u, v, psi = (float(x) for x in target)
    dist = (lambda q: 0.0) if near is None else (lambda q: max(abs(q.a - near[0]), abs(q.b - near[1])))
    try:
        best = gp_plan((u, v, psi), steps, k=k, branch=0, all_solutions=near is not None)
    except NoPlanError:
        return None
    return min((best,) + best.alternatives, key=lambda q: (dist(q), q.a + q.b))


# ----------------------------------------------------------------------------- C sources

_PRAGMA = """/* Generated by rollplan.codegen from the symbolic model with CasADi's CodeGenerator. */
#if defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wunused-parameter"
#endif
"""


def _check_prefix(prefix) -> str:
    if not isinstance(prefix, str) or not prefix.isidentifier() or not prefix.isascii() or prefix.startswith("_"):
        raise InputError(f"prefix = {prefix!r} is not allowed: it must be a C identifier (letters, digits, _)")
    return prefix


def _template(name: str) -> str:
    return (Path(__file__).with_name("c_templates") / name).read_text()


def generate(out, steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX) -> GeneratedCode:
    """Write the C99 library, ``plan_demo.c`` and a ``Makefile`` into folder ``out``.

    Parameters
    ----------
    out : path
        Output folder (created if missing; its parent must exist).
    steps_per_leaf : int
        Node intervals per leaf of the step map (a multiple of the 10 panels).
    prefix : str
        Prefix of the C symbols and file names.

    Returns
    -------
    GeneratedCode
    """
    prefix = _check_prefix(prefix)
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError(f"output folder {str(out)!r} is a file")
    if not out.exists() and not out.parent.is_dir() and str(out.parent):
        raise InputError(f"output folder {str(out)!r} cannot be created: {str(out.parent)!r} does not exist")
    funcs = generated_functions(steps_per_leaf, prefix)  # checks steps_per_leaf before the folder is made
    if not out.exists():
        out.mkdir()
    step, step_jac, table = funcs[3], funcs[4], funcs[5]
    lib = f"{prefix}_model"
    cg = ca.CodeGenerator(f"{lib}.c", {"with_header": True})
    for f in funcs:
        cg.add(f)
    with tempfile.TemporaryDirectory() as tmp:
        cg.generate(tmp + os.sep)
        model_c = _PRAGMA + (Path(tmp) / f"{lib}.c").read_text()
        model_h = (Path(tmp) / f"{lib}.h").read_text()
    sizes = {name: max(int(getattr(f, name)()) for f in (step, step_jac, table))
             for name in ("sz_arg", "sz_res", "sz_iw", "sz_w")}
    subs = {
        "@PREFIX@": prefix,
        "@PREFIX_UPPER@": prefix.upper(),
        "@SZ_ARG@": str(sizes["sz_arg"]),
        "@SZ_RES@": str(sizes["sz_res"]),
        "@SZ_IW@": str(max(sizes["sz_iw"], 1)),
        "@SZ_W@": str(max(sizes["sz_w"], 1)),
        "@TABLE_RADII@": str(TABLE_RADII),
        "@RADII@": ", ".join(repr(float(r)) for r in (0.0, *table_radii())),
        "@A_MAX@": repr(float(A_MAX)),
        "@A_MIN@": repr(_A_MIN),
        "@MAX_ITER@": str(_MAX_ITER),
        "@MAX_CELLS@": str(_MAX_CELLS),
        "@TOL@": repr(_TOL),
        "@STEPS_PER_LEAF@": str(int(steps_per_leaf)),
    }

    def fill(text: str) -> str:
        for key, value in subs.items():
            text = text.replace(key, value)
        return text

    files = {
        f"{lib}.c": model_c,
        f"{lib}.h": model_h,
        f"{prefix}.h": fill(_template("planner.h")),
        f"{prefix}_planner.c": fill(_template("planner.c")),
        "plan_demo.c": fill(_template("plan_demo.c")),
        "Makefile": fill(_template("Makefile")),
    }
    written = []
    for name, text in files.items():
        write_atomic(out / name, text.encode())
        written.append(out / name)
    code_bytes = sum(len(t.encode()) for n, t in files.items() if n != "Makefile")
    work = sizes["sz_w"]
    log.info("wrote %s: %d bytes of C, %d doubles of work memory", out, code_bytes, work)
    return GeneratedCode(out, prefix, int(steps_per_leaf), tuple(written), code_bytes, len(model_c.encode()), work)
