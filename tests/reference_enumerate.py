"""The tests' numpy reference of the C search: complete enumeration of the roots of (32)-(33), one scalar
equation per graph of each branch. Not used by the planner; the tests check the C search
(:mod:`rollplan.planners.geometric.compiled_search`) against it and it against brute forces.

On branch m of ``n eta = psi + 2 pi m`` (32) fixes ``eta_m`` and (33) becomes, on the level set
``E(a) - E(b) = eta_m``, ``g = rho(a)^2 + rho(b)^2 + 2 rho(a) rho(b) cos(eta_m / 2) - h_m^2 = 0`` (rho from a
per-k table, :func:`rho_table`). The level set is covered by graphs: over the root phase ``w = sqrt(-E)`` for
``k >= K_FAST`` (:class:`_WGraphs`), over ``sigma = a +- b`` on the monotone pieces of E below
(:class:`_SigmaGraphs`); every root on them is found by Hermite cells (:func:`roots`). The C search uses the sigma
graphs for ``k < 1/2`` and another graph, over the smaller radius, above; both take their constants from
:mod:`rollplan.planners.geometric.search_constants`.

Derivation and completeness argument: docs/design/enumeration.md.
"""

from __future__ import annotations

import hashlib
import math
import os
import tempfile
import time
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from rollplan.core.compiled import cache_dir, check_private, private_cache_dir
from rollplan.core.curves import A_MAX
from rollplan.core.plane import target_shift, wrap_exact
from rollplan.errors import NoPlanError
from rollplan.planners.geometric import leafmap, search_constants
from rollplan.planners.geometric.leafmap import (
    radius_of_root_phase,
    root_phase,
    signed_length,
    turn,
    turn_dr,
    turn_inverse,
    turn_pieces,
)
from rollplan.planners.geometric.planner import GeometricPhasePlanner
from rollplan.planners.geometric.planner import _no_root as no_root
from rollplan.planners.geometric.search_constants import (
    HERMITE_REL,
    K_MONOTONE,
    MIN_WIDTH,
    NOT_A_ROOT,
    PHASE_STEP,
    POLISH_BRACKET,
    POLISH_STEP,
    SAFETY,
    SIGMA_STEP,
    TABLE_INV_S,
    TABLE_PHASE,
    TABLE_STEP,
    X_STEP,
    table_radii,
)
from rollplan.problem import Problem
from rollplan.progress import report
from rollplan.result import CERTIFICATE_TOLERANCE

__all__ = ["K_MONOTONE", "K_ENUMERATED", "K_FAST", "PHASE_STEP", "X_STEP", "SIGMA_STEP", "HERMITE_REL", "SAFETY",
           "MIN_WIDTH", "TABLE_PHASE", "TABLE_STEP", "TABLE_INV_S", "POLISH_STEP", "POLISH_BRACKET", "NOT_A_ROOT",
           "Branch", "Root", "branches", "roots", "cache_dir", "rho_table", "table_radii", "RhoTable", "rho_lookup",
           "newton_step", "ReferencePlanner", "reference_plan"]

#: Smallest k the enumeration serves: every accepted k.
K_ENUMERATED = 0.0
#: Smallest k of the root-phase parametrisation (above K_MONOTONE: w is smooth in r for k > 1/2).
K_FAST = 0.6
_TABLE_CHUNK = 512
_POLISH_CHUNK = 2048
#: Table-level roots are located to this (absolute, in the graph's parameter) before the polish.
ROOT_TOL = 1e-10


class Branch(NamedTuple):
    """Branch m of ``n eta = psi + 2 pi m``: turn ``eta`` and shift ``h`` per step, the largest smaller
    radius on it (``x_end``) and a lower bound of ``a + b`` on it (``y0``; exact for ``k >= 1/2``)."""

    m: int
    eta: float
    h: float
    x_end: float
    y0: float


class Root(NamedTuple):
    """A root of (32)-(33): branch, leaf radii, the smaller radius x, and ``kind`` ("simple" or "double")."""

    m: int
    eta: float
    h: float
    a: float
    b: float
    x: float
    kind: str


# ----------------------------------------------------------------------------- tables


class RhoTable(NamedTuple):
    """Per-k table of the signed length rho of :func:`.leafmap.signed_length` at radii ``r`` (cubic Hermite
    between them), with ``eps``, a bound of the interpolation error. For ``k >= K_FAST`` the
    interpolation is in the root phase ``w`` (nodes ``w``, ``drdw = dr/dw``), otherwise in r (``w`` empty)."""

    k: float
    r: np.ndarray
    rho: np.ndarray
    drho: np.ndarray
    eps: float
    w: np.ndarray
    drdw: np.ndarray


def _hermite_parts(s):
    """Cubic Hermite basis and its derivative at local coordinates s in [0, 1]."""
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1, s3 - 2 * s2 + s, -2 * s3 + 3 * s2, s3 - s2),
            (6 * s2 - 6 * s, 3 * s2 - 4 * s + 1, -6 * s2 + 6 * s, 3 * s2 - 2 * s))


def rho_lookup(r, t: RhoTable):
    """``(rho, d rho / dr)`` at radii ``r`` from the table (cubic Hermite in r)."""
    i = np.clip(np.searchsorted(t.r, r, side="right") - 1, 0, t.r.size - 2)
    w = t.r[i + 1] - t.r[i]
    s = (r - t.r[i]) / w
    (h00, h10, h01, h11), (d00, d10, d01, d11) = _hermite_parts(s)
    g0, g1, p0, p1 = t.rho[i], t.rho[i + 1], t.drho[i], t.drho[i + 1]
    return h00 * g0 + h10 * w * p0 + h01 * g1 + h11 * w * p1, (d00 * g0 + d01 * g1) / w + d10 * p0 + d11 * p1


def _table_file(k: float) -> Path:
    """Cache file of the table of k, keyed by the sources that define it and the table's parameters."""
    h = hashlib.sha256()
    for src in (__file__, leafmap.__file__, search_constants.__file__):
        h.update(Path(src).read_bytes())
    h.update(repr((float(k), TABLE_PHASE, TABLE_STEP, TABLE_INV_S, SAFETY, K_FAST, np.__version__)).encode())
    return cache_dir() / f"rho_table_{h.hexdigest()[:32]}.npz"


@lru_cache(maxsize=8)
def rho_table(k: float) -> RhoTable:
    """Table of rho for inertia ratio k, from the disk cache (:func:`cache_dir`) or built and stored there
    atomically (a cache that cannot be read or written is rebuilt or skipped)."""
    path = _table_file(k)
    try:
        private_cache_dir()
        if path.exists():
            check_private(path)
    except OSError:   # no cache directory and none can be made: the table is built and not stored
        pass
    try:
        with np.load(path) as z:
            return RhoTable(float(k), z["r"], z["rho"], z["drho"], float(z["eps"]), z["w"], z["drdw"])
    except (OSError, KeyError, ValueError):
        pass
    t = _build_rho_table(k)
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".rho_table.", suffix=".tmp")
        try:
            with os.fdopen(fd, "wb") as fh:
                np.savez(fh, r=t.r, rho=t.rho, drho=t.drho, eps=t.eps, w=t.w, drdw=t.drdw)
            os.replace(tmp, path)
        finally:
            if os.path.exists(tmp):
                os.unlink(tmp)
    except OSError:
        pass
    return t


