"""Complete enumeration of the roots of (32)-(33): one scalar equation per branch.

Reduction (for ``k >= 1/2``; :mod:`.leafmap` gives the structure used here). One step turns psi
by ``eta(a, b) = E(a) - E(b)`` and shifts by ``h(a, b) = |F|``, ``F = exp(i E(a)) d(a) +
conj(d(b))``, with the turn E in closed form and strictly decreasing on ``(0, A_MAX]``. On branch
m of ``n eta = psi + 2 pi m`` (32) fixes ``eta_m`` and (33) the shift ``h_m``
(:func:`.brackets.target_shift`). Let ``e = |eta_m|``, ``x`` the smaller leaf radius and ``y``
the larger: ``E(y) = E(x) - e``, so

    y(x) = E^-1(E(x) - e),   0 <= x <= x_end = E^-1(E(A_MAX) + e),   dy/dx = E'(x) / E'(y) in [0, 1]

(``|E'|`` grows with r), ``(a, b) = (x, y)`` if ``eta_m >= 0`` and ``(y, x)`` otherwise. The
branch is one smooth curve, parametrised by x. With the leaf's symmetry (``d = rho exp(-i E/2)``,
real rho; :mod:`.leafmap`, items 3-4), ``h^2 = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta_m / 2)``
with ``eta_m`` fixed on the branch, so (33) on it is the scalar equation

    g(x) = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta_m / 2) - h_m^2 = 0,

with ``g'`` from ``E'`` (closed form) and ``rho'``. rho depends on one radius and k only, so it is
tabulated once per k (:func:`rho_table`: cubic Hermite in r on radii uniform in E and in r, its
interpolation error bounded by ``eps``, SAFETY times the largest error at the midpoints against the
accurate map) and cached on disk. Along the branch ``a + b = x + y(x)`` grows with x, and its
smallest value ``y(0) = E^-1(-e)`` grows with ``e``: the shortest plan on a branch is its first root
in x, and a branch whose ``y(0)`` is not below the best length found cannot hold a shorter plan.

Completeness argument. Per branch, g (on the table) is sampled on a grid uniform in the phase
``E(x)`` (steps of :data:`PHASE_STEP` rad) and in x, then every cell is split at its midpoint while
the cubic Hermite interpolant H of (g, g') at its ends misses g at the midpoint by more than
:data:`HERMITE_REL` of the cell's largest |g| and more than rounding (down to :data:`MIN_WIDTH`).
A cell is *excluded* only if ``min |H| > SAFETY * |g(mid) - H(mid)| + floor`` over the cell, with
``floor`` covering rounding and the table's error carried into g. g has no zero there as long as
the Hermite error anywhere in the cell is at most SAFETY times its value at the midpoint (where the
error factor of cubic Hermite interpolation peaks), i.e. as long as the cell resolves g's fourth
derivative, which the splitting enforces; and the true g differs from the tabulated one by less
than the floor. Every other cell is examined: each sign change of g between the ends and the
critical points of H is a root (bracketed Newton); where g keeps its sign but H has an extremum,
the critical point of g is located (bracketed secant on g') and gives two roots (a close pair) or
a double root (a tangency) if ``|g|`` is within the floor there. The roots are then polished by
Newton on g of the accurate map. So every root of (32)-(33) with ``0 < x <= x_end``, on every
branch, is found: simple roots, close pairs down to what the floor separates, and tangencies; the
certificate (:mod:`.certify`) then accepts or rejects each plan. The argument is not interval
arithmetic: it rests on the midpoint error estimating the Hermite error within SAFETY in resolved
cells (and likewise for the table); ``tests/test_enumerate.py`` checks the result against an
independent dense brute force.

For ``k < 1/2`` E is not monotone on ``(0, A_MAX]`` and this parametrisation does not apply:
the planner falls back to bracketing (:mod:`.brackets`), without this guarantee.

Everything is a pure function of numpy arrays (the C planner ports it).
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ...core.curves import A_MAX
from ...progress import report
from . import leafmap
from .brackets import target_shift
from .leafmap import signed_length, turn, turn_dr, turn_inverse

__all__ = ["K_MONOTONE", "PHASE_STEP", "HERMITE_REL", "SAFETY", "MIN_WIDTH", "Branch", "Root", "branches",
           "branch_values", "x_of_length", "roots", "cache_dir", "rho_table"]

#: Smallest k for which E is strictly decreasing on (0, A_MAX] (the reduction above).
K_MONOTONE = 0.5
#: Initial sampling step in the phase E(x) [rad].
PHASE_STEP = 0.5
#: Initial sampling step in x [R].
X_STEP = 0.02
#: A cell is split while its Hermite midpoint error exceeds this fraction of its largest |g|.
HERMITE_REL = 1e-2
#: Factor between the Hermite error anywhere in a cell and at its midpoint.
SAFETY = 4.0
#: Table of rho: steps in the turn E [rad] and in r [R].
TABLE_PHASE = 0.25
TABLE_STEP = 0.005
_TABLE_CHUNK = 512
#: Smallest cell width [R].
MIN_WIDTH = 1e-10


class Branch(NamedTuple):
    """Branch m of ``n eta = psi + 2 pi m``: turn ``eta`` and shift ``h`` per step, the range of
    the smaller radius ``[0, x_end]`` and the smallest ``a + b`` on it (``y0``)."""

    m: int
    eta: float
    h: float
    x_end: float
    y0: float


class Root(NamedTuple):
    """A root of (32)-(33): branch, leaf radii, parameter x, and ``kind`` ("simple" or "double")."""

    m: int
    eta: float
    h: float
    a: float
    b: float
    x: float
    kind: str


def branches(k: float, psi: float, steps: int, h_des: float, only: int | None = None) -> list:
    """Branches m that can hold a root, sorted by their smallest ``a + b`` (``k >= 1/2``).

    ``psi`` in (-pi, pi]; ``only`` restricts to one m. A branch is kept when
    ``|eta_m| <= |E(A_MAX)|`` and ``h_m`` is finite (:func:`.brackets.target_shift`).
    """
    lam = -float(turn(A_MAX, k))
    two_pi = 2.0 * math.pi
    lo = math.ceil((-steps * lam - psi) / two_pi)
    hi = math.floor((steps * lam - psi) / two_pi)
    m = np.arange(lo, hi + 1) if only is None else np.array([only])
    eta = (psi + two_pi * m) / steps
    h = target_shift(h_des, eta, steps)
    keep = np.isfinite(h) & (np.abs(eta) <= lam)
    m, eta, h = m[keep], eta[keep], h[keep]
    e = np.abs(eta)
    y0 = turn_inverse(-e, k)
    x_end = turn_inverse(-lam + e, k)
    order = np.argsort(y0, kind="stable")
    return [Branch(int(m[i]), float(eta[i]), float(h[i]), float(x_end[i]), float(y0[i])) for i in order]


class RhoTable(NamedTuple):
    """Per-k table of the signed length rho(r) of :func:`.leafmap.signed_length` and its r-derivative at
    radii ``r`` (cubic Hermite between them), with ``eps``, a bound of the interpolation error."""

    k: float
    r: np.ndarray
    rho: np.ndarray
    drho: np.ndarray
    eps: float


def _hermite_parts(s):
    """Cubic Hermite basis and its derivative at local coordinates s in [0, 1]."""
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2),
            (6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s))


def rho_lookup(r, t: RhoTable):
    """``(rho, d rho / dr)`` at radii ``r`` from the table (cubic Hermite)."""
    i = np.clip(np.searchsorted(t.r, r, side="right") - 1, 0, t.r.size - 2)
    w = t.r[i + 1] - t.r[i]
    s = (r - t.r[i]) / w
    (h00, h10, h01, h11), (d00, d10, d01, d11) = _hermite_parts(s)
    g0, g1, p0, p1 = t.rho[i], t.rho[i + 1], t.drho[i], t.drho[i + 1]
    return h00 * g0 + h10 * w * p0 + h01 * g1 + h11 * w * p1, (d00 * g0 + d01 * g1) / w + d10 * p0 + d11 * p1


def cache_dir() -> Path:
    """Directory of the per-k tables: ``$ROLLPLAN_CACHE_DIR``, else ``$XDG_CACHE_HOME/rollplan``, else
    ``~/.cache/rollplan``."""
    if os.environ.get("ROLLPLAN_CACHE_DIR"):
        return Path(os.environ["ROLLPLAN_CACHE_DIR"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rollplan"


def _table_file(k: float) -> Path:
    """Cache file of the table of k, keyed by the sources that define it and the table's parameters."""
    h = hashlib.sha256()
    for src in (__file__, leafmap.__file__):
        h.update(Path(src).read_bytes())
    h.update(repr((float(k), TABLE_PHASE, TABLE_STEP, SAFETY, np.__version__)).encode())
    return cache_dir() / f"rho_table_{h.hexdigest()[:32]}.npz"


