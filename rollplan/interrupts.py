"""Ctrl-C that reaches the solvers: a SIGINT during IPOPT, CVODES or a CasADi root finder stops the program.

What CasADi does with SIGINT (CasADi 3.6-3.8, checked in ``tests/test_interrupts.py``):
while a solver runs, CasADi polls Python for pending signals (once per IPOPT
iteration, once per right-hand-side evaluation of CVODES). When Python's
handler raises KeyboardInterrupt, CasADi aborts the solver, but it does not
pass the KeyboardInterrupt on: IPOPT returns with status
``NonIpopt_Exception_Thrown`` and a warning on stderr (which :func:`call` drops), CVODES
raises a RuntimeError (``CV_RHSFUNC_FAIL``, or ``CV_LSETUP_FAIL`` when the signal
arrives in the Jacobian's setup). A caller would take either for a failed
solve: the geometric planner would try the next branch (and return a longer
plan, or go on for minutes), a batch would record the row in flight as
failed. Evaluations of plain CasADi Functions (``map``) do not poll; Python
raises KeyboardInterrupt as soon as they return.

:func:`call` runs one solver call with a SIGINT handler that records the
signal before raising KeyboardInterrupt, and raises KeyboardInterrupt after the
call if a signal arrived during it, whatever the solver returned. It changes
the handler only in the main thread and only while Python's default handler is
installed (a program with its own SIGINT handler, or a worker process that
ignores SIGINT, is left alone).

Long calls into C++ that never return to Python (CasADi's construction of a large solver, minutes) run in a
helper thread by :func:`call_in_thread`, so that the main thread can act on Ctrl-C at once; an interrupted
command that left such a thread running ends by ``os._exit`` (:func:`rollplan.cli.main`).

SIGTERM: while :func:`terminate_as_interrupt` holds (the command, :func:`rollplan.cli.main`), SIGTERM raises
:class:`Terminated`, a KeyboardInterrupt: the command stops as for Ctrl-C (workers stopped, finished work kept,
outputs left whole) and exits 143; :func:`call` records it like SIGINT.

Start-up: :func:`guard_start_up` (called first thing by ``rollplan/__init__.py``)
makes a Ctrl-C while the modules load exit 130 at once with one line when the program
is the ``rollplan`` command or ``python -m rollplan.cli``; :func:`end_start_up`
(first thing in :func:`rollplan.cli.main`, inside its Ctrl-C handling) hands
SIGINT to the command: it raises KeyboardInterrupt as Python's default handler does.

Swallowed: a KeyboardInterrupt raised while CasADi's Python bindings choose among a function's overloads (the
symbolic construction of a model function: ``ca.cos`` of an SX calls back into Python) is taken for "not this
overload" and dropped, and one raised in a finalizer or an at-fork callback is printed as "Exception ignored"
and dropped: the Ctrl-C would be lost. So the command's handler also records the signal, a KeyboardInterrupt
that Python cannot raise is recorded instead of printed (``sys.unraisablehook``), and :func:`check` raises a
recorded signal once: at the next solver call (:func:`call`) or progress report. A KeyboardInterrupt raised
inside a C extension's conversion (CasADi's result to an array) reaches Python as a SystemError: the command takes
an unexpected error raised while a signal is pending (:func:`pending`) for the interrupt. A signal that was raised
normally may be raised a second time there (while the command stops): the command exits 130 either way.

Exit status 130 after a handled Ctrl-C: CPython (3.11, ``Python/pythonrun.c``) marks a KeyboardInterrupt
that leaves code run by ``exec`` of a string (``dataclasses`` builds every ``__init__`` that way while
modules load) as *unhandled*, keeps the mark although the command catches the interrupt later, and at the
exit of ``python -m rollplan.cli`` kills the process with SIGINT instead of returning the command's status.
:func:`forget_unhandled` clears the mark (every string ``exec`` resets it first); :func:`rollplan.cli.main`
calls it when it returns 130.

After the command's status is decided: Python's shutdown gives SIGINT back to the system's default action
(``_PySignal_Fini``), so a Ctrl-C that arrives while the finished command exits kills it (exit -2) instead of
letting it return its status. :func:`settle`, called by :func:`rollplan.cli.main` on its way out when the
program is the command, ignores SIGINT from then on (an ignored signal is left ignored by the shutdown).
"""