def _accurate_rho(r, k: float, label: str):
    """rho and d rho / dr at radii r by the accurate map, in chunks, with progress."""
    rho, drho = np.empty(r.size), np.empty(r.size)
    for i in range(0, r.size, _TABLE_CHUNK):
        rho[i:i + _TABLE_CHUNK], drho[i:i + _TABLE_CHUNK] = signed_length(r[i:i + _TABLE_CHUNK], k, derivative=True)
        report(label, min(i + _TABLE_CHUNK, r.size), r.size)
    return rho, drho


def _build_rho_table(k: float) -> RhoTable:
    """Table of rho for inertia ratio k on :func:`table_radii` (steps :data:`TABLE_STEP`, :data:`TABLE_PHASE`);
    ``eps`` is SAFETY times the largest error at the midpoints of the interpolation variable (where the
    error factor of cubic Hermite interpolation peaks) against the accurate map, plus rounding."""
    r = table_radii(k, TABLE_STEP, TABLE_PHASE, TABLE_INV_S)
    n = r.size
    label = f"leaf table (k = {k:g})"
    if k >= K_FAST:
        w, dwdr = root_phase(r, k)
        drdw = 1.0 / dwdr
        wm = 0.5 * (w[:-1] + w[1:])
        mid = turn_inverse(-wm * wm, k)
    else:
        w, drdw = np.zeros(0), np.zeros(0)
        mid = 0.5 * (r[:-1] + r[1:])
    rho, drho = _accurate_rho(np.concatenate([r, mid]), k, label)
    t = RhoTable(float(k), r, rho[:n], drho[:n], 0.0, w, drdw)
    approx = _w_lookup(wm, _coefficients(t))[0] if k >= K_FAST else rho_lookup(mid, t)[0]
    err = np.abs(approx - rho[n:]).max()
    return t._replace(eps=SAFETY * float(err) + 1e-13)


class _WTable(NamedTuple):
    """Monomial coefficients per cell of the Hermite cubics in w of rho (0..3) and of r (4..7), cell widths."""

    w: np.ndarray
    width: np.ndarray
    coef: np.ndarray


def _cubic_coefficients(y0, m0, y1, m1):
    """Monomial coefficients in s in [0, 1] of the Hermite cubic with values y and scaled slopes m."""
    return np.column_stack([y0, m0, -3 * y0 - 2 * m0 + 3 * y1 - m1, 2 * y0 + m0 - 2 * y1 + m1])


def _coefficients(t: RhoTable) -> _WTable:
    width = np.diff(t.w)
    drhodw = t.drho * t.drdw
    c_rho = _cubic_coefficients(t.rho[:-1], width * drhodw[:-1], t.rho[1:], width * drhodw[1:])
    c_r = _cubic_coefficients(t.r[:-1], width * t.drdw[:-1], t.r[1:], width * t.drdw[1:])
    return _WTable(t.w, width, np.hstack([c_rho, c_r]))


@lru_cache(maxsize=8)
def _w_table(k: float) -> _WTable:
    return _coefficients(rho_table(k))


def _w_lookup(w, wt: _WTable):
    """``(rho, d rho / dw, r)`` at root phases w (Hermite cubics of the table)."""
    i = np.searchsorted(wt.w, w, side="right") - 1
    i = np.minimum(np.maximum(i, 0), wt.width.size - 1)
    h = wt.width[i]
    s = (w - wt.w[i]) / h
    c = wt.coef[i]
    rho = ((c[:, 3] * s + c[:, 2]) * s + c[:, 1]) * s + c[:, 0]
    drho = ((3.0 * c[:, 3] * s + 2.0 * c[:, 2]) * s + c[:, 1]) / h
    r = ((c[:, 7] * s + c[:, 6]) * s + c[:, 5]) * s + c[:, 4]
    return rho, drho, r


@lru_cache(maxsize=8)
def _w_nodes(k: float) -> np.ndarray:
    """Initial sampling nodes in w of the w graphs (docs/design/enumeration.md)."""
    return np.unique(root_phase(table_radii(k, X_STEP, PHASE_STEP), k)[0])


# ----------------------------------------------------------------------------- branches


def branches(k: float, psi: float, steps: int, h_des: float, only: int | None = None) -> list:
    """Branches m that can hold a root, sorted by their lower bound of ``a + b``.

    ``psi`` in (-pi, pi]; ``only`` restricts to one m. A branch is kept when ``|eta_m|`` is at most
    the range of E on ``(0, A_MAX]``, ``h_m`` is finite (:func:`rollplan.core.plane.target_shift`) and its level
    set is not empty.
    """
    k = float(k)
    e_lo, e_hi = _turn_range(k)
    lam = e_hi - e_lo
    two_pi = 2.0 * math.pi
    lo = math.ceil((-steps * lam - psi) / two_pi)
    hi = math.floor((steps * lam - psi) / two_pi)
    m = np.arange(lo, hi + 1) if only is None else np.array([only])
    eta = (psi + two_pi * m) / steps
    h = target_shift(h_des, eta, steps)
    keep = np.isfinite(h) & (np.abs(eta) <= lam)
    m, eta, h = m[keep], eta[keep], h[keep]
    if k >= K_FAST:
        e = np.abs(eta)
        r = _radius(np.sqrt(np.concatenate([e, lam - e])), k)
        y0, x_end = r[:e.size], r[e.size:]
    else:
        gr = _SigmaGraphs(k, eta, h)
        y0, x_end = np.full(eta.size, np.inf), np.zeros(eta.size)
        np.minimum.at(y0, gr.br, gr.low)
        np.maximum.at(x_end, gr.br, gr.xmax)
    order = np.argsort(y0, kind="stable")
    order = order[np.isfinite(y0[order])]
    return list(map(Branch._make, zip(m[order].tolist(), eta[order].tolist(), h[order].tolist(),
                                      x_end[order].tolist(), y0[order].tolist())))


def _radius(w, k: float):
    """Radii of root phases w (``k >= K_FAST``): the table's Hermite cubic, then one Newton step on the
    closed form (quadratic from the cubic's error)."""
    return radius_of_root_phase(w, k, _w_lookup(w, _w_table(k))[2], steps=1)


@lru_cache(maxsize=32)
def _turn_range(k: float) -> tuple:
    """Smallest and largest E on [0, A_MAX] (E(0) = 0; extremes at the ends of the monotone pieces)."""
    ends = [0.0] + [float(turn(p[1], k)) for p in turn_pieces(k)]
    return min(ends), max(ends)


# ----------------------------------------------------------------------------- graphs


