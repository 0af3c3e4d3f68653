"""Shared fixtures; makes ``tests/references.py`` importable as ``references``.

``references`` holds the independent references of the tests: the paper's printed equations and
closed forms in numpy, and the printed (28)-(30), (35), (31) integrated by scipy's DOP853
(``references.trace``). It shares no code with rollplan (not its model, curves or integrators).
That rollplan's symbolic model agrees with the printed equations is tested on its own in
``tests/test_model.py`` and ``tests/test_integrate.py``.
"""

import ast
import contextlib
import functools
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import warnings
from pathlib import Path

#: PYTHONDONTWRITEBYTECODE: pytest would rewrite the asserts of every test module again in every worker of every run
#: (~6 s of CPU per worker), and of the hypothesis package too (a pytest plugin: ~0.8 s per process); it reads the
#: rewritten bytecode that is there, so this process writes it (once; the commands a test starts still inherit the
#: setting from the environment). Set before hypothesis is imported.
_NO_BYTECODE = sys.dont_write_bytecode
sys.dont_write_bytecode = False

import hypothesis  # noqa: E402
import pytest  # noqa: E402

#: ``references`` (and its scipy) and the planners are imported where a fixture needs them, not here: the
#: controlling process of a pytest-xdist run imports this file too and runs no test (~1 s of CPU saved there).
sys.path.insert(0, str(Path(__file__).resolve().parent))

import rollplan  # noqa: E402

#: Set (to anything) for a run whose compiled functions and C libraries are all built anew, in a new and empty
#: cache directory removed at the end, instead of the run-to-run build cache (:func:`_build_cache`).
FRESH_CACHE = "ROLLPLAN_TEST_FRESH_CACHE"
#: How many build caches (one per content of the package) are kept; the least recently used go first.
_KEEP_BUILD_CACHES = 3


def _package_digest(package=None) -> str:
    """SHA-256 of every file of the rollplan package (or of the folder ``package``: paths and bytes, bytecode
    excluded) and of the versions of Python, CasADi and numpy: two runs with the same digest build the same compiled
    functions and libraries."""
    import hashlib
    from importlib.metadata import version

    h = hashlib.sha256(f"{sys.version}|{version('casadi')}|{version('numpy')}".encode())
    package = Path(package or Path(rollplan.__file__).parent)
    for path in sorted(package.rglob("*")):
        if path.is_file() and "__pycache__" not in path.parts:
            h.update(str(path.relative_to(package)).encode() + b"\0" + path.read_bytes() + b"\0")
    return h.hexdigest()[:20]


def fresh_cache(config) -> bool:
    """True if the run builds everything anew in a fresh directory: :data:`FRESH_CACHE` set, or pytest's cache
    disabled (``-p no:cacheprovider``)."""
    return bool(os.environ.get(FRESH_CACHE)) or getattr(config, "cache", None) is None


def _build_cache(config) -> Path | None:
    """The cache directory this run shares with earlier runs of the same package content (``.pytest_cache``),
    so that a developer's second run loads the C libraries and compiled functions the first one built. It is
    keyed by :func:`_package_digest`, not only by the keys of rollplan's own cache: any change to the package
    (a source, a template, a C file) gives a new, empty directory, so a run never loads what another content
    built. None (a fresh directory instead) with :data:`FRESH_CACHE` set or pytest's cache disabled."""
    if fresh_cache(config):
        return None
    root = config.cache.mkdir("rollplan-build")
    root.chmod(0o700)
    folder = root / _package_digest()
    folder.mkdir(mode=0o700, exist_ok=True)
    os.utime(folder)
    for old in sorted((p for p in root.iterdir() if p.is_dir()), key=lambda p: p.stat().st_mtime)[:-_KEEP_BUILD_CACHES]:
        shutil.rmtree(old, ignore_errors=True)
    return folder


