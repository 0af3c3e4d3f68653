"""The constants of the C search (:mod:`.compiled_search`) and the radii of its rho table.

``rollplan_config.h`` takes them from here (:func:`.c_sources.config_header`); the numpy reference
enumeration of the tests (tests/reference_enumerate.py) uses the same ones. Their meaning: docs/design/enumeration.md.
"""

from __future__ import annotations

import math

import numpy as np

from ...core.curves import A_MAX
from .leafmap import turn

__all__ = ["K_MONOTONE", "PHASE_STEP", "X_STEP", "SIGMA_STEP", "HERMITE_REL", "SAFETY", "MIN_WIDTH", "TABLE_PHASE",
           "TABLE_STEP", "TABLE_INV_S", "POLISH_STEP", "POLISH_BRACKET", "NOT_A_ROOT", "table_radii"]

#: Smallest k for which E is strictly decreasing on (0, A_MAX].
K_MONOTONE = 0.5
#: Initial sampling steps of the graphs over the radius: in the turn E [rad] and in the radius [R].
PHASE_STEP = 0.5
X_STEP = 0.02
#: Initial sampling step of the sigma graphs [R].
SIGMA_STEP = 0.005
#: A cell is split while its Hermite midpoint error exceeds this fraction of its largest |g|.
HERMITE_REL = 1e-2
#: Factor between the Hermite error anywhere in a cell and at its midpoint.
SAFETY = 4.0
#: Table of rho: steps in the turn E [rad] and in r [R], and in 1 / s (see :func:`table_radii`).
TABLE_PHASE = 0.15
TABLE_STEP = 0.004
TABLE_INV_S = 0.005
#: Newton steps on the accurate map below this are taken without a new evaluation.
POLISH_STEP = 1e-8
#: A polish step across the root brackets it on the accurate map if it is at most this long (in the graph's
#: parameter; a longer one leaves the neighbourhood of the table's root, where other roots may lie).
POLISH_BRACKET = 1e-3
#: A polished root whose leaf-map miss exceeds this times the certificate's tolerance is no root (a tangency
#: of the table only): the leaf map errs by less than 1e-13 per leaf (:mod:`.leafmap`), 2e-10 over the most
#: steps, so the certificate could never accept it.
NOT_A_ROOT = 10.0
#: Smallest cell width (in the graph's parameter).
MIN_WIDTH = 1e-10


def table_radii(k: float, step: float, phase: float, inv_s: float = math.inf) -> np.ndarray:
    """Radii uniform in r with ``step``, each cell split evenly so that E changes by at most ``phase`` and
    ``1 / s = (1 - 2 r^2)^(-1/2)`` (whose powers make the leaf map steep near A_MAX) by at most ``inv_s``."""
    base = np.linspace(0.0, A_MAX, math.ceil(A_MAX / step) + 1)
    parts = np.maximum(np.ceil(np.abs(np.diff(turn(base, k))) / phase),
                       np.ceil(np.diff((1.0 - 2.0 * base * base) ** -0.5) / inv_s))
    parts = np.maximum(1, parts).astype(int)
    idx = np.repeat(np.arange(parts.size), parts)
    frac = (np.arange(idx.size) - np.repeat(np.cumsum(parts) - parts, parts)) / np.repeat(parts, parts)
    r = base[idx] + frac * (base[idx + 1] - base[idx])
    return np.append(r, A_MAX)