class _WGraphs:
    """The w graphs of branches (``k >= K_FAST``, docs/design/enumeration.md): one per branch."""

    def __init__(self, k: float, eta, h, lengths, y0):
        self.k = k
        self.wt = _w_table(k)
        self.nodes = _w_nodes(k)
        lam = -_turn_range(k)[0]
        self.eta = np.asarray(eta, float)
        self.e = np.abs(self.eta)
        self.c = np.cos(0.5 * self.eta)
        self.h2 = np.asarray(h, float) ** 2
        self.br = np.arange(self.eta.size)
        self.lo = np.zeros(self.eta.size)
        self.hi = np.sqrt(np.maximum(lam - self.e, 0.0))
        if lengths[0] > 0.0:   # a + b >= L0 needs y >= L0 / 2
            y_lo = root_phase(min(0.5 * lengths[0], A_MAX), k)[0]
            self.lo = np.sqrt(np.maximum(y_lo * y_lo - self.e, 0.0))
        if math.isfinite(lengths[1]):   # a + b <= L needs w(y) <= w(L) and x <= L - y0
            cap = root_phase(min(lengths[1], A_MAX), k)[0]
            self.hi = np.minimum(self.hi, np.sqrt(np.maximum(cap * cap - self.e, 0.0)))
            x_cap = root_phase(np.clip(lengths[1] - np.asarray(y0, float), 0.0, A_MAX), k)[0]
            self.hi = np.minimum(self.hi, x_cap)
        self.eps_g = _eps_g(k)
        self.monotone_length = True

    def grid(self):
        """Initial samples (p, graph index), sorted by graph then p; the table's nodes inside, and the ends."""
        ok = np.nonzero(self.hi > self.lo)[0]
        i0 = np.searchsorted(self.nodes, self.lo[ok], side="right")
        i1 = np.searchsorted(self.nodes, self.hi[ok], side="left")
        cnt = np.maximum(i1 - i0, 0) + 2
        start = np.cumsum(cnt) - cnt
        gi = np.repeat(ok, cnt)
        pos = np.arange(cnt.sum()) - np.repeat(start, cnt)
        p = self.nodes[np.clip(np.repeat(i0, cnt) + pos - 1, 0, self.nodes.size - 1)]
        p[start] = self.lo[ok]
        p[start + cnt - 1] = self.hi[ok]
        return p, gi

    def values(self, p, gi, accurate: bool = False):
        """``(g, g', a, b)`` at parameters p of graphs gi (table, or the accurate map)."""
        return self._values(p, gi, accurate)[:4]

    def _values(self, p, gi, accurate: bool):
        n = p.size
        wy = np.sqrt(p * p + self.e[gi])
        both = np.concatenate([p, wy])
        rho, drho, r = _w_lookup(both, self.wt)
        drdw = None
        if accurate:
            r = radius_of_root_phase(both, self.k, r, steps=1)   # the table's r is close: one step to rounding
            rho, drho = signed_length(r, self.k, derivative=True)
            drdw = 1.0 / root_phase(r, self.k)[1]
            drho = drho * drdw
        slope = np.where(wy > 0.0, p / np.maximum(wy, 1e-300), 1.0)
        ra, rb, pa, pb = rho[:n], rho[n:], drho[:n], drho[n:]
        c = self.c[gi]
        g = ra * ra + rb * rb + 2.0 * c * ra * rb - self.h2[gi]
        dg = 2.0 * (ra + c * rb) * pa + 2.0 * (rb + c * ra) * pb * slope
        plus = self.eta[gi] >= 0.0
        x, y = r[:n], r[n:]
        if drdw is None:
            return g, dg, np.where(plus, x, y), np.where(plus, y, x)
        dx, dy = drdw[:n], drdw[n:] * slope
        return g, dg, np.where(plus, x, y), np.where(plus, y, x), np.where(plus, dx, dy), np.where(plus, dy, dx)

    def accurate(self, p, gi):
        """``(g, g', a, b, da/dp, db/dp)`` on the accurate map."""
        return self._values(p, gi, True)


def _inverse_on(t, k: float, lo, hi, sign):
    """Radius on the piece ``[lo, hi]`` (sign of E' there) with ``E = t`` (t clipped to the piece's range),
    by bisection on the closed form (arrays)."""
    a, b = np.array(lo, float), np.array(hi, float)
    t = np.asarray(t, float)
    for _ in range(60):
        mid = 0.5 * (a + b)
        right = (turn(mid, k) - t) * sign < 0.0   # E(mid) before t along the piece: the root is to the right
        a, b = np.where(right, mid, a), np.where(right, b, mid)
    return 0.5 * (a + b)