from __future__ import annotations

import contextvars
import os
import signal
import sys
import threading
from contextlib import contextmanager, suppress

__all__ = ["call", "call_in_thread", "call_in_threads", "abandoned", "Terminated",
           "terminate_as_interrupt", "guard_start_up", "cli_follows", "end_start_up", "check", "pending",
           "forget_unhandled", "settle"]


class Terminated(KeyboardInterrupt):
    """SIGTERM, while :func:`terminate_as_interrupt` holds: the program stops as for Ctrl-C (exit 143)."""


class _State:
    pending = None    # the exception of a signal that arrived during the outermost call
    depth = 0         # nesting of calls
    abandoned = False  # a call_in_thread was interrupted: its thread still runs
    held = False      # the command holds SIGINT (end_start_up): pending stays until delivered by check()


def _record(signum, frame):
    _State.pending = KeyboardInterrupt
    raise KeyboardInterrupt


def _terminate(signum, frame):
    _State.pending = Terminated
    raise Terminated


#: What CasADi writes (through ``sys.stderr``) when it swallows the KeyboardInterrupt raised in IPOPT's callback.
_SWALLOWED = 'WARNING("KeyboardInterruptException")'


class _QuietInterrupts:
    """``sys.stderr`` during a solver call: text passes on at once, except that a line of CasADi's is held to its
    end and dropped if it is the warning about the interrupt it swallowed (the command says it was interrupted,
    in one line)."""

    def __init__(self, stream) -> None:
        self.stream, self._held = stream, ""

    def write(self, text: str) -> int:
        self._held += text
        out = []
        while self._held:
            end = self._held.find("\n") + 1
            if self._held.startswith("CasADi") or "CasADi".startswith(self._held):
                if not end:
                    break
                line, self._held = self._held[:end], self._held[end:]
                if _SWALLOWED not in line:
                    out.append(line)
            else:
                end = end or len(self._held)
                out.append(self._held[:end])
                self._held = self._held[end:]
        if out:
            self.stream.write("".join(out))
        return len(text)

    def release(self) -> None:
        """Pass on what is held (unless it is the warning)."""
        held, self._held = self._held, ""
        if held and _SWALLOWED not in held:
            self.stream.write(held)

    def flush(self) -> None:
        self.stream.flush()

    def __getattr__(self, name):
        return getattr(self.stream, name)


def call(function, *args, **kwargs):
    """``function(*args, **kwargs)``, raising KeyboardInterrupt if SIGINT arrived during it (module docstring)."""
    handler = signal.getsignal(signal.SIGINT)
    install = (_State.depth == 0 and threading.current_thread() is threading.main_thread()
               and (handler is signal.default_int_handler or (_State.held and handler is _record)))
    previous = quiet = None
    if _State.depth == 0:
        check()
        _State.pending = None
    if install:
        previous = signal.signal(signal.SIGINT, _record)
        quiet = sys.stderr = _QuietInterrupts(sys.stderr)
    _State.depth += 1
    try:
        result = function(*args, **kwargs)
    except Exception:
        if _State.pending:
            pending, _State.pending = _State.pending, None
            raise pending from None
        raise
    finally:
        _State.depth -= 1
        if install:
            signal.signal(signal.SIGINT, previous)
            quiet.release()
            if sys.stderr is quiet:
                sys.stderr = quiet.stream
    if _State.pending:
        pending, _State.pending = _State.pending, None
        raise pending
    return result


#: The name of the helper thread of :func:`call_in_thread`.
_HELPER = "rollplan-build"


