"""Run one function over many items and get the results in input order: in this process, in local
worker processes, or on a Dask distributed cluster.

Batch planning (:mod:`.batch`), atlas sweeps (:mod:`.atlas`) and Monte Carlo studies use it; they
write ``fn`` and a list of items and get the results back in the order of the items, whatever ran
them. The contract of ``fn``:

* a module-level function of an installed module (it is sent to other processes by reference), of
  one picklable argument, returning a picklable result;
* it builds what it needs lazily, once per process (e.g. through a cached planner), so a worker
  pays its start-up once however many items it gets;
* it should catch the errors of a bad item itself and return them as a result: an exception that
  escapes ``fn`` stops the whole run (locally) or reaches ``on_error`` (on a cluster, together with
  the loss of a worker).

Backends:

``jobs == 1`` (and no scheduler)
    In this process, one item after another.
``jobs > 1``
    A pool of worker processes on this machine. Where the ``fork`` start method exists (Linux), the
    workers are forked from this process after ``warm()`` has run here, so they start with whatever
    ``warm`` built (the planner and its compiled functions) and pay no start-up. With ``first_here``
    (items that share what ``fn`` builds lazily, e.g. the rows of a batch at one k) the first item runs
    here too before the fork, so whatever it built (the tables of its parameters, the solver's
    internals) is built once, not once per worker. Items go to the workers in chunks sized from the
    first item's time (one item when an item takes longer than :data:`CHUNK_SECONDS`), so short items
    do not pay a round trip each. Elsewhere, or when this process runs other threads (forking them is
    unsafe), the workers are spawned and run ``warm()`` once each. Ctrl-C in this process stops the
    workers at once; a worker never outlives this process (it is killed when this process ends, even
    by SIGKILL).
``scheduler = "tcp://host:port"``
    The items are tasks on a Dask distributed cluster (optional extra:
    ``pip install 'rollplan[distributed]'``). The workers must have the same version of rollplan
    installed (checked on connection). Tasks that share a worker process run one at a time (the
    CasADi functions of a cached planner are not shared between threads); give workers one thread
    each and as many processes as cores: ``dask worker ADDRESS --nworkers N --nthreads 1``.
    A task whose worker died repeatedly (Dask's ``KilledWorker``) is passed to ``on_error``; losing the
    scheduler raises :class:`ExecutorError`.
"""

from __future__ import annotations

import ctypes
import gc
import logging
import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Iterable, Iterator

from ..errors import InputError, check_whole
from ..progress import silence
from ..version import __version__

__all__ = ["Executor", "ExecutorError", "map_in_order", "start_method", "chunk_size", "DASK_EXTRA",
           "CONNECT_TIMEOUT", "WORKERS_TIMEOUT", "CHUNK_SECONDS", "MAX_JOBS"]

log = logging.getLogger(__name__)

#: How a user installs the Dask backend.
DASK_EXTRA = "pip install 'rollplan[distributed]'"
#: The most worker processes on this machine (``jobs``; ``batch --jobs``).
MAX_JOBS = 1024
#: Seconds to wait for a scheduler to answer.
CONNECT_TIMEOUT = 10.0
#: Seconds to wait for a scheduler to have at least one worker.
WORKERS_TIMEOUT = 60.0
#: Seconds of work a chunk of items sent to a local worker is sized for (items shorter than this go in
#: chunks, so the cost of sending an item and its result is small against the item's own).
CHUNK_SECONDS = 0.05

_TASK_LOCK = threading.Lock()


class ExecutorError(RuntimeError):
    """The machinery running the items failed (e.g. the Dask scheduler was lost); the items are not at fault."""


#: ``prctl`` option: the signal the kernel sends this process when its parent dies (Linux).
_PR_SET_PDEATHSIG = 1


