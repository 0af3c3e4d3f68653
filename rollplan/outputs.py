"""Writing outputs: atomically, one writer at a time, never over an input, with one line when it cannot.

* :func:`check_writable` -- before any computation: the output is a regular
  file or absent, not read-only, in an existing writable folder, its name fits
  the file system, and it is none of the command's input files.
* :func:`write_atomic` -- the data (bytes, or pieces of bytes written as they
  come: :func:`json_chunks` streams a long JSON document) goes to a temporary
  file next to the output, is synced, and replaces the output by one rename: a
  reader sees the old file or the new one, never a part. A replaced file keeps its permission bits; a
  symlink is written through (its target is replaced, the link stays).
* :func:`claim` -- a lock per output (``flock`` on a lock file next to it,
  removed on release): a second process that would write the same output is
  refused at once (:class:`~rollplan.errors.OutputError`, exit 2) instead of
  interleaving or silently replacing the first one's work. Re-entrant within
  a process; released by the kernel if the process dies.
* :class:`LineWriter` -- line-oriented output (batch): every line reaches the
  file at once (a killed process keeps every finished line); ``fsync`` in
  batches.
* :func:`make_folder` -- an output folder, created if missing.
* :func:`check_folder`, :func:`write_folder` -- a folder of files written as one output (``codegen``): the
  files are written into a temporary folder next to it and moved into place (a new folder appears whole by
  one rename); a folder that holds files rollplan did not write (or wrote and were changed since, by its
  list :data:`MANIFEST`) is refused unless ``overwrite``, which replaces the files of the same names only.

Every failure of the file system (disk full, file size limit, read-only file
system, a name too long, permissions) is an :class:`~rollplan.errors.OutputError`
with one line; a temporary file is never left behind by a failed write, and a
writer that was killed leaves only temporaries that the next writer of the
same output removes.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import math
import os
import re
import shutil
import stat
import tempfile
import threading
import time
from contextlib import contextmanager, suppress
from itertools import chain
from pathlib import Path

from .errors import InputError, OutputError
from .inputs import check_path, show_path

__all__ = ["WRITE_FAILURES", "write_all", "check_writable", "write_atomic", "json_chunks", "write_json",
           "check_figure_path",
           "save_figure", "claim", "LineWriter", "make_folder", "MANIFEST", "check_folder", "write_folder"]

_RANDOM = 8            # characters tempfile adds to a temporary name
_TMP_SUFFIX = ".tmp"
_LOCK_SUFFIX = ".lock"


#: Why a write failed, by errno, in words (the errors a user's disk or folder causes, not a bug of ours).
WRITE_FAILURES = {errno.ENOSPC: "the disk is full", errno.EDQUOT: "the disk quota is exhausted",
                  errno.EFBIG: "the file is larger than this process may write (file size limit)",
                  errno.EROFS: "the file system is read-only", errno.EACCES: "permission denied",
                  errno.EPERM: "permission denied", errno.ENAMETOOLONG: "the name is too long for the file system",
                  errno.ENOENT: "its folder does not exist", errno.ENOTDIR: "a part of the path is not a folder",
                  errno.EIO: "input/output error of the device", errno.EPIPE: "the reader closed the pipe"}


def write_all(fd: int, data: bytes) -> None:
    """Write all of ``data`` to the file descriptor ``fd`` (OSError if it cannot: a short write is followed by
    another, which reports the reason, e.g. EPIPE when a pipe's reader has gone)."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]


def _failure(what: str, path, exc: OSError) -> OutputError:
    """One line for an OSError met while writing ``path``."""
    reason = WRITE_FAILURES.get(exc.errno, exc.strerror or str(exc))
    return OutputError(f"{what} {show_path(path)} cannot be written: {reason}")


def _read_only(st: os.stat_result, path) -> bool:
    """No write permission: no write bit at all (refused even for root), or none for this user."""
    return (st.st_mode & 0o222) == 0 or not os.access(path, os.W_OK)


def _name_max(folder: Path) -> int:
    try:
        return int(os.pathconf(folder, "PC_NAME_MAX"))
    except (OSError, ValueError):
        return 255


def _sibling_stem(target: Path) -> str:
    """A hidden name stem for files next to ``target`` (temporaries, the lock) that fits the file system.

    ``.NAME.`` when it leaves room for a random part and a suffix, else a shortened
    name with a hash of the whole name (distinct for distinct outputs).
    """
    name = target.name
    room = _name_max(target.parent) - _RANDOM - len(_TMP_SUFFIX) - 3
    if len(name.encode()) <= room:
        return f".{name}."
    digest = hashlib.sha1(name.encode(errors="surrogateescape")).hexdigest()[:10]
    short = name.encode(errors="surrogateescape")[: max(0, room - 12)].decode(errors="ignore")
    return f".{short}~{digest}."


def _target(path) -> Path:
    """The file that writing ``path`` replaces: a symlink's target (followed), else the path itself."""
    return Path(os.path.realpath(path)) if os.path.islink(path) else Path(path)


def _check_parent(p: Path, folder: Path, what: str, text: str, failed: str) -> None:
    """OutputError (one line: ``what`` ``text`` ``failed``: why) unless ``folder``, the folder of the new
    output ``p``, exists, is a writable folder and allows ``p``'s name."""
    try:
        fst = os.stat(folder)
    except OSError:
        raise OutputError(f"{what} {show_path(text)} {failed}: folder {show_path(folder)} does not exist") from None
    if not stat.S_ISDIR(fst.st_mode):
        raise OutputError(f"{what} {show_path(text)} {failed}: {show_path(folder)} is not a folder")
    if _read_only(fst, folder):
        raise OutputError(f"{what} {show_path(text)} {failed}: no permission to write in folder {show_path(folder)}")
    size, limit = len(p.name.encode(errors="surrogateescape")), _name_max(folder)
    if size > limit:
        raise OutputError(f"{what} {show_path(text)} {failed}: its name has {size} bytes, the file system "
                          f"allows {limit}")


def check_writable(path, what: str = "output", inputs=()) -> Path:
    """The file that writing ``path`` replaces, or OutputError (one line) unless it can be written.

    An existing output must be a writable regular file; its folder must exist
    and be writable; its name must fit the file system; it must not be one of
    ``inputs`` (paths of the command's input files; None entries are skipped).
    """
    text = check_path(path, what)
    if text.endswith(os.sep):
        raise OutputError(f"{what} {show_path(text)} ends with {os.sep!r}: give a file name")
    p = _target(text)
    folder = p.parent
    try:
        st = os.stat(p)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        if exc.errno != errno.ENAMETOOLONG:
            raise _failure(what, text, exc) from None
        st = None   # said below, with the sizes
    if st is not None:
        if stat.S_ISDIR(st.st_mode):
            raise OutputError(f"{what} {show_path(text)} is a directory: give a file name")
        if not stat.S_ISREG(st.st_mode):
            raise OutputError(f"{what} {show_path(text)} is not allowed: it exists and is not a regular file")
        if _read_only(st, p):
            raise OutputError(f"{what} {show_path(text)} is read-only: make it writable or choose another name")
    _check_parent(p, folder, what, text, "is not writable")
    for source in inputs:
        if source is None:
            continue
        try:
            same = st is not None and os.path.samefile(p, source)
        except OSError:
            same = False
        if same:
            raise OutputError(f"{what} {show_path(text)} is the input file {show_path(source)}: choose another name "
                              "(inputs are never overwritten)")
    return p


# ----------------------------------------------------------------------------- locks

_held: dict = {}                 # real path of an output -> [fd, lock path, count]
_held_guard = threading.Lock()


def _lock_path(target: Path) -> Path:
    return target.parent / (_sibling_stem(target) + "lock")


def _stale_temporaries(target: Path) -> None:
    """Remove temporaries of ``target`` left by a killed writer (called with its lock held)."""
    stem = _sibling_stem(target)
    pattern = re.compile(re.escape(stem) + r"[a-z0-9_]{%d}" % _RANDOM + re.escape(_TMP_SUFFIX))
    try:
        names = os.listdir(target.parent)
    except OSError:
        return
    for name in names:
        if name.startswith(stem) and pattern.fullmatch(name):
            with suppress(OSError):
                os.unlink(target.parent / name)


def _acquire(path, what: str) -> str:
    target = _target(check_path(path, what))
    key = os.path.realpath(target)
    with _held_guard:
        if key in _held:
            _held[key][2] += 1
            return key
        lock = _lock_path(target)
        for _ in range(20):
            try:
                fd = os.open(lock, os.O_RDWR | os.O_CREAT | getattr(os, "O_CLOEXEC", 0), 0o644)
            except OSError as exc:
                raise _failure(what, path, exc) from None
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                    break  # the file system cannot lock (ENOLCK, EOPNOTSUPP): write unlocked, as before locks
                owner = ""
                with suppress(OSError):
                    owner = os.read(fd, 32).decode(errors="replace").strip()
                os.close(fd)
                pid = f" (pid {owner})" if owner.isdigit() else ""
                raise OutputError(f"{what} {show_path(path)} is being written by another process{pid}: wait "
                                  "for it to finish or choose another name") from None
            try:  # the lock file may have been removed by its last holder since we opened it: then retry
                same = os.path.samestat(os.fstat(fd), os.stat(lock))
            except OSError:
                same = False
            if same:
                break
            os.close(fd)
        else:
            raise OutputError(f"{what} {show_path(path)}: its lock file {show_path(lock)} keeps changing")
        with suppress(OSError):  # the pid is only for the message of a refused second writer
            os.ftruncate(fd, 0)
            os.write(fd, f"{os.getpid()}\n".encode())
        _held[key] = [fd, lock, 1]
    _stale_temporaries(target)
    return key


def _release(key: str) -> None:
    with _held_guard:
        entry = _held[key]
        entry[2] -= 1
        if entry[2]:
            return
        del _held[key]
    fd, lock, _ = entry
    with suppress(OSError):
        os.unlink(lock)   # while still locked: a waiting opener sees another inode and retries
    os.close(fd)


@contextmanager
def claim(*paths, what: str = "output"):
    """Hold the lock of each output in ``paths`` (None skipped) for the ``with`` block.

    Raises OutputError at once if another process holds one of them. Re-entrant:
    a path this process holds already is not locked again.
    """
    keys = []
    try:
        for p in paths:
            if p is not None:
                keys.append(_acquire(p, what))
        yield
    finally:
        for key in reversed(keys):
            _release(key)


# ----------------------------------------------------------------------------- writing


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


def _new_mode(target: Path) -> int:
    try:
        return stat.S_IMODE(os.stat(target).st_mode)
    except OSError:
        return 0o666 & ~_umask()


def _sync_folder(folder: Path) -> None:
    try:
        fd = os.open(folder, os.O_RDONLY | getattr(os, "O_DIRECTORY", 0))
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def write_atomic(path, data, what: str = "output") -> None:
    """Write ``data`` (bytes, or an iterable of bytes written piece by piece as it yields them) to ``path`` through
    a synced temporary file and one atomic rename (module docstring).

    Raises OutputError (one line) if the output cannot be written; the old file
    is then left as it was (also when ``data`` raises while it is written).
    """
    pieces = (data,) if isinstance(data, (bytes, bytearray, memoryview)) else data
    target = check_writable(path, what)
    with claim(path, what=what):
        fd, tmp = -1, None
        try:
            fd, tmp = tempfile.mkstemp(dir=target.parent, prefix=_sibling_stem(target), suffix=_TMP_SUFFIX)
            os.fchmod(fd, _new_mode(target))
            for piece in pieces:
                write_all(fd, piece)
            os.fsync(fd)
            os.close(fd)
            fd = -1
            os.replace(tmp, target)
            tmp = None
        except OSError as exc:
            raise _failure(what, path, exc) from None
        finally:
            if fd >= 0:
                os.close(fd)
            if tmp is not None and os.path.exists(tmp):
                os.unlink(tmp)
        _sync_folder(target.parent)


#: Bytes of JSON text gathered before :func:`json_chunks` yields them.
JSON_CHUNK = 1 << 16
#: Items of a list of numbers (or of rows of numbers) that :func:`json_chunks` encodes in one piece.
JSON_ROWS = 1024
_NUMBER_TYPES = {float, int}


def _numbers(obj, depth: int = 0) -> bool:
    """Whether ``obj`` is a non-empty list of plain finite floats and ints, or of such lists (rows of samples,
    three levels at most)."""
    types = set(map(type, obj))
    if types <= {int}:
        return True
    if types <= {float}:
        return all(map(math.isfinite, obj))
    if types <= _NUMBER_TYPES:      # ints beyond a float's range are JSON numbers too
        return all(math.isfinite(v) for v in obj if type(v) is float)
    return depth < 3 and types == {list} and all(v and _numbers(v, depth + 1) for v in obj)


def _number_depth(obj) -> int:
    """1 for a non-empty list of plain floats and ints, 2 for a non-empty list of non-empty lists of them (rows of
    samples), else 0: the shapes whose text :func:`_numbers_text` makes with json's C encoder."""
    types = set(map(type, obj))
    if types <= _NUMBER_TYPES:
        return 1 if types else 0
    if types == {list} and all(obj) and set(map(type, chain.from_iterable(obj))) <= _NUMBER_TYPES:
        return 2
    return 0


def _numbers_text(items, level: int, depth: int) -> str:
    """The items of ``items`` (:func:`_number_depth` ``depth``) as ``json.dumps(items, indent=1)`` writes them inside
    the list's brackets at nesting ``level``: json's compact C-encoded text (the same number texts; its error for a
    number that is not finite), indented by replacing its separators, which no number's text contains."""
    inner = "\n" + " " * (level + 1)
    if depth == 1:
        return json.dumps(items, allow_nan=False)[1:-1].replace(", ", "," + inner)
    inner2 = inner + " "
    text = json.dumps(items, allow_nan=False, separators=(",", ":"))[2:-2]
    rows = text.replace("],[", "\0").replace(",", "," + inner2).replace("\0", inner + "]," + inner + "[" + inner2)
    return "[" + inner2 + rows + inner + "]"


def _item_text(v, level: int) -> str:
    """``json.dumps(v, indent=1)`` at nesting ``level`` of a number or a list that :func:`_numbers` accepts."""
    if type(v) is not list:
        return repr(v)
    inner = "\n" + " " * (level + 1)
    items = map(repr, v) if type(v[0]) is not list else (_item_text(x, level + 1) for x in v)
    return "[" + inner + ("," + inner).join(items) + "\n" + " " * level + "]"


def _json_pieces(obj, level: int):
    """The pieces of ``json.dumps(obj, indent=1)`` at nesting ``level``: json's own text, but lists of plain finite
    numbers (or rows of them: the bulk of a motion's samples) joined a thousand items at a time, not item by item
    as json's pure-Python indenting encoder does."""
    if isinstance(obj, (list, tuple)):
        if not obj:
            yield "[]"
            return
        inner = "\n" + " " * (level + 1)
        depth = _number_depth(obj)
        if depth:
            for i in range(0, len(obj), JSON_ROWS):
                yield ("," if i else "[") + inner + _numbers_text(obj[i:i + JSON_ROWS], level, depth)
            yield "\n" + " " * level + "]"
            return
        if _numbers(obj):
            for i in range(0, len(obj), JSON_ROWS):
                yield ("," if i else "[") + inner + ("," + inner).join(
                    [_item_text(v, level + 1) for v in obj[i:i + JSON_ROWS]])
            yield "\n" + " " * level + "]"
            return
        yield "[" + inner
        for i, v in enumerate(obj):
            if i:
                yield "," + inner
            yield from _json_pieces(v, level + 1)
        yield "\n" + " " * level + "]"
    elif isinstance(obj, dict):
        if not obj:
            yield "{}"
            return
        inner = "\n" + " " * (level + 1)
        yield "{" + inner
        for i, (k, v) in enumerate(obj.items()):
            if not isinstance(k, str):      # json's own conversion of other keys (and its error)
                k = next(iter(json.loads(json.dumps({k: None}, allow_nan=False))))
            yield ("," + inner if i else "") + json.encoder.encode_basestring_ascii(k) + ": "
            yield from _json_pieces(v, level + 1)
        yield "\n" + " " * level + "}"
    else:
        text = json.dumps(obj, allow_nan=False)
        if text[:1] in "[{":    # not a JSON scalar: json's own (a subclass, default=...); indented by json
            text = json.dumps(obj, indent=1, allow_nan=False).replace("\n", "\n" + " " * level)
        yield text


def json_chunks(obj, size: int = JSON_CHUNK):
    """``obj`` as indented JSON (finite numbers only) and a final newline, in pieces of bytes of about ``size``
    yielded while it is encoded: together exactly ``json.dumps(obj, indent=1) + "\n"``, never the whole text at
    once (a list of thousands of plans streams into its file or a pipe)."""
    gathered, n = [], 0
    try:
        for text in _json_pieces(obj, 0):
            gathered.append(text)
            n += len(text)
            if n >= size:
                yield "".join(gathered).encode()
                gathered, n = [], 0
    except RecursionError:      # circular (or too deep): json's own error
        json.dumps(obj, indent=1, allow_nan=False)
        raise
    gathered.append("\n")
    yield "".join(gathered).encode()


def write_json(path, obj, what: str = "output") -> None:
    """Write ``obj`` as indented JSON (finite numbers only) with :func:`write_atomic`, streamed
    (:func:`json_chunks`)."""
    write_atomic(path, json_chunks(obj), what)


def check_figure_path(path, what: str = "figure") -> Path:
    """:func:`check_writable` plus a file format matplotlib can write, judged by the suffix."""
    from matplotlib.figure import Figure

    text = check_path(path, what)
    formats = Figure().canvas.get_supported_filetypes()
    suffix = Path(text).suffix.lstrip(".").lower()
    if suffix not in formats:
        ext = ("." + suffix) if suffix else "(none)"
        raise InputError(f"figure path {show_path(text)} is not allowed: its extension {ext!r} "
                         f"is not a figure format; use one of {', '.join('.' + f for f in sorted(formats))}")
    return check_writable(path, what)


def save_figure(fig, path, dpi=120) -> None:
    """Save a matplotlib figure atomically (format from the suffix).

    A figure with a layout engine (``layout="constrained"``) is laid out and then drawn once: matplotlib's
    saving draws such a figure a first time without output only to run its layout engine, and here that first
    draw runs the layout engine alone (the same layout, the same file, about a fifth less time).
    """
    import io

    import matplotlib

    buf = io.BytesIO()
    engine = fig.get_layout_engine()
    if engine is not None and matplotlib.rcParams["savefig.bbox"] != "tight":
        def layout_only(renderer):   # the draw before the output, as Figure.draw runs the engine
            del fig.draw
            if fig.axes:
                with suppress(ValueError):   # as Figure.draw: a layout that cannot be made is left as it is
                    engine.execute(fig)

        fig.draw = layout_only
    try:
        fig.savefig(buf, format=Path(path).suffix.lstrip(".").lower() or "png", dpi=dpi)
    finally:
        fig.__dict__.pop("draw", None)
    write_atomic(path, buf.getvalue(), "figure")


class LineWriter:
    """Append lines to an existing output file: each line reaches the file at once, fsync in batches.

    Each :meth:`write` is one ``write`` call on a file opened for appending, so
    a killed process keeps every finished line (at most the line being written
    is torn); a line that cannot be written whole (disk full) is cut off again,
    leaving the finished lines. ``fsync`` runs every ``sync_every`` lines or ``sync_seconds``
    seconds and at :meth:`close`, which bounds what a power loss can take.
    Hold the output's :func:`claim` while writing.
    """

    def __init__(self, path, what: str = "output", sync_every: int = 64, sync_seconds: float = 1.0) -> None:
        self.path, self.what = path, what
        self.sync_every, self.sync_seconds = sync_every, sync_seconds
        self._unsynced, self._synced_at = 0, time.monotonic()
        try:
            self._fd = os.open(path, os.O_WRONLY | os.O_APPEND | getattr(os, "O_CLOEXEC", 0))
            self._size = os.fstat(self._fd).st_size
        except OSError as exc:
            raise _failure(what, path, exc) from None

    def write(self, line: str) -> None:
        data = line.encode()
        try:
            write_all(self._fd, data)
        except OSError as exc:
            with suppress(OSError):
                os.ftruncate(self._fd, self._size)   # no torn line (shrinking needs no space)
            raise _failure(self.what, self.path, exc) from None
        self._size += len(data)
        self._unsynced += 1
        try:
            if self._unsynced >= self.sync_every or time.monotonic() - self._synced_at >= self.sync_seconds:
                self.sync()
        except OSError as exc:
            raise _failure(self.what, self.path, exc) from None

    def sync(self) -> None:
        if self._unsynced:
            os.fsync(self._fd)
        self._unsynced, self._synced_at = 0, time.monotonic()

    def close(self) -> None:
        if self._fd < 0:
            return
        try:
            self.sync()
        except OSError as exc:
            raise _failure(self.what, self.path, exc) from None
        finally:
            os.close(self._fd)
            self._fd = -1

    def __enter__(self) -> LineWriter:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def make_folder(path, what: str = "output folder", parents: bool = False) -> Path:
    """The output folder ``path``, created if missing (with ``parents``, its missing parents too; otherwise
    its parent must exist); OutputError unless it is a writable folder."""
    text = check_path(path, what)
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise OutputError(f"{what} {show_path(text)} is a file: give a folder")
    if not p.exists():
        parent = next((q for q in p.absolute().parents if q.exists()), None)
        if parent is not None and parent.is_dir() and _read_only(os.stat(parent), parent):
            raise OutputError(f"{what} {show_path(text)} cannot be created: no permission to write in folder "
                              f"{show_path(parent)}")
        try:
            p.mkdir(parents=parents)
        except FileNotFoundError:
            raise OutputError(f"{what} {show_path(text)} cannot be created: folder {show_path(p.parent)} "
                              "does not exist") from None
        except OSError as exc:
            raise _failure(what, text, exc) from None
    try:
        st = os.stat(p)
    except OSError as exc:
        raise _failure(what, text, exc) from None
    if _read_only(st, p):
        raise OutputError(f"{what} {show_path(text)} cannot be written: no permission to write in it")
    return p


# ----------------------------------------------------------------------------- folders

#: The list of the files that :func:`write_folder` wrote into a folder (name -> SHA-256), and of the names the
#: folder's own build makes (``products``), kept in the folder.
MANIFEST = ".rollplan-files.json"
_STAGING = ".rollplan-new."


def _digest(path: Path) -> str | None:
    try:
        return hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError:
        return None


def _manifest(folder: Path) -> dict:
    """The folder's :data:`MANIFEST` as ``{"files": {name: sha256}, "products": [names]}`` (empty if none)."""
    try:
        data = json.loads((folder / MANIFEST).read_text())
        files = {str(k): str(v) for k, v in dict(data.get("files", {})).items()}
        products = [str(n) for n in data.get("products", [])]
    except (OSError, ValueError, TypeError, AttributeError):
        return {"files": {}, "products": []}
    return {"files": files, "products": products}


def _not_ours(folder: Path) -> list:
    """Names in ``folder`` that :func:`write_folder` did not write: not in its manifest with the content it wrote
    (``NAME (changed)`` for those changed since), nor a product of its build, nor a temporary folder of ours."""
    listed = _manifest(folder)
    foreign = []
    for name in sorted(os.listdir(folder)):
        if name == MANIFEST or name in listed["products"] or name.startswith(_STAGING):
            continue
        if name not in listed["files"]:
            foreign.append(name)
        elif _digest(folder / name) != listed["files"][name]:
            foreign.append(f"{name} (changed)")
    return foreign


def check_folder(path, what: str = "output folder", overwrite: bool = False) -> Path:
    """The output folder ``path`` if :func:`write_folder` may write it, else OutputError (one line): an existing
    writable folder that holds only files rollplan wrote there (any with ``overwrite``), or a name in an
    existing writable folder. Nothing is created."""
    text = check_path(path, what)
    p = Path(text)
    try:
        exists = p.exists()
    except OSError as exc:   # a name too long for the file system: said by _check_parent, with the sizes
        if exc.errno != errno.ENAMETOOLONG:
            raise _failure(what, text, exc) from None
        exists = False
    if exists:
        if not p.is_dir():
            raise OutputError(f"{what} {show_path(text)} is a file: give a folder")
        try:
            st = os.stat(p)
            foreign = [] if overwrite else _not_ours(p)
        except OSError as exc:
            raise _failure(what, text, exc) from None
        if _read_only(st, p):
            raise OutputError(f"{what} {show_path(text)} cannot be written: no permission to write in it")
        if foreign:
            shown = ", ".join(foreign[:4]) + (f" and {len(foreign) - 4} more" if len(foreign) > 4 else "")
            raise OutputError(f"{what} {show_path(text)} holds files that rollplan did not write ({shown}): "
                              "choose a new or empty folder, or give overwrite=True to replace the files of the "
                              "same names in it")
        return p
    _check_parent(p, p.parent, what, text, "cannot be created")
    return p


def write_folder(path, files: dict, what: str = "output folder", overwrite: bool = False, products=()) -> Path:
    """Write ``files`` (name -> bytes) into the folder ``path`` as one output (:func:`check_folder` first).

    The files, each synced, and the folder's :data:`MANIFEST` go into a temporary folder next to the output
    (inside it if it exists); a new folder is then renamed into place (it appears whole), in an existing one
    each file replaces its namesake by one rename (the other files stay). ``products`` are the names the
    folder's own build makes (they do not make the folder someone else's). Raises OutputError (one line) if
    the folder cannot be written (disk full...); the temporary folder is then removed and the output left as
    it was.
    """
    p = check_folder(path, what, overwrite)
    existing = p.exists()
    where = p if existing else p.absolute().parent
    staging = None
    try:
        staging = Path(tempfile.mkdtemp(dir=where, prefix=_STAGING if existing else _sibling_stem(p),
                                        suffix=_TMP_SUFFIX))
        listed = _manifest(p) if existing else {"files": {}, "products": []}
        kept = {n: h for n, h in listed["files"].items() if n not in files and _digest(p / n) == h}
        digests = {}
        for name, data in [*files.items(), (MANIFEST, None)]:
            if name == MANIFEST:
                data = (json.dumps({"files": {**kept, **digests}, "products": sorted({*listed["products"],
                                                                                     *products})},
                                   indent=1, sort_keys=True) + "\n").encode()
            fd = os.open(staging / name, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0),
                         _new_mode(p / name))
            try:
                write_all(fd, data)
                os.fsync(fd)
            finally:
                os.close(fd)
            if name != MANIFEST:
                digests[name] = hashlib.sha256(data).hexdigest()
        _sync_folder(staging)
        if not existing:
            os.chmod(staging, 0o777 & ~_umask())
            os.rename(staging, p)
            staging = None
            _sync_folder(where)
        else:
            for name in [*files, MANIFEST]:
                os.replace(staging / name, p / name)
            os.rmdir(staging)
            staging = None
            _sync_folder(p)
    except OSError as exc:
        raise _failure(what, path, exc) from None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
    return p
