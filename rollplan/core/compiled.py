"""CasADi functions compiled to C, cached on disk, with the virtual machine as fallback.

:func:`compiled` takes a :class:`casadi.Function`, generates C with CasADi's ``CodeGenerator``
(with the function's Jacobian, named ``jac_<name>``, in the same library when asked, so that
:func:`casadi.external` gives solvers compiled derivatives), compiles it with the system C compiler
into a shared library in the user's cache directory and loads it with :func:`casadi.external`. The
next call, in this or any later process, only loads the library. :func:`compiled_lazy` does the
same but builds the function only when the library is not cached yet (building a large graph
costs more at start-up than loading its library).

Cache directory
    ``$ROLLPLAN_CACHE_DIR`` if set, else ``$XDG_CACHE_HOME/rollplan`` (``~/.cache/rollplan`` when
    ``XDG_CACHE_HOME`` is unset): the directory of the planner's leaf tables too.
Key
    SHA-256 of rollplan's version, CasADi's version, the compiler command, the flags, the platform,
    and either the function's serialized form (its whole expression graph and options:
    :func:`compiled`) or a name, a descriptor of its construction parameters and the bytes of the
    source files that define it (:func:`compiled_lazy`). A change of any of them gives another
    file name, so a stale library is never loaded; a library that does not load, or whose
    signature differs from the function's, is rebuilt.
Ownership
    The cache directory is created private (mode 0700). Compiled code is loaded only from a directory and
    a file that the current user owns and that group and others cannot write: in a shared folder (e.g.
    ``ROLLPLAN_CACHE_DIR`` on a world-writable ``/tmp``) another user could plant a library under the
    predictable name, with its digest beside it. Otherwise :class:`~rollplan.errors.UnsafeCacheError` is
    raised (nothing is loaded, built or written there).
Integrity
    Beside every library a ``.sha256`` file holds the digest of its bytes, written before the library
    is moved into place; a library is loaded only if its bytes match it. A damaged file (truncated or
    overwritten by another process or a full disk) is rebuilt instead of loaded: loading a truncated
    shared object can kill the process with SIGBUS, which no exception handler sees.
Concurrency
    Every build writes into its own temporary directory inside the cache directory and moves the
    finished library into place with ``os.replace`` (atomic on one file system): a reader sees no
    file or a complete one, never a half-written one; concurrent builders of the same function
    each write a complete library and the last rename wins. No lock is needed.
Interrupts
    The compiler runs in its own process group; on Ctrl-C (KeyboardInterrupt) or on timeout the
    whole group (driver, cc1, as, ld) is killed at once, the temporary directory removed, and the
    KeyboardInterrupt propagates (after a timeout the virtual machine is used).
Plain C libraries
    :func:`shared_library` builds a shared library from C sources that a function gives (e.g. the C planner
    of :mod:`rollplan.planners.geometric.c_sources`), with the same directory, atomic rename, interrupts and
    fallback (None instead of a function), and loads it with a given loader (e.g. ``ctypes.CDLL``). Its key is
    the content of the C sources, the compiler and its flags only; the sources' key is remembered under the
    hash of the code that writes them (a ``.key`` file), so that they are generated only when that changes.
Fallback
    Without a C compiler, with ``ROLLPLAN_NO_COMPILE=1``, or when a build or a load fails, the
    function itself (CasADi's SX/MX virtual machine) is returned and one warning per reason logged.
"""

from __future__ import annotations

import hashlib
import logging
import os
import platform
import shutil
import signal
import stat
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import casadi as ca

from ..errors import UnsafeCacheError
from ..progress import report
from ..version import __version__

__all__ = ["DEFAULT_FLAGS", "BUILD_TIMEOUT", "cache_dir", "private_cache_dir", "check_private", "compiler_command",
           "compiled", "compiled_lazy",
           "shared_library", "no_compiler_reason", "clear_cache", "last_build"]

log = logging.getLogger(__name__)

