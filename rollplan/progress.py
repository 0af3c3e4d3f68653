"""Progress of long work on stderr: tqdm bars on a terminal, periodic plain lines in a log.

Long computations report ``progress(label, done, total)``; :class:`Progress` shows
each label as a tqdm bar when its stream is a terminal, and otherwise (a log
file, a pipe, CI) as one plain line per ``interval`` seconds, plus the first
and the last, so a log holds readable lines instead of one run-on line of
carriage returns::

    batch: 40/200 targets (20%), 1 failed, 3.1 s elapsed, about 12 s left

Deep loops (e.g. the CVODES trace of a 1000-step plan) call :func:`report`,
which does nothing unless a caller (the command line) has installed a
:class:`Progress` with :func:`reporting`; no API has to pass a callback down.
"""

from __future__ import annotations

import sys
import time
from contextlib import contextmanager
from contextvars import ContextVar

from . import interrupts

__all__ = ["Progress", "DEFAULT_INTERVAL", "report", "reporting", "silence"]

#: Seconds between two plain progress lines when the stream is not a terminal.
DEFAULT_INTERVAL = 10.0


def _is_terminal(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False


def _seconds(s: float) -> str:
    if s < 60:
        return f"{s:.1f} s" if s < 10 else f"{s:.0f} s"
    m, s = divmod(int(round(s)), 60)
    return f"{m} min {s:02d} s" if m < 60 else f"{m // 60} h {m % 60:02d} min"


class _Lines:
    """One label shown as plain lines, at most one per ``interval`` seconds (and the first and last)."""

    def __init__(self, label: str, total: int, stream, interval: float, unit: str, delay: float) -> None:
        self.label, self.total, self.stream, self.interval, self.unit = label, total, stream, interval, unit
        self.start = time.monotonic()
        self.delay = delay
        self.last = None
        self.n = 0
        self.finished = False

    def update(self, done: int, total: int, postfix: dict) -> None:
        self.n, self.total = done, total
        now = time.monotonic()
        final = total > 0 and done >= total
        if self.last is None and now - self.start < self.delay:
            return  # short work: say nothing
        if self.finished or not (self.last is None or final or now - self.last >= self.interval):
            return
        self.last = now
        self.finished = final
        elapsed = now - self.start
        pct = f" ({100.0 * done / total:.0f}%)" if total > 0 else ""
        extra = "".join(f", {v}" if isinstance(v, str) else f", {v} {k}" for k, v in postfix.items())
        left = ""
        if 0 < done < total and elapsed > 0:
            left = f", about {_seconds(elapsed * (total - done) / done)} left"
        unit = f" {self.unit}" if self.unit else ""
        print(f"{self.label}: {done}/{total}{unit}{pct}{extra}, {_seconds(elapsed)} elapsed{left}",
              file=self.stream, flush=True)

    def close(self) -> None:
        pass


class _Bar:
    """One label shown as a tqdm bar."""

    def __init__(self, label: str, total: int, stream, unit: str, delay: float) -> None:
        from tqdm import tqdm

        self.bar = tqdm(total=total, desc=label, file=stream, unit=unit or "it", dynamic_ncols=True, delay=delay)
        self.n = 0

    def update(self, done: int, total: int, postfix: dict) -> None:
        self.bar.total = total
        if postfix:
            self.bar.set_postfix(postfix, refresh=False)
        self.bar.update(done - self.bar.n)
        self.n = done

    def close(self) -> None:
        self.bar.close()


class Progress:
    """``progress(label, done, total, **postfix)``: one bar (or plain-line report) per label.

    Parameters
    ----------
    stream : file, optional
        Where to write (default ``sys.stderr`` at the time of the first report).
    interval : float
        Seconds between plain lines when ``stream`` is not a terminal.
    enabled : bool
        False shows nothing (``--quiet``).
    terminal : bool, optional
        Force bars (True) or plain lines (False); default: whether ``stream`` is a terminal.
    unit : str
        What is counted (shown after the count).
    delay : float
        Show a label only once its work has lasted this long [s] (0: at once).

    Use as a context manager, or call :meth:`close` at the end; extra keyword
    arguments of a report are shown after the count (``failed=2`` as "2 failed",
    ``stage="writing"`` as "writing"). A
    report whose ``done`` is below the last one of its label starts that label anew.
    """

    def __init__(self, stream=None, interval: float = DEFAULT_INTERVAL, enabled: bool = True,
                 terminal: bool | None = None, unit: str = "", delay: float = 0.0) -> None:
        self.stream = stream
        self.interval = float(interval)
        self.enabled = bool(enabled)
        self.terminal = terminal
        self.unit = unit
        self.delay = float(delay)
        self._shown: dict = {}

    def __call__(self, label: str, done: int, total: int, **postfix) -> None:
        interrupts.check()   # a Ctrl-C swallowed on its way is raised here (rollplan.interrupts)
        if not self.enabled:
            return
        shown = self._shown.get(label)
        if shown is not None and done < shown.n:  # the same work again (e.g. a second trace)
            shown.close()
            shown = None
        if shown is None:
            stream = self.stream if self.stream is not None else sys.stderr
            terminal = _is_terminal(stream) if self.terminal is None else self.terminal
            shown = self._shown[label] = (_Bar(label, total, stream, self.unit, self.delay) if terminal else
                                          _Lines(label, total, stream, self.interval, self.unit, self.delay))
        shown.update(int(done), int(total), postfix)

    def close(self) -> None:
        for shown in self._shown.values():
            shown.close()
        self._shown.clear()

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


_CURRENT: ContextVar = ContextVar("rollplan_progress", default=None)


def report(label: str, done: int, total: int, **postfix) -> None:
    """Report progress to the :class:`Progress` installed by :func:`reporting` (nothing if none is)."""
    interrupts.check()
    progress = _CURRENT.get()
    if progress is not None:
        progress(label, done, total, **postfix)


@contextmanager
def reporting(progress):
    """Within the block, :func:`report` goes to ``progress`` (a callable ``(label, done, total, **postfix)``)."""
    token = _CURRENT.set(progress)
    try:
        yield progress
    finally:
        _CURRENT.reset(token)


def silence() -> None:
    """Stop :func:`report` in this context for good (a worker process forked from a reporting parent)."""
    _CURRENT.set(None)
