"""C code generation: a self-contained C99 planner for the robot's microcontroller.

:func:`generate` writes the planner library into a folder: the model functions generated from the symbolic
model by CasADi's :class:`~casadi.CodeGenerator` (:mod:`rollplan.core.c_functions`), the generated header
``rollplan_config.h`` and the static planner sources ``rollplan_planner.c`` and ``.h`` of the package, copied
unchanged (:mod:`rollplan.planners.geometric.c_sources`, the same files the Python planner compiles), with the
glue ``<prefix>.h``, a demo, a Makefile and the files of the microcontroller builds.

What is generated, the planner, its k range and the certificate: docs/design/c-planner.md.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import casadi as ca
import numpy as np

from ..core import families
from ..core.c_functions import (
    DEFAULT_PREFIX,
    DEFAULT_STEPS_PER_LEAF,
    MAX_STEPS_PER_LEAF,
    c_curve,
    certificate_functions,
    generated_functions,
    leaf_degree,
    leaf_function,
    model_functions,
    motion_functions,
    step_functions,
    to_float,
)
from ..core.curves import A_MAX
from ..core.integrate import piece_rhs, rk8_step
from ..errors import InputError, check_choice, check_flag, show
from ..outputs import check_folder, write_folder
from ..planners.geometric.c_sources import (
    C_FAMILIES,
    CERT_BASE,
    CERT_TOL,
    CONFIG_HEADER,
    DEFAULT_K_MAX,
    FLOAT_CERT_TOL,
    PSI_MAX,
    STATIC_FILES,
    accuracy,
    config_values,
    sources,
)
from ..planners.geometric.search_constants import K_MONOTONE
from ..problem import K_MAX

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
    "PSI_MAX",
    "generated_functions",
    "generate",
    "auto_steps_per_leaf",
]

log = logging.getLogger(__name__)

#: Node intervals per leaf that ``steps_per_leaf="auto"`` tries, in this order: the first whose step map is accurate to
#: STEP_MAP_TOL up to k_max is taken. The last is the cap (MAX_STEPS_PER_LEAF), accurate up to K_MAX
#: (240 serves k_max = 5, 320 k_max = 10, 400 k_max = 16, 480 k_max = 20, 640 k_max = 30, 2000 k_max = 100).
AUTO_STEPS_PER_LEAF = (240, 320, 400, 480, 560, 640, 800, 1000, 1200, 1600, 2000)
#: Accuracy the step map must have on ``0 < a, b <= A_MAX``, ``k <= k_max`` for :func:`generate` to accept k_max.
STEP_MAP_TOL = 1e-10
#: Longest prefix (it starts every C symbol and file name).
MAX_PREFIX_CHARS = 64


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


def rk8_trace(ab, k: float, gamma: float = 0.0, delta: float = 0.1, x0=(0.0, 0.0, 0.0),
              curve: str = "circles") -> np.ndarray:
    """(u_a, v_a, psi) after one trace of the figure eight by fixed RK8 steps, as the C certificate does it.

    Each panel of a leaf gets ``ceil(w (CERT_BASE + max |psi'|) / delta)`` equal steps (``max |psi'|`` over five
    points of the panel; psi' of (30) does not depend on the state). The C certificate uses
    ``delta = CERT_DELTA`` and step doubling; :func:`generate` uses a small ``delta`` to check the step map.
    ``curve``: the leaf family (:data:`rollplan.core.families.FAMILIES`).
    """
    x = np.asarray(x0, float)
    p = np.asarray(ab, float)
    for i, (piece, f) in enumerate(_piece_rhs(curve)):
        for b0, b1 in zip(piece.breaks[:-1], piece.breaks[1:]):
            w = b1 - b0
            rate = max(abs(float(f(b0 + q * w / 4, ca.DM.zeros(3), p, k, gamma)[2])) for q in range(5))
            n = int(np.ceil(w * (CERT_BASE + rate) / delta))
            phis = b0 + np.arange(n) * (w / n)
            xs = _rk8_steps(curve, i, n)(x, phis.reshape(1, -1), w / n, p, k, gamma)
            x = np.array(xs[:, -1]).ravel()
    return x


@lru_cache(maxsize=8)
def _piece_rhs(curve: str) -> tuple:
    """``(piece, right side)`` of each piece of the figure eight of the family ``curve``, built once."""
    eight = families.figure_eight(curve)
    return tuple((piece, piece_rhs(eight, i)) for i, piece in enumerate(eight.pieces))


@lru_cache(maxsize=256)
def _rk8_steps(curve: str, piece: int, n: int) -> ca.Function:
    """``n`` RK8 steps on piece ``piece`` of the family ``curve`` (the step of :func:`rk8_step`, accumulated)."""
    return _rk8_step(curve, piece).mapaccum(n)


@lru_cache(maxsize=16)
def _rk8_step(curve: str, piece: int) -> ca.Function:
    return rk8_step(_piece_rhs(curve)[piece][1])


def _valid_k_max(k_max) -> float:
    if isinstance(k_max, bool) or not isinstance(k_max, (int, float, np.integer, np.floating)) \
            or not K_MONOTONE <= float(k_max) <= K_MAX:
        raise InputError(f"k_max = {k_max!r} is not allowed: it must be a number in [{K_MONOTONE:g}, {K_MAX:g}]")
    return float(k_max)


#: The corners of the admissible box where the step map is checked (its error peaks near A_MAX).
_CHECK_LEAVES = ((A_MAX, A_MAX), (A_MAX, 0.05), (0.05, A_MAX))


@lru_cache(maxsize=32)
def _fine_trace(ab: tuple, k: float, curve: str = "circles") -> tuple:
    return tuple(rk8_trace(ab, k, curve=curve))


def _step_map_error(k_max: float, step: ca.Function, curve: str = "circles") -> float:
    """Largest error of the step map ``step`` against fine RK8 traces (:func:`rk8_trace`) at the corners of the
    admissible box, ``a, b in {0.05, A_MAX}``, for ``k in {0, k_max / 2, k_max}``."""
    worst = 0.0
    for k in (0.0, 0.5 * k_max, k_max):
        for ab in _CHECK_LEAVES:
            shift, eta, _ = (np.array(v).ravel() for v in step(ab, k))
            worst = max(worst, float(np.max(np.abs(np.concatenate([shift, eta])
                                                   - np.array(_fine_trace(ab, k, curve))))))
    return worst


def _check_k_max(k_max, steps_per_leaf: int, step: ca.Function, curve: str = "circles") -> float:
    """``k_max`` as a float if the step map is accurate to STEP_MAP_TOL up to it; InputError otherwise.

    The step map's error grows with k and with the leaf radii (the turn rate psi' peaks as the leaf
    nears the singular equator); it is measured by :func:`_step_map_error`.
    """
    k_max = _valid_k_max(k_max)
    worst = _step_map_error(k_max, step, curve)
    if not worst <= STEP_MAP_TOL:
        raise InputError(f"k_max = {k_max:g} is not allowed with {steps_per_leaf} steps per leaf: the step map "
                         f"is off by {worst:.1e} (more than {STEP_MAP_TOL:g}) near A_MAX; give more steps per leaf "
                         f"(auto: the smallest that serves it) or a smaller k_max")
    return k_max


@lru_cache(maxsize=8)
def _step_map(steps_per_leaf: int, curve: str) -> ca.Function:
    """The step map that :func:`_check_k_max` checks (:func:`step_functions`), built once per size and family."""
    return step_functions(steps_per_leaf, curve=curve)[0]


@lru_cache(maxsize=4)
def _functions(steps_per_leaf: int, prefix: str, curve: str) -> tuple:
    """:func:`generated_functions`, built once per process for each size, prefix and family (CasADi functions do not
    change): a second :func:`generate` of the same kind skips seconds of symbolic work."""
    return tuple(generated_functions(steps_per_leaf, prefix, curve))


def auto_steps_per_leaf(k_max, curve: str = "circles") -> int:
    """The smallest of :data:`AUTO_STEPS_PER_LEAF` whose step map is accurate to STEP_MAP_TOL up to ``k_max`` (the
    check of :func:`_check_k_max`); InputError naming the cap when none is."""
    k_max = _valid_k_max(k_max)
    worst = math.inf
    for steps_per_leaf in AUTO_STEPS_PER_LEAF:
        worst = _step_map_error(k_max, _step_map(steps_per_leaf, curve), curve)
        if worst <= STEP_MAP_TOL:
            return steps_per_leaf
    raise InputError(f"k_max = {k_max:g} is not allowed: even the largest automatic size, {AUTO_STEPS_PER_LEAF[-1]} "
                     f"steps per leaf, leaves the step map off by {worst:.1e} (more than {STEP_MAP_TOL:g}) near "
                     f"A_MAX; give a smaller k_max")


# ----------------------------------------------------------------------------- C sources


def _check_real(real) -> str:
    if real not in ("double", "float"):
        raise InputError(f"real = {real!r} is not allowed: it must be 'double' or 'float'")
    return real


def _check_prefix(prefix) -> str:
    if not isinstance(prefix, str) or not prefix.isidentifier() or not prefix.isascii() or prefix.startswith("_") \
            or len(prefix) > MAX_PREFIX_CHARS:
        raise InputError(f"prefix = {show(prefix)} is not allowed: it must be a C identifier (letters, digits, _) "
                         f"of at most {MAX_PREFIX_CHARS} characters")
    if f"{prefix}.h" in (CONFIG_HEADER, *STATIC_FILES):
        raise InputError(f"prefix = {show(prefix)} is not allowed: {prefix}.h is the name of a file of the planner "
                         f"({', '.join((CONFIG_HEADER, *STATIC_FILES))})")
    return prefix


#: Files for the microcontroller builds (QEMU's mps2-an500 and mps2-an386 boards), copied into the output.
#: What the generated Makefile builds in its folder (its ``clean`` target removes them).
_BUILD_PRODUCTS = ("plan_demo", "plan_demo.o", "rollplan_planner.o", "@PREFIX@_model.o", "lib@PREFIX@.a",
                   "lib@PREFIX@.so", "build")
_EMBEDDED = ("startup.c", "mps2-common.ld", "mps2-an500.ld", "mps2-an386.ld", "planner_only.c", "stack_bound.py")


def _template(name: str) -> str:
    return (Path(__file__).with_name("c_templates") / name).read_text()


def generate(out, steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF, prefix: str = DEFAULT_PREFIX,
             k_max: float = DEFAULT_K_MAX, real: str = "double", overwrite: bool = False,
             curve: str = "circles") -> GeneratedCode:
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
    curve : str
        Leaf family of the figure eight (:data:`rollplan.planners.geometric.c_sources.C_FAMILIES`): the search's
        leaf map and the model functions (certificate, step map, time law) of that family; the static C files are
        the same for every family, ``rollplan_config.h`` says which (``RP_FAMILY``).

    Returns
    -------
    GeneratedCode
    """
    prefix = _check_prefix(prefix)
    real = _check_real(real)
    check_choice("curve", curve, C_FAMILIES)
    out = check_folder(out, overwrite=check_flag("overwrite", overwrite))   # refused before any work
    k_max = _valid_k_max(k_max)
    if isinstance(steps_per_leaf, str) and steps_per_leaf == "auto":
        steps_per_leaf = auto_steps_per_leaf(k_max, curve)              # refused before anything is written
    leaf_degree(steps_per_leaf, len(c_curve(curve).pieces[0].breaks) - 1)   # refused before anything is written
    k_max = _check_k_max(k_max, steps_per_leaf, _step_map(steps_per_leaf, curve), curve)   # refused before the rest
    funcs = list(_functions(steps_per_leaf, prefix, curve))
    library = sources(prefix, steps_per_leaf, k_max, real, functions=funcs, curve=curve)
    values = config_values(funcs, steps_per_leaf, k_max, real, curve)
    subs = {
        "@PREFIX@": prefix,
        "@PREFIX_UPPER@": prefix.upper(),
        **{f"@{name}@": value for name, value in values.items()},
        "@REAL@": real,
        "@ACCURACY@": accuracy(real),
        "@QEMU_TOL@": "1e-12" if real == "double" else "1e-5",
        "@M4F_EXTRA@": "" if real == "double" else "-Wdouble-promotion",
    }

    def fill(text: str) -> str:
        for key, value in subs.items():
            text = text.replace(key, value)
        return text

    interface = fill(_template("interface.h"))
    files = {
        **library,
        f"{prefix}.h": interface if real == "double" else to_float(interface),
        "plan_demo.c": fill(_template("plan_demo.c")),
        "Makefile": fill(_template("Makefile")),
        **{name: fill(_template(name)) for name in _EMBEDDED},
    }
    products = [name.replace("@PREFIX@", prefix) for name in _BUILD_PRODUCTS]
    write_folder(out, {name: text.encode() for name, text in files.items()}, overwrite=overwrite, products=products)
    written = [out / name for name in files]
    code_bytes = sum(len(t.encode()) for n, t in files.items() if n.endswith((".c", ".h")))
    work = int(values["SZ_W"])
    log.info("wrote %s: %d bytes of C, %d doubles of work memory", out, code_bytes, work)
    return GeneratedCode(out, prefix, int(steps_per_leaf), tuple(written), code_bytes,
                         len(library[f"{prefix}_model.c"].encode()), work)