#: Compiler flags (part of the key). -O2 without -ffast-math: IEEE arithmetic, as in the virtual machine.
DEFAULT_FLAGS = ("-O2", "-fPIC", "-shared", "-fno-math-errno")
#: Seconds one build may take before the virtual machine is used instead.
BUILD_TIMEOUT = 300.0

_warned: set = set()
_last: dict = {}


def cache_dir() -> Path:
    """The cache directory (module docstring); created on first write, not here."""
    if os.environ.get("ROLLPLAN_CACHE_DIR"):
        return Path(os.environ["ROLLPLAN_CACHE_DIR"])
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rollplan"


def private_cache_dir() -> Path:
    """The cache directory, created with mode 0700 if missing (OSError when it cannot be), checked with
    :func:`check_private`."""
    root = cache_dir()
    root.mkdir(mode=0o700, parents=True, exist_ok=True)
    check_private(root)
    _check_ancestors(root)
    return root


def _check_ancestors(root: Path) -> None:
    """Raise :class:`~rollplan.errors.UnsafeCacheError` if another user could replace the cache directory: a
    folder above it (on its path as given, where a link may be swapped, or on its resolved path) that another
    user owns (root aside) or that group or others may write without the sticky bit (which, as on /tmp, keeps
    them from renaming or removing what they do not own)."""
    if os.name == "nt":
        return
    given = Path(os.path.abspath(root))
    for folder in {*given.parents, *Path(os.path.realpath(root)).parents}:
        st = os.stat(folder)
        if st.st_uid not in (os.geteuid(), 0):
            why = f"is owned by uid {st.st_uid}"
        elif st.st_mode & 0o022 and not st.st_mode & stat.S_ISVTX:
            why = f"is writable by group or others without the sticky bit (mode {st.st_mode & 0o7777:04o})"
        else:
            continue
        raise UnsafeCacheError(f"the cache directory {root}: the folder {folder} above it {why}, so another user "
                               "could replace it: refusing to use it; set ROLLPLAN_CACHE_DIR to a folder of your "
                               "own in a private place")


def check_private(path) -> None:
    """Raise :class:`~rollplan.errors.UnsafeCacheError` unless ``path`` (the cache directory or a file in it)
    is owned by the current user and not writable by group or others (module docstring: Ownership)."""
    if os.name == "nt":
        return
    st = os.stat(path)
    what = "the cache directory" if Path(path).is_dir() else "the cached file"
    if st.st_uid != os.geteuid():
        why, fix = f"is owned by uid {st.st_uid}, not by this user (uid {os.geteuid()})", ""
    elif st.st_mode & 0o022:
        why, fix = f"is writable by group or others (mode {st.st_mode & 0o7777:04o})", f"chmod go-w {path}, or "
    else:
        return
    raise UnsafeCacheError(f"{what} {path} {why}: refusing to use it; {fix}set "
                           "ROLLPLAN_CACHE_DIR to a folder of your own (it is created with mode 0700)")


def compiler_command() -> str | None:
    """The C compiler: ``$CC`` if set and found, else cc, gcc or clang; None when none is found or
    ``ROLLPLAN_NO_COMPILE`` is set (not empty, not 0)."""
    if os.environ.get("ROLLPLAN_NO_COMPILE", "") not in ("", "0"):
        return None
    for cand in (os.environ.get("CC"), "cc", "gcc", "clang"):
        if cand and cand.split() and shutil.which(cand.split()[0]):
            return cand
    return None


def last_build() -> dict:
    """What the most recent :func:`compiled` or :func:`compiled_lazy` call did: ``source`` is
    ``"cache"``, ``"built"`` or ``"vm"`` (with ``reason``); times in s (for measurements and tests)."""
    return dict(_last)


