"""The C search, called from Python: the shortest root of (32)-(33) in C.

The C planner (the static sources ``rollplan/csrc/rollplan_planner.c`` and ``.h`` with the generated model
functions and ``rollplan_config.h`` of :mod:`.c_sources`; built here for ``0 <= k <= K_MAX``, every k the
planner accepts) enumerates the roots on one graph per branch over the smaller leaf radius for ``k >= 1/2`` and on
sigma graphs below (docs/design/enumeration.md), and runs a bounded search for the shortest root.
:func:`shortest_root` returns its shortest root uncertified, and :func:`all_roots` every root of every branch
(``<prefix>_plan_all``), for the Python planner to polish and certify; :func:`listed_roots` gives them with their
rotation gamma, and :func:`certify_roots` certifies a list of them by the C certificate (``<prefix>_certify``).
It is the planner's only search: without a
C compiler (or with ``ROLLPLAN_NO_COMPILE=1``) both raise a :class:`~rollplan.errors.SolverError` whose one line
says what to install (:func:`unavailable`). The tests check it against a numpy enumeration
(tests/reference_enumerate.py).

How it is built, loaded and called: docs/design/c-planner.md."""

from __future__ import annotations

import ctypes
import hashlib
import math
import os
import shutil
import tempfile
import threading
import time
from functools import lru_cache
from pathlib import Path
from typing import NamedTuple

import numpy as np

from ... import interrupts
from ...core.compiled import check_private, last_build, no_compiler_reason, shared_library
from ...core.families import FAMILIES
from ...errors import InputError, OutputError, SolverError, UnsafeCacheError
from ...outputs import write_atomic
from ...problem import K_MAX
from .c_sources import C_FAMILIES, DEFAULT_K_MAX, generator_files, sources
from .search_constants import K_MONOTONE

__all__ = ["PREFIX", "DEFAULT_K_MAX", "UNAVAILABLE", "SearchResult", "ListedRoot", "Certified", "FamilyPlan",
           "library", "unavailable", "shortest_root", "all_roots", "listed_roots", "certify_roots", "certified_plan",
           "certified_plans", "check_family_k", "family_plans"]

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


class ListedRoot(NamedTuple):
    """A root of (32)-(33) listed by the C search (``<prefix>_plan_all`` without its certificate): leaf radii [R],
    rotation gamma of (31), holonomy eta and shift h of one step, branch m (relative to the psi passed in), the miss
    of the target predicted by the leaf map, and the branches searched and roots found."""

    a: float
    b: float
    gamma: float
    eta: float
    h: float
    m: int
    predicted: float
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


class Certified(NamedTuple):
    """The C certificate of a root (``<prefix>_certify``): final (u_a, v_a, psi) [R, rad] of its finest run, its
    residual to the target and the error bound; ``status`` OK or NOT_CERTIFIED (to CERT_TOL)."""

    final: tuple
    residual: float
    bound: float
    status: int


class _Library(NamedTuple):
    """The entry points of the compiled C planner (ctypes)."""

    plan_with: object
    plan_all: object
    plan_many: object
    certify: object
    path: str
    table_save: object
    table_load: object


def _load(path: str):
    lib = ctypes.CDLL(path)
    try:
        plan_with, plan_all = getattr(lib, f"{PREFIX}_plan_with"), getattr(lib, f"{PREFIX}_plan_all")
        plan_many = getattr(lib, f"{PREFIX}_plan_many")
        certify = getattr(lib, f"{PREFIX}_certify")
        table_save, table_load = getattr(lib, f"{PREFIX}_table_save"), getattr(lib, f"{PREFIX}_table_load")
    except AttributeError as exc:   # not the planner's library: rebuilt
        raise OSError(str(exc)) from exc
    d, opt, plan = ctypes.c_double, ctypes.POINTER(_Options), ctypes.POINTER(_Plan)
    dp = ctypes.POINTER(ctypes.c_double)
    plan_with.argtypes = [d, d, d, ctypes.c_int, d, opt, plan]
    plan_all.argtypes = [d, d, d, ctypes.c_int, d, opt, plan, ctypes.c_int, ctypes.POINTER(ctypes.c_int)]
    plan_many.argtypes = [ctypes.c_int, ctypes.c_void_p, ctypes.c_int, d, opt, ctypes.c_void_p, ctypes.c_void_p,
                          ctypes.c_void_p]
    certify.argtypes = [d, d, d, ctypes.c_int, d, d, d, d, dp, dp, dp]
    table_save.argtypes = [d, ctypes.c_int, dp, dp, dp, ctypes.POINTER(ctypes.c_int)]
    table_load.argtypes = [d, ctypes.c_int, dp, dp, d]
    plan_with.restype = plan_all.restype = plan_many.restype = certify.restype = ctypes.c_int
    table_save.restype = table_load.restype = ctypes.c_int
    return _Library(plan_with, plan_all, plan_many, certify, str(path), table_save, table_load)