@lru_cache(maxsize=8)
def rho_table(k: float) -> RhoTable:
    """Table of rho for inertia ratio k, from the disk cache (:func:`cache_dir`) or built and stored there
    atomically (a cache that cannot be read or written is rebuilt or skipped)."""
    path = _table_file(k)
    try:
        with np.load(path) as z:
            return RhoTable(float(k), z["r"], z["rho"], z["drho"], float(z["eps"]))
    except (OSError, KeyError, ValueError):
        pass
    t = _build_rho_table(k)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".rho_table.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, r=t.r, rho=t.rho, drho=t.drho, eps=t.eps)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except OSError:
        pass
    return t


def _build_rho_table(k: float) -> RhoTable:
    """Table of rho for inertia ratio k: radii uniform in the turn E (steps :data:`TABLE_PHASE`) and in r
    (:data:`TABLE_STEP`); ``eps`` is SAFETY times the largest error at the midpoints (where the error
    factor of cubic Hermite interpolation peaks) against the accurate map, plus rounding."""
    t_end = float(turn(A_MAX, k))
    r = np.concatenate([turn_inverse(np.linspace(0.0, t_end, math.ceil(abs(t_end) / TABLE_PHASE) + 2), k),
                        np.linspace(0.0, A_MAX, math.ceil(A_MAX / TABLE_STEP) + 1)])
    r = np.unique(np.clip(r[np.isfinite(r)], 0.0, A_MAX))
    mid = 0.5 * (r[:-1] + r[1:])
    both = np.concatenate([r, mid])
    rho, drho = np.empty(both.size), np.empty(both.size)
    for i in range(0, both.size, _TABLE_CHUNK):
        rho[i:i + _TABLE_CHUNK], drho[i:i + _TABLE_CHUNK] = signed_length(both[i:i + _TABLE_CHUNK], k, derivative=True)
        report(f"leaf table (k = {k:g})", min(i + _TABLE_CHUNK, both.size), both.size)
    n = r.size
    t = RhoTable(float(k), r, rho[:n], drho[:n], 0.0)
    err = np.abs(rho_lookup(mid, t)[0] - rho[n:]).max()
    return t._replace(eps=SAFETY * float(err) + 1e-13)