def _key(parts, blobs=()) -> str:
    h = hashlib.sha256()
    for part in (__version__, ca.__version__, platform.machine(), sys.platform, *parts):
        h.update(str(part).encode())
        h.update(b"\0")
    for blob in blobs:
        h.update(blob)
        h.update(b"\0")
    return h.hexdigest()[:32]


def compiled(fn: ca.Function, jacobian: bool = False, flags=DEFAULT_FLAGS,
             timeout: float = BUILD_TIMEOUT) -> ca.Function:
    """``fn`` compiled to C and loaded from the disk cache (built on first use).

    Parameters
    ----------
    fn : casadi.Function
        Any function CasADi generates C for (SX, or MX without external solvers). Large straight-line
        SX functions compile slowly (the compiler's time grows steeply with the size of one C
        function): build them as a small kernel mapped over data (``Function.map``) instead.
    jacobian : bool
        Put ``fn.jacobian()`` in the library too, so that derivatives of the loaded function are
        compiled as well.
    flags : sequence of str
        Compiler flags (part of the key).
    timeout : float
        Seconds a build may take.

    Returns
    -------
    casadi.Function
        The loaded function (same inputs and outputs), or ``fn`` itself without a compiler or when
        the build fails (one warning logged per reason).
    """
    _last.clear()
    cc = compiler_command()
    if cc is None:
        return _fallback(fn, no_compiler_reason())
    key = _key((fn.name(), cc, " ".join(flags), jacobian), (fn.serialize().encode(),))
    return _get(fn.name(), key, lambda: fn, cc, flags, timeout, jacobian)


def compiled_lazy(name: str, build, descriptor: str, sources=(), jacobian: bool = False, flags=DEFAULT_FLAGS,
                  timeout: float = BUILD_TIMEOUT) -> ca.Function:
    """Like :func:`compiled`, but ``build()`` (which returns a function named ``name``) runs only when
    no library is cached or it must be used in the virtual machine.

    The key holds ``name``, ``descriptor`` (the construction parameters, e.g. ``"steps=32"``) and the
    bytes of ``sources`` (the files whose code defines the function, e.g. the model and the module
    that builds it: editing them changes the key) instead of the serialized graph.
    """
    _last.clear()
    cc = compiler_command()
    if cc is None:
        return _fallback(build(), no_compiler_reason())
    key = _key((name, descriptor, cc, " ".join(flags), jacobian), [Path(s).read_bytes() for s in sources])
    return _get(name, key, build, cc, flags, timeout, jacobian)


def no_compiler_reason() -> str:
    """Why :func:`compiler_command` gives None, in one line that says what to install."""
    if os.environ.get("ROLLPLAN_NO_COMPILE", "") not in ("", "0"):
        return "ROLLPLAN_NO_COMPILE is set"
    return ("no C compiler found: install gcc or clang (Debian/Ubuntu: apt install gcc; Fedora: dnf install gcc; "
            "macOS: xcode-select --install; conda: conda install c-compiler) or set CC to one")


def _fallback(fn, why: str, instead: str = "CasADi's virtual machine"):
    if why not in _warned:
        _warned.add(why)
        log.warning("rollplan: %s; using %s (slower)", why, instead)
    _last.update(source="vm", reason=why)
    return fn


def _same_signature(a: ca.Function, b: ca.Function) -> bool:
    return (a.n_in() == b.n_in() and a.n_out() == b.n_out()
            and all(a.sparsity_in(i) == b.sparsity_in(i) for i in range(a.n_in()))
            and all(a.sparsity_out(i) == b.sparsity_out(i) for i in range(a.n_out())))


def _load(name: str, path: Path, fn: ca.Function | None):
    """The library's function, or None when it does not load or (given ``fn``) its signature differs."""
    try:
        ext = ca.external(name, str(path))
    except Exception as exc:   # a truncated, foreign or corrupt file: rebuilt
        log.debug("cannot load %s: %s", path, exc)
        return None
    return ext if fn is None or _same_signature(ext, fn) else None