def _die_with_parent(parent: int) -> None:
    """Make this worker end when its parent process ``parent`` ends, however it ends (SIGKILL included): the
    kernel kills it (Linux, ``PR_SET_PDEATHSIG``); elsewhere a thread checks the parent every second. A
    worker whose parent is gone already exits at once."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        armed = libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0
    except (OSError, AttributeError):   # no prctl (not Linux)
        armed = False
    if os.getppid() != parent:
        os._exit(1)
    if not armed:
        def watch():
            while os.getppid() == parent:
                time.sleep(1.0)
            os._exit(1)

        threading.Thread(target=watch, name="rollplan-parent-watch", daemon=True).start()


def _worker_init(parent: int) -> None:
    """Worker initializer: the worker dies with its parent (:func:`_die_with_parent`); Ctrl-C and SIGTERM are
    handled by the parent, which stops the pool (a worker ignores SIGINT, and SIGTERM, the parent's way of
    stopping it, ends it at once); progress is the parent's to show (a forked worker inherits the parent's
    reporter)."""
    _die_with_parent(parent)
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    silence()


def _spawned_worker_init(warm, parent: int) -> None:
    _worker_init(parent)
    if warm is not None:
        warm()


def _one_at_a_time(fn, item):
    """Run ``fn(item)`` on a Dask worker, one task at a time per worker process."""
    with _TASK_LOCK:
        return fn(item)


def _worker_version() -> str:
    return __version__


def start_method() -> str:
    """``fork`` where it exists and this process runs no other thread (a fork copies locks held by other
    threads, e.g. those of a Dask client, and can deadlock the workers); ``spawn`` otherwise."""
    if "fork" in multiprocessing.get_all_start_methods() and threading.active_count() == 1:
        return "fork"
    return "spawn"


class Executor:
    """Where items run (see the module docstring); a context manager.

    Parameters
    ----------
    jobs : int
        Worker processes on this machine (1: in this process). Ignored with ``scheduler``.
    scheduler : str, optional
        Address of a Dask distributed scheduler, e.g. ``"tcp://10.0.0.5:8786"``.
    warm : callable, optional
        ``warm()`` builds what ``fn`` will need (e.g. the planner), once per process: here before
        workers are forked, or in each spawned worker. Optional: ``fn`` must work without it.
    first_here : bool
        With forked workers, run the first item in this process before forking them (see the module
        docstring): for items that share what ``fn`` builds lazily. Without it (few long items with
        nothing shared, e.g. a sweep over parameters) every item runs in a worker.

    Use ``with Executor(...) as ex: for result in ex.map(fn, items): ...``; leaving the block
    stops the workers (at once if it is left by an exception, e.g. Ctrl-C).
    """

    def __init__(self, jobs: int = 1, scheduler: str | None = None, warm: Callable | None = None,
                 first_here: bool = False) -> None:
        self.jobs = check_whole("jobs", jobs, 1)
        if scheduler is not None and (not isinstance(scheduler, str) or not scheduler.strip()):
            raise InputError(f"scheduler = {scheduler!r} is not allowed: give the address of a Dask scheduler, "
                             "e.g. 'tcp://host:8786'")
        self.scheduler = scheduler
        self.warm = warm
        self.first_here = bool(first_here)
        self._pool = None
        self._client = None
        self._futures: list = []

    # -- context -----------------------------------------------------------------------
    def __enter__(self) -> Executor:
        if self.scheduler is not None:
            self._client = _connect(self.scheduler)
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        self.close(abort=exc_type is not None)

    def close(self, abort: bool = False) -> None:
        """Stop the workers: at once with ``abort`` (cancelling what runs), else after they finish."""
        pool, self._pool = self._pool, None
        if pool is not None:
            if abort:
                pool.terminate()
            else:
                pool.close()
            pool.join()
        client, self._client = self._client, None
        if client is not None:
            if abort and self._futures:
                try:
                    client.cancel(self._futures)
                except Exception:  # the cluster may be gone already  # noqa: BLE001
                    log.debug("cancelling the remaining tasks failed", exc_info=True)
            self._futures = []
            client.close()

    @property
    def where(self) -> str:
        """Where the items run, for messages."""
        if self.scheduler is not None:
            return f"Dask scheduler {self.scheduler}"
        return "this process" if self.jobs == 1 else f"{self.jobs} local worker processes"

    # -- map ---------------------------------------------------------------------------
    def map(self, fn: Callable, items: Iterable, on_error: Callable | None = None) -> Iterator:
        """``fn(item)`` for every item, yielded in the order of ``items``.

        ``on_error(item, exc)`` gives the result of an item whose task failed on a cluster (a worker
        lost, or an exception escaping ``fn``); without it the exception is raised.
        """
        items = list(items)
        if not items:
            return iter(())
        if self._client is not None:
            return self._map_dask(fn, items, on_error)
        if self.jobs == 1 or len(items) == 1:
            if self.warm is not None:
                self.warm()
            return map(fn, items)
        return self._map_pool(fn, items)

    def _map_pool(self, fn, items):
        rest, elapsed = items, None
        if self.first_here and start_method() == "fork":
            if self.warm is not None:
                self.warm()
            start = time.perf_counter()
            yield fn(items[0])   # here: what fn builds lazily is built once, before the fork, for every worker
            elapsed = time.perf_counter() - start
            rest = items[1:]
        method = start_method()   # again: the first item may have started a thread
        ctx = multiprocessing.get_context(method)
        if method != "fork":
            workers = min(self.jobs, len(rest))
            self._pool = ctx.Pool(workers, initializer=_spawned_worker_init, initargs=(self.warm, os.getpid()))
            log.info("%d worker processes (%s)", workers, method)
            yield from self._pool.imap(fn, rest, chunksize=1)   # in input order
            return
        if self.warm is not None:
            self.warm()   # built once here (nothing new if the first item ran here); the forked workers share it
        workers = min(self.jobs, len(rest))
        chunk = chunk_size(elapsed, len(rest), workers)
        # Objects moved to the permanent generation are not traversed by the workers' garbage collector,
        # so their pages stay shared instead of being copied into every worker.
        gc.freeze()
        try:
            self._pool = ctx.Pool(workers, initializer=_worker_init, initargs=(os.getpid(),))
        finally:
            gc.unfreeze()
        log.info("%d worker processes (fork), %d item(s) per chunk", workers, chunk)
        yield from self._pool.imap(fn, rest, chunksize=chunk)   # in input order

    def _map_dask(self, fn, items, on_error):
        client = self._client
        self._futures = client.map(_one_at_a_time, [fn] * len(items), items, pure=False)
        return self._results(self._futures, items, on_error)

    @staticmethod
    def _results(futures, items, on_error):
        for future, item in zip(futures, items):
            try:
                yield future.result()
            except Exception as exc:  # noqa: BLE001 -- a lost worker (KilledWorker) or scheduler, or fn's own
                if _is_connection_error(exc):
                    raise ExecutorError(f"lost the Dask scheduler: {exc}") from exc
                if on_error is None:
                    raise
                log.warning("task failed on the cluster: %s: %s", type(exc).__name__, exc)
                yield on_error(item, exc)


def _is_connection_error(exc) -> bool:
    """The cluster failed, not the item: a closed connection, or a task cancelled under us (Dask cancels every
    pending task with reason 'scheduler-connection-lost' when the scheduler goes away; this module cancels
    none while it still waits for results)."""
    from concurrent.futures import CancelledError

    from distributed.comm.core import CommClosedError

    return isinstance(exc, (CommClosedError, OSError, TimeoutError, CancelledError))


def _connect(address: str):
    """A Dask client on ``address`` with at least one worker running this version of rollplan."""
    try:
        from distributed import Client
        from distributed.comm import get_address_host_port
    except ImportError:
        raise InputError(f"--scheduler needs Dask distributed, an optional extra: {DASK_EXTRA}") from None
    try:
        get_address_host_port(address)   # a malformed address, before a client is made
    except (ValueError, TypeError) as exc:
        raise InputError(f"scheduler = {address!r} is not a scheduler address ({exc}); give e.g. 'tcp://host:8786'"
                         ) from None
    try:
        client = Client(address, timeout=CONNECT_TIMEOUT, set_as_default=False)
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(f"scheduler = {address!r} cannot be reached: {str(exc).splitlines()[0] if str(exc) else exc}"
                         ) from None
    try:
        try:
            client.wait_for_workers(1, timeout=WORKERS_TIMEOUT)
        except TimeoutError:
            raise InputError(f"scheduler = {address!r} has no workers (waited {WORKERS_TIMEOUT:g} s); start some "
                             f"with: dask worker {address} --nthreads 1") from None
        try:
            versions = client.run(_worker_version)
        except Exception as exc:  # noqa: BLE001 -- e.g. rollplan not importable on a worker
            raise InputError(f"the workers of {address} cannot run rollplan ({type(exc).__name__}: {exc}); install "
                             f"rollplan {__version__} on every worker") from None
        wrong = {w: v for w, v in versions.items() if v != __version__}
        if wrong:
            w, v = next(iter(wrong.items()))
            raise InputError(f"worker {w} of {address} runs rollplan {v}, this is {__version__}: install the same "
                             "version on every worker")
    except BaseException:
        client.close()
        raise
    log.info("connected to %s: %d workers", address, len(versions))
    return client


def map_in_order(fn: Callable, items: Iterable, jobs: int = 1, scheduler: str | None = None,
                 warm: Callable | None = None, on_error: Callable | None = None, progress=None,
                 label: str = "tasks") -> list:
    """``[fn(item) for item in items]``, run by an :class:`Executor` (``jobs`` local processes or a Dask
    ``scheduler``); ``progress(label, done, total)`` after each result."""
    items = list(items)
    out = []
    with Executor(jobs, scheduler, warm) as ex:
        for result in ex.map(fn, items, on_error):
            out.append(result)
            if progress is not None:
                progress(label, len(out), len(items))
    return out


def chunk_size(seconds: float | None, items: int, workers: int) -> int:
    """Items per chunk sent to a local worker: as many items of ``seconds`` each as make
    :data:`CHUNK_SECONDS` of work, but at most an eighth of each worker's share (so the workers end
    together and progress stays smooth); 1 when the time of an item is not known (``None``)."""
    if seconds is None or not seconds >= 0:
        return 1
    per_worker = items // (8 * max(workers, 1))
    return max(1, min(int(CHUNK_SECONDS / max(seconds, 1e-6)), per_worker))


def cpu_count() -> int:
    """Cores this process may use (its CPU affinity where known)."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1
