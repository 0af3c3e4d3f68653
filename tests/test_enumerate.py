"""The accurate leaf map and the complete enumeration of the geometric-phase planner.

Leaf map (:mod:`rollplan.planners.geometric.leafmap`): the closed-form turn, the Gauss rule of the
displacement, the symmetry that makes ``exp(i E/2) d`` real, and ``step`` against scipy DOP853 on
the printed equations (``tests/references.py``) over the accepted domain, up to (A_MAX, K_MAX).

Enumeration (the numpy reference of the C search, ``tests/reference_enumerate.py``) against a brute force of its
own: for each branch m, a dense scan in the first leaf radius a (uniform in the turn E(a) and in a, ten times finer
than the planner's grid or more: :func:`_branch_grid`), b from ``E(b) = E(a) - eta_m`` by bisection on the closed
form, h from the complex step map (not the rho form the planner uses), every sign change refined by bisection and
every local minimum of ``|h^2 - h_m^2|`` checked for a close pair by golden-section search (each on all intervals of
the branch at once), a close pair's two roots by brentq. For every k (E not monotone below 1/2) a 2-D brute force
scans the level set ``E(a) - E(b) = eta_m`` both over a and over b, on monotone pieces of E found numerically (a
dense scan and scipy's bounded minimiser), refined by brentq and scipy's bounded minimiser. Plans are certified by
DOP853 over their first figure eight and the exact symmetry of the others (:func:`_certified_by_dop853`).
"""

import json
import math
from functools import cache

import numpy as np
import pytest
from conftest import READY
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import brentq, minimize_scalar

import rollplan
from rollplan import InputError
from rollplan.core.curves import A_MAX
from rollplan.core.plane import n_step_gain
from rollplan.planners.geometric import leafmap
from rollplan.problem import K_MAX

import reference_enumerate as en
import references

wrap = references.wrap


def _leaf_end(r, side, k, gamma=0.0, x0=(0.0, 0.0, 0.0)):
    """references.leaf_end kept by its arguments: a leaf that several tests integrate by DOP853 (1.6 s at
    (A_MAX, K_MAX)) is integrated once per process, however its arguments are given (the first leaf of
    :func:`_trace` is the leaf of test_leaf_turn_and_displacement_against_dop853)."""
    return _leaf_end_of(float(r), float(side), float(k), float(gamma), tuple(map(float, x0)))


@cache
def _leaf_end_of(r, side, k, gamma, x0):
    return tuple(references.leaf_end(r, side, k, gamma, x0))


def _trace(a, b, k, gamma=0.0, steps=1):
    """references.trace by the same DOP853 calls, through :func:`_leaf_end`."""
    x = (0.0, 0.0, 0.0)
    for _ in range(steps):
        for r, side in ((a, 1.0), (b, -1.0)):
            x = _leaf_end(r, side, k, gamma, x)
    return np.array(x)


# ----------------------------------------------------------------------------- leaf map


@pytest.mark.parametrize("r,k", [(0.05, 0.0), (0.3, 2.5), (A_MAX, 2.5), (0.5, 10.0), (A_MAX, 20.0),
                                 pytest.param(0.6899, 50.0, marks=pytest.mark.slow),
                                 pytest.param(A_MAX, K_MAX, marks=pytest.mark.slow), (0.2, 0.3)])
def test_leaf_turn_and_displacement_against_dop853(r, k):
    """E(r, k) in closed form and d(r, k) by the Gauss rule against DOP853 on the printed (28)-(30)."""
    ref = _leaf_end(r, 1.0, k)
    d = complex(leafmap.displacement(r, k)[0])
    assert abs(float(leafmap.turn(r, k)) - ref[2]) < 1e-10
    assert abs(d - complex(ref[0], ref[1])) < 1e-10


def test_turn_derivative_inverse_and_monotonicity():
    """dE/dr (closed form) against central differences; E strictly decreasing for k >= 1/2;
    turn_inverse inverts E."""
    r = np.linspace(0.01, A_MAX, 300)
    for k in (0.5, 1.0, 2.5, 30.0, K_MAX):
        e = leafmap.turn(r, k)
        fd = (leafmap.turn(r + 1e-7, k) - leafmap.turn(r - 1e-7, k)) / 2e-7
        assert np.allclose(leafmap.turn_dr(r, k), fd, rtol=1e-6, atol=1e-6)
        assert np.all(np.diff(e) < 0)
        assert np.abs(leafmap.turn_inverse(e, k) - r).max() < 1e-12
    assert np.isnan(leafmap.turn_inverse(0.1, 2.5))


def test_displacement_derivative_against_differences():
    r = np.array([0.05, 0.3, 0.6, A_MAX - 1e-3])
    for k in (0.0, 2.5, 30.0):
        _, dd = leafmap.displacement(r, k, derivative=True)
        h = 1e-7
        fd = (leafmap.displacement(r + h, k) - leafmap.displacement(r - h, k)) / (2 * h)
        assert np.all(np.abs(dd - fd) < 1e-5 * (1 + np.abs(dd)))


@settings(max_examples=25, deadline=None)
@given(st.lists(st.floats(0.0, A_MAX), min_size=1, max_size=300), st.floats(0.0, K_MAX),
       st.integers(1, 400), st.booleans())
