"""Ctrl-C that reaches the solvers: a SIGINT during IPOPT, CVODES or a CasADi root finder stops the program.

What CasADi does with SIGINT (CasADi 3.6-3.8, checked in ``tests/test_interrupts.py``):
while a solver runs, CasADi polls Python for pending signals (once per IPOPT
iteration, once per right-hand-side evaluation of CVODES). When Python's
handler raises KeyboardInterrupt, CasADi aborts the solver, but it does not
pass the KeyboardInterrupt on: IPOPT returns with status
``NonIpopt_Exception_Thrown`` and a warning on stderr, CVODES raises a
RuntimeError (``CV_RHSFUNC_FAIL``). A caller would take either for a failed
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
"""

from __future__ import annotations

import signal
import threading

__all__ = ["call"]

class _State:
    pending = False   # SIGINT arrived during the outermost call
    depth = 0         # nesting of calls


def _record(signum, frame):
    _State.pending = True
    raise KeyboardInterrupt


def call(function, *args, **kwargs):
    """``function(*args, **kwargs)``, raising KeyboardInterrupt if SIGINT arrived during it (module docstring)."""
    install = (_State.depth == 0 and threading.current_thread() is threading.main_thread()
               and signal.getsignal(signal.SIGINT) is signal.default_int_handler)
    previous = None
    if _State.depth == 0:
        _State.pending = False
    if install:
        previous = signal.signal(signal.SIGINT, _record)
    _State.depth += 1
    try:
        result = function(*args, **kwargs)
    except Exception:
        if _State.pending:
            raise KeyboardInterrupt from None
        raise
    finally:
        _State.depth -= 1
        if install:
            signal.signal(signal.SIGINT, previous)
    if _State.pending:
        raise KeyboardInterrupt
    return result
