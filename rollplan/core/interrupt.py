"""Ctrl-C through CasADi's IPOPT: noted while a solve runs, raised when it returns.

CasADi's IPOPT interface checks for signals during a solve, catches the
KeyboardInterrupt this raises, ends that solve (status
``NonIpopt_Exception_Thrown``) and drops the interrupt, so a loop of solves
would run on. Inside :func:`interruptible`, SIGINT is also noted in a flag,
and :func:`raise_if_interrupted` (called after each solve) raises it again.
"""

from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

__all__ = ["interruptible", "raise_if_interrupted"]

_pending = [False]


def _handler(signum, frame):
    _pending[0] = True
    raise KeyboardInterrupt


@contextmanager
def interruptible():
    """Note SIGINT for :func:`raise_if_interrupted` while the block runs (main thread, default handler only;
    nested blocks share the outermost one's handler)."""
    if threading.current_thread() is not threading.main_thread() or \
            signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        yield
        return
    _pending[0] = False
    signal.signal(signal.SIGINT, _handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, signal.default_int_handler)
        _pending[0] = False


def raise_if_interrupted() -> None:
    """Raise KeyboardInterrupt if SIGINT arrived inside :func:`interruptible` (and was dropped on the way)."""
    if _pending[0]:
        _pending[0] = False
        raise KeyboardInterrupt