def pytest_configure(config):
    """The test run gets a cache directory (compiled functions, C libraries) that the user's cache does not feed:
    the run-to-run build cache of this package content (:func:`_build_cache`), or with :data:`FRESH_CACHE` a new
    and empty one. Made once by the controlling process; pytest-xdist's workers and every subprocess of a test
    inherit it through the environment."""
    if os.environ.get("PYTEST_XDIST_WORKER"):
        return
    folder = _build_cache(config)
    if folder is None:
        folder = tempfile.mkdtemp(prefix="rollplan-test-cache-")
        config.stash[_CACHE] = folder
    os.environ["ROLLPLAN_CACHE_DIR"] = str(folder)
    if _NO_BYTECODE:
        # PYTHONDONTWRITEBYTECODE: each worker and each command a test starts would compile rollplan's modules from
        # source again (~0.2 s of CPU per command); Python still reads bytecode that is there, so write it once
        import compileall

        compileall.compile_dir(str(Path(rollplan.__file__).parent), quiet=2)
    # what a default plan compiles on first use (the C search, the certificate's functions), built once here:
    # tests that count the lines of a command's output do not see the first use's progress, whichever runs first.
    # Built while the workers start and collect the tests; each process's first test waits for it (_warmed_up).
    marker = os.path.join(tempfile.mkdtemp(prefix="rollplan-test-warm-"), "done")
    os.environ[_WARM_MARKER] = marker

    def warm_up():
        try:
            subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0.5", "0.3", "--psi", "0.4"],
                           check=False, capture_output=True, timeout=600)
        finally:
            Path(marker).touch()

    config.stash[_WARM] = threading.Thread(target=warm_up, name="rollplan-test-warm-up", daemon=True)
    config.stash[_WARM].start()


def pytest_unconfigure(config):
    warm = config.stash.get(_WARM, None)
    if warm is not None:
        warm.join(600)
        shutil.rmtree(os.path.dirname(os.environ.pop(_WARM_MARKER)), ignore_errors=True)
    folder = config.stash.get(_CACHE, None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)


_CACHE = pytest.StashKey[str]()
_WARM = pytest.StashKey[threading.Thread]()
_WARM_MARKER = "ROLLPLAN_TEST_WARMED_UP"


@pytest.fixture(scope="session", autouse=True)
def _warmed_up(request):
    """The first test of each process starts once the run's first plan (pytest_configure) has built what a default
    plan compiles on first use; in the process that started it, once its thread has ended (a test may count the
    threads of the process)."""
    warm = request.config.stash.get(_WARM, None)
    if warm is not None:
        warm.join(600)
        return
    marker = os.environ.get(_WARM_MARKER)
    deadline = time.monotonic() + 600
    while marker and not os.path.exists(marker) and time.monotonic() < deadline:
        time.sleep(0.05)

#: No wall-clock deadline for an example of a property-based test: the machine may be shared, and a deadline then
#: fails a test whose example waited for a CPU ("Unreliable test timings" on a loaded machine), not a slow one.
hypothesis.settings.register_profile("rollplan", deadline=None)
hypothesis.settings.load_profile("rollplan")


@pytest.fixture(autouse=True)
def _signal_handlers_restored():
    """Each test starts with the SIGINT and SIGTERM handlers the run started with, whatever an earlier test in
    the same worker left: rollplan.interrupts installs its own handler only over Python's default one, so a
    leftover handler made a test's Ctrl-C go unheard (an endless CVODES call never returned)."""
    import signal

    saved = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    for sig, handler in _START_HANDLERS.items():
        signal.signal(sig, handler)
    yield
    for sig, handler in saved.items():
        signal.signal(sig, handler)


def _start_handlers() -> dict:
    """The run's own handlers; a SIGINT ignored by inheritance (a background job of a shell without job control)
    is given Python's default handler, here and so in every command a test starts: the tests of Ctrl-C need it
    heard."""
    import signal

    if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
        signal.signal(signal.SIGINT, signal.default_int_handler)
    return {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}


#: The signal handlers when the tests were collected (Python's defaults, or pytest's own).
_START_HANDLERS = _start_handlers()


@pytest.fixture(scope="session")
def planner():
    """One geometric-phase planner for the whole session (step map and leaf tables built once)."""
    from rollplan.planners.geometric import GeometricPhasePlanner

    return GeometricPhasePlanner()


@pytest.fixture(scope="session")
def scipy_trace():
    """Independent reference: (u_a, v_a, psi) after ``steps`` figure eights (a, b) rotated by gamma,
    from zero, by DOP853 on the printed (28)-(30), (35) (units of R, rad)."""
    import references

    return references.trace


