"""Bracketing the roots of (32)-(33) on the cells of the leaf tables, and the target shift of (33).

:func:`target_shift` gives ``h_m`` of (33) for a branch m (``eta_m = (psi + 2 pi m) / n``, (32)); the
enumeration uses it. A cell of the (a, b) grid of :class:`~.leaves.LeafTables` *brackets* branch m when
``eta_m`` lies between its corners' smallest and largest eta and ``h_m`` between their smallest and largest
h; each bracket carries a start for a root solver (:func:`cell_start`). The planner's ``solve`` no longer
uses the brackets (the enumeration serves every k); they remain for the benchmarks.

See docs/design/geometric-planner.md (the bracketing).
"""

from __future__ import annotations

import math

import numpy as np

from ...core.plane import n_step_gain

__all__ = ["BRACKET_FIELDS", "target_shift", "cell_start", "find_brackets"]

#: Fields of a bracket record (a row of the structured array :func:`find_brackets` returns).
BRACKET_FIELDS = (
    ("lower", "lower bound of a + b in the cell [R]"),
    ("a0", "cell centre a [R]"), ("b0", "cell centre b [R]"),
    ("da", "cell half-width in a [R]"), ("db", "cell half-width in b [R]"),
    ("m", "branch m"), ("eta_m", "turn per step of the branch, (32) [rad]"),
    ("h_m", "shift per step of the branch, (33) [R]"),
    ("a_s", "solver start a [R]"), ("b_s", "solver start b [R]"),
    ("off", "distance of the tables' model root from the cell centre [cell widths]"),
)
_DTYPE = np.dtype([(name, float) for name, _ in BRACKET_FIELDS])


def target_shift(h_des, eta_m, steps: int):
    """Shift one step must produce on branches eta_m, from (33)-(34); nan where unreachable.

    ``h = h_des / |sin(n eta / 2) / sin(eta / 2)|`` (:func:`rollplan.core.plane.n_step_gain`);
    where ``sin(n eta / 2) = 0`` but ``sin(eta / 2) != 0`` the n shifts cancel and
    no h reaches a nonzero h_des.
    """
    gain = n_step_gain(eta_m, steps)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(gain < 1e-12, np.nan, h_des / np.where(gain < 1e-12, 1.0, gain))


def cell_start(eta, h, r, ii, jj, eta_m, h_m):
    """Start of the root solve in cell (ii, jj): the root of the tables' bilinear model, linearized at
    the cell centre, clipped to the cell (the centre where the model is singular).

    ``eta``, ``h``: tabulated eta(a_i, b_j), h(a_i, b_j); returns arrays (a_s, b_s, off), where
    ``off`` is how far the unclipped model root lies from the cell centre, in cell widths
    (inf where the model is singular): a cell where the zero curves of (32) and (33) run
    parallel passes the corner test but has its model root far outside.
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


def find_brackets(c: dict, h_des: float, psi: float, steps: int) -> np.ndarray:
    """Grid cells that bracket a root of (32)-(33) on some branch m.

    ``c`` is :meth:`~.leaves.LeafTables.cells`; ``psi`` in (-pi, pi]. Returns a
    structured array with the fields of :data:`BRACKET_FIELDS`, one record per
    (cell, m), sorted by the lower bound of a + b. Only the cells whose
    smallest eta lies within one cell width below ``eta_m`` are tested
    (bisection in the index of the cells).
    """
    two_pi = 2 * np.pi
    m_all = np.arange(math.ceil((steps * c["eta_lo"] - psi) / two_pi) - 1,
                      math.floor((steps * c["eta_hi"] - psi) / two_pi) + 2)
    eta_all = (psi + two_pi * m_all) / steps
    h_all = target_shift(h_des, eta_all, steps)
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
    # m within [ceil, floor] of the cell's branch range, h_m within the cell's h range
    lo = np.ceil((steps * c["emin"][cell] - psi) / two_pi)
    hi = np.floor((steps * c["emax"][cell] - psi) / two_pi)
    ok = (lo <= m) & (m <= hi) & (c["hmin"][cell] <= h_m) & (h_m <= c["hmax"][cell])
    cell, m = cell[ok], m[ok]
    r, n = c["r"], c["n"]
    ii, jj = cell // n, cell % n
    eta_m = (psi + two_pi * m) / steps
    h_m = target_shift(h_des, eta_m, steps)
    a_s, b_s, off = cell_start(c["eta"], c["h"], r, ii, jj, eta_m, h_m)
    out = np.zeros(cell.size, _DTYPE)
    for name, value in (("lower", r[ii] + r[jj]), ("a0", 0.5 * (r[ii] + r[ii + 1])), ("b0", 0.5 * (r[jj] + r[jj + 1])),
                        ("da", 0.5 * (r[ii + 1] - r[ii])), ("db", 0.5 * (r[jj + 1] - r[jj])), ("m", m),
                        ("eta_m", eta_m), ("h_m", h_m), ("a_s", a_s), ("b_s", b_s), ("off", off)):
        out[name] = value
    return out[np.lexsort((m, cell, out["lower"]))]
