"""The C search, called from Python: the shortest root of (32)-(33) in C.

The C planner (the static sources ``rollplan/csrc/rollplan_planner.c`` and ``.h`` with the generated model
functions and ``rollplan_config.h`` of :mod:`.c_sources`; built here for ``0 <= k <= K_MAX``, every k the
planner accepts) enumerates the roots on one graph per branch over the smaller leaf radius for ``k >= 1/2`` and on
sigma graphs below (docs/design/enumeration.md), and runs a bounded search for the shortest root.
:func:`shortest_root` returns its shortest root uncertified, and :func:`all_roots` every root of every branch
(``<prefix>_plan_all``), for the Python planner to polish and certify. It is the planner's only search: without a
C compiler (or with ``ROLLPLAN_NO_COMPILE=1``) both raise a :class:`~rollplan.errors.SolverError` whose one line
says what to install (:func:`unavailable`). The tests check it against a numpy enumeration
(tests/reference_enumerate.py).

How it is built, loaded and called: docs/design/c-planner.md."""

from __future__ import annotations

import ctypes
import math
import threading
from functools import lru_cache
from typing import NamedTuple

from ... import interrupts
from ...core.compiled import last_build, no_compiler_reason, shared_library
from ...core.families import FAMILIES
from ...errors import InputError, SolverError
from ...problem import K_MAX
from .c_sources import C_FAMILIES, DEFAULT_K_MAX, generator_files, sources
from .search_constants import K_MONOTONE

__all__ = ["PREFIX", "DEFAULT_K_MAX", "UNAVAILABLE", "SearchResult", "FamilyPlan", "library", "unavailable",
           "shortest_root", "all_roots", "check_family_k", "family_plans"]

#: Prefix of the generated C symbols (the code generator's default).
PREFIX = "rollplan"
#: Status codes of the generated planner (``<prefix>.h``).
OK, BAD_INPUT, NO_PLAN, NO_CONVERGENCE, NOT_CERTIFIED, TOO_MANY = 0, 2, 3, 4, 5, 6
#: Roots asked of ``<prefix>_plan_all`` at first (asked again with room for all if there are more).
_FIRST_CAPACITY = 4096

_lock = threading.Lock()
#: A call of the C search is made directly (not by a helper thread) only when it is short: k the last k the C
#: planner prepared its table for (its table is kept), at most DEFAULT_K_MAX, and at most this many steps.
_DIRECT_STEPS = 16
_last_k = [math.nan]
#: Status of the :class:`~rollplan.errors.SolverError` raised when the C search cannot be built or loaded.
UNAVAILABLE = "no C search"
#: Why :func:`library` gave None (set when it does).
_why = [""]


class _Plan(ctypes.Structure):
    """``<prefix>_plan_t`` of the generated header (casadi_real = double)."""

    _fields_ = [("a", ctypes.c_double), ("b", ctypes.c_double), ("gamma", ctypes.c_double),
                ("eta", ctypes.c_double), ("h", ctypes.c_double), ("m", ctypes.c_long),
                ("residual", ctypes.c_double), ("bound", ctypes.c_double), ("predicted", ctypes.c_double),
                ("branches", ctypes.c_int), ("roots", ctypes.c_long)]


class _Options(ctypes.Structure):
    """``<prefix>_options_t`` of the generated header."""

    _fields_ = [("use_branch", ctypes.c_int), ("branch", ctypes.c_long), ("certify", ctypes.c_int)]


class SearchResult(NamedTuple):
    """The shortest root of (32)-(33) found by the C search: leaf radii [R], branch m (relative to the psi
    passed in), and the branches searched and roots tried."""

    a: float
    b: float
    m: int
    branches: int
    roots: int


class FamilyPlan(NamedTuple):
    """A plan of the C search of a leaf family, certified on board: leaf sizes [R], rotation gamma, branch m
    (relative to the psi passed in), shift of one step, the leaf map's predicted miss, and the branches searched
    and roots tried."""

    a: float
    b: float
    gamma: float
    m: int
    h: float
    predicted: float
    branches: int
    roots: int


class _Library(NamedTuple):
    """The entry points of the compiled C planner (ctypes)."""

    plan_with: object
    plan_all: object