def test_displacement_does_not_depend_on_its_blocks(r, k, chunk, derivative):
    """The leaf rule applied block by block: the same values to round-off (the BLAS kernel may sum a block in
    another order) for any block size as with the default."""
    r = np.array(r)
    got = leafmap.displacement(r, k, derivative=derivative, chunk=chunk)
    want = leafmap.displacement(r, k, derivative=derivative)
    for one, other in zip(*((got, want) if derivative else ((got,), (want,)))):
        assert np.all(np.abs(one - other) <= 1e-14 * np.abs(other).max(initial=1.0))


@pytest.mark.parametrize("chunk", [0, -1, 2.5, True])
def test_displacement_refuses_a_block_that_is_not_a_positive_integer(chunk):
    with pytest.raises(ValueError, match=f"chunk = {chunk!r}"):
        leafmap.displacement([0.1, 0.2], 2.5, chunk=chunk)


def test_symmetry_exp_half_turn_times_displacement_is_real():
    """The leaf's mirror symmetry: exp(i E / 2) d is real, checked on DOP853's leaf ends."""
    for r, k in ((0.2, 2.5), (0.6, 5.0), (A_MAX, 20.0)):
        ref = _leaf_end(r, 1.0, k)
        assert abs((complex(ref[0], ref[1]) * np.exp(0.5j * ref[2])).imag) < 1e-10
    r = np.linspace(0.001, A_MAX, 400)
    for k in (0.0, 2.5, 40.0):
        d, e = leafmap.leaf_values(r, k)
        assert np.abs((d * np.exp(0.5j * e)).imag).max() < 1e-12


# the cases: `rollplan step --a 0.69 --k 100`, step(0.6899, 0.05, k=50), (0.69, 0.69, k=20)
@pytest.mark.parametrize("a,b,k,gamma", [pytest.param(A_MAX, A_MAX, K_MAX, 0.0, marks=pytest.mark.slow),
                                         pytest.param(0.6899, 0.05, 50.0, 0.0, marks=pytest.mark.slow),
                                         pytest.param(A_MAX, A_MAX, 20.0, 0.0, marks=pytest.mark.slow),
                                         (0.3, 0.4, 2.5, 0.7), (0.1, A_MAX, 30.0, -2.0),
                                         (0.45, 0.2, 0.0, 1.0), (0.6, 0.3, 0.25, 0.0)])
def test_step_against_dop853_over_the_domain(a, b, k, gamma):
    s = rollplan.step(a, b, k=k, gamma=gamma)
    ref = _trace(a, b, k, gamma, 1)
    assert np.abs(np.r_[s.shift, s.eta] - ref).max() < 1e-10
    assert s.h == pytest.approx(math.hypot(ref[0], ref[1]), abs=1e-10)


@pytest.mark.parametrize("kwargs,word", [(dict(a=0.7, k=2.5), "a"), (dict(a=0.3, k=100.5), "k"),
                                         (dict(a=0.3, k=float("nan")), "k"), (dict(a=0.3, b=0.0, k=1.0), "b")])
def test_step_refuses_outside_the_domain(kwargs, word):
    with pytest.raises(InputError, match=word):
        rollplan.step(**kwargs)


# ----------------------------------------------------------------------------- brute force


def b_of(a, eta, k):
    """b with E(b) = E(a) - eta: plain bisection on the closed form (vectorised), nan outside."""
    a = np.asarray(a, float)
    e_min = float(leafmap.turn(A_MAX, k))
    target_e = leafmap.turn(a, k) - eta
    lo, hi = np.zeros(a.shape), np.full(a.shape, A_MAX)
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        right = leafmap.turn(mid, k) > target_e
        lo, hi = np.where(right, mid, lo), np.where(right, hi, mid)
    return np.where((target_e >= e_min) & (target_e <= 0.0), 0.5 * (lo + hi), np.nan)


def leaf_gap(a, eta, h_m, k):
    """h(a, b(a))^2 - h_m^2 by the complex step map."""
    s, _ = leafmap.step_values(a, b_of(np.array([a]), eta, k), k)
    return float(abs(s[0]) ** 2 - h_m * h_m)


def _radius_of_turn(e, k):
    return brentq(lambda r: float(leafmap.turn(r, k)) - e, 0.0, A_MAX, xtol=1e-15)


def _brute_branch(eta, h_m, k, samples_per_rad, min_samples):
    """Roots a of branch (eta, h_m) by the dense scan of the module docstring."""
    return _brute_branches([eta], [h_m], k, samples_per_rad, min_samples)[0]


def _branch_grid(eta, k, samples_per_rad, min_samples):
    """The scan grid in a of branch eta, empty where E(a) - eta leaves [E(A_MAX), 0]: uniform in E(a) at
    ``samples_per_rad`` points per radian of turn, which resolve h^2 - h_m^2 where it turns with E, and
    ``min_samples`` uniform in a, which resolve it where E is flat (small a; a spacing of at most
    A_MAX / min_samples: less than a hundredth of the planner's X_STEP for the default 4000)."""
    e_min = float(leafmap.turn(A_MAX, k))
    lo_e, hi_e = max(e_min, e_min + eta), min(0.0, eta)       # E(a) - eta within [E(A_MAX), 0]
    if lo_e > hi_e:
        return np.zeros(0)
    a_lo = _radius_of_turn(hi_e, k) if hi_e < 0 else 0.0
    a_hi = _radius_of_turn(lo_e, k) if lo_e > e_min else A_MAX
    n = max(2, int(samples_per_rad * (hi_e - lo_e)))
    grid = np.unique(np.concatenate([np.linspace(a_lo, a_hi, min_samples),
                                     leafmap.turn_inverse(np.linspace(hi_e, lo_e, n), k)]))
    return grid[(grid > 0) & np.isfinite(grid)]