def _kill_group(proc: subprocess.Popen) -> None:
    """Kill the compiler driver and its children (cc1, as, ld): its whole process group."""
    try:
        if os.name == "nt":
            proc.kill()
        else:
            os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    proc.wait()


def _run_compiler(cmd, cwd: Path, timeout: float, label: str):
    """``(exit code, output)`` of the compiler, run in its own process group (progress reported under
    ``label`` while it runs); the group is killed on timeout or interrupt, after which the exception
    propagates."""
    log_path = cwd / "build.log"
    deadline = time.monotonic() + timeout
    with open(log_path, "w") as logf:
        proc = subprocess.Popen(cmd, cwd=cwd, stdout=logf, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL,
                                start_new_session=(os.name != "nt"))
        try:
            while True:
                try:
                    code = proc.wait(timeout=min(0.5, max(deadline - time.monotonic(), 0.0)))
                    break
                except subprocess.TimeoutExpired:
                    if time.monotonic() >= deadline:
                        raise
                    report(label, 0, 1)
        except BaseException:
            _kill_group(proc)
            raise
    report(label, 1, 1)
    return code, log_path.read_text(errors="replace")


def _digest_path(lib: Path) -> Path:
    return lib.with_name(lib.name + ".sha256")


def _intact(lib: Path) -> bool:
    """True if ``lib`` exists and its bytes match the digest written beside it (module docstring)."""
    try:
        return _digest_path(lib).read_text().strip() == hashlib.sha256(lib.read_bytes()).hexdigest()
    except (OSError, UnicodeDecodeError):
        return False


def _check_cached(lib: Path) -> None:
    """Create the cache directory if missing (OSError when it cannot be) and refuse it or ``lib`` (if present)
    unless private (:func:`check_private`)."""
    private_cache_dir()
    if os.path.exists(lib):
        check_private(lib)


def _seal(out: Path, lib: Path) -> None:
    """Write the digest of the built ``out`` beside ``lib``, then move ``out`` to ``lib`` (both atomic: a reader
    sees no file or a complete one; a digest and a library of two concurrent builders that differ make the
    library count as damaged, which is rebuilt, never loaded)."""
    digest = _digest_path(lib)
    tmp = out.with_name(out.name + ".sha256")
    tmp.write_text(hashlib.sha256(out.read_bytes()).hexdigest() + "\n")
    for path in (tmp, out):   # whatever the umask: writable by this user only (check_private)
        os.chmod(path, os.stat(path).st_mode & ~0o022)
    os.replace(tmp, digest)
    os.replace(out, lib)