#: Serializes the calls of the second instance of :func:`_second_certify`.
_second_lock = threading.Lock()


@lru_cache(maxsize=1)
def _second_certify():
    """``(library, <prefix>_certify)`` of a second instance of the C library, loaded from a copy of its file (a
    separate copy in memory: its own static work memory), so that a second thread can certify while the first
    does; None if it cannot be loaded."""
    lib = _library()
    folder = tempfile.mkdtemp(prefix="rollplan-certify-")
    try:
        copy = os.path.join(folder, os.path.basename(lib.path))
        shutil.copyfile(lib.path, copy)
        second = ctypes.CDLL(copy)   # another file: loaded again, not shared with the first
        entry = getattr(second, f"{PREFIX}_certify")
    except (OSError, AttributeError):
        return None
    finally:
        shutil.rmtree(folder, ignore_errors=True)   # the loaded copy stays mapped
    entry.argtypes, entry.restype = lib.certify.argtypes, lib.certify.restype
    return second, entry


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


def _table_path(lib, k: float) -> Path:
    """The file of the rho table of k of the library ``lib`` (beside it in the cache directory; its name holds the
    library's, which holds the digest of its sources, and k exactly)."""
    path = Path(lib.path)
    return path.with_name(f"{path.stem}-table-{float(k).hex()}.bin")


def _load_table(lib, k: float) -> bytes:
    """Give the C planner ``lib`` its rho table of k from the cache directory (``<prefix>_table_load``; the C planner
    takes it only if it has as many radii as its own table of k and its values at three radii evaluated again equal
    it exactly): the table's bytes given, or b"" when there is none or it is unusable (a file not private, or whose
    bytes do not match the SHA-256 digest it starts with), and the C planner builds the table.

    What this detects: damage (the digest), a table of another k or another build of the planner (the three radii).
    What it does not: a deliberate edit with the digest recomputed (the digest is not keyed; the other radii and the
    midpoint error are taken as stored). The file is trusted as the cache's compiled libraries are, by living in
    a private cache directory (:func:`rollplan.core.compiled.check_private`); a plan from an edited table is still
    certified by its own integration, but roots could be missed."""
    path = _table_path(lib, k)
    try:
        check_private(path)
        raw = path.read_bytes()
    except (OSError, UnsafeCacheError):
        return b""
    body = raw[32:]
    if len(raw) < 32 or hashlib.sha256(body).digest() != raw[:32] or len(body) % 8:
        return b""
    data = np.frombuffer(body, dtype="<f8")
    if data.size < 6 or not math.isfinite(data[0]) or data.size != 2 + 2 * int(data[0]):
        return b""
    n = int(data[0])
    rho, drho = np.ascontiguousarray(data[2:2 + n]), np.ascontiguousarray(data[2 + n:])
    dp = ctypes.POINTER(ctypes.c_double)
    status = lib.table_load(float(k), n, rho.ctypes.data_as(dp), drho.ctypes.data_as(dp), float(data[1]))
    return body if status == OK else b""


def _save_table(lib, k: float, loaded: bytes) -> None:
    """Write the C planner's rho table of k (``<prefix>_table_save``) into the cache directory unless it is the one
    ``loaded``: the SHA-256 digest of the rest, then n, the midpoint error, rho and d rho / dr (little-endian
    doubles). Nothing when it cannot be written (another process writing it, a full disk: a later process builds
    the table again)."""
    n, err, capacity = ctypes.c_int(0), ctypes.c_double(0.0), 4096
    dp = ctypes.POINTER(ctypes.c_double)
    for _ in range(2):
        rho, drho = np.empty(capacity), np.empty(capacity)
        status = lib.table_save(float(k), capacity, rho.ctypes.data_as(dp), drho.ctypes.data_as(dp),
                                ctypes.byref(err), ctypes.byref(n))
        if status != TOO_MANY:
            break
        capacity = n.value
    if status != OK:
        return
    body = np.concatenate(([n.value, err.value], rho[:n.value], drho[:n.value])).astype("<f8").tobytes()
    if body == loaded:
        return
    path = _table_path(lib, k)
    try:
        write_atomic(path, hashlib.sha256(body).digest() + body, what="rho table")
        os.chmod(path, 0o600)
    except (OutputError, OSError):
        pass