def branch_values(x, eta, h, k: float, table: RhoTable | None = None):
    """``(g, g', a, b)`` at parameters ``x`` of the branches with turn ``eta`` and shift ``h`` per step
    (arrays broadcast to ``x``; see the module docstring), with
    ``g = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta / 2) - h^2`` (:mod:`.leafmap`, item 4); rho from
    ``table`` if given, else from the accurate map."""
    x = np.atleast_1d(np.asarray(x, float))
    eta = np.broadcast_to(np.asarray(eta, float), x.shape)
    h = np.broadcast_to(np.asarray(h, float), x.shape)
    e = np.abs(eta)
    y = _other(x, eta, k)
    with np.errstate(divide="ignore", invalid="ignore"):
        dy = np.where(e == 0.0, 1.0, np.nan_to_num(turn_dr(x, k) / turn_dr(y, k)))
    plus = eta >= 0.0
    a, b = np.where(plus, x, y), np.where(plus, y, x)
    da_dx, db_dx = np.where(plus, 1.0, dy), np.where(plus, dy, 1.0)
    both = np.concatenate([a, b])
    rho, drho = rho_lookup(both, table) if table is not None else signed_length(both, k, derivative=True)
    n = x.size
    ra, rb, pa, pb = rho[:n], rho[n:], drho[:n], drho[n:]
    c = np.cos(0.5 * eta)
    g = ra * ra + rb * rb + 2.0 * c * ra * rb - h * h
    dg = 2.0 * (ra + c * rb) * pa * da_dx + 2.0 * (rb + c * ra) * pb * db_dx
    return g, dg, a, b