def _brute_branches(etas, h_ms, k, samples_per_rad, min_samples):
    """Roots a of each branch (eta_i, h_i) by the dense scan of the module docstring: every branch's grid, sign
    changes and minima in one array (a bisection or golden-section step is one vectorised call for all branches,
    not one per branch). A list of root lists, one per branch."""
    grids = [_branch_grid(eta, k, samples_per_rad, min_samples) for eta in etas]
    grid = np.concatenate(grids)
    which = np.repeat(np.arange(len(grids)), [g.size for g in grids])
    eta_of, h_of = np.asarray(etas, float)[which], np.asarray(h_ms, float)[which]
    bs = b_of(grid, eta_of, k)
    ok = np.isfinite(bs) & (bs > 0)
    grid, bs, which, eta_of, h_of = grid[ok], bs[ok], which[ok], eta_of[ok], h_of[ok]
    h2_of = h_of * h_of
    shift, _ = leafmap.step_values(grid, bs, k)
    f = np.abs(shift) ** 2 - h2_of

    def g(a, i):   # leaf_gap for an array of a, at the branches of the grid points i
        return np.abs(leafmap.step_values(a, b_of(a, eta_of[i], k), k)[0]) ** 2 - h2_of[i]

    same = which[:-1] == which[1:]                              # neighbours on one branch
    changes = np.nonzero((np.sign(f[:-1]) * np.sign(f[1:]) < 0) & same)[0]
    roots = [[] for _ in grids]
    for i, a in zip(changes, _bisect(lambda a: g(a, changes), grid[changes], grid[changes + 1])):
        roots[which[i]].append(a)
    # local minima of |f| without a sign change: a close pair or a tangency inside one interval
    af = np.abs(f)
    low = np.nonzero((af[1:-1] < af[:-2]) & (af[1:-1] < af[2:]) & same[:-1] & same[1:])[0] + 1
    low = low[(f[low - 1] * f[low] > 0) & (f[low] * f[low + 1] > 0)]
    sign = np.sign(f[low])
    lowest = _golden_minimum(lambda a: sign * g(a, low), grid[low - 1], grid[low + 1])
    for j in np.nonzero(np.sign(g(lowest, low)) != sign)[0]:
        i = low[j]
        args = (float(eta_of[i]), float(h_of[i]), k)
        roots[which[i]].append(brentq(leaf_gap, grid[i - 1], lowest[j], args=args, xtol=1e-15, rtol=1e-15))
        roots[which[i]].append(brentq(leaf_gap, lowest[j], grid[i + 1], args=args, xtol=1e-15, rtol=1e-15))
    return roots


def _bisect(f, lo, hi, halvings=60):
    """The root in each bracket [lo_i, hi_i] of a sign change of the vectorised f, all brackets halved together
    (60 halvings: far below the spacing of doubles for the brute force's brackets; it stops sooner once every
    bracket is two neighbouring doubles, whose midpoint no further halving changes)."""
    lo, hi = np.array(lo, float), np.array(hi, float)
    if lo.size == 0:
        return lo
    f_lo = f(lo)
    for _ in range(halvings):
        mid = 0.5 * (lo + hi)
        if np.all((mid == lo) | (mid == hi)):
            break
        f_mid = f(mid)
        right = np.sign(f_mid) == np.sign(f_lo)   # the sign change is in [mid, hi]
        lo, f_lo, hi = np.where(right, mid, lo), np.where(right, f_mid, f_lo), np.where(right, hi, mid)
    return 0.5 * (lo + hi)


def _golden_minimum(f, lo, hi, steps=90):
    """A local minimum of the vectorised f in each interval [lo_i, hi_i], by golden-section search on all intervals
    together (90 steps shrink them by 0.618^90 < 1e-18; it stops sooner once every interval is within four
    spacings of doubles)."""
    lo, hi = np.array(lo, float), np.array(hi, float)
    if lo.size == 0:
        return lo
    inv = (math.sqrt(5.0) - 1.0) / 2.0
    c, d = hi - inv * (hi - lo), lo + inv * (hi - lo)
    f_c, f_d = f(c), f(d)
    for _ in range(steps):
        if np.all(hi - lo <= 4.0 * np.spacing(hi)):
            break
        left = f_c < f_d   # the minimum is in [lo, d]: d becomes the old c
        lo, hi = np.where(left, lo, c), np.where(left, d, hi)
        new = np.where(left, hi - inv * (hi - lo), lo + inv * (hi - lo))
        f_new = f(new)
        c, f_c, d, f_d = (np.where(left, new, d), np.where(left, f_new, f_d),
                          np.where(left, c, new), np.where(left, f_c, f_new))
    return 0.5 * (lo + hi)


#: The brute force's roots by its arguments: a target scanned by two tests is scanned once per process.
_BRUTE_ROOTS: dict = {}


def _brute_roots(target, steps, k, branches=None, samples_per_rad=40, min_samples=4000):
    """All (m, a, b) solving (32)-(33) by a dense scan in a (see the module docstring)."""
    key = (tuple(map(float, target)), int(steps), float(k), None if branches is None else tuple(branches),
           samples_per_rad, min_samples)
    if key not in _BRUTE_ROOTS:
        _BRUTE_ROOTS[key] = tuple(_scan_roots(target, steps, k, branches, samples_per_rad, min_samples))
    return list(_BRUTE_ROOTS[key])