def _load(path: str):
    lib = ctypes.CDLL(path)
    try:
        plan_with, plan_all = getattr(lib, f"{PREFIX}_plan_with"), getattr(lib, f"{PREFIX}_plan_all")
    except AttributeError as exc:   # not the planner's library: rebuilt
        raise OSError(str(exc)) from exc
    d, opt, plan = ctypes.c_double, ctypes.POINTER(_Options), ctypes.POINTER(_Plan)
    plan_with.argtypes = [d, d, d, ctypes.c_int, d, opt, plan]
    plan_all.argtypes = [d, d, d, ctypes.c_int, d, opt, plan, ctypes.c_int, ctypes.POINTER(ctypes.c_int)]
    plan_with.restype = plan_all.restype = ctypes.c_int
    return _Library(plan_with, plan_all)


@lru_cache(maxsize=len(FAMILIES))
def library(curve: str = "circles"):
    """``<prefix>_plan_with`` and ``<prefix>_plan_all`` of the compiled C planner (ctypes) of the leaf family
    ``curve`` (:data:`.c_sources.C_FAMILIES`), built on first use; None without it. Its tables are sized for every
    k the planner accepts (``k_max = K_MAX``); its step map ``<prefix>_step_eval``, which the search does not use,
    has the default size (accurate up to k = 5)."""
    # a build (seconds) runs in a helper thread: CasADi's code generation would swallow a Ctrl-C
    name = "c_planner_search" if curve == "circles" else f"c_planner_search_{curve}"
    lib = interrupts.call_in_thread(shared_library, name, lambda: sources(PREFIX, k_max=K_MAX, curve=curve), _load,
                                    "no C search", memo=generator_files())
    if lib is None:
        _why[0] = last_build().get("reason") or no_compiler_reason()
    return lib


def unavailable() -> SolverError:
    """The error of a planner search without the C library: one line naming why and what to install."""
    return SolverError(f"the geometric planner's search is compiled C and cannot be used: {_why[0]}",
                       UNAVAILABLE)


def _library(curve: str = "circles"):
    """:func:`library`, or the :func:`unavailable` error."""
    lib = library(curve)
    if lib is None:
        raise unavailable()
    return lib


def _incomplete(status: int) -> SolverError:
    return SolverError(f"the C search did not complete (status {status} of the C planner)", f"C status {status}")


def _call(entry, k: float, direct: bool, *args) -> int:
    """``entry(*args)`` of the C planner (one call at a time: the planner keeps static state). A call that may be
    long (a new k builds the rho table: 1.3 s at k = 99; a high k or many steps search many branches; every root)
    runs in a helper thread (:func:`rollplan.interrupts.call_in_thread`), so that Ctrl-C acts at once; ``direct``
    allows a direct call where it is short (see :data:`_DIRECT_STEPS`)."""
    def locked():
        with _lock:
            return entry(*args)

    short = direct and (entry, k) == _last_k[0] and k <= DEFAULT_K_MAX
    status = locked() if short else interrupts.call_in_thread(locked)
    _last_k[0] = (entry, k)
    return status


def shortest_root(u: float, v: float, psi: float, steps: int, k: float, branch: int | None = None):
    """The shortest root of (32)-(33) for the target ``(u, v, psi)`` [R, rad] in ``steps`` figure eights at
    inertia ratio k (in [K_MIN, K_MAX]), over all branches or on ``branch`` only (m relative to psi), by the
    compiled C search, uncertified; a result with ``a`` and ``b`` NaN when the (complete) search found no root.
    SolverError without the library (:func:`unavailable`) or when the search does not complete."""
    lib = _library()
    if branch is not None and abs(branch) > 2**31 - 1:   # |eta| beyond the range of E: no root on it
        return SearchResult(math.nan, math.nan, 0, 0, 0)
    options = _Options(int(branch is not None), 0 if branch is None else int(branch), 0)
    plan = _Plan()
    status = _call(lib.plan_with, k, steps <= _DIRECT_STEPS, float(u), float(v), float(psi), int(steps), float(k),
                   ctypes.byref(options), ctypes.byref(plan))
    if status == NO_PLAN:
        return SearchResult(math.nan, math.nan, 0, int(plan.branches), int(plan.roots))
    if status != OK or not (math.isfinite(plan.a) and math.isfinite(plan.b)):
        raise _incomplete(status)
    return SearchResult(plan.a, plan.b, int(plan.m), int(plan.branches), int(plan.roots))