def _other(x, eta, k: float):
    """The larger radius y(x) of branches with turn ``eta`` at the smaller radius x (arrays)."""
    e = np.abs(eta)
    y = np.where(e == 0.0, x, turn_inverse(turn(x, k) - e, k))
    return np.where(np.isnan(y), A_MAX, y)


def x_of_length(total, brs: list, k: float):
    """Per branch, the x in ``[0, x_end]`` where ``a + b = x + y(x)`` reaches ``total`` (clipped;
    ``x + y(x)`` increases with x), by bisection."""
    eta = np.array([br.eta for br in brs])
    lo = np.zeros(eta.size)
    hi = np.array([br.x_end for br in brs])
    top = hi.copy()
    for _ in range(48):
        mid = 0.5 * (lo + hi)
        below = mid + _other(mid, eta, k) < total
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return np.where(top + _other(top, eta, k) <= total, top, hi)


def _grid(brs: list, k: float, x_lo, x_hi):
    """Initial samples of x on ``[x_lo, x_hi]`` of each branch, uniform in the phase E(x) and in x:
    (x, branch index) arrays, sorted by branch then x."""
    xs, owner = [], []
    for i in range(len(brs)):
        if x_hi[i] <= x_lo[i]:
            continue
        t0, t1 = float(turn(x_lo[i], k)), float(turn(x_hi[i], k))
        nt = max(2, math.ceil(abs(t1 - t0) / PHASE_STEP) + 1)
        nx = max(2, math.ceil((x_hi[i] - x_lo[i]) / X_STEP) + 1)
        xi = np.concatenate([turn_inverse(np.linspace(t0, t1, nt), k), np.linspace(x_lo[i], x_hi[i], nx)])
        xi = np.unique(np.clip(xi[np.isfinite(xi)], x_lo[i], x_hi[i]))
        xs.append(xi)
        owner.append(np.full(xi.size, i))
    if not xs:
        return np.zeros(0), np.zeros(0, int)
    return np.concatenate(xs), np.concatenate(owner)


def _hermite(g0, p0, g1, p1, w, s):
    """Cubic Hermite interpolant at the local coordinate s in [0, 1] of cells of width w."""
    h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, -2 * s**3 + 3 * s**2, s**3 - s**2
    return h00 * g0 + h10 * w * p0 + h01 * g1 + h11 * w * p1


def _critical(g0, p0, g1, p1, w):
    """Local coordinates in (0, 1) of the critical points of the Hermite cubic of each cell (nan if none);
    shape (cells, 2)."""
    # H'(s) / w = A s^2 + B s + C with the derivative of the Hermite basis
    A = 3.0 * (2 * g0 + w * p0 - 2 * g1 + w * p1) / w
    B = 2.0 * (-3 * g0 - 2 * w * p0 + 3 * g1 - w * p1) / w
    C = p0
    out = np.full((g0.size, 2), np.nan)
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = B * B - 4 * A * C
        sq = np.sqrt(np.maximum(disc, 0.0))
        quad = np.abs(A) > 1e-300
        r1 = np.where(quad, (-B - sq) / (2 * A), -C / B)
        r2 = np.where(quad, (-B + sq) / (2 * A), np.nan)
    for j, r in enumerate((r1, r2)):
        ok = (disc >= 0) & np.isfinite(r) & (r > 0) & (r < 1)
        out[:, j] = np.where(ok, r, np.nan)
    return np.sort(out, axis=1)