class _SigmaGraphs:
    """The sigma graphs of branches (every k, docs/design/enumeration.md): one per branch and rectangle of pieces."""

    def __init__(self, k: float, eta, h, lengths=(0.0, math.inf)):
        self.k = k
        eta = np.asarray(eta, float)
        h = np.asarray(h, float)
        pieces = turn_pieces(k)
        cols = {n: [] for n in ("br", "eta", "h", "kap", "sa", "alo", "ahi", "blo", "bhi", "sb", "lo", "hi",
                                "low", "xmax")}
        idx = np.arange(eta.size)
        for lo_i, hi_i, s_i in pieces:
            ti = sorted((float(turn(lo_i, k)), float(turn(hi_i, k))))
            for lo_j, hi_j, s_j in pieces:
                tj = sorted((float(turn(lo_j, k)), float(turn(hi_j, k))))
                t_lo = np.maximum(ti[0], tj[0] + eta)      # E(a) in E(piece i) and E(a) - eta in E(piece j)
                t_hi = np.minimum(ti[1], tj[1] + eta)
                ok = t_hi > t_lo
                if not ok.any():
                    continue
                e_, t_lo, t_hi, b_ = eta[ok], t_lo[ok], t_hi[ok], idx[ok]
                ends = np.concatenate([t_lo, t_hi])
                a_end = _inverse_on(ends, k, lo_i, hi_i, s_i)
                b_end = _inverse_on(ends - np.concatenate([e_, e_]), k, lo_j, hi_j, s_j)
                q = e_.size
                if s_i < 0:   # a decreasing in E(a): the end of larger E has the smaller a
                    a_end = np.concatenate([a_end[q:], a_end[:q]])
                    b_end = np.concatenate([b_end[q:], b_end[:q]])
                kap = s_i * s_j
                sig = a_end + kap * b_end
                keep = sig[q:] > sig[:q]
                n = int(keep.sum())
                cols["br"].append(b_[keep])
                cols["eta"].append(e_[keep])
                cols["h"].append(h[b_][keep])
                cols["kap"].append(np.full(n, float(kap)))
                cols["sa"].append(np.full(n, float(s_i)))
                cols["sb"].append(np.full(n, float(s_j)))
                cols["alo"].append(a_end[:q][keep])
                cols["ahi"].append(a_end[q:][keep])
                cols["blo"].append(np.full(n, lo_j))
                cols["bhi"].append(np.full(n, hi_j))
                cols["lo"].append(sig[:q][keep])
                cols["hi"].append(sig[q:][keep])
                b_min = np.minimum(b_end[:q], b_end[q:])[keep]
                cols["low"].append(a_end[:q][keep] + b_min)
                cols["xmax"].append(np.minimum(np.maximum(a_end[:q], a_end[q:]),
                                               np.maximum(b_end[:q], b_end[q:]))[keep])
        for name, v in cols.items():
            setattr(self, name, np.concatenate(v) if v else np.zeros(0))
        self.br = self.br.astype(int)
        self.c = np.cos(0.5 * self.eta)
        self.h2 = self.h ** 2
        if math.isfinite(lengths[1]):   # sigma = a + b on kappa = +1 graphs
            self.hi = np.where(self.kap > 0, np.minimum(self.hi, lengths[1]), self.hi)
        self.table = rho_table(k)
        self.eps_g = _eps_g(k)
        self.monotone_length = False

    def grid(self):
        ok = np.nonzero(self.hi > self.lo)[0]
        cnt = np.ceil((self.hi[ok] - self.lo[ok]) / SIGMA_STEP).astype(int) + 1
        start = np.cumsum(cnt) - cnt
        gi = np.repeat(ok, cnt)
        frac = (np.arange(cnt.sum()) - np.repeat(start, cnt)) / np.repeat(cnt - 1, cnt)
        return self.lo[gi] + frac * (self.hi[gi] - self.lo[gi]), gi

    def radii(self, p, gi):
        """``(a, b)`` on graphs gi at parameters p: bracketed Newton on ``E(a) - E(kappa (p - a)) = eta``."""
        k, kap = self.k, self.kap[gi]
        b_lo, b_hi = self.blo[gi], self.bhi[gi]
        lo = np.maximum(self.alo[gi], np.where(kap > 0, p - b_hi, p + b_lo))
        hi = np.minimum(self.ahi[gi], np.where(kap > 0, p - b_lo, p + b_hi))
        hi = np.maximum(hi, lo)
        span = self.hi[gi] - self.lo[gi]
        with np.errstate(divide="ignore", invalid="ignore"):
            frac = np.where(span > 0, (p - self.lo[gi]) / span, 0.5)
        a = np.clip(self.alo[gi] + frac * (self.ahi[gi] - self.alo[gi]), lo, hi)
        sa, eta = self.sa[gi], self.eta[gi]
        for _ in range(80):
            b = _clip(kap * (p - a), b_lo, b_hi)
            f = turn(a, k) - turn(b, k) - eta
            df = turn_dr(a, k) + kap * turn_dr(b, k)
            right = f * sa < 0.0                   # Phi increases along s_a: the root is to the right
            lo, hi = np.where(right, a, lo), np.where(right, hi, a)
            with np.errstate(divide="ignore", invalid="ignore"):
                nxt = a - f / df
            bad = ~np.isfinite(nxt) | (nxt <= lo) | (nxt >= hi)
            nxt = np.where(bad, 0.5 * (lo + hi), nxt)
            done = np.all((np.abs(nxt - a) <= 1e-16 + 2e-16 * a) | (hi - lo <= 4e-16 * (1.0 + hi)) | (f == 0.0))
            a = np.where(f == 0.0, a, nxt)
            if done:
                break
        return a, _clip(kap * (p - a), b_lo, b_hi)

    def values(self, p, gi, accurate: bool = False):
        """``(g, g', a, b)`` at parameters p of graphs gi (table, or the accurate map)."""
        return self._values(p, gi, accurate)[:4]

    def accurate(self, p, gi):
        """``(g, g', a, b, da/dp, db/dp)`` on the accurate map."""
        return self._values(p, gi, True)

    def _values(self, p, gi, accurate: bool):
        a, b = self.radii(p, gi)
        n = p.size
        both = np.concatenate([a, b])
        rho, drho = signed_length(both, self.k, derivative=True) if accurate else rho_lookup(both, self.table)
        ea, eb = turn_dr(a, self.k), turn_dr(b, self.k)
        kap = self.kap[gi]
        den = eb + kap * ea
        with np.errstate(divide="ignore", invalid="ignore"):
            da = np.where(den != 0.0, eb / den, 0.5)
            db = np.where(den != 0.0, ea / den, 0.5 * kap)
        ra, rb, pa, pb = rho[:n], rho[n:], drho[:n], drho[n:]
        c = self.c[gi]
        g = ra * ra + rb * rb + 2.0 * c * ra * rb - self.h2[gi]
        dg = 2.0 * (ra + c * rb) * pa * da + 2.0 * (rb + c * ra) * pb * db
        return g, dg, a, b, da, db


@lru_cache(maxsize=8)
def _eps_g(k: float) -> float:
    """Bound of the table's error carried into g (``|d g| <= 2 (|rho_a| + |rho_b|) (eps_a + eps_b) + ...``)."""
    t = rho_table(k)
    return 8.0 * float(np.abs(t.rho).max()) * t.eps + t.eps ** 2


# ----------------------------------------------------------------------------- cells and roots


def _clip(x, lo, hi):
    """``np.clip`` without its overhead on small arrays."""
    return np.minimum(np.maximum(x, lo), hi)


def _hermite(g0, p0, g1, p1, w, s):
    """Cubic Hermite interpolant at the local coordinate s in [0, 1] of cells of width w."""
    m0, m1 = w * p0, w * p1
    return ((((2.0 * g0 - 2.0 * g1 + m0 + m1) * s + (3.0 * (g1 - g0) - 2.0 * m0 - m1)) * s + m0) * s) + g0


def _critical(g0, p0, g1, p1, w):
    """Local coordinates in (0, 1) of the critical points of the Hermite cubic of each cell (nan if none);
    shape (cells, 2)."""
    # H'(s) / w = A s^2 + B s + C with the derivative of the Hermite basis
    A = 3.0 * (2 * g0 + w * p0 - 2 * g1 + w * p1) / w
    B = 2.0 * (-3 * g0 - 2 * w * p0 + 3 * g1 - w * p1) / w
    C = p0
    with np.errstate(divide="ignore", invalid="ignore"):
        disc = B * B - 4 * A * C
        sq = np.sqrt(np.maximum(disc, 0.0))
        quad = np.abs(A) > 1e-300
        r1 = np.where(quad, (-B - sq) / (2 * A), -C / B)
        r2 = np.where(quad, (-B + sq) / (2 * A), np.nan)
    ok1 = (disc >= 0) & (r1 > 0) & (r1 < 1)
    ok2 = (disc >= 0) & (r2 > 0) & (r2 < 1)
    return np.sort(np.column_stack([np.where(ok1, r1, np.nan), np.where(ok2, r2, np.nan)]), axis=1)