def _scan_roots(target, steps, k, branches, samples_per_rad, min_samples):
    u, v, psi = target
    psi = float(wrap(psi))
    h_des = math.hypot(u, v)
    lam = -float(leafmap.turn(A_MAX, k))
    ms = range(math.ceil((-steps * lam - psi) / (2 * math.pi)), math.floor((steps * lam - psi) / (2 * math.pi)) + 1)
    scanned = []                                     # (m, eta, h_m) of the branches to scan
    for m in (branches if branches is not None else ms):
        eta = (psi + 2 * math.pi * m) / steps
        gain = float(n_step_gain(eta, steps))
        if gain < 1e-12 or abs(eta) > lam:
            continue
        scanned.append((m, eta, h_des / gain))
    if not scanned:
        return []
    roots = _brute_branches([e for _, e, _ in scanned], [h for _, _, h in scanned], k, samples_per_rad, min_samples)
    found = [(m, eta, a) for (m, eta, _), branch in zip(scanned, roots) for a in branch]
    if not found:
        return []
    bs = b_of(np.array([a for _, _, a in found]), np.array([eta for _, eta, _ in found]), k)
    return [(m, a, float(b)) for (m, _, a), b in zip(found, bs)]


def _enumerated(target, steps, k, branch=None):
    u, v, psi = target
    brs = en.branches(k, float(wrap(psi)), steps, math.hypot(u, v), branch)
    return [(r.m, r.a, r.b) for r in en.roots(brs, k)]


def same_sets(brute, enum, tol=1e-7):
    missed = [r for r in brute if not any(e[0] == r[0] and abs(e[1] - r[1]) < tol and abs(e[2] - r[2]) < tol
                                          for e in enum)]
    extra = [e for e in enum if not any(e[0] == r[0] and abs(e[1] - r[1]) < tol and abs(e[2] - r[2]) < tol
                                        for r in brute)]
    return missed, extra


def repeated(first, steps):
    """The ends of ``steps`` figure eights from zero, given ``first`` = the ends (u_a, v_a, psi) of one from zero
    (arrays of shape (N, 3) and (N,)), by the symmetry of the printed equations (28)-(30): their right side does not
    depend on (u_a, v_a), and psi only turns the rates of (u_a, v_a) by -psi, so a figure eight started at
    (u, v, psi) ends at ``(u + i v) + exp(-i psi) S``, ``psi + eta``, where ``(S, eta)`` is its end from zero.
    Checked against DOP853 over every step by test_codegen.test_traces_are_the_trace_of_each_plan."""
    first, steps = np.atleast_2d(np.asarray(first, float)), np.atleast_1d(steps)
    shift, eta = first[:, 0] + 1j * first[:, 1], first[:, 2]
    end, psi = np.zeros(len(first), complex), np.zeros(len(first))
    for j in range(int(steps.max())):
        on = steps > j
        end[on] += np.exp(-1j * psi[on]) * shift[on]
        psi[on] += eta[on]
    return np.stack([end.real, end.imag, psi], axis=1)


def _certified_by_dop853(target, steps, k, p):
    """The miss of plan p: its first figure eight by DOP853 on the printed equations, the others by
    :func:`repeated`."""
    x = repeated(_trace(p.a, p.b, k, p.gamma, 1), steps)[0]
    return max(abs(x[0] - target[0]), abs(x[1] - target[1]), abs(wrap(x[2] - target[2])))


@settings(max_examples=200, deadline=None)
@given(h=st.floats(1e-9, 1.0), slope=st.floats(0.1, 1e3), off=st.floats(-0.5, 0.5), curve=st.floats(-10.0, 10.0))
def test_newton_step_is_newton_on_the_shift(h, slope, off, curve):
    """newton_step is Newton's step on f = |S| - h: on a shift S(x) = slope x + curve x^2 (|S| = S for x > 0,
    g = S^2 - h^2) it equals f / f' by the closed form, and for a linear shift it lands on the root x* = h / slope
    in one step from anywhere in (0, 2 x*], which Newton on g misses by (x - x*)^2 / (2 x) (g'' / (2 g'))."""
    x = h / slope * (1.0 + off)
    s, ds = slope * x + curve * x * x, slope + 2.0 * curve * x
    if s <= 0.0 or abs(ds) < 1e-6 * slope:   # |S| = S; at S' = 0 Newton's step is not defined
        return
    g, dg = s * s - h * h, 2.0 * s * ds
    step, miss = en.newton_step(np.array([g]), np.array([dg]), np.array([h * h]))
    assert miss[0] == pytest.approx(abs(s - h), rel=1e-9, abs=1e-15 * s)
    assert step[0] == pytest.approx((s - h) / ds, rel=1e-9, abs=1e-15 * x)
    step, _ = en.newton_step(np.array([(slope * x) ** 2 - h * h]), np.array([2.0 * slope * slope * x]),
                             np.array([h * h]))
    root = h / slope
    assert abs(x - step[0] - root) <= 1e-12 * root
    if abs(off) > 0.1:   # where Newton on g is off by more than rounding
        assert abs(x - ((slope * x) ** 2 - h * h) / (2.0 * slope * slope * x) - root) > 1e-6 * root