def _cells(brs: list, k: float, x_lo, x_hi, table: RhoTable):
    """Resolved cells of the branches ``brs``: dict of arrays ``own`` (branch index), x0, x1, g0, p0,
    g1, p1, gm, err (see the module docstring)."""
    eta = np.array([br.eta for br in brs])
    hh = np.array([br.h for br in brs])
    xs, own = _grid(brs, k, x_lo, x_hi)
    if xs.size < 2:
        return None
    g, p, _, _ = branch_values(xs, eta[own], hh[own], k, table)
    same = own[:-1] == own[1:]
    o, x0, x1, g0, p0, g1, p1 = own[:-1][same], xs[:-1][same], xs[1:][same], g[:-1][same], p[:-1][same], \
        g[1:][same], p[1:][same]
    done = []
    while x0.size:
        xm = 0.5 * (x0 + x1)
        gm, pm, _, _ = branch_values(xm, eta[o], hh[o], k, table)
        err = np.abs(gm - _hermite(g0, p0, g1, p1, x1 - x0, 0.5))
        big = np.maximum(np.maximum(np.abs(g0), np.abs(g1)), np.abs(gm))
        s = (err > HERMITE_REL * big) & (err > 1e-15 * (1.0 + hh[o] ** 2)) & (x1 - x0 > MIN_WIDTH)
        keep = ~s
        done.append((o[keep], x0[keep], x1[keep], g0[keep], p0[keep], g1[keep], p1[keep], gm[keep], err[keep]))
        o = np.concatenate([o[s], o[s]])
        x0, x1 = np.concatenate([x0[s], xm[s]]), np.concatenate([xm[s], x1[s]])
        g0, g1 = np.concatenate([g0[s], gm[s]]), np.concatenate([gm[s], g1[s]])
        p0, p1 = np.concatenate([p0[s], pm[s]]), np.concatenate([pm[s], p1[s]])
    cols = [np.concatenate(c) for c in zip(*done)]
    if cols[0].size == 0:
        return None
    order = np.lexsort((cols[1], cols[0]))
    return dict(zip(("own", "x0", "x1", "g0", "p0", "g1", "p1", "gm", "err"), (c[order] for c in cols)))


def _bracketed(lo, hi, glo, eta, h, k: float, table, which: int = 0, iters: int = 100):
    """Roots in [lo, hi] of g (``which`` 0) or g' (1) with a sign change there, all at once:
    Newton on g (or the secant on g') kept inside the shrinking bracket, bisection otherwise."""
    lo, hi = lo.copy(), hi.copy()
    slo = np.sign(glo)
    x = 0.5 * (lo + hi)
    active = np.arange(x.size)
    prev_x, prev_f = lo.copy(), glo.copy()
    for _ in range(iters):
        if active.size == 0:
            break
        xa = x[active]
        out = branch_values(xa, eta[active], h[active], k, table)
        f = out[which]
        same = np.sign(f) == slo[active]
        lo[active] = np.where(same, xa, lo[active])
        hi[active] = np.where(same, hi[active], xa)
        with np.errstate(divide="ignore", invalid="ignore"):
            if which == 0:
                nxt = xa - f / out[1]
            else:
                nxt = xa - f * (xa - prev_x[active]) / (f - prev_f[active])
        prev_x[active], prev_f[active] = xa, f
        bad = ~np.isfinite(nxt) | (nxt <= lo[active]) | (nxt >= hi[active])
        nxt = np.where(bad, 0.5 * (lo[active] + hi[active]), nxt)
        x[active] = nxt
        go = (f != 0.0) & (np.abs(nxt - xa) > 2e-16 * (1.0 + np.abs(xa))) & \
             (hi[active] - lo[active] > 4e-16 * (1.0 + np.abs(xa)))
        active = active[go]
    return x