def _cells(gr, p, gi):
    """Resolved cells of the graphs from samples (p, gi) sorted by graph then p: dict of arrays ``own``
    (graph index), x0, x1, g0, p0, g1, p1, gm, err, s0, s1 (a + b at the ends) (docs/design/enumeration.md)."""
    same = (gi[:-1] == gi[1:]) & (p[1:] > p[:-1])
    o, x0, x1 = gi[:-1][same], p[:-1][same], p[1:][same]
    xm = 0.5 * (x0 + x1)
    n_pts = p.size
    g, dg, a, b = gr.values(np.concatenate([p, xm]), np.concatenate([gi, o]))
    length = a + b
    g0, g1, p0, p1 = g[:n_pts - 1][same], g[1:n_pts][same], dg[:n_pts - 1][same], dg[1:n_pts][same]
    s0, s1 = length[:n_pts - 1][same], length[1:n_pts][same]
    gm, pm, sm = g[n_pts:], dg[n_pts:], length[n_pts:]
    done = []
    while True:
        err = np.abs(gm - _hermite(g0, p0, g1, p1, x1 - x0, 0.5))
        big = np.maximum(np.maximum(np.abs(g0), np.abs(g1)), np.abs(gm))
        s = (err > HERMITE_REL * big) & (err > 1e-15 * (1.0 + gr.h2[o])) & (x1 - x0 > MIN_WIDTH)
        if not done and not s.any():    # resolved at once: the cells are in order already
            c = dict(own=o, x0=x0, x1=x1, g0=g0, p0=p0, g1=g1, p1=p1, gm=gm, err=err, s0=s0, s1=s1)
            return c if o.size else None
        keep = ~s
        done.append((o[keep], x0[keep], x1[keep], g0[keep], p0[keep], g1[keep], p1[keep], gm[keep], err[keep],
                     s0[keep], s1[keep]))
        if not s.any():
            break
        o = np.concatenate([o[s], o[s]])
        x0, x1 = np.concatenate([x0[s], xm[s]]), np.concatenate([xm[s], x1[s]])
        g0, g1 = np.concatenate([g0[s], gm[s]]), np.concatenate([gm[s], g1[s]])
        p0, p1 = np.concatenate([p0[s], pm[s]]), np.concatenate([pm[s], p1[s]])
        s0, s1 = np.concatenate([s0[s], sm[s]]), np.concatenate([sm[s], s1[s]])
        xm = 0.5 * (x0 + x1)
        gm, pm, a, b = gr.values(xm, o)
        sm = a + b
    cols = [np.concatenate(c) for c in zip(*done)] if len(done) > 1 else list(done[0])
    if cols[0].size == 0:
        return None
    order = np.lexsort((cols[1], cols[0]))
    return dict(zip(("own", "x0", "x1", "g0", "p0", "g1", "p1", "gm", "err", "s0", "s1"), (c[order] for c in cols)))


def _bracketed(gr, lo, hi, glo, own, which: int = 0, iters: int = 100, x=None, tol: float = 0.0,
               accurate: bool = False):
    """Roots in [lo, hi] of g (``which`` 0) or g' (1) of graphs ``own`` with a sign change there, all at
    once: Newton on g (or the secant on g') kept inside the shrinking bracket, bisection otherwise; g of
    the table, or of the accurate map with ``accurate``."""
    values = gr.accurate if accurate else gr.values
    lo, hi = lo.copy(), hi.copy()
    slo = np.sign(glo)
    x = 0.5 * (lo + hi) if x is None else x.copy()
    active = np.arange(x.size)
    prev_x, prev_f = lo.copy(), glo.copy()
    for _ in range(iters):
        if active.size == 0:
            break
        xa = x[active]
        out = values(xa, own[active])
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
        # converged when the Newton (secant) step itself is below the tolerance, even if it would touch
        # the bracket's end; otherwise a step leaving the bracket is replaced by bisection
        small = np.abs(nxt - xa) <= tol + 2e-16 * (1.0 + np.abs(xa))
        bad = ~np.isfinite(nxt) | (nxt <= lo[active]) | (nxt >= hi[active])
        nxt = np.where(small, _clip(nxt, lo[active], hi[active]), np.where(bad, 0.5 * (lo[active] + hi[active]), nxt))
        x[active] = nxt
        go = (f != 0.0) & ~small & (hi[active] - lo[active] > 4e-16 * (1.0 + np.abs(xa)))
        active = active[go]
    return x


def _cubic_root(g0, p0, g1, p1, w, lo, hi):
    """A root of the cell's Hermite cubic in the local sub-interval [lo, hi] of [0, 1] where it changes
    sign (a few bisection-safeguarded Newton steps on the cubic): the start of :func:`_bracketed`."""
    h0, h1 = _hermite(g0, p0, g1, p1, w, lo), _hermite(g0, p0, g1, p1, w, hi)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = np.where(h1 != h0, lo + (hi - lo) * h0 / (h0 - h1), 0.5 * (lo + hi))
        A = 2 * g0 + w * p0 - 2 * g1 + w * p1
        B = -3 * g0 - 2 * w * p0 + 3 * g1 - w * p1
        for _ in range(2):
            f = ((A * s + B) * s + w * p0) * s + g0
            df = (3 * A * s + 2 * B) * s + w * p0
            s = s - f / df
            s = np.where((s >= lo) & (s <= hi), s, 0.5 * (lo + hi))   # nan fails both
    return s