#: The k of the table each family's C planner keeps (a table of another k is loaded from the cache directory or
#: built, then saved there).
_family_k: dict = {}


def _call(entry, k: float, direct: bool, *args, lib=None) -> int:
    """``entry(*args)`` of the C planner (one call at a time: the planner keeps static state). A call that may be
    long (a new k builds the rho table: 1.3 s at k = 99; a high k or many steps search many branches; every root)
    runs in a helper thread (:func:`rollplan.interrupts.call_in_thread`), so that Ctrl-C acts at once; ``direct``
    allows a direct call where it is short (see :data:`_DIRECT_STEPS`). With ``lib`` (a family's C planner, whose
    rho table takes seconds to build) the table of a new k is taken from the cache directory, or saved there once
    built."""
    def locked():
        with _lock:
            if lib is None or _family_k.get(lib.path) == k:
                return entry(*args)
            loaded = _load_table(lib, k)
            status = entry(*args)
            if status not in (OK, NO_PLAN, NOT_CERTIFIED, TOO_MANY):   # (the table of k may not be built)
                _family_k.pop(lib.path, None)
                return status
            _family_k[lib.path] = k
            _save_table(lib, k, loaded)
            return status

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
    return [SearchResult(p.a, p.b, p.m, p.branches, p.roots) for p in listed_roots(u, v, psi, steps, k, branch)]


def listed_roots(u: float, v: float, psi: float, steps: int, k: float, branch: int | None = None):
    """:func:`all_roots` with each root's rotation gamma, eta, h and predicted miss: a list of
    :class:`ListedRoot`, shortest (a + b) first."""
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
    return [ListedRoot(p.a, p.b, p.gamma, p.eta, p.h, int(p.m), p.predicted, int(p.branches), int(p.roots))
            for p in plans[:count.value]]


#: Seconds of certificates per call of the helper thread of :func:`certify_roots` (Ctrl-C acts at once anyway).
_CHUNK_SECONDS = 0.25


def certify_roots(roots, u: float, v: float, psi: float, steps: int, k: float, progress=None,
                  threads: int | None = None) -> list:
    """The C certificate (``<prefix>_certify``: the n-step motion integrated by fixed-step RK8 with step doubling,
    independent of the leaf map) of each root of ``roots`` (with ``a``, ``b``, ``gamma``) for the target
    ``(u, v, psi)`` [R, rad] in ``steps`` figure eights at inertia ratio k: a list of :class:`Certified`, in order.
    The roots are certified in chunks of about :data:`_CHUNK_SECONDS`, each by a helper thread
    (:func:`rollplan.interrupts.call_in_thread`: Ctrl-C acts at once); ``progress(done, total)`` after each.
    With ``threads`` = 2 (the default on two or more cores) each chunk is shared by two threads, the second on a
    second instance of the library (:func:`_second_certify`); the results do not depend on it."""
    lib = _library()
    if threads is None:
        threads = 2 if (os.cpu_count() or 1) >= 2 else 1
    second = _second_certify() if threads >= 2 and len(roots) > 1 else None
    out, total, size = [], len(roots), 4

    def run(entry, lock, part, got):
        final, residual, bound = (ctypes.c_double * 3)(), ctypes.c_double(), ctypes.c_double()
        with lock:
            for r in part:
                status = entry(r.a, r.b, r.gamma, steps, k, u, v, psi, final, ctypes.byref(residual),
                               ctypes.byref(bound))
                got.append(Certified(tuple(final), residual.value, bound.value, status))

    def chunk(part):
        if second is None or len(part) < 2:
            got = []
            run(lib.certify, _lock, part, got)
            return got
        half = len(part) // 2
        first, other = [], []
        helper = threading.Thread(target=run, args=(second[1], _second_lock, part[half:], other), daemon=True)
        helper.start()
        run(lib.certify, _lock, part[:half], first)
        helper.join()
        if len(other) != len(part) - half:
            raise SolverError("the second C certificate thread failed", "C certificate")
        return first + other

    while len(out) < total:
        start = time.perf_counter()
        out += interrupts.call_in_thread(chunk, roots[len(out):len(out) + size])
        spent = time.perf_counter() - start
        size = max(1, min(4 * size, int(size * _CHUNK_SECONDS / spent) if spent > 0 else 4 * size))
        if progress is not None:
            progress(len(out), total)
    return out