def _examine(act, c, crit, eta, hh, k, table, eps_g):
    """Roots in the active cells ``act`` of :func:`_cells` output ``c`` (see the module docstring):
    arrays of x, branch index and kind."""
    o, x0, x1, g0, p0, g1, p1 = (c[n] for n in ("own", "x0", "x1", "g0", "p0", "g1", "p1"))
    w = x1 - x0
    # sub-intervals of the active cells: ends and the Hermite critical points
    pts = np.column_stack([x0[act], x0[act, None] + w[act, None] * crit[act], x1[act]])   # (n, 4), nan = none
    pts = np.where(np.isnan(pts), x1[act, None], pts)                                   # collapse to the end
    inner = branch_values(pts[:, 1:3].ravel(), np.repeat(eta[o[act]], 2), np.repeat(hh[o[act]], 2), k, table)
    vals = np.column_stack([g0[act], inner[0].reshape(-1, 2), g1[act]])
    dvals = np.column_stack([p0[act], inner[1].reshape(-1, 2), p1[act]])
    owner = o[act]
    found_x, found_o, found_kind = [], [], []
    # sign changes: simple roots
    for j in range(3):
        lo, hi, vlo, vhi = pts[:, j], pts[:, j + 1], vals[:, j], vals[:, j + 1]
        sc = (hi > lo) & (vlo * vhi < 0)
        if sc.any():
            xr = _bracketed(lo[sc], hi[sc], vlo[sc], eta[owner[sc]], hh[owner[sc]], k, table)
            found_x.append(xr)
            found_o.append(owner[sc])
            found_kind += ["simple"] * int(sc.sum())
        exact = (vhi == 0.0) & (hi > 0)
        found_x.append(hi[exact])
        found_o.append(owner[exact])
        found_kind += ["simple"] * int(exact.sum())
    # close pairs and tangencies: g keeps its sign around an interior point where g' changes sign
    for j in (1, 2):
        lo, mid, hi = pts[:, j - 1], pts[:, j], pts[:, j + 1]
        keep_sign = (vals[:, j] * vals[:, j - 1] > 0) & (vals[:, j] * vals[:, j + 1] > 0) & (hi > lo)
        halves = ((lo, mid, dvals[:, j - 1], dvals[:, j]), (mid, hi, dvals[:, j], dvals[:, j + 1]))
        for side_lo, side_hi, dl, dh in halves:
            cand = keep_sign & (side_hi > side_lo) & (dl * dh < 0)
            if not cand.any():
                continue
            xc = _bracketed(side_lo[cand], side_hi[cand], dl[cand], eta[owner[cand]], hh[owner[cand]], k, table,
                            which=1)
            gc = branch_values(xc, eta[owner[cand]], hh[owner[cand]], k, table)[0]
            ref = vals[cand, j]
            pair = gc * ref < 0
            if pair.any():   # two roots, one on each side of the critical point, all pairs at once
                idx = np.nonzero(cand)[0][pair]
                lo2 = np.concatenate([side_lo[idx], xc[pair]])
                hi2 = np.concatenate([xc[pair], side_hi[idx]])
                own2 = np.concatenate([owner[idx], owner[idx]])
                g_lo = branch_values(lo2, eta[own2], hh[own2], k, table)[0]
                found_x.append(_bracketed(lo2, hi2, g_lo, eta[own2], hh[own2], k, table))
                found_o.append(own2)
                found_kind += ["simple"] * int(own2.size)
            tang = ~pair & (np.abs(gc) <= 1e-13 * (1.0 + hh[owner[cand]] ** 2) + eps_g)
            found_x.append(xc[tang])
            found_o.append(owner[cand][tang])
            found_kind += ["double"] * int(tang.sum())
    xr, orr = np.concatenate(found_x), np.concatenate(found_o)
    kinds = np.array(found_kind, dtype=object)
    return xr, orr, kinds

def _polish(x, eta, h, k: float, x_end, iters: int = 6):
    """Newton on g of the accurate map from the table's roots (a few steps; a step that would leave
    [0, x_end] or grow is not taken): the roots to rounding on the accurate map."""
    x = x.copy()
    if x.size == 0:
        return x
    g, dg, _, _ = branch_values(x, eta, h, k)
    for _ in range(iters):
        with np.errstate(divide="ignore", invalid="ignore"):
            nxt = np.clip(x - g / dg, 0.0, x_end)
        ok = np.isfinite(nxt)
        if not ok.any():
            break
        g2, dg2, _, _ = branch_values(np.where(ok, nxt, x), eta, h, k)
        better = ok & (np.abs(g2) < np.abs(g))
        x = np.where(better, nxt, x)
        g, dg = np.where(better, g2, g), np.where(better, dg2, dg)
        if not better.any():
            break
    return x