def _examine(gr, act, c, crit, eps_g):
    """Roots in the active cells ``act`` of :func:`_cells` output ``c`` (docs/design/enumeration.md): arrays of
    parameter, graph index and kind (1 simple, 2 double)."""
    o, x0, x1, g0, p0, g1, p1 = (c[n][act] for n in ("own", "x0", "x1", "g0", "p0", "g1", "p1"))
    n = act.size
    w = x1 - x0
    cr = crit[act]
    has = ~np.isnan(cr)
    # each cell cut at the critical points of its Hermite cubic (a missing one collapses to the end)
    loc = np.ones((n, 4))
    loc[:, 0] = 0.0
    loc[:, 1:3] = np.where(has, cr, 1.0)
    pts = x0[:, None] + w[:, None] * loc
    vals, dvals = np.empty((n, 4)), np.empty((n, 4))
    vals[:, 0], vals[:, 1:] = g0, g1[:, None]
    dvals[:, 0], dvals[:, 1:] = p0, p1[:, None]
    any_inner = bool(has.any())
    if any_inner:
        rows, cols = np.nonzero(has)
        vals[rows, cols + 1], dvals[rows, cols + 1], _, _ = gr.values(pts[rows, cols + 1], o[rows])
    found_x, found_o, found_kind = [], [], []
    # sign changes between consecutive points: simple roots, all at once
    sc = (pts[:, 1:] > pts[:, :3]) & (vals[:, :3] * vals[:, 1:] < 0)
    rows, j = np.nonzero(sc)
    if rows.size:
        lo, hi = pts[rows, j], pts[rows, j + 1]
        start = x0[rows] + w[rows] * _cubic_root(g0[rows], p0[rows], g1[rows], p1[rows], w[rows], loc[rows, j],
                                                 loc[rows, j + 1])
        found_x.append(_bracketed(gr, lo, hi, vals[rows, j], o[rows], x=_clip(start, lo, hi), tol=ROOT_TOL))
        found_o.append(o[rows])
        found_kind.append(np.ones(rows.size, int))
    # an end whose sign the table cannot tell (|g| within the floor): the accurate map's signs decide (H is
    # monotone between the points, so one root at most)
    floor_g = 1e-13 * (1.0 + gr.h2[o]) + eps_g
    unt = (pts[:, 1:] > pts[:, :3]) & ~sc & ((np.abs(vals[:, :3]) <= floor_g[:, None])
                                              | (np.abs(vals[:, 1:]) <= floor_g[:, None]))
    rows, j = np.nonzero(unt)
    if rows.size:
        ends = np.concatenate([j, j + 1])
        r2 = np.concatenate([rows, rows])
        g_end = vals[r2, ends].copy()
        doubt = np.abs(g_end) <= floor_g[r2]
        if doubt.any():
            g_end[doubt] = gr.accurate(pts[r2[doubt], ends[doubt]], o[r2[doubt]])[0]
        ga, gb = g_end[:rows.size], g_end[rows.size:]
        cross = ga * gb < 0
        if cross.any():
            rc, jc = rows[cross], j[cross]
            found_x.append(_bracketed(gr, pts[rc, jc], pts[rc, jc + 1], ga[cross], o[rc], tol=ROOT_TOL,
                                      accurate=True))
            found_o.append(o[rc])
            found_kind.append(np.ones(rc.size, int))
    rows, j = np.nonzero(vals == 0.0)           # exact zeros at the points
    if rows.size:
        found_x.append(pts[rows, j])
        found_o.append(o[rows])
        found_kind.append(np.ones(rows.size, int))
    # close pairs and tangencies: g keeps its sign around an interior point where g' changes sign
    for j in (1, 2) if any_inner else ():
        lo, mid, hi = pts[:, j - 1], pts[:, j], pts[:, j + 1]
        keep_sign = (vals[:, j] * vals[:, j - 1] > 0) & (vals[:, j] * vals[:, j + 1] > 0) & (hi > lo)
        halves = ((lo, mid, dvals[:, j - 1], dvals[:, j]), (mid, hi, dvals[:, j], dvals[:, j + 1]))
        for side_lo, side_hi, dl, dh in halves:
            cand = keep_sign & (side_hi > side_lo) & (dl * dh < 0)
            if not cand.any():
                continue
            xc = _bracketed(gr, side_lo[cand], side_hi[cand], dl[cand], o[cand], which=1, tol=ROOT_TOL)
            gc = gr.values(xc, o[cand])[0]
            ref = vals[cand, j]
            pair = gc * ref < 0
            if pair.any():   # two roots, one on each side of the critical point, all pairs at once
                idx = np.nonzero(cand)[0][pair]
                lo2 = np.concatenate([side_lo[idx], xc[pair]])
                hi2 = np.concatenate([xc[pair], side_hi[idx]])
                own2 = np.concatenate([o[idx], o[idx]])
                g_lo = gr.values(lo2, own2)[0]
                found_x.append(_bracketed(gr, lo2, hi2, g_lo, own2, tol=ROOT_TOL))
                found_o.append(own2)
                found_kind.append(np.ones(own2.size, int))
            tang = ~pair & (np.abs(gc) <= floor_g[cand])
            if tang.any():
                for part in _tangencies(gr, side_lo[cand][tang], xc[tang], side_hi[cand][tang], o[cand][tang],
                                        np.sign(ref[tang])):
                    found_x.append(part[0])
                    found_o.append(part[1])
                    found_kind.append(part[2])
    if not found_x:
        return np.zeros(0), np.zeros(0, int), np.zeros(0, int)
    return np.concatenate(found_x), np.concatenate(found_o), np.concatenate(found_kind)


def _outward(gr, x, gx, w, direction, ref, own):
    """A root beyond ``x`` (``direction`` +1: to the right, -1: to the left) of graph ``own`` where the accurate g
    (``gx`` at x) has the sign opposite to ``ref``, the table's: steps doubling from ``w`` until g has ref's sign
    (the root between the last two points, bracketed on the accurate map) or the graph's end. Each step checks
    that g still moves toward ref's sign (``direction g'`` of ref's sign: g monotone that way, so one root at
    most between two points); if not, it stops. The root, or None."""
    lim = float(gr.hi[own] if direction > 0 else gr.lo[own])
    o = np.array([own])
    for _ in range(64):
        nxt = min(x + w, lim) if direction > 0 else max(x - w, lim)
        if nxt == x or math.isnan(nxt):
            return None
        g, dg = (float(v[0]) for v in gr.accurate(np.array([nxt]), o)[:2])
        if np.sign(g) == ref or g == 0.0:
            lo, hi, glo = (x, nxt, gx) if direction > 0 else (nxt, x, g)
            return float(_bracketed(gr, np.array([lo]), np.array([hi]), np.array([glo]), o, tol=ROOT_TOL,
                                    accurate=True)[0])
        if np.sign(dg) * direction != ref:
            return None
        x, gx, w = nxt, g, 2.0 * w
    return None


def _tangencies(gr, lo, xc, hi, own, ref):
    """Tangencies of the tabulated g at ``xc`` (``|g|`` within the floor, of sign ``ref`` on [lo, hi]) decided on
    the accurate map: a sign change of the accurate g between lo and xc or between xc and hi is a root there (a
    close pair the table's error hid; kind 1), bracketed on the accurate map; where the accurate g at lo (hi) has
    the sign opposite to the table's, the root is beyond it (:func:`_outward`; kind 1). With none, xc is a double
    root (kind 2; polished, and no root if the leaf map misses there by more than :data:`NOT_A_ROOT` times the
    certificate's tolerance). Returns (parameter, graph, kind) arrays, three parts."""
    gl, gc, gh = (gr.accurate(p, own)[0] for p in (lo, xc, hi))
    left, right = gl * gc < 0, gc * gh < 0
    lo2 = np.concatenate([lo[left], xc[right]])
    hi2 = np.concatenate([xc[left], hi[right]])
    own2 = np.concatenate([own[left], own[right]])
    g_lo = np.concatenate([gl[left], gc[right]])
    pairs = _bracketed(gr, lo2, hi2, g_lo, own2, tol=ROOT_TOL, accurate=True) if own2.size else np.zeros(0)
    beyond_x, beyond_o, found = [], [], left | right
    for i in np.nonzero((np.sign(gl) == -ref) | (np.sign(gh) == -ref))[0].tolist():   # rare: one at a time
        w = float(hi[i] - lo[i])
        for x, g, direction in ((lo[i], gl[i], -1), (hi[i], gh[i], 1)):
            if np.sign(g) == -ref[i]:
                root = _outward(gr, float(x), float(g), w, direction, ref[i], int(own[i]))
                if root is not None:
                    beyond_x.append(root)
                    beyond_o.append(int(own[i]))
                    found[i] = True
    single = ~found
    return ((pairs, own2, np.ones(own2.size, int)),
            (np.array(beyond_x, float), np.array(beyond_o, int), np.ones(len(beyond_x), int)),
            (xc[single], own[single], np.full(int(single.sum()), 2)))


def _accurate(gr, x, own):
    """``gr.accurate`` in pieces of :data:`_POLISH_CHUNK` roots, with progress (many roots at high k)."""
    if x.size <= _POLISH_CHUNK:
        return gr.accurate(x, own)
    parts = []
    for i in range(0, x.size, _POLISH_CHUNK):
        parts.append(gr.accurate(x[i:i + _POLISH_CHUNK], own[i:i + _POLISH_CHUNK]))
        report(f"polish (k = {gr.k:g})", min(i + _POLISH_CHUNK, x.size), x.size)
    return tuple(np.concatenate(c) for c in zip(*parts))