def test_close_pair_hidden_by_the_table_is_found_on_the_accurate_map():
    """k = 5, one step, eta = 0.3 (branch 0): h just above a local minimum of |S| on the branch,
    h = sqrt(q_min) (1 + 1e-8), makes two roots about 3e-8 apart that the table (its error in rho ~1e-7) shows
    as one tangency; the accurate map splits it (enumerate._tangencies). Reference: scipy's bounded minimiser and
    brentq on the complex step map of the brute force."""
    k, eta = 5.0, 0.3
    res = minimize_scalar(lambda a: leaf_gap(a, eta, 0.0, k), bounds=(0.5716, 0.5816), method="bounded",
                          options={"xatol": 1e-14})
    h = math.sqrt(res.fun) * (1.0 + 1e-8)
    assert leaf_gap(res.x, eta, h, k) < 0.0
    lo, hi = res.x - 1e-6, res.x + 1e-6
    assert leaf_gap(lo, eta, h, k) > 0.0 and leaf_gap(hi, eta, h, k) > 0.0
    brute = [brentq(leaf_gap, a0, a1, args=(eta, h, k), xtol=1e-16, rtol=1e-15)
             for a0, a1 in ((lo, res.x), (res.x, hi))]
    got = sorted(r.a for r in en.roots(en.branches(k, eta, 1, h, 0), k) if abs(r.a - res.x) < 1e-3)
    assert len(got) == 2 and got[1] - got[0] > 1e-8
    np.testing.assert_allclose(got, brute, rtol=0, atol=1e-10)
    # the dense scan of the brute force steps over the pair: its minimum search finds it
    scanned = sorted(a for a in _brute_branch(eta, h, k, 40, 4000) if abs(a - res.x) < 1e-3)
    np.testing.assert_allclose(scanned, brute, rtol=0, atol=1e-10)


@pytest.mark.slow
def test_first_root_behind_a_tangency_at_the_end_of_the_graph():
    """A shift of 1.2e-3 R in 5 steps, eta ~ 2e-7, k = 3.11: at a = 0, g = -h^2 is within the table's floor and flat,
    a tangency of the table that the polish moves onto a = 0 (no root). The branch's first root, at a = b = 0.0166,
    is still the shortest one returned (it was lost), the same as the brute force's first root."""
    u, v, psi, n, k = 0.0009695511170914938, -0.0006893752926909919, 1.0268242372426444e-06, 5, 3.111167772746886
    brs = en.branches(k, psi, n, math.hypot(u, v), 0)
    first = en.roots(brs, k, first_only=True)
    brute = _brute_branch(brs[0].eta, brs[0].h, k, 40, 4000)
    assert len(first) == 1 and min(brute) < 0.02
    assert first[0].a == pytest.approx(min(brute), abs=1e-12)


@pytest.mark.slow
def test_no_roots_where_the_table_is_flat_and_the_accurate_map_misses():
    """k = 100, n = 12, a target 7e-5 R away: h = 7e-6 is within the table's floor over much of the branch, and the
    polish of its flat cells ended at points where the accurate map misses by 4.5e-4 to 1.5e-3 (258 of them were
    returned as roots). The reference returns none, as the brute force and the planner (no plan) find."""
    u, v, psi, n, k = -7.273e-05, -1.623e-05, -1.67708, 12, 100.0
    brs = en.branches(k, psi, n, math.hypot(u, v), 0)
    assert en.roots(brs, k) == []
    assert all(_brute_branch(b.eta, b.h, k, 40, 1000) == [] for b in brs)
    with pytest.raises(rollplan.NoPlanError):
        rollplan.plan((u, v, psi), k=k, steps=n, branch=0, all_solutions=True)


@pytest.mark.slow
def test_brute_force_of_many_branches_at_once_is_that_of_each_branch():
    """The dense scan of several branches in one array (_brute_branches) finds, on each branch, the roots that the
    scan of that branch alone finds: nothing is paired across the seam of two branches' grids (between branches
    with roots, and between one where h^2 - h_m^2 < 0 everywhere, h_m = 100, and one where it is mostly > 0)."""
    k, steps, target = 2.5, 5, (0.0621, 0.0847, 2.4915)
    brs = [(b.eta, b.h) for b in en.branches(k, target[2], steps, math.hypot(*target[:2])) if b.m in (-5, -10, 0, 3)]
    brs += [(brs[0][0], 100.0), (brs[0][0], 1e-6), (brs[0][0], 100.0)]
    together = _brute_branches([e for e, _ in brs], [h for _, h in brs], k, 40, 1000)   # any grid: the same for both
    assert sum(map(len, together)) >= 4
    for (eta, h), roots in zip(brs, together):
        alone = _brute_branch(eta, h, k, 40, 1000)
        assert len(roots) == len(alone) and np.allclose(roots, alone, rtol=0, atol=1e-12), (eta, h)


# the three failures
def test_named_failure_shortest_on_branch_minus_5():
    """(0.0621, 0.0847, 2.4915), n = 5, k = 2.5: the shortest plan is L = 35.723 on m = -5 (a close
    pair of roots in one cell of the old bracketing grid)."""
    target = (0.0621, 0.0847, 2.4915)
    p = rollplan.plan(target, steps=5, k=2.5, legs="one")
    assert p.branch == -5 and p.path_length == pytest.approx(35.723, abs=5e-4)
    assert _certified_by_dop853(target, 5, 2.5, p) < 1e-9