def call_in_thread(function, *args, **kwargs):
    """``function(*args, **kwargs)`` run by a helper thread while this (the main) thread waits for it: for long
    calls into C++ that release the GIL but never return to Python, during which Python cannot run its signal
    handlers (CasADi's construction of a solver: minutes for a large NLP). Ctrl-C (and SIGTERM) then act at
    once: the KeyboardInterrupt is raised here, the helper thread is left running (a daemon) and
    :func:`abandoned` is True. In another thread the call is made directly."""
    if threading.current_thread() is not threading.main_thread():
        return function(*args, **kwargs)
    box = {}

    def run():
        try:
            box["result"] = function(*args, **kwargs)
        except BaseException as exc:  # noqa: BLE001 -- passed to the waiting thread
            box["error"] = exc

    helper = threading.Thread(target=run, name=_HELPER, daemon=True)
    helper.start()
    try:
        while helper.is_alive():
            helper.join(0.2)
    except KeyboardInterrupt:
        _State.abandoned = True
        raise
    if "error" in box:
        raise box["error"]
    return box["result"]


def call_in_threads(functions) -> list:
    """Each of ``functions`` (callables without arguments) run by its own helper thread, all at once, while this
    (the main) thread waits for them: their results, in order. Ctrl-C (and SIGTERM) act at once as in
    :func:`call_in_thread` (the helpers are left running, :func:`abandoned` is True); the first error of a
    helper is raised when all have ended. Each runs in a copy of the caller's context (its progress reporting,
    :mod:`rollplan.progress`). In another thread they run one after the other."""
    functions = list(functions)
    if threading.current_thread() is not threading.main_thread():
        return [function() for function in functions]
    boxes = [{} for _ in functions]

    def run(function, box):
        try:
            box["result"] = function()
        except BaseException as exc:  # noqa: BLE001 -- passed to the waiting thread
            box["error"] = exc

    helpers = [threading.Thread(target=contextvars.copy_context().run, args=(run, f, b), name=_HELPER, daemon=True)
               for f, b in zip(functions, boxes)]
    for helper in helpers:
        helper.start()
    try:
        for helper in helpers:
            while helper.is_alive():
                helper.join(0.2)
    except KeyboardInterrupt:
        _State.abandoned = True
        raise
    for box in boxes:
        if "error" in box:
            raise box["error"]
    return [box["result"] for box in boxes]


def abandoned() -> bool:
    """True if an interrupted :func:`call_in_thread` left its helper thread running (also when the interrupt was
    raised elsewhere, e.g. recorded by :func:`call` around it): the program should end by ``os._exit`` (the
    C++ work in that thread must not meet the interpreter's shutdown, nor hold it up)."""
    return _State.abandoned or any(t.name == _HELPER and t.is_alive() for t in threading.enumerate())


@contextmanager
def terminate_as_interrupt():
    """For the ``with`` block, SIGTERM raises :class:`Terminated` (a KeyboardInterrupt: the program stops as for
    Ctrl-C, also inside the solvers, see :func:`call`); only in the main thread and when SIGTERM has its
    default action (a program with its own handler is left alone). The action is restored after the block."""
    install = (threading.current_thread() is threading.main_thread()
               and signal.getsignal(signal.SIGTERM) is signal.SIG_DFL)
    if install:
        signal.signal(signal.SIGTERM, _terminate)
    try:
        yield
    finally:
        if install:
            signal.signal(signal.SIGTERM, signal.SIG_DFL)


def _interrupted_at_start(signum, frame):
    """One line, written at once (no other output splits it), and exit 130. Inside the interpreter's import
    machinery, where the command's modules load, the process exits at once: an exception raised there can come out
    as another one (numpy's C extension turns it into an ImportError and a traceback), and nothing of the command
    has run. Elsewhere (a program of the command's name that never hands SIGINT on) SystemExit, so that its own
    clean-up runs."""
    for stream in (sys.stdout, sys.stderr):
        with suppress(AttributeError, OSError, ValueError):
            stream.flush()
    os.write(2, b"rollplan: interrupted\n")
    if _importing(frame):
        os._exit(130)
    raise SystemExit(130)


