"""The C search's source files: the static planner of the package and what each generation adds to it.

``rollplan/csrc/rollplan_planner.c`` and ``.h`` are ordinary source files (no template): everything that varies
by generation comes from the generated header ``rollplan_config.h`` (:func:`config_header`: the prefix of the
exported names, the number type, work sizes, table sizes and every constant, from the Python definitions) and
the model functions ``<prefix>_model.c`` of :mod:`rollplan.core.c_functions`. :func:`sources` gives all of
them; the Python planner compiles them (:mod:`.compiled_search`), ``rollplan codegen`` writes them with a demo
and a Makefile. Layout, build and loading: docs/design/c-planner.md.
"""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np

from ...core.c_functions import (
    DEFAULT_PREFIX,
    DEFAULT_STEPS_PER_LEAF,
    MATH_FUNCTIONS,
    PHASE,
    RK8_STAGES,
    c_curve,
    generated_functions,
    model_code,
    to_float,
)
from ...core.curves import A_MAX
from ...core.families import FAMILIES
from ...core.integrate import DOP853_C
from ...errors import show_limit
from ...problem import K_MIN, MAX_STEPS
from ...result import CERTIFICATE_TOLERANCE
from . import leafmap
from . import search_constants as sc
from .search_constants import K_MONOTONE

__all__ = ["CSRC", "STATIC_FILES", "CONFIG_HEADER", "DEFAULT_K_MAX", "CERT_TOL", "FLOAT_CERT_TOL", "CERT_DELTA",
           "CERT_BASE", "CERT_SAFETY", "PSI_MAX", "C_FAMILIES",
           "FAMILY_MULT", "static_sources", "config_values", "accuracy", "config_header",
           "sources", "generator_files"]

#: The package folder of the static C sources.
CSRC = Path(__file__).resolve().parents[2] / "csrc"
#: The static C sources of the planner (copied unchanged by ``rollplan codegen``).
STATIC_FILES = ("rollplan_planner.c", "rollplan_planner.h")
#: The generated header the static sources include.
CONFIG_HEADER = "rollplan_config.h"
#: Largest k of the generated C planner unless told otherwise (``rollplan codegen --k-max``).
DEFAULT_K_MAX = 5.0
#: Tolerance of the on-board certificate: residual + error bound [R and rad] (the project's tolerance).
CERT_TOL = CERTIFICATE_TOLERANCE
#: Tolerance of the certificate of a single-precision build (``real="float"``): float rounding
#: alone leaves errors of 1e-6 R, and more near A_MAX, so such plans are good to this, not to CERT_TOL.
FLOAT_CERT_TOL = 1e-4
#: Steps of the RK8 certificate: a panel of width w gets ceil(w (CERT_BASE + max |psi'|) / CERT_DELTA) of them.
CERT_DELTA = 1.0
CERT_BASE = 2.0
#: The certificate's error bound is |x_2N - x_N| / CERT_SAFETY (Richardson's estimate for order 8 divides by 255).
CERT_SAFETY = 16.0
#: Largest |psi| [rad] the C planner accepts (its reduction modulo 2 pi is exact up to it).
PSI_MAX = 1e6
#: The leaf families the C search serves, in the order of their index RP_FAMILY (every family).
C_FAMILIES = FAMILIES
#: A family's leaf map (other than the circles') integrates the leaf with this many times the certificate's steps.
FAMILY_MULT = 4
#: 2 pi to 50 digits.
_TWO_PI_DIGITS = "6.2831853071795864769252867665590057683943387987502"


def static_sources() -> dict:
    """``{file name: text}`` of the static C sources (:data:`STATIC_FILES` in :data:`CSRC`)."""
    return {name: (CSRC / name).read_text(encoding="utf-8") for name in STATIC_FILES}


def _two_pi_parts() -> dict:
    """2 pi as TWO_PI_1 + TWO_PI_2 + TWO_PI_3, the first two with 32 significant bits, so that m * TWO_PI_1 and
    m * TWO_PI_2 are exact for |m| < 2^21 (Cody and Waite's argument reduction, used by the C planner)."""
    parts, rest = [], Fraction(_TWO_PI_DIGITS)
    for _ in range(2):
        e = math.frexp(float(rest))[1]
        part = Fraction(math.floor(rest * 2 ** (32 - e)), 2 ** (32 - e))
        parts.append(float(part))
        rest -= part
    parts.append(float(rest))
    return {f"TWO_PI_{i + 1}": repr(p) for i, p in enumerate(parts)}


