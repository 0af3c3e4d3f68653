"""Leaf tables: the two leaves of the figure eight tabulated over their radius, per k.

Each leaf of the figure eight (31), (35) depends on one radius only, so one
trace from zero (gamma = 0) of leaf ``i`` with radius ``r`` is a function of
``(r, k)``: its end state ``(u_a, v_a, psi)``. :class:`LeafTables` tabulates
both leaves on an adaptive grid of radii on [0, A_MAX] (coarse: the tables
serve only to bracket roots), and :meth:`LeafTables.cells` indexes the cells of
the (a, b) grid by the range of ``eta`` and ``h`` over their corners, as the
bracketing of :mod:`.brackets` needs. Both are cached per k.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

from ...core.curves import A_MAX, figure_eight
from ...core.integrate import spectral_step
from ...core.plane import rotate

__all__ = ["TABLE_NODES", "LeafTables"]

#: Coarse Chebyshev degree for tabulating the leaves.
TABLE_NODES = 12
#: Tables kept per planner (one per (k, fineness)).
_CACHE = 8


def _remember(cache: dict, key, value, size: int = _CACHE) -> None:
    """Store ``value`` in a small cache, dropping the oldest entry beyond ``size``."""
    cache[key] = value
    while len(cache) > size:
        cache.pop(next(iter(cache)))


class LeafTables:
    """Per-k tables of the two leaves and the index of the (a, b) grid cells built from them."""

    def __init__(self) -> None:
        curve = figure_eight()
        self._leaves = [spectral_step(curve, TABLE_NODES, pieces=(i,)) for i in range(len(curve.pieces))]
        self._tables: dict = {}
        self._cells: dict = {}

    def table(self, k: float, fine: bool = False) -> np.ndarray:
        """Leaf maps on an adaptive grid of radii, shape (7, M): r, then (u_a, v_a, psi) of each leaf.

        The grid is refined until psi turns by less than 0.5 rad (0.2 rad when
        ``fine``, for finding all branches) and the shift moves by less than
        0.1 R (0.04 R) between neighbouring radii.
        """
        key = (k, fine)
        if key in self._tables:
            return self._tables[key]
        turn, move, cap = (0.2, 0.04, 2500) if fine else (0.5, 0.1, 1500)
        grid = np.linspace(0.0, A_MAX, 129)
        vals = np.zeros((7, 0))
        while grid.size:
            p = np.vstack([grid, grid])
            res = [np.array(leaf.map(grid.size)(ca.DM.zeros(3), p, k, 0)) for leaf in self._leaves]
            vals = np.hstack([vals, np.vstack([grid, res[0], res[1]])])
            vals = vals[:, np.argsort(vals[0])]
            diff = np.abs(np.diff(vals[1:], axis=1))
            coarse = (diff[[2, 5]].max(axis=0) > turn) | (diff[[0, 1, 3, 4]].max(axis=0) > move)
            if vals.shape[1] > cap:
                break
            grid = 0.5 * (vals[0, :-1] + vals[0, 1:])[coarse]
        _remember(self._tables, key, vals)
        return vals

    def cells(self, k: float, fine: bool = False) -> dict:
        """Index of the cells of the (a, b) grid of :meth:`table` (cached with the tables).

        For every cell (i, j): the range of eta and of h over its four corners;
        cells are sorted by their smallest eta so that the cells whose eta
        range holds a given value are found by bisection. Keys: ``r`` (grid),
        ``n`` (cells per axis), ``eta``, ``h`` (corner values), ``emin``,
        ``emax``, ``hmin``, ``hmax`` (per cell), ``order``, ``emin_sorted``,
        ``width`` (largest eta range of a cell), ``eta_lo``, ``eta_hi``.
        """
        key = (k, fine)
        if key in self._cells:
            return self._cells[key]
        t = self.table(k, fine)
        r, d0, eta0, d1, eta1 = t[0], t[1:3], t[3], t[4:6], t[6]
        eta = eta0[:, None] + eta1[None, :]
        shift = rotate(eta0, d0)[:, :, None] + d1[:, None, :]   # Rot(eta0) D_bar, |.| = h
        h = np.hypot(shift[0], shift[1])

        def span(z):
            lo = np.minimum(np.minimum(z[:-1, :-1], z[1:, :-1]), np.minimum(z[:-1, 1:], z[1:, 1:]))
            hi = np.maximum(np.maximum(z[:-1, :-1], z[1:, :-1]), np.maximum(z[:-1, 1:], z[1:, 1:]))
            return lo.ravel(), hi.ravel()

        emin, emax = span(eta)
        hmin, hmax = span(h)
        order = np.argsort(emin, kind="stable")
        cells = {"r": r, "n": r.size - 1, "order": order, "emin_sorted": emin[order],
                 "emin": emin, "emax": emax, "hmin": hmin, "hmax": hmax, "eta": eta, "h": h,
                 "width": float((emax - emin).max()) if emin.size else 0.0,
                 "eta_lo": float(emin.min()), "eta_hi": float(emax.max())}
        _remember(self._cells, key, cells)
        return cells