def _get(name: str, key: str, build, cc: str, flags, timeout: float, jacobian: bool) -> ca.Function:
    """Load ``name-key`` from the cache, or build, compile and cache it."""
    root = cache_dir()
    lib = root / f"{name}-{key}{'.dll' if os.name == 'nt' else '.so'}"
    t0 = time.perf_counter()
    try:
        _check_cached(lib)
    except OSError as exc:
        return _fallback(build(), f"cannot write the cache directory {root} ({exc.strerror})")
    if _intact(lib):
        ext = _load(name, lib, None)
        if ext is not None:
            _last.update(source="cache", load_s=time.perf_counter() - t0, path=str(lib))
            return ext
        log.info("rollplan: rebuilding the unusable %s", lib)
    fn = build()
    if fn.name() != name:
        raise ValueError(f"the built function is named {fn.name()!r}, expected {name!r}")
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".build-{name}-", dir=root))
    except OSError as exc:
        return _fallback(fn, f"cannot write the cache directory {root} ({exc.strerror})")
    try:
        log.info("rollplan: compiling %s (first use; cached in %s)", name, root)
        t1 = time.perf_counter()
        src = f"{name}.c"
        cg = ca.CodeGenerator(src, {"with_header": False})
        cg.add(fn)
        if jacobian:
            cg.add(fn.jacobian())
        cg.generate(str(tmp) + os.sep)
        t2 = time.perf_counter()
        out = tmp / lib.name
        cmd = cc.split() + list(flags) + ["-o", str(out), str(tmp / src), "-lm"]
        try:
            code, output = _run_compiler(cmd, tmp, timeout, f"compiling {name} (first use; cached after)")
        except subprocess.TimeoutExpired:
            return _fallback(fn, f"compiling {name} took more than {timeout:g} s")
        except OSError as exc:
            return _fallback(fn, f"cannot run the C compiler {cc!r} ({exc.strerror})")
        if code != 0:
            log.debug("compiler output:\n%s", output)
            return _fallback(fn, f"the C compiler failed on {name} (exit {code})")
        t3 = time.perf_counter()
        _seal(out, lib)
        ext = _load(name, lib, fn)
        if ext is None:
            return _fallback(fn, f"the compiled {name} does not load")
        _last.update(source="built", codegen_s=t2 - t1, compile_s=t3 - t2, load_s=time.perf_counter() - t3,
                     path=str(lib))
        return ext
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def shared_library(name: str, sources, load, instead: str, memo=(), flags=DEFAULT_FLAGS + ("-std=c99",),
                   timeout: float = BUILD_TIMEOUT):
    """A shared library compiled from C sources, cached on disk (module docstring), loaded by ``load``.

    Parameters
    ----------
    name : str
        Name of the library (its file name starts with it).
    sources : callable
        ``sources()`` returns ``{file name: text}``: the ``.c`` files compiled into the library and the files
        they include (headers), written side by side into the build folder. Called in this process.
    load : callable
        ``load(path)`` returns the loaded library; an OSError means an unusable file (rebuilt).
    instead : str
        What the caller uses without the library (named in the one warning per reason).
    memo : sequence of path
        The files whose bytes decide what ``sources()`` returns (the code that writes them).
    flags : sequence of str
        Compiler flags.

    The library's key is the SHA-256 of the names and texts of the sources, the compiler command and flags and
    the platform: it is rebuilt exactly when the C it is compiled from changes. Beside it, the key of the sources
    is remembered under the hash of ``memo`` (and CasADi's version), so that a later process loads the library
    without calling ``sources()``; when a file of ``memo`` changes, ``sources()`` runs again and the library is
    rebuilt only if the C it gives differs.

    Returns
    -------
    The loaded library, or None without a compiler or when the build fails (one warning per reason).
    """
    _last.clear()
    cc = compiler_command()
    if cc is None:
        return _fallback(None, no_compiler_reason(), instead)
    root = cache_dir()
    suffix = ".dll" if os.name == "nt" else ".so"
    t0 = time.perf_counter()
    memo_key = _key((name, cc, " ".join(flags)), [Path(m).read_bytes() for m in memo])
    memo_path = root / f"{name}-sources-{memo_key}.key"
    try:
        _check_cached(memo_path)
        key = memo_path.read_text().strip() if memo_path.is_file() else ""
    except OSError as exc:
        return _fallback(None, f"cannot write the cache directory {root} ({exc.strerror})", instead)
    texts = None
    if not (len(key) == 32 and key.isalnum()):
        try:
            texts = _sources(name, sources)
        except Exception as exc:   # a generator that fails: the caller's alternative serves
            log.debug("generating %s failed", name, exc_info=True)
            return _fallback(None, f"generating {name} failed ({type(exc).__name__})", instead)
        key = _source_key(texts, cc, flags)
    lib = root / f"{name}-{key}{suffix}"
    try:
        _check_cached(lib)
    except OSError as exc:
        return _fallback(None, f"cannot write the cache directory {root} ({exc.strerror})", instead)
    if _intact(lib):
        try:
            out = load(str(lib))
            _remember(memo_path, key)
            _last.update(source="cache", load_s=time.perf_counter() - t0, path=str(lib))
            return out
        except OSError as exc:
            log.info("rollplan: rebuilding the unusable %s (%s)", lib, exc)
    if texts is None:   # remembered, but the library is gone or damaged: generated again
        try:
            texts = _sources(name, sources)
        except Exception as exc:
            log.debug("generating %s failed", name, exc_info=True)
            return _fallback(None, f"generating {name} failed ({type(exc).__name__})", instead)
        key = _source_key(texts, cc, flags)
        lib = root / f"{name}-{key}{suffix}"
    try:
        tmp = Path(tempfile.mkdtemp(prefix=f".build-{name}-", dir=root))
    except OSError as exc:
        return _fallback(None, f"cannot write the cache directory {root} ({exc.strerror})", instead)
    try:
        log.info("rollplan: building %s (first use; cached in %s)", name, root)
        t1 = time.perf_counter()
        out = tmp / lib.name
        for file, text in texts.items():
            (tmp / file).write_text(text, encoding="utf-8")
        cmd = cc.split() + list(flags) + ["-o", str(out), *(f for f in texts if f.endswith(".c")), "-lm"]
        try:
            code, output = _run_compiler(cmd, tmp, timeout, f"compiling {name} (first use; cached after)")
        except subprocess.TimeoutExpired:
            return _fallback(None, f"building {name} took more than {timeout:g} s", instead)
        except OSError as exc:
            return _fallback(None, f"cannot run {cmd[0]!r} ({exc.strerror})", instead)
        if code != 0:
            log.debug("build output:\n%s", output)
            return _fallback(None, f"building {name} failed (exit {code} of {Path(cmd[0]).name})", instead)
        t2 = time.perf_counter()
        _seal(out, lib)
        try:
            loaded = load(str(lib))
        except OSError:
            return _fallback(None, f"the compiled {name} does not load", instead)
        _remember(memo_path, key)
        _last.update(source="built", compile_s=t2 - t1, load_s=time.perf_counter() - t2, path=str(lib))
        return loaded
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