def _enumeration_constants(k_max: float) -> dict:
    """The constants of :mod:`.leafmap` and :mod:`.search_constants` the C planner uses, and the sizes of its static
    tables for ``k <= k_max``."""
    if leafmap.ORDER % 2:
        raise ValueError("the C leaf map evaluates the nodes chi < pi only (symmetry): it needs an even ORDER")
    x, w = np.polynomial.legendre.leggauss(leafmap.ORDER)
    buckets = [(kk, p) for kk, p in leafmap.BUCKETS if kk < k_max] + [next((kk, p) for kk, p in leafmap.BUCKETS
                                                                           if kk >= k_max)]
    # the table's radii (search_constants.table_radii): their number grows with k for k >= 1/2 (E is monotone, its
    # steps grow with k; below 1/2 |E'| is smaller than at 1/2); the cell of the last radius is one more
    ntable = 1 + max(sc.table_radii(kk, sc.TABLE_STEP, sc.TABLE_PHASE, sc.TABLE_INV_S).size
                     for kk in (K_MIN, K_MONOTONE, k_max))
    if ntable >= 2 ** 16:
        raise ValueError(f"the rho table at k_max = {k_max:g} needs {ntable} radii: its buckets hold 16-bit indices")
    return {
        "ORDER": str(leafmap.ORDER),
        "GAUSS_X": ", ".join(repr(float(v)) for v in x),
        "GAUSS_W": ", ".join(repr(float(v)) for v in w),
        "NBUCKET": str(len(buckets)),
        "BUCKET_K": ", ".join(repr(float(kk)) for kk, _ in buckets),
        "BUCKET_P": ", ".join(str(p) for _, p in buckets),
        "MAX_PANELS": str(buckets[-1][1]),
        "PHASE_STEP": repr(sc.PHASE_STEP),
        "X_STEP": repr(sc.X_STEP),
        "SIGMA_STEP": repr(sc.SIGMA_STEP),
        "K_MONOTONE": repr(float(K_MONOTONE)),
        "HERMITE_REL": repr(sc.HERMITE_REL),
        "POLISH_STEP": repr(sc.POLISH_STEP),
        "POLISH_BRACKET": repr(sc.POLISH_BRACKET),
        "NOT_A_ROOT": repr(sc.NOT_A_ROOT),
        "SAFETY": repr(sc.SAFETY),
        "MIN_WIDTH": repr(sc.MIN_WIDTH),
        "TABLE_PHASE": repr(sc.TABLE_PHASE),
        "TABLE_STEP": repr(sc.TABLE_STEP),
        "TABLE_INV_S": repr(sc.TABLE_INV_S),
        "NTABLE": str(ntable),
    }


def config_values(functions, steps_per_leaf: int, k_max: float, real: str, curve: str = "circles") -> dict:
    """``{NAME: C text}`` of every value ``rollplan_config.h`` defines as ``RP_NAME``, for the model functions
    ``functions`` (:func:`~rollplan.core.c_functions.generated_functions`, in that order), the planner's
    ``k_max``, ``casadi_real`` = ``real`` (``"double"`` or ``"float"``) and the leaf family ``curve`` (one of
    :data:`C_FAMILIES`)."""
    sizes = {name: max(int(getattr(f, name)()) for f in functions[3:])
             for name in ("sz_arg", "sz_res", "sz_iw", "sz_w")}
    eight = c_curve(curve)
    breaks = eight.pieces[0].breaks
    if len(eight.pieces) != 2 or any(tuple(piece.breaks) != tuple(breaks) for piece in eight.pieces):
        raise ValueError("the C certificate assumes the leaves share their panels")
    double = real == "double"
    return {
        "SZ_ARG": str(sizes["sz_arg"]),
        "SZ_RES": str(sizes["sz_res"]),
        "SZ_IW": str(max(sizes["sz_iw"], 1)),
        "SZ_W": str(max(sizes["sz_w"], 1)),
        "REAL_TINY": "DBL_MIN" if double else "FLT_MIN",
        "REAL_EPS": "DBL_EPSILON" if double else "FLT_EPSILON",
        "REAL_MAX": "DBL_MAX" if double else "FLT_MAX",
        "A_MAX": repr(float(A_MAX)),
        "K_MIN": repr(float(K_MIN)),
        "K_MAX": repr(float(k_max)),
        "PSI_MAX": repr(PSI_MAX),
        "MAX_STEPS": show_limit(MAX_STEPS),
        "CERT_TOL": repr(CERT_TOL if double else FLOAT_CERT_TOL),
        "CERT_DELTA": repr(CERT_DELTA),
        "CERT_BASE": repr(CERT_BASE),
        "CERT_SAFETY": repr(CERT_SAFETY),
        "STEPS_PER_LEAF": str(int(steps_per_leaf)),
        "NPANEL": str(len(breaks) - 1),
        "BREAKS": ", ".join(repr(float(b)) for b in breaks),
        "RK8_STAGES": str(RK8_STAGES),
        "RK8_C": ", ".join(repr(float(c)) for c in DOP853_C),
        "FAMILY": str(C_FAMILIES.index(curve)),
        "PHASE": repr(PHASE[curve]),
        "FAMILY_MULT": str(FAMILY_MULT),
        **_two_pi_parts(),
        **_enumeration_constants(float(k_max)),
    }