@pytest.fixture(scope="session")
def asym_plan():
    """A plan for the default robot with a != b (psi = 0.5), two steps: four leaves, three poles between them."""
    return rollplan.plan((0.05, 0.08, 0.5), 2, robot=rollplan.Robot())


@contextlib.contextmanager
def cache_wide(name):
    """A folder of the run's cache directory (``ROLLPLAN_CACHE_DIR``: the run-to-run build cache of this package
    content, or this run's fresh one) under a lock that every pytest-xdist worker and every run shares: what one
    builds there, the others (and the next run of the same package content) find."""
    import fcntl

    root = Path(os.environ["ROLLPLAN_CACHE_DIR"])
    root.mkdir(mode=0o700, parents=True, exist_ok=True)
    with open(root / f"test-{name}.lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        try:
            yield root / f"test-{name}"
        finally:
            fcntl.flock(lock, fcntl.LOCK_UN)


def _compiler_identity() -> str:
    """A short digest of the C compiler's and make's ``--version``: what else a build from the same sources depends
    on."""
    import hashlib

    texts = [subprocess.run([tool, "--version"], capture_output=True, text=True, check=False).stdout
             for tool in ("cc", "make") if shutil.which(tool)]
    return hashlib.sha256("\0".join(texts).encode()).hexdigest()[:12]


@pytest.fixture(scope="session")
def generated_c():
    """The C planner written by ``rollplan codegen`` with its defaults and built by its Makefile (``plan_demo`` and
    ``librollplan.so``), shared by the pytest-xdist workers and kept with the run-to-run build cache (the same
    package content and compiler give the same files; a fresh cache builds it, as on a clean clone): use it
    read-only (build other targets in a copy). For ``test_codegen``, ``test_certify``, ``test_embedded``."""
    import pickle

    from rollplan import codegen

    with cache_wide(f"c-planner-{_compiler_identity()}") as folder:
        done = folder / "generated.pickle"
        if not done.exists():       # not built, or a build that did not finish
            shutil.rmtree(folder, ignore_errors=True)
            folder.mkdir()
            made = codegen.generate(folder / "planner")
            run = subprocess.run(["make", "-C", str(made.out), "plan_demo", "librollplan.so"], check=False,
                                 capture_output=True, text=True)
            assert run.returncode == 0, run.stderr
            (folder / "generated.tmp").write_bytes(pickle.dumps(made))
            (folder / "generated.tmp").replace(done)
        return pickle.loads(done.read_bytes())


@pytest.fixture(scope="session")
def generated_c_float(tmp_path_factory):
    """The C planner written by ``rollplan codegen --real float`` (single precision)."""
    from rollplan import codegen

    return codegen.generate(tmp_path_factory.mktemp("c") / "planner_f32", real="float")


def fill(path):
    """Write zeros to ``path`` until the disk is full."""
    with open(path, "wb", buffering=0) as fh, contextlib.suppress(OSError):
        while True:
            fh.write(b"\0" * 512)


@pytest.fixture
def full_disk(tmp_path):
    """A folder on a 1 MiB tmpfs filled to the last byte (root only: mount)."""
    disk = tmp_path / "disk"
    disk.mkdir()
    if subprocess.run(["mount", "-t", "tmpfs", "-o", "size=1m", "tmpfs", str(disk)], capture_output=True,
                      check=False).returncode:
        pytest.skip("cannot mount a tmpfs (needs root)")
    try:
        fill(disk / "filler")
        yield disk
    finally:
        subprocess.run(["umount", str(disk)], check=False)


#: The warnings that Python's default filters do not show (outside ``__main__``).
_HIDDEN_WARNINGS = (DeprecationWarning, PendingDeprecationWarning, ImportWarning, ResourceWarning)


@functools.cache
def _parser():
    """The command's parser, built once per process: it holds no state between two parses (``parse_args`` makes a
    new namespace each time) and reads no environment, and building it costs ~7 ms, the most of a refused input."""
    from rollplan.cli import build_parser

    return build_parser()


def run(capsys, *argv, cwd=None):
    """``rollplan argv`` in this process, in the folder ``cwd`` (default: this one): (exit code, stdout, stderr)
    as a separate process gives them (``capsys``, or ``capfd`` to see what C code writes to the descriptors too).
    An exception that escapes the command fails the test as a traceback would; the environment, the working folder
    and the open matplotlib figures are as they were before. For what needs a process of its own (start-up, signals,
    a traceback of the interpreter, the environment read at import), start one."""
    from unittest import mock

    from rollplan.cli import main

    argv = [str(a) for a in argv]
    env, here = dict(os.environ), os.getcwd()
    pyplot = sys.modules.get("matplotlib.pyplot")
    figures = set(pyplot.get_fignums()) if pyplot else set()
    try:
        if cwd is not None:
            os.chdir(cwd)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                with mock.patch.object(sys.modules["rollplan.cli.run"], "build_parser", _parser):
                    code = main(argv)
            except SystemExit as exc:  # argparse's own checks
                code = 0 if exc.code is None else exc.code
        shown = set()
        for w in caught:   # on stderr, as a separate process shows them (Python's default filters: once a place)
            place = (str(w.message), w.category, w.filename, w.lineno)
            if not issubclass(w.category, _HIDDEN_WARNINGS) and place not in shown:
                shown.add(place)
                sys.stderr.write(warnings.formatwarning(w.message, w.category, w.filename, w.lineno))
    finally:
        os.chdir(here)
        if os.environ != env:
            os.environ.clear()
            os.environ.update(env)
        pyplot = sys.modules.get("matplotlib.pyplot")
        for number in set(pyplot.get_fignums()) - figures if pyplot else ():
            pyplot.close(number)
    out, err = capsys.readouterr()
    return code, out, err


@functools.cache
def _parsed(path: Path):
    return ast.parse(path.read_text(encoding="utf-8"), str(path))


def package_tree(path) -> ast.Module:
    """The syntax tree of a source file of the package, parsed once per process for every test that reads it."""
    return _parsed(Path(path).resolve())


@functools.cache
def _walked(path: Path) -> tuple:
    return tuple(ast.walk(_parsed(path)))


def package_nodes(path) -> tuple:
    """Every node of :func:`package_tree` in ``ast.walk`` order, listed once per process (walking the whole package
    again costs each test that reads it ~0.1 s)."""
    return _walked(Path(path).resolve())


def run_program(folder, name: str, text: str, *args: str) -> subprocess.CompletedProcess:
    """Write ``text`` as the program ``folder/name`` and run it in a fresh interpreter with ``args`` (its output
    captured as text; two minutes at most): for what must not depend on what ran before in the test process (its
    threads, signal handlers, process-wide settings)."""
    script = Path(folder) / name
    script.write_text(text)
    return subprocess.run([sys.executable, str(script), *args], check=False, capture_output=True, text=True,
                          timeout=120)


#: A launcher of the command (``[sys.executable, "-c", READY, *argv]``): ``rollplan.cli.main`` on the command line, as
#: ``python -m rollplan.cli`` runs it, once its modules are imported saying "ready" on stderr (a test times its signal
#: from there); SIGINT is Python's KeyboardInterrupt even where the test's process ignores it.
READY = ("import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); "
         "from rollplan.cli import main; sys.stderr.write('ready\\n'); sys.stderr.flush(); "
         "sys.exit(main(sys.argv[1:]))")


def require_c_search(curve: str = "circles") -> None:
    """Skip without a C compiler; with one, the compiled C search of the leaf family ``curve`` must build (a failed
    build fails the test) and is loaded, so that what the test runs next is the search, not its build."""
    from rollplan.core import compiled
    from rollplan.planners.geometric import compiled_search

    if compiled.compiler_command() is None:
        pytest.skip("no C compiler: the compiled search is not built")
    assert compiled_search.library(curve) is not None, compiled.last_build()


def one_line(err):
    """True if ``err`` is one line and no traceback (how every refusal is reported)."""
    return len(err.strip().splitlines()) == 1 and "Traceback" not in err


def recorded_fallback(newton_step, args, used):
    """``newton_step(*args)``; for CVODES's step with sensitivities (the correction's fallback: jacobians on, no
    substeps) a wrapper that records each call in ``used``."""
    step = newton_step(*args)
    if (args[1] if len(args) > 1 else True) and (args[2] if len(args) > 2 else None) is None:
        return lambda *a, **kw: used.append(kw) or step(*a, **kw)
    return step