def roots(brs: list, k: float, first_only: bool = False, lengths=(0.0, math.inf)) -> list:
    """Every root of g on the branches ``brs`` with ``0 < x <= x_end`` and ``lengths[0] <= a + b <=
    lengths[1]`` (:class:`Root`, sorted by ``a + b``); with ``first_only`` only the first root of
    each branch in x (its shortest plan). See the module docstring for why none is missed."""
    brs = [br for br in brs if br.x_end > 0.0]
    if not brs:
        return []
    eta = np.array([br.eta for br in brs])
    hh = np.array([br.h for br in brs])
    x_lo = x_of_length(lengths[0], brs, k) if lengths[0] > 0.0 else np.zeros(len(brs))
    x_hi = x_of_length(lengths[1], brs, k) if math.isfinite(lengths[1]) else np.array([br.x_end for br in brs])
    table = rho_table(float(k))
    c = _cells(brs, k, x_lo, x_hi, table)
    if c is None:
        return []
    o, x0, x1, g0, p0, g1, p1, gm, err = (c[n] for n in ("own", "x0", "x1", "g0", "p0", "g1", "p1", "gm", "err"))
    w = x1 - x0
    crit = _critical(g0, p0, g1, p1, w)
    hcrit = _hermite(g0[:, None], p0[:, None], g1[:, None], p1[:, None], w[:, None], np.nan_to_num(crit))
    hc = np.where(np.isnan(crit), np.inf, np.abs(hcrit))
    crosses = (~np.isnan(crit) & (hcrit * g0[:, None] <= 0)).any(axis=1)    # H changes sign inside
    eps_g = 8.0 * float(np.abs(table.rho).max()) * table.eps + table.eps ** 2   # table error carried into g
    floor = 1e-13 * (1.0 + hh[o] ** 2) + eps_g
    low = np.minimum(np.minimum(np.abs(g0), np.abs(g1)), hc.min(axis=1))
    sign_change = (np.sign(g0) != np.sign(g1)) | (np.sign(g0) != np.sign(gm))
    act = np.nonzero(sign_change | crosses | (low <= SAFETY * err + floor))[0]
    if act.size == 0:
        return []
    if not first_only:
        xr, orr, kinds = _examine(act, c, crit, eta, hh, k, table, eps_g)
    else:   # the active cells of each branch in order, a few at a time, until it has a root
        rank = np.arange(act.size) - np.searchsorted(o[act], o[act])
        parts, done, start = [], np.zeros(len(brs), bool), 0
        while True:
            sel = act[(rank >= start) & (rank < start + 2) & ~done[o[act]]]
            if sel.size == 0:
                break
            part = _examine(sel, c, crit, eta, hh, k, table, eps_g)
            parts.append(part)
            done[part[1][part[0] > 0.0]] = True
            start += 2
        xr, orr, kinds = (np.concatenate([q[j] for q in parts]) for j in range(3))
    ok = xr > 0.0
    xr, orr, kinds = xr[ok], orr[ok], kinds[ok]
    order = np.lexsort((xr, orr))
    xr, orr, kinds = xr[order], orr[order], kinds[order]
    if first_only:     # the first two of each branch: polishing may merge a close pair
        rank = np.arange(xr.size) - np.searchsorted(orr, orr)
        keep = rank < 2
        xr, orr, kinds = xr[keep], orr[keep], kinds[keep]
    xr = _polish(xr, eta[orr], hh[orr], k, np.array([br.x_end for br in brs])[orr])
    order = np.lexsort((xr, orr))
    xr, orr, kinds = xr[order], orr[order], kinds[order]
    dup = np.zeros(xr.size, bool)
    dup[1:] = (orr[1:] == orr[:-1]) & (np.abs(xr[1:] - xr[:-1]) <= 1e-13)
    xr, orr, kinds = xr[~dup], orr[~dup], kinds[~dup]
    if first_only:
        first = np.ones(xr.size, bool)
        first[1:] = orr[1:] != orr[:-1]
        xr, orr, kinds = xr[first], orr[first], kinds[first]
    if xr.size == 0:
        return []
    _, _, a, b = branch_values(xr, eta[orr], hh[orr], k)
    out = [Root(brs[orr[i]].m, brs[orr[i]].eta, brs[orr[i]].h, float(a[i]), float(b[i]), float(xr[i]), str(kinds[i]))
           for i in range(xr.size)]
    return sorted(out, key=lambda r: r.a + r.b)