def newton_step(g, dg, h2):
    """Newton step for a root of ``g = q - h^2`` (``q = |S|^2``, S the shift of a step, ``h2 = h^2``) taken on
    ``f = sqrt(q) - h = g / (sqrt(q) + h)`` instead, ``f' = g' / (2 sqrt(q))``: ``(step, |f|)``, the next
    point being ``x - step``.

    g is f (|S| + h): near a root, ``g'' ~ 2 |S|'^2`` while ``g' ~ 2 h |S|'``, so Newton on g leaves an error
    ~ step^2 / h, large for a small shift h; on f it is ~ step^2 |S|'' / |S|', whatever h. Where q is
    not positive (S = 0 up to rounding) it is Newton's step on g.
    """
    q = g + h2
    sq = np.sqrt(np.maximum(q, 0.0))
    den = sq + np.sqrt(h2)
    with np.errstate(divide="ignore", invalid="ignore"):
        f = np.where(den > 0.0, g / np.where(den > 0.0, den, 1.0), 0.0)
        step = np.where(sq > 0.0, 2.0 * sq * f / dg, g / dg)
    return step, np.abs(f)


def _polish(gr, x, own, iters: int = 6):
    """Newton (:func:`newton_step`) on the accurate map from the table's roots, root by root: once a step
    is below :data:`POLISH_STEP` (the quadratic regime) it is taken without a new evaluation; a step that
    does not decrease |f| ends the root's polish at its best point, unless g changed sign over it (a step of at
    most :data:`POLISH_BRACKET`): then the root is bracketed there on the accurate map. Returns (x, a, b): the
    roots to rounding on the accurate map (a and b moved with the last step by their derivatives)."""
    x, a, b = x.copy(), np.empty(x.size), np.empty(x.size)
    best, g_best = np.full(x.size, np.inf), np.zeros(x.size)
    todo, xt = np.arange(x.size), x
    for i in range(iters + 1):
        g, dg, a_, b_, da, db = _accurate(gr, xt, own[todo])
        step, miss = newton_step(g, dg, gr.h2[own[todo]])
        better = miss < best[todo]
        across = ~better & (g * g_best[todo] < 0.0) & (np.abs(xt - x[todo]) <= POLISH_BRACKET)   # bracket it
        if across.any():
            idx = todo[across]
            lo, hi = np.minimum(x[idx], xt[across]), np.maximum(x[idx], xt[across])
            g_lo = np.where(x[idx] < xt[across], g_best[idx], g[across])
            x[idx] = _bracketed(gr, lo, hi, g_lo, own[idx], accurate=True)
            a[idx], b[idx] = gr.accurate(x[idx], own[idx])[2:4]
        upd = todo[better]
        x[upd], a[upd], b[upd], best[upd], g_best[upd] = xt[better], a_[better], b_[better], miss[better], g[better]
        step = np.where(np.isfinite(step), step, 0.0)
        nxt = _clip(xt - step, gr.lo[own[todo]], gr.hi[own[todo]])
        step = xt - nxt
        small = better & (np.abs(step) <= POLISH_STEP)
        fin = todo[small]
        x[fin], a[fin], b[fin] = nxt[small], a_[small] - step[small] * da[small], b_[small] - step[small] * db[small]
        go = better & ~small & (i < iters)
        todo, xt = todo[go], nxt[go]
        if todo.size == 0:
            break
    return x, a, b


def roots(brs: list, k: float, first_only: bool = False, lengths=(0.0, math.inf), polish: bool = True) -> list:
    """Every root of g on the branches ``brs`` with ``lengths[0] <= a + b <= lengths[1]`` (:class:`Root`,
    sorted by ``a + b``); with ``first_only`` only the shortest root of each branch. ``polish``: Newton
    on the accurate map (else the table's roots). Why none is missed: docs/design/enumeration.md."""
    brs = [br for br in brs if br.x_end > 0.0]
    if not brs:
        return []
    k = float(k)
    eta = np.array([br.eta for br in brs])
    hh = np.array([br.h for br in brs])
    gr = (_WGraphs(k, eta, hh, lengths, [br.y0 for br in brs]) if k >= K_FAST
          else _SigmaGraphs(k, eta, hh, lengths))
    p, gi = gr.grid()
    if p.size < 2:
        return []
    c = _cells(gr, p, gi)
    if c is None:
        return []
    o, x0, x1, g0, p0, g1, p1, gm, err = (c[n] for n in ("own", "x0", "x1", "g0", "p0", "g1", "p1", "gm", "err"))
    w = x1 - x0
    floor = SAFETY * err + 1e-13 * (1.0 + gr.h2[o]) + gr.eps_g
    # quick exclusion: with g0, g1 of one sign, |H| >= min(|g0|, |g1|) - max(|w p0 - dg|, |w p1 - dg|) / 4
    # (H minus the chord is s (1 - s) ((1 - s) (w p0 - dg) - s (w p1 - dg)), dg = g1 - g0)
    dg = g1 - g0
    bound = np.minimum(np.abs(g0), np.abs(g1)) - 0.25 * np.maximum(np.abs(w * p0 - dg), np.abs(w * p1 - dg))
    cand = np.nonzero((g0 * g1 <= 0.0) | (bound <= floor))[0]
    if gr.monotone_length and math.isfinite(lengths[1]):   # cells beyond the length bound: no root below it
        cand = cand[c["s0"][cand] <= lengths[1] + 1e-9]
    crit = np.full((o.size, 2), np.nan)
    g0c, p0c, g1c, p1c, wc = g0[cand], p0[cand], g1[cand], p1[cand], w[cand]
    cc = _critical(g0c, p0c, g1c, p1c, wc)
    crit[cand] = cc
    has = ~np.isnan(cc)
    hcrit = _hermite(g0c[:, None], p0c[:, None], g1c[:, None], p1c[:, None], wc[:, None], np.where(has, cc, 0.0))
    hc = np.where(has, np.abs(hcrit), np.inf)
    crosses = (has & (hcrit * g0c[:, None] <= 0)).any(axis=1)    # H changes sign inside
    low = np.minimum(np.minimum(np.abs(g0c), np.abs(g1c)), hc.min(axis=1))
    sign_change = (np.sign(g0c) != np.sign(g1c)) | (np.sign(g0c) != np.sign(gm[cand]))
    act = cand[sign_change | crosses | (low <= floor[cand])]
    if act.size == 0:
        return []
    if not (first_only and gr.monotone_length):
        xr, orr, kinds = _examine(gr, act, c, crit, gr.eps_g)
    else:   # the active cells of each branch in order, a few at a time, until it has a root
        rank = np.arange(act.size) - np.searchsorted(o[act], o[act])
        parts, done, start = [], np.zeros(o.max() + 1, bool), 0
        while True:
            sel = act[(rank >= start) & (rank < start + 2) & ~done[o[act]]]
            if sel.size == 0:
                break
            part = _examine(gr, sel, c, crit, gr.eps_g)
            parts.append(part)
            done[part[1][part[0] > 0.0]] = True
            start += 2
        xr, orr, kinds = (np.concatenate([q[j] for q in parts]) for j in range(3))
    order = np.lexsort((xr, orr))
    xr, orr, kinds = xr[order], orr[order], kinds[order]
    if first_only and gr.monotone_length:     # the first two of each branch: polishing may merge a close pair
        rank = np.arange(xr.size) - np.searchsorted(orr, orr)
        keep = rank < 2
        xr, orr, kinds = xr[keep], orr[keep], kinds[keep]
    if xr.size == 0:
        return []
    real = np.ones(xr.size, bool)
    if polish:
        xr, a, b = _polish(gr, xr, orr)
        # a tangency of the table at the end of the graph is polished onto a (or b) = 0 up to the table's last bits
        # (1e-34, not 0, with other BLAS kernels): the accurate map decides, as in the C search's candidate()
        g, dg = gr.accurate(xr, orr)[:2]
        real = newton_step(g, dg, gr.h2[orr])[1] <= NOT_A_ROOT * CERTIFICATE_TOLERANCE
    else:
        _, _, a, b = gr.values(xr, orr)
    bi = gr.br[orr]
    length = a + b
    inside = (a > 0.0) & (b > 0.0) & real
    ok = inside & (length >= lengths[0] - 1e-12) & (length <= lengths[1] + 1e-12)
    # first_only: a branch whose every candidate was polished onto a = 0 or b = 0 (a tangency of the table at the
    # end of the graph, no root) has not given its first root yet: its roots are searched again, all of them
    lost = np.setdiff1d(bi[~inside], bi[ok]).tolist() if first_only else []
    a, b, bi, kinds, length = a[ok], b[ok], bi[ok], kinds[ok], length[ok]
    order = np.lexsort((length, bi))
    a, b, bi, kinds, length = a[order], b[order], bi[order], kinds[order], length[order]
    dup = np.zeros(a.size, bool)    # the same root twice (a close pair merged, a corner shared by graphs)
    dup[1:] = (bi[1:] == bi[:-1]) & (np.abs(a[1:] - a[:-1]) <= 1e-12) & (np.abs(b[1:] - b[:-1]) <= 1e-12)
    a, b, bi, kinds = a[~dup], b[~dup], bi[~dup], kinds[~dup]
    if first_only:
        first = np.ones(a.size, bool)
        first[1:] = bi[1:] != bi[:-1]
        a, b, bi, kinds = a[first], b[first], bi[first], kinds[first]
    names = ("", "simple", "double")
    out = [Root(brs[j].m, brs[j].eta, brs[j].h, ai, bi_, min(ai, bi_), names[kd])
           for j, ai, bi_, kd in zip(bi.tolist(), a.tolist(), b.tolist(), kinds.tolist())]
    for j in lost:
        out += roots([brs[j]], k, lengths=lengths, polish=polish)[:1]
    return sorted(out, key=lambda r: r.a + r.b)


