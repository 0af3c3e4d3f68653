"""Reachability atlas: the step map (h, eta)(a, b) over the admissible square.

One trace of the figure eight (31) with leaf radii (a, b) shifts the contact
point by ``h(a, b)`` and turns psi by ``eta(a, b)`` (Section III.B of the
paper; (28)-(30) integrated over one step). ``n`` traces reach the shift and
turn (the n-step law of :mod:`rollplan.core.plane`)

    H_n = h |sin(n eta / 2) / sin(eta / 2)|,   Psi_n = n eta,       (32)-(34)

so the image of the square ``(0, A_MAX]^2`` under ``(a, b) -> (H_n, Psi_n)``
is the set of (shift, turn) pairs ``n`` figure eights can reach. Where the
Jacobian determinant ``det d(h, eta)/d(a, b)`` vanishes the map folds: there
two solution branches of (32)-(33) meet and disappear, and the root solver's
Newton matrix is singular. The maps are evaluated by the spectral step map,
batched with CasADi ``map`` over threads; the determinant is exact (AD). The
grid is evaluated in blocks of rows, so the work reports its progress and can
run on a Dask cluster (:mod:`.executor`), one block per task, for one k or a
sweep over several (:func:`compute_atlases`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import casadi as ca
import numpy as np

from ..core import families
from ..core.curves import A_MAX
from ..core.integrate import spectral_step
from ..core.plane import n_step_gain
from ..errors import InputError, check_choice, check_whole
from ..planners import METHODS
from ..planners.geometric import ComposedPlanner, GeometricPhasePlanner, default_planner
from ..problem import check_k, check_steps
from .executor import Executor, cpu_count

__all__ = ["Atlas", "DEFAULT_RESOLUTION", "MAX_RESOLUTION", "atlas_function", "compute_atlas", "compute_atlases",
           "atlas_to_dict", "n_step_totals"]

#: Grid points per axis of an atlas by default (the command line's and results/atlas_k2.5.png's).
DEFAULT_RESOLUTION = 101
#: Largest grid points per axis.
MAX_RESOLUTION = 1000
#: An atlas is evaluated in about this many blocks of rows (the unit of progress and of cluster tasks).
_BLOCKS = 25


@dataclass(frozen=True)
class Atlas:
    """Maps of one step of the figure eight over the (a, b) grid, for one k.

    Attributes
    ----------
    k : float
        Inertia ratio.
    steps : int
        Number of traces n of the totals ``shift_total``, ``turn_total``.
    a, b : ndarray, shape (N,)
        Leaf radii of the grid [units of R], in (0, A_MAX].
    h : ndarray, shape (N, N)
        Shift of one step ``h(a_i, b_j)`` [units of R].
    eta : ndarray, shape (N, N)
        Holonomy angle of one step ``eta(a_i, b_j)`` [rad].
    det : ndarray, shape (N, N)
        ``det d(h, eta)/d(a, b)`` [rad]; zero on the fold.
    shift_total : ndarray, shape (N, N)
        Shift reached by n steps, ``H_n`` [units of R].
    turn_total : ndarray, shape (N, N)
        Turn reached by n steps, ``Psi_n = n eta`` [rad] (not wrapped).
    fold_cells : int
        Grid cells whose corners' ``det`` change sign.
    curve : str
        Leaf family of the figure eight (:data:`rollplan.core.families.FAMILIES`; a, b are then leaf sizes).
    """

    k: float
    steps: int
    a: np.ndarray
    b: np.ndarray
    h: np.ndarray
    eta: np.ndarray
    det: np.ndarray
    shift_total: np.ndarray
    turn_total: np.ndarray
    fold_cells: int
    curve: str = "circles"


def atlas_function(step_map: ca.Function) -> ca.Function:
    """``G(ab[2], k) -> (h, eta, det d(h, eta)/d(ab))`` from a step map ``F(x0, p, k, gamma)``.

    The step starts from zero with gamma = 0 (h and eta do not depend on gamma).
    """
    ab = ca.SX.sym("ab", 2)
    k = ca.SX.sym("k")
    xf = step_map(ca.DM.zeros(3), ab, k, 0)
    h = ca.norm_2(xf[:2])
    eta = xf[2]
    jac = ca.jacobian(ca.vertcat(h, eta), ab)
    return ca.Function("atlas", [ab, k], [h, eta, ca.det(jac)], ["ab", "k"], ["h", "eta", "det"])


def n_step_totals(h, eta, steps: int):
    """``(H_n, Psi_n)`` of n steps from (h, eta): ``h |sin(n eta/2)/sin(eta/2)|`` (limit ``n h``), ``n eta``."""
    h, eta = np.asarray(h, float), np.asarray(eta, float)
    return h * n_step_gain(eta, steps), steps * eta


def _evaluate(fun: ca.Function, k: float, a_rows, b, threads: int):
    """(h, eta, det) on the grid ``a_rows`` x ``b``, each of shape (len(a_rows), len(b))."""
    aa, bb = np.meshgrid(np.asarray(a_rows, float), np.asarray(b, float), indexing="ij")
    pts = np.vstack([aa.ravel(), bb.ravel()])
    batch = fun.map(pts.shape[1], "thread", threads) if threads > 1 else fun.map(pts.shape[1])
    return tuple(np.array(v).reshape(aa.shape) for v in batch(pts, k))


def _block(task):
    """A block of rows of an atlas on a cluster worker (the workers' default planner, one thread)."""
    k, a_rows, b, curve = task
    return _evaluate(_cached_atlas_function(default_planner(), curve), k, a_rows, b, 1)


def compute_atlases(ks, steps: int = 1, resolution: int = DEFAULT_RESOLUTION, planner=None, threads: int | None = None,
                    scheduler: str | None = None, progress=None, curve: str = "circles") -> list:
    """:func:`compute_atlas` for each k of ``ks``, in order: a sweep over k, in blocks of rows.

    Parameters
    ----------
    ks : sequence of float
        Inertia ratios, each in [0, K_MAX].
    steps, resolution, planner, threads
        As in :func:`compute_atlas` (``planner`` and ``threads`` apply to a run in this process).
    scheduler : str, optional
        Address of a Dask distributed scheduler: evaluate the blocks on its workers instead.
    progress : callable, optional
        ``progress("atlas", blocks done, blocks)`` after each block.
    curve : str
        Leaf family of the figure eight (default the circles (35); docs/design/curve-families.md).
    """
    curve = check_choice("curve", curve, families.FAMILIES)
    try:
        ks = [check_k(k) for k in ks]
    except TypeError:
        raise InputError(f"ks = {ks!r} is not allowed: give a sequence of inertia ratios") from None
    if not ks:
        raise InputError("ks is empty: give at least one inertia ratio")
    steps = check_steps(steps)  # the planner's own limits
    resolution = check_whole("resolution", resolution, 2, MAX_RESOLUTION)
    r = A_MAX * np.arange(1, resolution + 1) / resolution
    per = math.ceil(resolution / _BLOCKS)
    blocks = [(k, r[i:i + per], r, curve) for k in ks for i in range(0, resolution, per)]
    if scheduler is not None:
        runner, fn = Executor(1, scheduler), _block
    else:
        fun = _cached_atlas_function(_step_planner(planner), curve)
        cores = threads or cpu_count()
        runner, fn = Executor(1), (lambda task: _evaluate(fun, task[0], task[1], task[2], cores))
    parts = []
    with runner:
        for part in runner.map(fn, blocks):
            parts.append(part)
            if progress is not None:
                progress("atlas", len(parts), len(blocks))
    out = []
    for j, k in enumerate(ks):
        mine = parts[j * len(blocks) // len(ks):(j + 1) * len(blocks) // len(ks)]
        h, eta, det = (np.vstack([p[i] for p in mine]) for i in range(3))
        total_h, total_psi = n_step_totals(h, eta, int(steps))
        s = np.sign(det)
        corners = np.stack([s[:-1, :-1], s[1:, :-1], s[:-1, 1:], s[1:, 1:]])
        fold = int(np.count_nonzero(corners.min(0) != corners.max(0)))
        out.append(Atlas(k, int(steps), r, r.copy(), h, eta, det, total_h, total_psi, fold, curve))
    return out


def compute_atlas(k: float, steps: int = 1, resolution: int = DEFAULT_RESOLUTION, planner=None,
                  threads: int | None = None, scheduler: str | None = None, progress=None,
                  curve: str = "circles") -> Atlas:
    """Evaluate h, eta and the fold determinant on a ``resolution`` x ``resolution`` grid of (0, A_MAX]^2.

    Parameters
    ----------
    k : float
        Inertia ratio k >= 0 (14).
    steps : int
        n >= 1 for the totals ``H_n``, ``Psi_n``.
    resolution : int
        Grid points per axis, in [2, MAX_RESOLUTION]; ``a_i = A_MAX i / N``, i = 1..N.
    planner : ComposedPlanner or GeometricPhasePlanner, optional
        The method ``"geometric"`` (or its pole-to-pole planner) whose step map to use (default: the
        registry's, :data:`rollplan.planners.METHODS`).
    threads : int, optional
        Threads of the CasADi ``map`` (default: all cores).
    scheduler : str, optional
        Address of a Dask distributed scheduler to evaluate the grid on (see :func:`compute_atlases`).
    progress : callable, optional
        ``progress("atlas", done, total)`` per block of rows.
    curve : str
        Leaf family of the figure eight (default the circles (35)).
    """
    return compute_atlases([k], steps, resolution, planner, threads, scheduler, progress, curve)[0]


def _step_planner(planner) -> GeometricPhasePlanner:
    """The pole-to-pole planner whose step map an atlas evaluates: the method ``"geometric"``'s (the registry's
    by default, or the one given), or the planner given."""
    planner = METHODS["geometric"]() if planner is None else planner
    if isinstance(planner, ComposedPlanner):
        planner = planner.planner
    if not isinstance(planner, GeometricPhasePlanner):
        raise InputError(f"planner = {planner!r:.60} is not allowed: give the method 'geometric' "
                         "(rollplan.planners.METHODS['geometric']()) or a GeometricPhasePlanner")
    return planner


@lru_cache(maxsize=8)
def _cached_atlas_function(planner, curve: str = "circles") -> ca.Function:
    """The atlas function of the planner's step map (circles), or of the spectral step of another family's
    figure eight with the planner's nodes."""
    if curve == "circles":
        return atlas_function(planner.step_map)
    return atlas_function(spectral_step(families.figure_eight(curve), planner.nodes))


def atlas_to_dict(at: Atlas) -> dict:
    """The atlas as the JSON object of ``rollplan atlas --json`` (2-D arrays as lists of rows over a)."""
    rows = lambda z: [[float(v) for v in row] for row in np.asarray(z)]
    return {"curve": at.curve, "k": at.k, "steps": at.steps, "a": [float(v) for v in at.a],
            "b": [float(v) for v in at.b],
            "h": rows(at.h), "eta": rows(at.eta), "det": rows(at.det),
            "shift_total": rows(at.shift_total), "turn_total": rows(at.turn_total), "fold_cells": at.fold_cells,
            "ranges": {"h": [float(at.h.min()), float(at.h.max())], "eta": [float(at.eta.min()), float(at.eta.max())],
                       "shift_total": [float(at.shift_total.min()), float(at.shift_total.max())],
                       "turn_total": [float(at.turn_total.min()), float(at.turn_total.max())]}}