def test_named_failure_branch_zero():
    target = (-0.2724, 0.1488, -2.9291)
    p = rollplan.plan(target, steps=3, k=2.5, branch=0, legs="one")
    assert p.branch == 0 and p.path_length == pytest.approx(19.4840, abs=5e-5)
    assert _certified_by_dop853(target, 3, 2.5, p) < 1e-9


@pytest.mark.slow
def test_named_failure_all_plans_complete():
    """(0.2, 0.1, 2), n = 3, k = 2.5: at least 46 plans, the same set as the brute force."""
    target = (0.2, 0.1, 2.0)
    p = rollplan.plan(target, steps=3, k=2.5, all_solutions=True, legs="one")
    plans = (p,) + p.alternatives
    assert len(plans) >= 46
    brute = _brute_roots(target, 3, 2.5)
    enum = [(q.branch, q.a, q.b) for q in plans]
    assert same_sets(brute, enum) == ([], [])
    assert all(_certified_by_dop853(target, 3, 2.5, q) < 1e-9 for q in plans[:5])


@pytest.mark.parametrize("target,steps,k,branches", [
    ((0.0621, 0.0847, 2.4915), 5, 2.5, [-5, -10, 0, 3]),
    pytest.param((0.2, 0.1, 2.0), 3, 2.5, None, marks=pytest.mark.slow),
    pytest.param((0.5, -0.3, 1.0), 2, 1.5, None, marks=pytest.mark.slow),
    pytest.param((0.1, 0.4, -2.0), 1, 5.0, None, marks=pytest.mark.slow),
    pytest.param((-0.3, 0.2, 0.4), 4, 10.0, [0, 1, -1, 5], marks=pytest.mark.slow),
])
def test_enumeration_against_brute_force(target, steps, k, branches):
    """Every root on the branches, against the dense scan; neither misses one of the other's."""
    psi = float(wrap(target[2]))
    turns = round((target[2] - psi) / (2 * math.pi))
    assert turns == 0
    brute = _brute_roots(target, steps, k, branches=branches)
    enum = []
    for m in (branches if branches is not None else [None]):
        enum += _enumerated(target, steps, k, m)
    missed, extra = same_sets(brute, enum)
    assert missed == [] and extra == []


@pytest.mark.slow
@pytest.mark.parametrize("k", [1.5, 2.5, 5.0, 10.0, 20.0])
def test_random_targets_default_is_the_shortest_and_all_complete(k):
    """Random targets, n in 1..5: the enumeration equals the brute force on every branch that the
    brute force scans (all for n <= 2 and k <= 5, the five of smallest |eta| otherwise), and the
    default plan is the shortest root that DOP853 certifies."""
    rng = np.random.default_rng(int(k * 10))
    for _ in range(3):
        steps = int(rng.integers(1, 6))
        dist, direction, psi = rng.uniform(0.05, 1.5), rng.uniform(-np.pi, np.pi), rng.uniform(-np.pi, np.pi)
        target = (dist * np.cos(direction), dist * np.sin(direction), psi)
        brs = en.branches(k, psi, steps, dist)
        sub = None if (steps <= 2 and k <= 5) else [b.m for b in brs[:5]]
        brute = _brute_roots(target, steps, k, branches=sub)
        enum = [(r.m, r.a, r.b) for r in en.roots([b for b in brs if sub is None or b.m in sub], k)]
        assert same_sets(brute, enum) == ([], [])
        try:
            p = rollplan.plan(target, steps=steps, k=k, legs="one")
        except rollplan.NoPlanError:
            assert not en.roots(brs, k)
            continue
        assert _certified_by_dop853(target, steps, k, p) < 1e-9
        shortest = min(2 * math.pi * steps * (a + b) for _, a, b in brute) if brute else math.inf
        assert p.path_length <= shortest + 1e-8


# ----------------------------------------------------------------------------- command line


def _cli(capsys, *args):
    from rollplan.cli import main
    code = main(list(args))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.mark.slow
def test_cli_step_at_the_corner_of_the_domain_and_beyond(capsys):
    """`rollplan step --a 0.69 --k 100` prints the DOP853 shift; k above K_MAX is refused (exit 2)."""
    code, out, _ = _cli(capsys, "step", "--a", "0.69", "--k", "100", "--json", "-")   # full precision: JSON
    ref = _trace(A_MAX, A_MAX, K_MAX)
    final = json.loads(out)["final"]
    assert code == 0 and abs(final["u_a"] - ref[0]) < 1e-10 and abs(final["v_a"] - ref[1]) < 1e-10
    code, _, err = _cli(capsys, "step", "--a", "0.3", "--k", "100.5")
    assert code == 2 and "k = 100.5" in err and "100" in err and len(err.strip().splitlines()) == 1


def test_cli_branch_and_compact_all(capsys):
    code, out, _ = _cli(capsys, "plan", "--to", "-0.2724", "0.1488", "--psi", "-2.9291", "--steps", "3",
                        "--branch", "0")
    assert code == 0 and "(branch m = 0)" in out and "path length   19.484 R" in out   # 6 digits in summaries
    code, out, _ = _cli(capsys, "plan", "--to", "0", "1", "--k", "2.5", "--all")
    count = int(out.split("all plans:")[1].split()[0])
    rows = out.split("residual\n")[-1].strip().splitlines()
    assert code == 0 and count == len(rows) > 1
    lengths = [float(r.split()[4]) for r in rows]
    assert lengths == sorted(lengths) and abs(lengths[0] - 2 * math.pi * 2 * 0.300428806) < 1e-5