def _importing(frame) -> bool:
    """True if a frame of the interpreter's import machinery is on ``frame``'s stack."""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib._bootstrap"):
            return True
        frame = frame.f_back
    return False


def cli_follows() -> bool:
    """True if this program is the ``rollplan`` command or ``python -m rollplan.cli`` (rollplan.cli.main runs
    next)."""
    argv = getattr(sys, "orig_argv", sys.argv)
    script = os.path.basename(sys.argv[0]) if sys.argv else ""
    return script == "rollplan" or any(argv[i:i + 2] == ["-m", "rollplan.cli"] for i in range(len(argv)))


def _run_as_rollplan_module() -> bool:
    """True while ``python -m rollplan.<module>`` finds its module (``sys.argv[0]`` is ``"-m"`` then); not for
    ``python -m`` of another package that imports rollplan."""
    argv = getattr(sys, "orig_argv", [])
    named = next((argv[i + 1] for i in range(len(argv) - 1) if argv[i] == "-m"), "")
    return bool(sys.argv) and sys.argv[0] == "-m" and named.split(".")[0] == "rollplan"


def guard_start_up() -> bool:
    """Install the start-up handler (module docstring) if this program is the command or ``python -m`` of a
    rollplan module, in the main thread, with Python's default handler; True if installed."""
    started = cli_follows() or _run_as_rollplan_module()
    if not (started and threading.current_thread() is threading.main_thread()
            and signal.getsignal(signal.SIGINT) is signal.default_int_handler):
        return False
    signal.signal(signal.SIGINT, _interrupted_at_start)
    return True


def end_start_up() -> None:
    """If the start-up handler holds SIGINT (this program is the command), hand it to the command: a Ctrl-C raises
    KeyboardInterrupt and is also recorded until :func:`check` delivers it (module docstring, "Swallowed")."""
    if threading.current_thread() is threading.main_thread() and \
            signal.getsignal(signal.SIGINT) is _interrupted_at_start:
        _State.held, _State.pending = True, None
        sys.unraisablehook = _unraisable
        signal.signal(signal.SIGINT, _record)


def check() -> None:
    """Raise a Ctrl-C (or SIGTERM) that the command recorded and that was swallowed on its way (module docstring,
    "Swallowed"), once; nothing outside the command or when none is pending. Called by :func:`call` and by every
    progress report (:func:`rollplan.progress.report`)."""
    signal_type = pending()
    if signal_type is not None and threading.current_thread() is threading.main_thread():
        _State.pending = None
        raise signal_type


def pending():
    """The Ctrl-C (KeyboardInterrupt) or SIGTERM (:class:`Terminated`) that the command recorded and that was not
    delivered by :func:`check`, or None (always None outside the command). An error raised while one is pending
    is taken for the interrupt (:func:`rollplan.cli.main`): Python turns a KeyboardInterrupt raised inside a C
    extension's conversion (CasADi's result to an array) into a SystemError."""
    return _State.pending if _State.held else None


def _unraisable(unraisable) -> None:
    """``sys.unraisablehook`` of the command: a KeyboardInterrupt that Python could not raise (in a finalizer or an
    at-fork callback) is recorded for :func:`check`, not printed as a traceback; anything else as Python does."""
    if isinstance(unraisable.exc_value, KeyboardInterrupt):
        _State.pending = type(unraisable.exc_value)
        return
    sys.__unraisablehook__(unraisable)



def forget_unhandled() -> None:
    """Clear CPython's record of a KeyboardInterrupt that left an ``exec`` of a string (module docstring), so
    that a command which handled the interrupt exits with its own status."""
    exec("")


def settle() -> None:
    """The command's exit status is decided: ignore SIGINT from now on (module docstring), when this program is
    the ``rollplan`` command (nothing changes in a program that calls :func:`rollplan.cli.main`)."""
    if cli_follows() and threading.current_thread() is threading.main_thread():
        signal.signal(signal.SIGINT, signal.SIG_IGN)