def accuracy(real: str) -> str:
    """The sentence of the generated headers on what a plan of this build is certified to."""
    if real == "double":
        return f"plans are certified to {CERT_TOL:g}."
    return f"single precision: plans are certified to {FLOAT_CERT_TOL:g} (R and rad) only."


def config_header(values: dict, prefix: str = DEFAULT_PREFIX, real: str = "double") -> str:
    """The text of ``rollplan_config.h``: ``RP_NAME(x)`` (``<prefix>_x``), ``RP_R`` and the math functions of
    ``casadi_real``, and ``#define RP_<NAME> <value>`` for each of ``values`` (:func:`config_values`)."""
    suffix = "" if real == "double" else "f"
    lines = [
        "/*",
        f" * {CONFIG_HEADER} -- generated by rollplan: what the static planner sources {STATIC_FILES[0]} and",
        f" * {STATIC_FILES[1]} take from this generation. Prefix {prefix}; casadi_real is {real} in this build;",
        f" * {accuracy(real)}",
        " */",
        "#ifndef ROLLPLAN_CONFIG_H",
        "#define ROLLPLAN_CONFIG_H",
        "",
        "#include <float.h>",
        "#include <math.h>",
        "",
        f'#include "{prefix}_model.h"',
        "",
        f"/* Exported names and the generated model functions: RP_NAME(x) is {prefix}_x. */",
        f"#define RP_NAME(x) {prefix}_##x",
        f'#define RP_REAL_NAME "{real}"',
        "/* A floating literal and the math functions of casadi_real. */",
        "#define RP_R(x) x" + ("##f" if suffix else ""),
        *(f"#define RP_{name.upper()} {name}{suffix}" for name in MATH_FUNCTIONS),
        "",
        "/* Sizes and constants (rollplan.planners.geometric.c_sources.config_values). */",
        *(f"#define RP_{name} {value}" for name, value in values.items()),
        "",
        "#endif /* ROLLPLAN_CONFIG_H */",
        "",
    ]
    text = "\n".join(lines)
    return text if real == "double" else to_float(text)


def sources(prefix: str = DEFAULT_PREFIX, steps_per_leaf: int = DEFAULT_STEPS_PER_LEAF,
            k_max: float = DEFAULT_K_MAX, real: str = "double", functions=None, curve: str = "circles") -> dict:
    """``{file name: text}`` of the C planner library: ``<prefix>_model.c`` and ``.h`` (the model functions,
    ``functions`` or :func:`~rollplan.core.c_functions.generated_functions`), ``rollplan_config.h`` and the static
    sources. Generated in this process (CasADi's CodeGenerator); no check of ``k_max`` (``rollplan.codegen``
    checks the step map's accuracy up to it). ``curve``: the leaf family (:data:`C_FAMILIES`) of the search's leaf
    map and of the model functions (the certificate integrates that family's figure eight)."""
    if functions is None:
        functions = generated_functions(steps_per_leaf, prefix, curve)
    model_c, model_h = model_code(functions, prefix, real)
    values = config_values(functions, steps_per_leaf, k_max, real, curve)
    return {f"{prefix}_model.c": model_c, f"{prefix}_model.h": model_h,
            CONFIG_HEADER: config_header(values, prefix, real), **static_sources()}


def generator_files() -> list:
    """The files whose contents decide what :func:`sources` returns: the static sources, the modules of
    :mod:`rollplan.core` and :mod:`rollplan.planners.geometric`, and those of the constants it writes
    (:mod:`rollplan.result`, :mod:`rollplan.problem`, :mod:`rollplan.errors`)."""
    package = CSRC.parent
    files = [CSRC / name for name in STATIC_FILES]
    files += sorted((package / "core").glob("*.py")) + sorted((package / "planners" / "geometric").rglob("*.py"))
    return files + [package / name for name in ("result.py", "problem.py", "errors.py")]