@pytest.mark.slow
def test_ctrl_c_stops_a_high_k_plan_promptly(tmp_path):
    """SIGINT during a K_MAX plan (its leaf table built afresh, then the search): exit 130 within seconds."""
    import os
    import signal
    import subprocess
    import sys
    import time

    env = {**os.environ, "ROLLPLAN_CACHE_DIR": str(tmp_path)}   # no table on disk: the plan takes seconds
    p = subprocess.Popen([sys.executable, "-c", READY, "plan", "--to", "0", "1", "--k", "99.5"], env=env,
                         stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    assert p.stderr.readline() == "ready\n"
    time.sleep(0.5)
    assert p.poll() is None, "the plan ended before the interrupt"
    t0 = time.perf_counter()
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=60)
    assert p.returncode == 130 and time.perf_counter() - t0 < 3.0


# ----------------------------------------------------------------------------- every k: a 2-D brute force


def _monotone_pieces(k):
    """The monotone pieces of E(., k) on [0, A_MAX], found numerically (a dense scan of the closed form and
    scipy's bounded minimiser), independent of ``leafmap.turn_pieces``."""
    r = np.linspace(0.0, A_MAX, 20001)
    e = leafmap.turn(r, k)
    i = int(np.argmax(e))
    if 0 < i < r.size - 1:
        top = minimize_scalar(lambda x: -float(leafmap.turn(x, k)), bounds=(r[i - 1], r[i + 1]), method="bounded",
                              options={"xatol": 1e-15}).x
        return [(0.0, top), (top, A_MAX)]
    return [(0.0, A_MAX)]


def _invert_on(t, k, lo, hi):
    """Radii in [lo, hi] with E = t (E monotone there), by bisection on the closed form; nan outside."""
    t = np.asarray(t, float)
    e_lo, e_hi = float(leafmap.turn(lo, k)), float(leafmap.turn(hi, k))
    up = e_hi > e_lo
    a, b = np.full(t.shape, lo), np.full(t.shape, hi)
    for _ in range(64):
        mid = 0.5 * (a + b)
        right = (leafmap.turn(mid, k) < t) if up else (leafmap.turn(mid, k) > t)
        a, b = np.where(right, mid, a), np.where(right, b, mid)
    inside = (t >= min(e_lo, e_hi)) & (t <= max(e_lo, e_hi))
    return np.where(inside, 0.5 * (a + b), np.nan)


def _h2(a, b, k):
    s, _ = leafmap.step_values(np.atleast_1d(a), np.atleast_1d(b), k)
    return np.abs(s) ** 2


@cache
def _grid_leaves(k, n):
    """The scan grid of :func:`_scan_sheets` and its leaves' ``(d, E)`` (leafmap.leaf_values), once per (k, n): every
    branch and sheet scans the same grid."""
    grid = np.linspace(1e-9, A_MAX, n)
    return (grid, *leafmap.leaf_values(grid, k))


def _h2_on_grid(ok, other, k, n, swap):
    """``h^2`` of :func:`_h2` where one leaf runs over the grid points ``ok`` and the other has the radii ``other``:
    the grid's leaves from :func:`_grid_leaves`, the composition of leafmap.step_values (item 4 of
    docs/design/leaf-map.md)."""
    _, d_grid, e_grid = _grid_leaves(k, n)
    d_other, e_other = leafmap.leaf_values(other, k)
    (da, ea), db = ((d_other, e_other), d_grid[ok]) if swap else ((d_grid[ok], e_grid[ok]), d_other)
    return np.abs(da + np.exp(-1j * ea) * np.conj(db)) ** 2


def _scan_sheets(eta, h_m, k, pieces, n, swap):
    """Roots on the sheets ``b = E_j^-1(E(a) - eta)`` scanned in a (or, with ``swap``, a over b): sign
    changes of h^2 - h_m^2 refined by brentq, local minima of |h^2 - h_m^2| checked by scipy's bounded
    minimiser for a close pair. Returns (a, b) pairs."""
    out = []
    grid = _grid_leaves(k, n)[0]
    for lo, hi in pieces:
        def other(x, lo=lo, hi=hi):
            t = leafmap.turn(x, k) + (eta if swap else -eta)
            return _invert_on(t, k, lo, hi)

        def f(x, other=other):
            y = float(other(np.array([x]))[0])
            a, b = (y, x) if swap else (x, y)
            return float(_h2(a, b, k)[0]) - h_m * h_m

        y = other(grid)
        ok = np.isfinite(y) & (y > 0)
        if ok.sum() < 2:
            continue
        xs, ys = grid[ok], y[ok]
        vals = _h2_on_grid(ok, ys, k, n, swap) - h_m * h_m
        # contiguous runs of valid samples only (the sheet may be cut by the piece's range)
        runs = np.split(np.arange(xs.size), np.nonzero(np.diff(np.nonzero(ok)[0]) > 1)[0] + 1)
        for run in runs:
            xr, fr = xs[run], vals[run]
            for i in np.nonzero(np.sign(fr[:-1]) * np.sign(fr[1:]) < 0)[0]:
                x = brentq(f, xr[i], xr[i + 1], xtol=1e-15, rtol=1e-15)
                out.append((x, float(other(np.array([x]))[0])))
            af = np.abs(fr)
            for i in np.nonzero((af[1:-1] < af[:-2]) & (af[1:-1] < af[2:]))[0] + 1:
                if fr[i - 1] * fr[i] <= 0 or fr[i] * fr[i + 1] <= 0:
                    continue
                sign = float(np.sign(fr[i]))
                res = minimize_scalar(lambda x, s=sign: s * f(x), bounds=(xr[i - 1], xr[i + 1]), method="bounded",
                                      options={"xatol": 1e-14})
                if np.sign(f(res.x)) != sign:
                    for lo2, hi2 in ((xr[i - 1], res.x), (res.x, xr[i + 1])):
                        x = brentq(f, lo2, hi2, xtol=1e-15, rtol=1e-15)
                        out.append((x, float(other(np.array([x]))[0])))
    return [(y, x) if swap else (x, y) for x, y in out]


