"""Computation of the paper's case study (Section III.C): the stages, with no prose.

The case study traces the symmetric figure eight ``a = b`` of two circles (35)
once (n = 1) and asks:

* the radius ``a`` with ``h/R = 1`` under pure rolling (k = 0), where the
  closed form (36) holds, and the rotation gamma of (31) that points the shift
  along +v_a;
* for the same ``a``, the shift ``h`` and gamma for k = 2.5 and k = 5, and the
  zeros ``k_1, k_2, ...`` of ``h(k)`` (Fig. 9);
* for k = 2.5, the radii ``a_1, a_2, ...`` with ``h/R = 1`` (Fig. 10) and the
  gammas of the first two (Figs 11-12);
* two qualitative claims: the half-step contact path on the plane crosses
  itself ``i`` times for ``k in [k_i, k_{i+1}]``, and the realizable solution
  ``a_1`` has a shorter contact path than the pure-rolling one.

Method. For a symmetric figure eight the second leaf mirrors the first, and
the shift of one step is twice the shift of the first half-step; it lies on
the axis at angle ``-eta_1/2`` (``eta_1``: turn of psi over the first leaf),
so the *signed* shift

    s(a, k) = u_a cos(eta_1 / 2) - v_a sin(eta_1 / 2),   h = |s|          (*)

is smooth and changes sign at the zeros of h(k). (This identity is checked on
every sweep: ``max | |s| - h |`` is recorded.) Zeros of ``s(k)`` and roots of
``h(a) - 1`` are bracketed on sweeps that evaluate the spectral step map in
batches (CasADi ``map``) and refined by Brent's method. Every root is refined a
second, independent way with the adaptive CVODES integrator, and for k = 0 a
third way with the closed form (36). The gamma that points the shift along
+v_a is ``gamma = wrap(pi/2 - atan2(v_a, u_a))`` (the displacement turns by +gamma).

Each stage function returns its results and a dict of named numbers (the
evidence); :mod:`.report` turns them into rows and prose.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import casadi as ca
import numpy as np

from ...core.curves import A_MAX
from ...core.integrate import DEFAULT_NODES, CvodesIntegrator, spectral_step
from ...core.plane import wrap
from ...core.roots import brent
from ...errors import InputError
from ...planners.geometric import GeometricPhasePlanner, Plan, default_planner
from ...problem import Problem
from ...result import SolverStats, certify
from .values import A_MIN, K_RANGE, PAPER, shift_pure_rolling

__all__ = ["Sweep", "Crossings", "CaseStudy", "refine_root", "bracket_roots", "count_self_intersections",
           "converged_crossings", "pure_rolling_stage", "shift_stage", "zeros_stage", "radius_stage",
           "crossings_stage", "trajectories_stage"]

log = logging.getLogger(__name__)

#: Progress callback: ``progress(label, done, total)``.
Progress = Callable[[str, int, int], None]


def refine_root(fun: Callable[[float], float], lo: float, hi: float, xtol: float = 1e-14,
                known: dict | None = None) -> float:
    """Root of a scalar function in a sign-changing bracket ``[lo, hi]`` (Brent's method,
    :func:`rollplan.core.roots.brent`), ``fun`` evaluated once at each point (``known``: values already
    computed, point -> value).

    Raises InputError when ``fun(lo)`` and ``fun(hi)`` have the same sign.
    """
    values = dict(known or {})

    def once(x):
        if x not in values:
            values[x] = fun(x)
        return values[x]

    f_lo, f_hi = once(lo), once(hi)
    if f_lo == 0.0:
        return lo
    if f_hi == 0.0:
        return hi
    if np.sign(f_lo) == np.sign(f_hi):
        raise InputError(f"[{lo:g}, {hi:g}] does not bracket a root: f = {f_lo:g}, {f_hi:g}")
    return brent(once, lo, hi, xtol=xtol * (1.0 + abs(lo)), rtol=4 * np.finfo(float).eps)


def bracket_roots(x: np.ndarray, f: np.ndarray) -> list:
    """Grid cells ``(x[i], x[i+1])`` on which the sampled ``f`` changes sign (or hits zero)."""
    s = np.sign(f)
    idx = np.nonzero((s[:-1] * s[1:] < 0) | (s[:-1] == 0))[0]
    return [(int(i), float(x[i]), float(x[i + 1])) for i in idx]


# ----------------------------------------------------------------------------- geometry


def count_self_intersections(u: np.ndarray, v: np.ndarray, block: int = 8) -> int:
    """Number of proper crossings of the polyline ``(u[i], v[i])`` with itself.

    Every pair of non-adjacent segments whose blocks' bounding boxes overlap
    is tested with strict orientation signs (a segment pair that only touches
    at an end point, or is collinear, does not count). Blocks of ``block``
    consecutive segments prune the O(N^2) pairs; numpy only.
    """
    p = np.column_stack([u, v]).astype(float)
    a, b = p[:-1], p[1:]
    n = len(a)
    if n < 3:
        return 0
    nb = -(-n // block)
    idx = np.arange(nb * block).reshape(nb, block)
    idx_c = idx.clip(max=n - 1)
    lo = np.minimum(a, b)[idx_c].min(axis=1)
    hi = np.maximum(a, b)[idx_c].max(axis=1)
    overlap = np.all((lo[:, None, :] <= hi[None, :, :]) & (lo[None, :, :] <= hi[:, None, :]), axis=2)
    bi, bj = np.nonzero(np.triu(overlap))
    i = np.broadcast_to(idx[bi][:, :, None], (bi.size, block, block)).ravel()
    j = np.broadcast_to(idx[bj][:, None, :], (bi.size, block, block)).ravel()
    keep = (j > i + 1) & (j < n)  # padding indices (>= n) dropped; each pair once (bi <= bj)
    i, j = i[keep], j[keep]
    d_i, d_j = b[i] - a[i], b[j] - a[j]

    def side(o, dv, q):
        return np.sign(dv[:, 0] * (q[:, 1] - o[:, 1]) - dv[:, 1] * (q[:, 0] - o[:, 0]))

    hit = (side(a[i], d_i, a[j]) * side(a[i], d_i, b[j]) < 0) & (side(a[j], d_j, a[i]) * side(a[j], d_j, b[i]) < 0)
    return int(hit.sum())


def converged_crossings(path: np.ndarray, levels: int = 3) -> tuple:
    """Self-intersections of a sampled smooth path, under refinement.

    ``path`` is an ``(N + 1, 2)`` polyline sampled uniformly in the curve
    parameter with ``N`` divisible by ``2^(levels-1)``. The crossings are
    counted on every ``2^m``-th point, ``m = levels-1, ..., 0`` (the nested
    coarser samplings), and returned coarse to fine. A coarse polyline can
    cut across a tight loop and add crossings; the counts must settle under
    refinement.
    """
    step = 2 ** (levels - 1)
    if (len(path) - 1) % step:
        raise InputError(f"a path of {len(path) - 1} segments cannot be halved {levels - 1} times")
    return tuple(count_self_intersections(*path[:: 2 ** m].T) for m in range(levels - 1, -1, -1))


@dataclass(frozen=True)
class Sweep:
    """The step map of the symmetric figure eight along one parameter.

    Attributes
    ----------
    variable : str
        ``"k"`` (inertia ratio, a fixed) or ``"a"`` (radius [R], k fixed).
    fixed : float
        The other parameter (a [R] or k).
    x : ndarray, shape (N,)
        Values of the swept parameter.
    h : ndarray, shape (N,)
        Shift h/R of one step.
    signed : ndarray, shape (N,)
        Signed shift s of (*) (module doc), ``|s| = h``.
    eta1 : ndarray, shape (N,)
        Turn of psi over the first leaf [rad].
    roots : tuple of float
        Zeros of s (variable k) or roots of ``h = level`` (variable a), refined on the spectral map.
    roots_cvodes : tuple of float
        The same roots refined with CVODES (independent integrator).
    roots_double_grid : int
        Number of roots bracketed on a grid of twice the resolution (must equal ``len(roots)``).
    symmetry_error : float
        ``max | |s| - h |`` on the sweep (checks the identity behind (*)).
    time_s : float
        Wall time of the batched sweep [s].
    """

    variable: str
    fixed: float
    x: np.ndarray
    h: np.ndarray
    signed: np.ndarray
    eta1: np.ndarray
    roots: tuple
    roots_cvodes: tuple
    roots_double_grid: int
    symmetry_error: float
    time_s: float


@dataclass(frozen=True)
class Crossings:
    """Self-intersections of the half-step contact path on the plane at one k.

    Attributes
    ----------
    k : float
        Inertia ratio.
    interval : int
        i with ``k in [k_i, k_{i+1}]`` (k_0 = 0, computed zeros), or -1 for an
        extra probe.
    counts : tuple of int
        Crossings of the first-leaf CVODES path sampled with ``samples[m]``
        points (must agree under refinement).
    samples : tuple of int
        Samples per half-step of each count.
    """

    k: float
    interval: int
    counts: tuple
    samples: tuple

    @property
    def count(self) -> int:
        """The count on the finest polyline."""
        return self.counts[-1]

    @property
    def converged(self) -> bool:
        return len(set(self.counts)) == 1


class CaseStudy:
    """Step map of the symmetric figure eight ``a = b``, spectral (batched) and CVODES.

    Parameters
    ----------
    planner : GeometricPhasePlanner, optional
        Supplies the certifier and the trajectory sampler (CVODES).
    nodes : int
        Chebyshev degree per panel of the first-leaf spectral map.
    chunk : int
        Batch size of the sweeps (one CasADi ``map`` call per batch).
    """

    def __init__(self, planner: GeometricPhasePlanner | None = None, nodes: int = DEFAULT_NODES,
                 chunk: int = 200) -> None:
        # the planner's root solver is not used here; Newton is the cheaper one to build
        self.planner = planner or default_planner("newton")
        self.chunk = int(chunk)
        curve = self.planner.curve
        # The step map composed from its two leaves (spectral_step traces the
        # pieces in the same way), so the first leaf's end state is at hand.
        leaves = [spectral_step(curve, nodes, pieces=(i,)) for i in range(2)]
        a, k = ca.SX.sym("a"), ca.SX.sym("k")
        ab = ca.vertcat(a, a)
        x1 = leaves[0](ca.DM.zeros(3), ab, k, 0)
        x = leaves[1](x1, ab, k, 0)
        s = x[0] * ca.cos(x1[2] / 2) - x[1] * ca.sin(x1[2] / 2)
        #: (a, k) -> (u_a, v_a, psi, eta_1, s), one step of the symmetric figure eight from rest.
        self.symmetric = ca.Function("symmetric_step", [a, k], [ca.vertcat(x, x1[2], s)], ["a", "k"], ["out"])
        self._batch = self.symmetric.map(self.chunk)
        self._cvodes = CvodesIntegrator(curve, reltol=1e-13, abstol=1e-14)
        self._cvodes_ints = self._cvodes.integrators(1)
        self._path_ints: dict = {}

    # -- evaluation -----------------------------------------------------------------
    def spectral(self, a: float, k: float) -> np.ndarray:
        """(u_a, v_a, psi, eta_1, s) of one step, spectral map."""
        return np.array(self.symmetric(a, k)).ravel()

    def cvodes(self, a: float, k: float) -> np.ndarray:
        """(u_a, v_a, psi, eta_1, s) of one step, CVODES (independent integrator)."""
        _, xs = self._cvodes.trace([a, a], k, 0.0, 1, 1, integrators=self._cvodes_ints)
        u, v, psi = xs[-1]
        eta1 = xs[0, 2]
        return np.array([u, v, psi, eta1, u * math.cos(eta1 / 2) - v * math.sin(eta1 / 2)])

    def batch(self, a, k, label: str = "sweep", progress: Progress | None = None) -> np.ndarray:
        """(5, N) outputs for vectors ``a`` and ``k`` (broadcast), in CasADi ``map`` batches."""
        a, k = np.broadcast_arrays(np.asarray(a, float), np.asarray(k, float))
        n = a.size
        out = np.zeros((5, n))
        for start in range(0, n, self.chunk):
            stop = min(start + self.chunk, n)
            pa = np.full(self.chunk, a.flat[stop - 1])
            pk = np.full(self.chunk, k.flat[stop - 1])
            pa[: stop - start], pk[: stop - start] = a.flat[start:stop], k.flat[start:stop]
            out[:, start:stop] = np.array(self._batch(pa[None, :], pk[None, :]))[:, : stop - start]
            if progress is not None:
                progress(label, stop, n)
        return out

    @staticmethod
    def h(out: np.ndarray):
        return np.hypot(out[0], out[1])

    @staticmethod
    def gamma_to_va(out: np.ndarray) -> float:
        """Rotation gamma of (31) that points the shift along +v_a [rad]."""
        return float(wrap(math.pi / 2 - math.atan2(out[1], out[0])))

    # -- sweeps and roots -------------------------------------------------------------
    def sweep(self, variable: str, fixed: float, x: np.ndarray, level: float | None = None,
              progress: Progress | None = None) -> Sweep:
        """Batched sweep and its roots.

        ``variable="k"``: zeros of the signed shift s(k) at radius ``fixed``.
        ``variable="a"``: roots of ``h(a) = level`` at inertia ratio ``fixed``.
        Roots are bracketed on the sweep, refined on the spectral map and again
        with CVODES; the count is cross-checked on a grid of twice the resolution.
        """
        if variable not in ("k", "a"):
            raise InputError(f"variable = {variable!r} is not allowed: choose 'k' or 'a'")
        if variable == "a" and level is None:
            raise InputError("level is missing: an a sweep finds the roots of h(a) = level")
        x = np.asarray(x, float)
        pair = (lambda v: (fixed, v)) if variable == "k" else (lambda v: (v, fixed))

        def target(out):  # the function whose sign changes are the roots, from (5, N) outputs
            return out[4] if variable == "k" else np.hypot(out[0], out[1]) - level

        def spectral(v):
            return float(target(self.spectral(*pair(v))[:, None])[0])

        def cvodes(v):
            return float(target(self.cvodes(*pair(v))[:, None])[0])

        t0 = time.perf_counter()
        out = self.batch(*pair(x), label=f"h({variable}) sweep", progress=progress)
        elapsed = time.perf_counter() - t0
        h = self.h(out)
        f = target(out)
        roots, roots_cv = [], []
        for _, lo, hi in bracket_roots(x, f):
            r = refine_root(spectral, lo, hi)
            roots.append(r)
            # CVODES refinement, in a tight bracket around the spectral root if it holds one.
            d = max(1e-7, 1e-7 * abs(r))
            lo_c, hi_c = max(lo, r - d), min(hi, r + d)
            known = {lo_c: cvodes(lo_c), hi_c: cvodes(hi_c)}
            if np.sign(known[lo_c]) == np.sign(known[hi_c]):
                lo_c, hi_c = lo, hi
            roots_cv.append(refine_root(cvodes, lo_c, hi_c, xtol=1e-12, known=known))
        # Count check on a grid of twice the resolution (midpoints added).
        mid = 0.5 * (x[:-1] + x[1:])
        f_mid = target(self.batch(*pair(mid), label=f"h({variable}) check", progress=progress))
        xx, ff = np.empty(x.size + mid.size), np.empty(x.size + mid.size)
        xx[0::2], xx[1::2] = x, mid
        ff[0::2], ff[1::2] = f, f_mid
        double = len(bracket_roots(xx, ff))
        if double != len(roots):
            log.warning("%s sweep: %d roots on the grid, %d on the doubled grid", variable, len(roots), double)
        return Sweep(variable, float(fixed), x, h, out[4].copy(), out[3].copy(), tuple(roots), tuple(roots_cv),
                     double, float(np.max(np.abs(np.abs(out[4]) - h))), elapsed)

    # -- plans for the figures ---------------------------------------------------------
    def symmetric_plan(self, a: float, k: float) -> Plan:
        """The one-step plan of the paper's figures: a = b, gamma pointing the shift along +v_a.

        Certified by the planner's certifier (:mod:`rollplan.planners.geometric.certify`) against the goal
        ``(0, h, 0)`` (contact point at the pole).
        """
        out = self.spectral(a, k)
        gamma = self.gamma_to_va(out)
        h = float(np.hypot(out[0], out[1]))
        problem = Problem((0.0, h, 0.0), k=k)
        final, bound, _ = self.planner.certifier.certify(a, a, k, gamma, 1, self.planner.tol)
        cert = certify(problem, final, self.planner.certifier.name, error_bound=bound, tolerance=self.planner.tol)
        stats = SolverStats("none", "given (paper's case study)", 0, 0.0)
        return Plan(problem, a, a, gamma, 0, h, float(out[2]), 4 * math.pi * a, cert, stats, (), self.planner)

    def half_step_path(self, a: float, k: float, samples: int) -> np.ndarray:
        """(samples + 1, 2) contact path (u_a, v_a) of the first leaf, by CVODES."""
        if samples not in self._path_ints:
            grid = np.linspace(0.0, 2.0 * np.pi, samples + 1)[1:]
            self._path_ints[samples] = [self._cvodes.piece_integrator(0, grid)]
        ints = self._path_ints[samples]
        _, xs = self._cvodes.trace([a, a], k, 0.0, 1, samples, integrators=ints)
        return np.vstack([[0.0, 0.0], xs[:, :2]])


# ----------------------------------------------------------------------------- stages


def _gamma_h(study: CaseStudy, a: float, k: float):
    """(gamma, h) pointing the shift along +v_a, spectral and CVODES."""
    sp, cv = study.spectral(a, k), study.cvodes(a, k)
    return study.gamma_to_va(sp), float(study.h(sp)), study.gamma_to_va(cv), float(study.h(cv))


def pure_rolling_stage(study: CaseStudy) -> dict:
    """The radius a0 with h/R = 1 at k = 0 (three ways) and gamma there; the printed radius checked too."""
    a_grid = np.linspace(A_MIN, A_MAX, 400)
    closed = lambda a: float(shift_pure_rolling(a)) - 1.0  # noqa: E731
    roots36 = [refine_root(closed, lo, hi) for _, lo, hi in bracket_roots(a_grid, shift_pure_rolling(a_grid) - 1.0)]
    k0 = study.sweep("a", 0.0, a_grid, level=1.0)
    if len(k0.roots) != 1 or len(roots36) != 1:
        log.warning("h/R = 1 at k = 0 has %d roots (spectral), %d (closed form)", len(k0.roots), len(roots36))
    a0, a0p = k0.roots[0], float(PAPER["a_k0"])
    g0, h0, g0c, h0c = _gamma_h(study, a0, 0.0)
    g0p, _, g0pc, _ = _gamma_h(study, a0p, 0.0)
    a6 = round(a0, 6)  # the printed h(k = 2.5) needs the root to more digits than the 6 printed
    return {"a0": a0, "a0_printed": a0p, "a0_spectral": a0, "a0_cvodes": k0.roots_cvodes[0],
            "a0_closed_form": roots36[0], "roots_k0_spectral": list(k0.roots), "roots_k0_closed_form": roots36,
            "h36_at_printed": float(shift_pure_rolling(a0p)),
            "h_spectral_at_printed": float(study.h(study.spectral(a0p, 0.0))),
            "h_cvodes_at_printed": float(study.h(study.cvodes(a0p, 0.0))),
            "gamma_k0": g0, "gamma_k0_cvodes": g0c, "gamma_k0_printed_a": g0p, "gamma_k0_printed_a_cvodes": g0pc,
            "h_k0": h0, "h_k0_cvodes": h0c, "a0_rounded": a6,
            "h_k2.5_rounded_a": float(study.h(study.spectral(a6, 2.5)))}


def shift_stage(study: CaseStudy, a0: float, a0p: float) -> dict:
    """h and gamma for k = 2.5 and 5 at a0 and at the printed radius, both integrators."""
    ev = {}
    for kk in (2.5, 5.0):
        g, hh, gc, hc = _gamma_h(study, a0, kk)
        gp, hp, gpc, hpc = _gamma_h(study, a0p, kk)
        key = f"{kk:g}"
        ev.update({f"h_k{key}": hh, f"h_k{key}_cvodes": hc, f"h_k{key}_printed_a": hp,
                   f"h_k{key}_printed_a_cvodes": hpc, f"gamma_k{key}": g, f"gamma_k{key}_cvodes": gc,
                   f"gamma_k{key}_printed_a": gp, f"gamma_k{key}_printed_a_cvodes": gpc})
    return ev


def zeros_stage(study: CaseStudy, a0: float, a0p: float, k_points: int, progress: Progress | None = None):
    """Fig. 9: h(k) at a0 and at the printed radius, its zeros, and h at the printed zeros; (sweeps, evidence)."""
    ks = np.linspace(*K_RANGE, k_points)
    k_sweep = study.sweep("k", a0, ks, progress=progress)
    k_sweep_p = study.sweep("k", a0p, ks, progress=progress)
    ev = {"zeros_spectral": list(k_sweep.roots), "zeros_cvodes": list(k_sweep.roots_cvodes),
          "zeros_printed_a": list(k_sweep_p.roots), "zeros_printed_a_cvodes": list(k_sweep_p.roots_cvodes),
          "k_sweep_symmetry_error": k_sweep.symmetry_error, "h_at_zeros_cvodes": []}
    for i in range(min(5, len(k_sweep.roots))):
        kp = float(PAPER[f"k{i + 1}"])
        ev["h_at_zeros_cvodes"].append(float(study.h(study.cvodes(a0, k_sweep.roots[i]))))
        ev[f"h_at_printed_k{i + 1}"] = (float(study.h(study.spectral(a0, kp))), float(study.h(study.cvodes(a0, kp))))
    return (k_sweep, k_sweep_p), ev


def radius_stage(study: CaseStudy, a_points: int, progress: Progress | None = None):
    """Fig. 10: h(a) at k = 2.5, the roots of h/R = 1, and gamma for the first two; (sweep, evidence)."""
    a_sweep = study.sweep("a", 2.5, np.linspace(A_MIN, A_MAX, a_points), level=1.0, progress=progress)
    ev = {"a_roots_spectral": list(a_sweep.roots), "a_roots_cvodes": list(a_sweep.roots_cvodes),
          "a_roots_double_grid": a_sweep.roots_double_grid}
    for i in range(2):
        g, _, gc, hc = _gamma_h(study, a_sweep.roots[i], 2.5)
        ev.update({f"gamma_a{i + 1}": g, f"gamma_a{i + 1}_cvodes": gc, f"h_a{i + 1}_cvodes": hc})
    return a_sweep, ev


def crossings_stage(study: CaseStudy, a0: float, k_roots, samples: int, per_interval: int,
                    progress: Progress | None = None) -> tuple:
    """Self-intersections of the half-step plane path at probes in every [k_i, k_i+1] (and between the
    computed and the printed k_5)."""
    zeros = [0.0] + list(k_roots)
    probes = []
    for i in range(len(zeros) - 1):
        lo, hi = zeros[i], zeros[i + 1]
        probes += [(lo + t * (hi - lo), i) for t in np.linspace(0.0, 1.0, per_interval + 2)[1:-1]]
    k5p = float(PAPER["k5"])
    if len(k_roots) >= 5 and k_roots[4] < k5p:
        probes.append((0.5 * (k_roots[4] + k5p), -1))
    crossings = []
    for n, (kk, i) in enumerate(probes, 1):
        counts = converged_crossings(study.half_step_path(a0, kk, 4 * samples), 3)
        crossings.append(Crossings(float(kk), i, counts, tuple(samples * 2 ** m for m in range(3))))
        if progress is not None:
            progress("self-intersections", n, len(probes))
    return tuple(crossings)


def trajectories_stage(study: CaseStudy, a0: float, a_roots, samples: int, progress: Progress | None = None):
    """The plans of Figs 6-8, 11-12 with their trajectories sampled ``samples`` times per half-step (leaf), and
    their path lengths; (plans, evidence)."""
    plans = {}
    for name, (a, kk) in {"k0": (a0, 0.0), "k2.5": (a0, 2.5), "k5": (a0, 5.0),
                          "a1": (a_roots[0], 2.5), "a2": (a_roots[1], 2.5)}.items():
        p = study.symmetric_plan(a, kk)
        plans[name] = (p, p.sample(1 + 2 * p.steps * samples))   # the start, then samples per leaf
        if progress is not None:
            progress("trajectories", len(plans), 5)
    ev = {"path_length_formula": {n: plans[n][0].path_length for n in plans},
          "path_length_polyline": {n: plans[n][1].path_length() for n in plans},
          "plan_residuals": {n: plans[n][0].residual for n in plans}}
    return plans, ev