def _plan_dtype():
    """The numpy dtype of ``<prefix>_plan_t`` (the layout of :class:`_Plan`)."""
    dt = np.dtype([(name, {ctypes.c_double: np.float64, ctypes.c_long: np.int_, ctypes.c_int: np.intc}[t])
                   for name, t in _Plan._fields_], align=True)
    if dt.itemsize != ctypes.sizeof(_Plan):
        raise SolverError("the C planner's plan_t does not match its numpy layout", UNAVAILABLE)
    return dt


#: Targets per call of ``<prefix>_plan_many`` from :func:`certified_plans` (a call runs a few ms to ~0.1 s, so
#: that Ctrl-C acts between calls).
_CHUNK = 256


def certified_plan(u: float, v: float, psi: float, steps: int, k: float, branch: int | None = None):
    """``(status, plan, final)``: the shortest certified plan for the target ``(u, v, psi)`` [R, rad] by one call
    of the C planner (search, Newton polish on the accurate leaf map and the RK8 certificate
    ``<prefix>_certify``): the C status (:data:`OK`, :data:`NO_PLAN` or :data:`NOT_CERTIFIED`),
    the ``_Plan`` (residual and bound of its certificate; on NOT_CERTIFIED those of the best rejected root) and
    the certificate's final ``(u_a, v_a, psi)`` (NaN unless OK). SolverError without the library
    (:func:`unavailable`) or when the search does not complete."""
    lib = _library()
    plan, final, status = _Plan(), (ctypes.c_double * 3)(), ctypes.c_int(NO_PLAN)
    if branch is not None and abs(branch) > 2**31 - 1:   # |eta| beyond the range of E: no root on it
        return NO_PLAN, plan, (math.nan,) * 3
    options = _Options(int(branch is not None), 0 if branch is None else int(branch), 1)
    target = (ctypes.c_double * 3)(u, v, psi)
    _call(lib.plan_many, k, steps <= _DIRECT_STEPS, 1, target, int(steps), float(k), ctypes.byref(options),
          ctypes.byref(plan), final, ctypes.byref(status))
    if status.value not in (OK, NO_PLAN, NOT_CERTIFIED):
        raise _incomplete(status.value)
    return status.value, plan, tuple(final)


def certified_plans(targets, steps: int, k: float, progress=None):
    """``(status, plans, finals)`` of many targets (array ``(N, 3)`` of ``(u, v, psi)`` [R, rad]) for one ``steps``
    and k, by ``<prefix>_plan_many`` (:func:`certified_plan` per target, in chunks of :data:`_CHUNK` targets per
    call): ``status`` (N,) the C statuses, ``plans`` a structured array (N,) of ``plan_t`` fields, ``finals``
    (N, 3). ``progress(done, total)`` is called after each chunk."""
    lib = _library()
    targets = np.ascontiguousarray(targets, dtype=np.float64).reshape(-1, 3)
    count = targets.shape[0]
    plans = np.zeros(count, dtype=_plan_dtype())
    finals = np.full((count, 3), math.nan)
    status = np.full(count, NO_PLAN, dtype=np.intc)
    options = _Options(0, 0, 1)
    size = plans.dtype.itemsize
    for start in range(0, count, _CHUNK):
        n = min(_CHUNK, count - start)
        _call(lib.plan_many, k, n == 1 and steps <= _DIRECT_STEPS, n, targets[start:].ctypes.data, int(steps),
              float(k), ctypes.byref(options), plans.ctypes.data + start * size, finals[start:].ctypes.data,
              status[start:].ctypes.data)
        if progress is not None:
            progress(start + n, count)
    return status, plans, finals


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
        status = _call(lib.plan_with, k, steps <= _DIRECT_STEPS, *args, ctypes.byref(plan), lib=lib)
        plans = [plan]
    else:
        capacity, count = _FIRST_CAPACITY, ctypes.c_int(0)
        while True:
            buffer = (_Plan * capacity)()
            status = _call(lib.plan_all, k, False, *args, buffer, capacity, ctypes.byref(count), lib=lib)
            if status != TOO_MANY or count.value <= capacity:
                break
            capacity = count.value
        plans = buffer[:count.value]
    if status in (NO_PLAN, NOT_CERTIFIED):
        return []
    if status != OK:
        raise _incomplete(status)
    return [FamilyPlan(p.a, p.b, p.gamma, int(p.m), p.h, p.predicted, int(p.branches), int(p.roots)) for p in plans]