def _sources(name: str, sources) -> dict:
    """``sources()``, with progress reported while it runs."""
    label = f"generating {name} (first use; cached after)"
    report(label, 0, 1)
    texts = sources()
    report(label, 1, 1)
    return texts


def _source_key(texts: dict, cc: str, flags) -> str:
    """The key of a library compiled from ``texts`` (``{file name: text}``) by ``cc`` with ``flags``."""
    h = hashlib.sha256()
    for part in (cc, " ".join(flags), platform.machine(), sys.platform):
        h.update(part.encode() + b"\0")
    for file in sorted(texts):
        h.update(file.encode() + b"\0" + texts[file].encode() + b"\0")
    return h.hexdigest()[:32]


def _remember(memo_path: Path, key: str) -> None:
    """Write ``key`` into ``memo_path`` atomically, writable by this user only (failures are harmless)."""
    try:
        if memo_path.is_file() and memo_path.read_text().strip() == key:
            return
        fd, tmp = tempfile.mkstemp(prefix=".memo-", dir=memo_path.parent)
        with os.fdopen(fd, "w") as fh:
            fh.write(key + "\n")
        os.chmod(tmp, 0o600)
        os.replace(tmp, memo_path)
    except OSError as exc:
        log.debug("cannot remember %s: %s", memo_path, exc)


def clear_cache() -> int:
    """Delete every compiled library (and leftover build directory, and the C planner's stored leaf tables) in
    :func:`cache_dir`; returns the number of libraries removed."""
    root = cache_dir()
    n = 0
    if root.is_dir():
        for p in root.iterdir():
            if p.suffix in (".so", ".dll"):
                p.unlink(missing_ok=True)
                _digest_path(p).unlink(missing_ok=True)
                n += 1
            elif p.suffix == ".key" or (p.suffix == ".bin" and "-table-" in p.name):
                p.unlink(missing_ok=True)
            elif p.name.startswith(".build-") and p.is_dir():
                shutil.rmtree(p, ignore_errors=True)
    return n