# ----------------------------------------------------------------------------- the planner on this search


#: Largest number of branches enumerated together.
_CHUNK = 64


class ReferencePlanner(GeometricPhasePlanner):
    """The geometric planner with this numpy search in place of the C search: the same polish and certificate,
    the bounded search for the shortest certified plan, or every root of every branch (``all_solutions``).
    Plans carry ``details["search"] == "numpy"``. Its roots are polished by IPOPT unless another root solver is
    given (the planner's default takes the C search's roots as polished)."""

    def __init__(self, root_solver: str = "ipopt", *args, **kwargs) -> None:
        super().__init__(root_solver, *args, **kwargs)

    def _solve(self, problem):
        t_start = time.perf_counter()
        goal_r = problem.scaled(problem.goal)
        psi_des, turns = wrap_exact(goal_r.psi)
        h_des = math.hypot(goal_r.u_a, goal_r.v_a)
        if h_des == 0.0:
            raise NoPlanError(f"no plan for {problem.describe()}: the target is the start point, and rollplan plans "
                              "motions with a nonzero displacement")
        target = (goal_r.u_a, goal_r.v_a, psi_des)
        branch = None if self.branch is None else self.branch + turns
        return self._solve_enumerated(problem, self.all_solutions, branch, target, turns, t_start)

    def _solve_enumerated(self, problem, all_solutions, branch, target, turns, t_start):
        """Complete enumeration (every k): every root of every branch (``all_solutions``) or the
        bounded search for the shortest certified plan (docs/design/geometric-planner.md)."""
        k, steps = problem.k, problem.steps
        h_des = math.hypot(target[0], target[1])
        brs = branches(k, target[2], steps, h_des, branch)
        where = problem.describe()
        found, rejected, tried = [], [], 0
        # branches in increasing order of the smallest a + b they can hold, in growing chunks; once a plan
        # is certified, only lengths below it are searched, and no branch whose smallest a + b is not
        # below it is visited (the first root of a branch in x is its shortest)
        best = math.inf
        label = f"search (k = {k:g}, {len(brs)} branches)"
        visited = 0
        start, size = 0, 4
        while start < len(brs):
            chunk = [br for br in brs[start:start + size] if br.y0 < best]
            start, size = start + size, min(2 * size, _CHUNK)
            if not chunk:
                if not all_solutions:
                    break       # y0 grows along brs: nothing left can be shorter
                continue
            visited += len(chunk)
            cands = roots(chunk, k, first_only=not all_solutions,
                          lengths=(0.0, math.inf if all_solutions else best))
            for r in cands:
                if not all_solutions and r.a + r.b >= best:
                    break
                queue = [r]
                while queue:   # a branch's next roots only if its first is rejected
                    q = queue.pop(0)
                    tried += 1
                    x, status, iters = self._polish(q, k)
                    cand = self._certified(problem, x, q.m - turns, target, status, iters)
                    if cand[1].passed:
                        found.append(cand)
                        if not all_solutions:
                            best = min(best, q.a + q.b)
                        break
                    if self._log_rejected(q, cand, turns):
                        rejected.append(cand[1].residual + cand[1].error_bound)
                    if not all_solutions and q is r:   # the branch's other roots, shortest first
                        queue = [q2 for q2 in roots([next(b_ for b_ in chunk if b_.m == r.m)], k)
                                 if abs(q2.a - r.a) > 1e-12 or abs(q2.b - r.b) > 1e-12]
            report(label, visited, len(brs))
        elapsed = time.perf_counter() - t_start
        if not found:
            self._raise_if_rejected(where, rejected)
            raise no_root(problem, f"{len(brs)} branches searched completely")
        found.sort(key=lambda c: c[0].a + c[0].b)
        details = {"candidates": tried, "solves": len(found), "branches": visited, "roots": tried, "search": "numpy"}
        plans = [self._plan(problem, cand, replace(cand[2], time_s=elapsed, details=details)) for cand in found]
        return replace(plans[0], alternatives=tuple(plans[1:]) if all_solutions else ())


def reference_plan(target, steps: int, k: float, near=None, branch: int | None = None):
    """The reference planner's certified plan for ``Problem(target, k, steps)``, for cross-checking the C planner:
    the shortest plan over all branches (the C planner's default), or on ``branch`` only; with ``near = (a, b)``
    the plan of all certified ones closest to it. None if there is none."""
    problem = Problem(tuple(float(x) for x in target), k=k, steps=steps)
    try:
        best = ReferencePlanner().solve(problem, all_solutions=near is not None, branch=branch)
    except NoPlanError:
        return None
    if near is None:
        return best
    return min((best,) + best.alternatives, key=lambda q: (max(abs(q.a - near[0]), abs(q.b - near[1])), q.a + q.b))