def all_roots(u: float, v: float, psi: float, steps: int, k: float, branch: int | None = None):
    """Every root of (32)-(33) on every branch (or on ``branch`` only), shortest (a + b) first, by the compiled
    C search (``<prefix>_plan_all``), uncertified: a list of :class:`SearchResult` (empty when there is no root).
    SolverError without the library (:func:`unavailable`) or when the search does not complete."""
    lib = _library()
    if branch is not None and abs(branch) > 2**31 - 1:   # |eta| beyond the range of E: no root on it
        return []
    options = _Options(int(branch is not None), 0 if branch is None else int(branch), 0)
    capacity, count = _FIRST_CAPACITY, ctypes.c_int(0)
    while True:
        plans = (_Plan * capacity)()
        status = _call(lib.plan_all, k, False, float(u), float(v), float(psi), int(steps), float(k),
                       ctypes.byref(options), plans, capacity, ctypes.byref(count))
        if status != TOO_MANY or count.value <= capacity:
            break
        capacity = count.value
    if status == NO_PLAN:
        return []
    if status != OK:
        raise _incomplete(status)
    return [SearchResult(p.a, p.b, int(p.m), int(p.branches), int(p.roots)) for p in plans[:count.value]]


def check_family_k(curve: str, k: float) -> None:
    """InputError unless the C search of the leaf family ``curve`` serves ``k``: the circles every k, another
    family (:data:`.c_sources.C_FAMILIES`) k >= 1/2, where its turn E is strictly decreasing in the leaf's size
    (docs/design/curve-families.md, (iv))."""
    if curve not in C_FAMILIES:
        raise InputError(f"curve = {curve!r:.40} is not allowed: choose one of {', '.join(C_FAMILIES)}")
    if curve != "circles" and not k >= K_MONOTONE:
        raise InputError(f"k = {k:g} is not allowed with curve = {curve}: it plans for k >= {K_MONOTONE:g} "
                         "(where the leaf's turn is monotone in its size); use curve = circles")


def family_plans(u: float, v: float, psi: float, steps: int, k: float, curve: str, branch: int | None = None,
                 every: bool = False, certified: bool = True) -> list:
    """Plans for the target ``(u, v, psi)`` [R, rad] in ``steps`` figure eights of the leaf family ``curve`` at
    inertia ratio k (:func:`check_family_k`) by that family's C search, each polished on the family's leaf map and
    certified on board along the family's curve: the shortest certified one (``<prefix>_plan_with``), or with
    ``every`` every certified root of every branch (``<prefix>_plan_all``), shortest first; on ``branch`` only if
    given. A list of :class:`FamilyPlan` (empty: no certified plan). SolverError without the library or when the
    search does not complete."""
    check_family_k(curve, k)
    lib = _library(curve)
    if branch is not None and abs(branch) > 2**31 - 1:
        return []
    options = _Options(int(branch is not None), 0 if branch is None else int(branch), int(bool(certified)))
    args = (float(u), float(v), float(psi), int(steps), float(k), ctypes.byref(options))
    if not every:
        plan = _Plan()
        status = _call(lib.plan_with, k, steps <= _DIRECT_STEPS, *args, ctypes.byref(plan))
        plans = [plan]
    else:
        capacity, count = _FIRST_CAPACITY, ctypes.c_int(0)
        while True:
            buffer = (_Plan * capacity)()
            status = _call(lib.plan_all, k, False, *args, buffer, capacity, ctypes.byref(count))
            if status != TOO_MANY or count.value <= capacity:
                break
            capacity = count.value
        plans = buffer[:count.value]
    if status in (NO_PLAN, NOT_CERTIFIED):
        return []
    if status != OK:
        raise _incomplete(status)
    return [FamilyPlan(p.a, p.b, p.gamma, int(p.m), p.h, p.predicted, int(p.branches), int(p.roots)) for p in plans]
