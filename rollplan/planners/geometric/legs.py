"""Two legs of figure eights through an intermediate pole state: targets one leg cannot reach.

Leg 1 goes from zero to an intermediate pole state ``w = (q, chi)``, leg 2 from zero to ``w^-1 * f`` (the
composition law); the length is ``L(|q|, chi) + L(|f_p - q|, psi_f - chi)`` with ``|q|``, ``|f_p - q|`` sides
of a triangle on ``|f_p|``. The search bins one-leg plans of a grid of leaf pairs in ``(r, chi)`` (a sampled
lower envelope), minimises over pairs of bins, polishes the best by IPOPT, and leaves each leg to the
geometric-phase planner. It guarantees a certified local minimum near the best bins, not a global one; the
optimum is degenerate (one leaf of each leg at :data:`LEAF_FLOOR`).

The search and what it guarantees: docs/design/composition.md (two legs).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ... import interrupts
from ...core.curves import A_MAX, figure_eight
from ...core.integrate import DEFAULT_NODES, spectral_step
from ...core.plane import relative, rotate
from .turn import leaf_maps

__all__ = ["LEAF_FLOOR", "Candidate", "two_leg_candidates", "intermediate_state", "second_leg"]

TWO_PI = 2.0 * math.pi
#: Smallest leaf radius of the search grid [R].
A_MIN = 0.005
#: Bins of the (r, chi) envelope.
R_BINS, CHI_BINS = 90, 120
#: Smallest leaf radius of a polished candidate [R] (the optimum rests on it; docs/design/composition.md).
LEAF_FLOOR = 1e-3
#: Iteration cap of one IPOPT polish; the unpolished grid pair is used
#: when it runs out. An iteration cap, not a time cap, so that the result does not depend on the machine's load.
POLISH_ITERATIONS = 60
#: Wall-time cap of one polish [s]: only a guard against a pathological solve.
POLISH_WALL_S = 5.0


@dataclass(frozen=True)
class Candidate:
    """A two-leg solution in leaf space (units of R, rad).

    Attributes
    ----------
    a1, b1, a2, b2 : float
        Leaf radii of the two legs.
    chi1, chi2 : float
        Headings reached by each leg (``n eta``), the intermediate heading ``chi1``.
    r1, r2 : float
        Distances covered by each leg.
    length : float
        ``2 pi n (a1 + b1 + a2 + b2)``.
    polished : bool
        False when the polish did not converge and the grid pair is kept.
    """

    a1: float
    b1: float
    a2: float
    b2: float
    chi1: float
    chi2: float
    r1: float
    r2: float
    length: float
    polished: bool


class _LeafTable:
    """One figure eight ``(a_i, b_j)`` from zero on a grid of radii, from the two leaf maps.

    A step is leaf 0 then leaf 1, so by the composition law ``D = D0(a) + Rot(-eta0(a)) D1(b)``,
    ``eta = eta0(a) + eta1(b)``.
    """

    def __init__(self, k: float) -> None:
        r = np.unique(np.concatenate([np.linspace(A_MIN, A_MAX, 400), np.linspace(0.55, A_MAX, 200)]))
        self.radii = r
        f0, f1 = leaf_maps()
        ab = np.vstack([r, r])
        x0 = np.array(f0.map(r.size)(ca.DM.zeros(3), ab, k, 0))
        x1 = np.array(f1.map(r.size)(ca.DM.zeros(3), ab, k, 0))
        d1 = rotate(-x0[2][:, None], np.stack([np.broadcast_to(x1[0], (r.size, r.size)),
                                               np.broadcast_to(x1[1], (r.size, r.size))]))
        self.h = np.hypot(x0[0][:, None] + d1[0], x0[1][:, None] + d1[1])   # (Na, Nb)
        self.eta = x0[2][:, None] + x1[2][None, :]

    def legs(self, steps: int):
        """``(r, chi, length)`` of the one-leg plans of ``steps`` traces of every grid pair (flattened)."""
        half = self.eta / 2
        small = np.abs(np.sin(half)) < 1e-12
        gain = np.where(small, float(steps), np.abs(np.sin(steps * half) / np.where(small, 1.0, np.sin(half))))
        length = TWO_PI * steps * (self.radii[:, None] + self.radii[None, :])
        return (self.h * gain).ravel(), (steps * self.eta).ravel(), length.ravel()


@lru_cache(maxsize=8)
def _leaf_table(k: float) -> _LeafTable:
    return _LeafTable(k)


@lru_cache(maxsize=16)
def _binned(k: float, steps: int):
    """The one-leg plans of a grid at k, their (r, chi) envelope and its 3 x 3 neighbourhood minimum."""
    r, chi, length = _leaf_table(k).legs(steps)
    r_max = float(np.percentile(r, 99.5))
    ir = np.minimum((r / r_max * R_BINS).astype(int), R_BINS)
    ic = np.floor(np.mod(chi + math.pi, TWO_PI) / TWO_PI * CHI_BINS).astype(int) % CHI_BINS
    idx = np.flatnonzero(ir < R_BINS)
    flat = ir[idx] * CHI_BINS + ic[idx]
    order = np.lexsort((length[idx], flat))
    flat, idx = flat[order], idx[order]
    first = np.r_[True, flat[1:] != flat[:-1]]
    env = np.full(R_BINS * CHI_BINS, np.inf)
    arg = np.full(R_BINS * CHI_BINS, -1)
    env[flat[first]], arg[flat[first]] = length[idx[first]], idx[first]
    env, arg = env.reshape(R_BINS, CHI_BINS), arg.reshape(R_BINS, CHI_BINS)
    near, near_arg = env.copy(), arg.copy()
    for dr in (-1, 0, 1):
        for dc in (-1, 0, 1):
            sh, sa = np.roll(env, dc, axis=1), np.roll(arg, dc, axis=1)
            if dr:
                sh, sa = np.roll(sh, dr, axis=0), np.roll(sa, dr, axis=0)
                sh[0 if dr == 1 else -1] = np.inf
            better = sh < near
            near[better], near_arg[better] = sh[better], sa[better]
    return (r, chi, length), r_max, env, arg, near, near_arg


def _picks(target, k: float, steps: int) -> list:
    """Bin pairs of the envelope for ``target``, best first: ``(estimated length, grid index 1, grid index 2)``."""
    h_f, psi_f = float(np.hypot(target[0], target[1])), float(target[2])
    _, r_max, env, arg, near, near_arg = _binned(k, steps)
    centres_r = (np.arange(R_BINS) + 0.5) * r_max / R_BINS
    centres_c = -math.pi + (np.arange(CHI_BINS) + 0.5) * TWO_PI / CHI_BINS
    dr = r_max / R_BINS
    picks = []
    for c in range(CHI_BINS):
        c2 = int(np.floor(np.mod(psi_f - centres_c[c] + math.pi, TWO_PI) / TWO_PI * CHI_BINS)) % CHI_BINS
        a_col, b_col = env[:, c], near[:, c2]
        if h_f == 0.0:
            tot = a_col + b_col
            i1 = i2 = int(np.argmin(tot))
            best = tot[i1]
        else:
            r1, r2 = centres_r[:, None], centres_r[None, :]
            ok = (np.abs(r1 - r2) <= h_f + 2 * dr) & (r1 + r2 >= h_f - 2 * dr)
            tot = np.where(ok, a_col[:, None] + b_col[None, :], np.inf)
            i1, i2 = np.unravel_index(np.argmin(tot), tot.shape)
            best = tot[i1, i2]
        if np.isfinite(best):
            picks.append((float(best), int(arg[i1, c]), int(near_arg[i2, c2])))
    picks.sort(key=lambda t: t[0])
    return picks


@lru_cache(maxsize=16)
def _polisher(steps: int, turn_in_place: bool):
    """IPOPT: minimise a1 + b1 + a2 + b2 s.t. n (eta1 + eta2) = psi_m and the triangle condition on r1, r2."""
    z = ca.MX.sym("z", 4)
    par = ca.MX.sym("par", 3)   # k, psi_m, h_f
    step = spectral_step(figure_eight(), DEFAULT_NODES)
    j = ca.DM(np.arange(steps))

    def leg(a, b):
        xf = step(ca.DM.zeros(3), ca.vertcat(a, b), par[0], 0)
        c, s = ca.sum1(ca.cos(j * xf[2])), ca.sum1(ca.sin(j * xf[2]))
        return xf[2], ca.sqrt((xf[0] ** 2 + xf[1] ** 2) * (c**2 + s**2) + 1e-300)

    eta1, r1 = leg(z[0], z[1])
    eta2, r2 = leg(z[2], z[3])
    g = [steps * (eta1 + eta2) - par[1], r1 - r2] + ([] if turn_in_place else [r1 + r2 - par[2]])
    opts = {"print_time": False, "ipopt.print_level": 0, "ipopt.sb": "yes", "ipopt.tol": 1e-12,
            "ipopt.constr_viol_tol": 1e-12, "ipopt.max_iter": POLISH_ITERATIONS,
            "ipopt.hessian_approximation": "limited-memory",
            "ipopt.max_wall_time": POLISH_WALL_S}
    solver = ca.nlpsol("two_legs", "ipopt", {"x": z, "p": par, "f": ca.sum1(z), "g": ca.vertcat(*g)}, opts)
    return solver, ca.Function("info", [z, par], [eta1, r1, eta2, r2])


def two_leg_candidates(target, k: float, steps: int, count: int = 4) -> list:
    """Two-leg candidates for the plane state ``target`` (units of R), shortest first (docs/design/composition.md)."""
    target = np.asarray(target, float)
    h_f, psi_f = float(np.hypot(target[0], target[1])), float(target[2])
    tip = h_f == 0.0
    (r, chi, _), *_ = _binned(k, steps)
    radii = _leaf_table(k).radii
    n_r = radii.size
    solver, info = _polisher(steps, tip)
    out, seen = [], []
    for total, g1, g2 in _picks(target, k, steps):
        if len(out) >= count:
            break
        z0 = np.array([radii[g1 // n_r], radii[g1 % n_r], radii[g2 // n_r], radii[g2 % n_r]])
        if any(np.abs(z0 - q).max() < 0.02 for q in seen):
            continue
        seen.append(z0)
        e1, _, e2, _ = (float(v) for v in info(z0, [k, 0.0, h_f]))
        psi_m = psi_f + TWO_PI * round((steps * (e1 + e2) - psi_f) / TWO_PI)
        lbg, ubg = [0.0, -h_f] + ([] if tip else [0.0]), [0.0, h_f] + ([] if tip else [np.inf])
        sol = interrupts.call(solver, x0=z0, p=[k, psi_m, h_f], lbx=LEAF_FLOOR, ubx=A_MAX, lbg=lbg, ubg=ubg)
        z = np.array(sol["x"]).ravel()
        e1, r1, e2, r2 = (float(v) for v in info(z, [k, psi_m, h_f]))
        violation = max(abs(steps * (e1 + e2) - psi_m), abs(r1 - r2) - h_f, 0.0 if tip else h_f - r1 - r2, 0.0)
        if violation <= 1e-8:
            out.append(Candidate(*(float(v) for v in z), steps * e1, steps * e2, r1, r2,
                                 TWO_PI * steps * float(z.sum()), True))
            continue
        # The polish did not converge (eta is steep near A_MAX): keep the grid pair. Leg 1 is the grid's
        # (r1, chi1); leg 2's distance is the grid's r2 put on the triangle; each leg is solved exactly later.
        r1 = float(r[g1])
        r2 = r1 if tip else min(max(float(r[g2]), abs(h_f - r1)), h_f + r1)
        out.append(Candidate(*(float(v) for v in z0), float(chi[g1]), float(chi[g2]), r1, r2, total, False))
    out.sort(key=lambda c: c.length)
    return out


def intermediate_state(target, r1: float, r2: float, chi: float) -> np.ndarray:
    """The intermediate pole state ``w = (q, chi)`` with ``|q| = r1``, ``|f_p - q| = r2``, left of ``f_p``."""
    target = np.asarray(target, float)
    h = float(np.hypot(target[0], target[1]))
    if h == 0.0:
        return np.array([r1, 0.0, chi])
    e = target[:2] / h
    x = (r1 * r1 - r2 * r2 + h * h) / (2 * h)
    y = math.sqrt(max(r1 * r1 - x * x, 0.0))
    return np.array([x * e[0] - y * e[1], x * e[1] + y * e[0], chi])


def second_leg(target, w) -> np.ndarray:
    """What leg 2 must do from zero: ``w^-1 * f``."""
    return relative(w, target)