def brute_roots_2d(target, steps, k, n=6000):
    """All (m, a, b) solving (32)-(33) for any k: the level set E(a) - E(b) = eta_m scanned over a (b on
    each monotone piece) and over b (a on each piece), so that no part of it is seen only where it is
    steep; roots found by both scans are merged."""
    u, v, psi = target
    psi = float(wrap(psi))
    h_des = math.hypot(u, v)
    pieces = _monotone_pieces(k)
    e_all = leafmap.turn(np.linspace(0.0, A_MAX, 20001), k)
    span = float(e_all.max() - min(e_all.min(), 0.0))
    out = []
    two_pi = 2 * math.pi
    for m in range(math.ceil((-steps * span - psi) / two_pi), math.floor((steps * span - psi) / two_pi) + 1):
        eta = (psi + 2 * math.pi * m) / steps
        gain = float(n_step_gain(eta, steps))
        if gain < 1e-12:
            continue
        h_m = h_des / gain
        for a, b in _scan_sheets(eta, h_m, k, pieces, n, False) + _scan_sheets(eta, h_m, k, pieces, n, True):
            new = not any(q[0] == m and abs(q[1] - a) < 1e-9 and abs(q[2] - b) < 1e-9 for q in out)
            if 0 < a <= A_MAX and 0 < b <= A_MAX and new:
                out.append((m, a, b))
    return out


@pytest.mark.parametrize("k", [0.0, 0.3, *(pytest.param(k, marks=pytest.mark.slow) for k in (0.55, 0.005, 0.1, 0.45))])
def test_enumeration_for_every_k_against_a_2d_brute_force(k):
    """Below K_FAST (E increasing, or with an interior maximum, or K_MONOTONE <= k < K_FAST): every root,
    against the scan of the level set in a and in b; targets with psi = 0 exercise the eta = 0 branch
    (a = b, and a != b with E(a) = E(b) where E is not monotone)."""
    rng = np.random.default_rng(int(k * 1000) + 7)
    targets = [((0.3, 0.2, 0.0), 1), ((0.05, -0.1, 0.0), 2), ((0.2, 0.1, 0.3), 1)]
    targets += [((rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-np.pi, np.pi)), int(rng.integers(1, 4)))]
    for target, steps in targets:
        brute = brute_roots_2d(target, steps, k)
        enum = _enumerated(target, steps, k)
        missed, extra = same_sets(brute, enum)
        assert missed == [] and extra == [], (target, steps, missed, extra)


@pytest.mark.slow
@pytest.mark.parametrize("k", [0.0, 0.005, 0.1, 0.3, 0.45])
def test_planner_below_one_half_is_the_shortest_and_complete(k):
    """The planner at k < 1/2 (formerly bracketed without a guarantee): random targets, n in 1..3; the
    default plan is the shortest root of the 2-D brute force that DOP853 certifies, and ``all_solutions``
    lists exactly the brute force's roots (certified ones; each checked by DOP853)."""
    rng = np.random.default_rng(int(k * 1000) + 11)
    e = leafmap.turn(np.linspace(0.0, A_MAX, 2001), k)
    span = float(e.max() - min(e.min(), 0.0))          # |eta| <= span: psi where branches exist
    for _ in range(4):
        steps = int(rng.integers(1, 4))
        dist, direction = rng.uniform(0.02, 0.5), rng.uniform(-np.pi, np.pi)
        psi = 0.0 if rng.uniform() < 0.3 else rng.uniform(-1.0, 1.0) * min(np.pi, 0.9 * steps * span)
        target = (dist * np.cos(direction), dist * np.sin(direction), psi)
        brute = brute_roots_2d(target, steps, k)
        try:
            p = rollplan.plan(target, steps=steps, k=k, all_solutions=True, legs="one")
        except rollplan.NoPlanError:
            assert brute == []
            continue
        plans = (p,) + p.alternatives
        assert all(_certified_by_dop853(target, steps, k, q) < 1e-9 for q in plans)
        missed, extra = same_sets(brute, [(q.branch, q.a, q.b) for q in plans])
        assert extra == []
        # a brute-force root the certificate rejected would be missing; none is expected here
        assert missed == []
        assert p.path_length <= min(2 * math.pi * steps * (a + b) for _, a, b in brute) + 1e-8
        d = rollplan.plan(target, steps=steps, k=k, legs="one")
        assert d.path_length == pytest.approx(p.path_length, abs=1e-9)
