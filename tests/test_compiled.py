"""Compiled CasADi functions cached on disk: reuse, staleness, atomic concurrent builds, fallback, Ctrl-C."""

import ast
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import casadi as ca
import numpy as np
import pytest

from rollplan.core import compiled as cmod


def _fn(scale: float = 2.0, name: str = "ctest") -> ca.Function:
    x, p = ca.SX.sym("x", 2), ca.SX.sym("p")
    return ca.Function(name, [x, p], [ca.vertcat(ca.sin(x[0]) * p * scale, x[0] * x[1])])


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setenv("ROLLPLAN_CACHE_DIR", str(tmp_path))
    monkeypatch.delenv("ROLLPLAN_NO_COMPILE", raising=False)
    if cmod.compiler_command() is None:
        pytest.skip("no C compiler")
    return tmp_path


def test_built_once_then_loaded_from_the_cache(cache):
    f = _fn()
    g = cmod.compiled(f, jacobian=True)
    assert cmod.last_build()["source"] == "built"
    assert np.allclose(np.array(g([0.3, 2.0], 1.5)), np.array(f([0.3, 2.0], 1.5)), rtol=0, atol=1e-15)
    cmod.compiled(f, jacobian=True)
    assert cmod.last_build()["source"] == "cache"
    libs = list(cache.glob("ctest-*.so"))
    assert len(libs) == 1 and not list(cache.glob(".build-*"))
    # the Jacobian comes from the library (compiled), equal to the VM's
    x = ca.MX.sym("x", 2)
    jc = ca.Function("j", [x], [ca.jacobian(g(x, 1.5), x)])([0.3, 2.0])
    jv = ca.Function("j", [x], [ca.jacobian(f(x, 1.5), x)])([0.3, 2.0])
    assert np.allclose(np.array(jc), np.array(jv), rtol=0, atol=1e-15)


def test_a_changed_function_gets_its_own_library(cache):
    cmod.compiled(_fn(2.0))
    cmod.compiled(_fn(3.0))
    assert cmod.last_build()["source"] == "built" and len(list(cache.glob("ctest-*.so"))) == 2


def test_lazy_build_runs_only_on_a_miss(cache, tmp_path):
    src = tmp_path / "src.py"
    src.write_text("a")
    calls = []

    def build():
        calls.append(1)
        return _fn(name="clazy")

    cmod.compiled_lazy("clazy", build, "d=1", [src])
    cmod.compiled_lazy("clazy", build, "d=1", [src])
    assert len(calls) == 1 and cmod.last_build()["source"] == "cache"
    src.write_text("b")                     # the source changed: a new key, built again
    cmod.compiled_lazy("clazy", build, "d=1", [src])
    assert len(calls) == 2 and cmod.last_build()["source"] == "built"


_CHILD = """
import sys, numpy as np, casadi as ca
from rollplan.core import compiled as c
x = ca.SX.sym("x", 2); p = ca.SX.sym("p")
e = ca.vertcat(ca.sin(x[0]) * p, x[0] * x[1])
for i in range({terms}):
    e = e + ca.sin(x[0] + i) * ca.cos(x[1] * i) / (1 + i)
f = ca.Function("cchild", [x, p], [e])
g = c.compiled(f)
print(c.last_build()["source"], float(np.abs(np.array(g([0.3, 2.0], 1.5) - f([0.3, 2.0], 1.5))).max()))
"""


def _child(cache, terms=0, env=None, **kw):
    e = {**os.environ, "ROLLPLAN_CACHE_DIR": str(cache), **(env or {})}
    return subprocess.Popen([sys.executable, "-c", _CHILD.format(terms=terms)], env=e, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, **kw)


@pytest.mark.slow
def test_concurrent_builds_leave_one_complete_library(cache):
    procs = [_child(cache, 200) for _ in range(3)]
    outs = [p.communicate(timeout=120) for p in procs]
    assert all(p.returncode == 0 for p in procs), outs
    for out, _ in outs:
        source, err = out.split()
        assert source in ("built", "cache") and float(err) < 1e-14
    assert len(list(cache.glob("cchild-*.so"))) == 1 and not list(cache.glob(".build-*"))


@pytest.mark.slow
def test_a_corrupt_library_is_rebuilt(cache):
    p = _child(cache)
    assert p.communicate(timeout=120)[0].startswith("built")
    lib = next(cache.glob("cchild-*.so"))
    lib.write_bytes(b"\x7fELF truncated")
    out, err = _child(cache).communicate(timeout=120)
    assert out.startswith("built"), err


def test_without_a_compiler_the_virtual_machine_serves(cache, monkeypatch):
    f = _fn()
    monkeypatch.setenv("ROLLPLAN_NO_COMPILE", "1")
    g = cmod.compiled(f)
    assert g is f and cmod.last_build()["source"] == "vm"
    monkeypatch.delenv("ROLLPLAN_NO_COMPILE")
    monkeypatch.delenv("CC", raising=False)
    monkeypatch.setenv("PATH", str(cache))   # no cc, gcc or clang on the path
    assert cmod.compiler_command() is None
    g = cmod.compiled(f)
    assert g is f and "no C compiler" in cmod.last_build()["reason"]
    assert not list(cache.glob("*.so"))


def test_a_plan_without_a_compiler_is_one_solver_error(tmp_path):
    """The C search is the planner's only search (issue 24): without a compiler a plan raises one SolverError line
    naming why, and nothing is compiled."""
    env = {**os.environ, "ROLLPLAN_CACHE_DIR": str(tmp_path), "ROLLPLAN_NO_COMPILE": "1"}
    code = ("import rollplan\ntry:\n    rollplan.plan((1, -0.5, 1), steps=3, k=2.5)\n"
            "except rollplan.SolverError as e:\n    print(e.status, '|', e)")
    run = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=300,
                         check=False)
    assert run.returncode == 0, run.stderr
    assert run.stdout == ("no C search | the geometric planner's search is compiled C and cannot be used: "
                          "ROLLPLAN_NO_COMPILE is set\n")
    assert not list(Path(tmp_path).glob("*.so"))


def _compilers_in(path: Path) -> list:
    ps = subprocess.run(["ps", "-ww", "-eo", "pid,args"], capture_output=True, text=True, check=False).stdout
    return [line for line in ps.splitlines() if str(path) in line and "python" not in line]


@pytest.mark.slow
@pytest.mark.skipif(os.name == "nt", reason="POSIX signals")
def test_ctrl_c_kills_the_compiler_promptly(cache):
    p = _child(cache, 6000)       # a large function: the compiler runs for seconds
    deadline = time.monotonic() + 60
    while not _compilers_in(cache) and time.monotonic() < deadline and p.poll() is None:
        time.sleep(0.05)
    assert _compilers_in(cache), "the compiler did not start"
    t0 = time.monotonic()
    p.send_signal(signal.SIGINT)
    p.communicate(timeout=10)
    assert time.monotonic() - t0 < 1.5 and p.returncode != 0
    time.sleep(0.2)
    assert not _compilers_in(cache) and not list(cache.glob("*.so")) and not list(cache.glob(".build-*"))


@pytest.mark.slow
def test_a_long_compile_shows_progress(cache):
    import io

    from rollplan.progress import Progress, reporting

    x = ca.SX.sym("x", 2)
    e = x[0]
    for i in range(600):
        e = e + ca.sin(x[0] + i) * ca.cos(x[1] * i) / (1 + i)
    buf = io.StringIO()
    with reporting(Progress(stream=buf, interval=0.0)):
        cmod.compiled(ca.Function("cprogress", [x], [e]))
    assert cmod.last_build()["source"] == "built"
    assert "compiling cprogress (first use; cached after): 0/1" in buf.getvalue()


_DAMAGE_SCRIPT = """
import ctypes, sys
from rollplan.core import compiled
src = sys.argv[1]
write = lambda: {"f.c": "int f(int x) { return 3 * x + 1; }"}
f = compiled.shared_library("dtest", write, lambda p: ctypes.CDLL(p).f, "python", memo=[src])
print(f(4), compiled.last_build()["source"])
"""


@pytest.mark.slow
def test_a_damaged_cached_library_is_rebuilt_not_loaded(cache):
    """A cached search library truncated to 1000 bytes killed `rollplan plan` with SIGBUS inside ctypes (no
    exception to catch): the library's bytes are checked against the digest written beside it before loading,
    and a damaged one (truncated, or one byte changed) or one without its digest is rebuilt. Each load runs in
    a fresh process (a process that has the library mapped must not see its file change under it)."""
    src = cache / "src.txt"
    src.write_text("v1")

    def run():
        r = subprocess.run([sys.executable, "-c", _DAMAGE_SCRIPT, str(src)], capture_output=True, text=True,
                           timeout=120, check=False, env={**os.environ, "ROLLPLAN_CACHE_DIR": str(cache)})
        assert r.returncode == 0, (r.returncode, r.stderr[-2000:])
        return r.stdout.split()

    assert run() == ["13", "built"]
    assert run() == ["13", "cache"]
    (lib,) = cache.glob("dtest-*.so")
    good = lib.read_bytes()
    for damaged in (good[:1000], good[:-1] + bytes([good[-1] ^ 1])):
        lib.write_bytes(damaged)
        assert run() == ["13", "built"]
    (cache / (lib.name + ".sha256")).unlink()
    assert run() == ["13", "built"]
    assert run() == ["13", "cache"]


def test_shared_library_is_built_once_then_loaded_and_refused_without_a_compiler(cache, monkeypatch):
    """A plain C library (the compiled search's way): a function gives the C files, the result is loaded
    by ctypes and computes; the second call loads the cached file; a failing generator, C that does not
    compile or no compiler give None."""
    import ctypes

    src = cache / "src.txt"
    src.write_text("v1")
    write = lambda: {"f.c": '#include "g.h"\nint f(int x) { return G * x + 1; }', "g.h": "#define G 3\n"}

    def get(sources=write):
        return cmod.shared_library("stest", sources, lambda p: ctypes.CDLL(p).f, "python", memo=[src])

    assert get()(4) == 13 and cmod.last_build()["source"] == "built"
    assert get()(5) == 16 and cmod.last_build()["source"] == "cache"
    assert len(list(cache.glob("stest-*.so"))) == 1 and not list(cache.glob(".build-*"))
    src.write_text("v2")
    assert get(lambda: 1 / 0) is None and "generating stest failed" in cmod.last_build()["reason"]
    assert get(lambda: {"f.c": "int f(int x) { return x }"}) is None and "failed" in cmod.last_build()["reason"]
    monkeypatch.setenv("ROLLPLAN_NO_COMPILE", "1")
    assert get() is None and cmod.last_build()["source"] == "vm"


def test_without_a_compiler_one_line_says_what_to_install(tmp_path, monkeypatch):
    """No C compiler on the PATH: the C search is not built and the reason, one line, names what to install
    (the line a caller that needs the C search shows)."""
    from rollplan.planners.geometric import compiled_search

    monkeypatch.delenv("CC", raising=False)
    monkeypatch.delenv("ROLLPLAN_NO_COMPILE", raising=False)
    monkeypatch.setenv("PATH", str(tmp_path))
    assert cmod.compiler_command() is None
    reason = cmod.no_compiler_reason()
    assert "\n" not in reason and "install gcc or clang" in reason and "apt install gcc" in reason
    compiled_search.library.cache_clear()
    try:
        assert compiled_search.library() is None
        assert cmod.last_build() == {"source": "vm", "reason": reason}
    finally:
        compiled_search.library.cache_clear()


def test_shared_library_is_keyed_by_the_c_it_compiles(cache):
    """The library's key is the text of its C files (and the compiler and its flags): when the code that writes
    them changes (``memo``) but not the C, the sources are generated again and the library is loaded, not
    rebuilt; when a header it includes changes, it is rebuilt; an unchanged ``memo`` does not call the generator."""
    import ctypes

    src, calls = cache / "src.txt", []
    src.write_text("v1")

    def get(factor):
        def write():
            calls.append(factor)
            return {"f.c": '#include "g.h"\nint f(int x) { return G * x + 1; }', "g.h": f"#define G {factor}\n"}
        return cmod.shared_library("ktest", write, lambda p: ctypes.CDLL(p).f, "python", memo=[src])

    assert get(3)(4) == 13 and cmod.last_build()["source"] == "built" and calls == [3]
    assert get(3)(4) == 13 and cmod.last_build()["source"] == "cache" and calls == [3]   # not generated again
    src.write_text("v2")   # the generator's code changed, its C did not
    assert get(3)(4) == 13 and cmod.last_build()["source"] == "cache" and calls == [3, 3]
    src.write_text("v3")
    assert get(5)(4) == 21 and cmod.last_build()["source"] == "built" and calls == [3, 3, 5]
    assert len(list(cache.glob("ktest-*.so"))) == 2


@pytest.mark.slow
def test_the_c_search_is_generated_again_only_when_the_code_that_writes_it_changes():
    """The C search library is keyed by its C text; its generated sources are remembered under the hash of
    generator_files(). Every rollplan file whose code runs while the sources are generated, and every module
    that the generating modules import (constants read), is one of them; plots, the CLI, studies, execution and
    the code generator are not (editing a plot does not even generate the sources again)."""
    import importlib

    from rollplan.planners.geometric import c_sources

    package = Path(importlib.import_module("rollplan").__file__).parent
    listed = {p.resolve() for p in c_sources.generator_files()}
    assert all(p.is_file() for p in listed)
    ran = set()

    def profile(frame, event, arg):
        if event == "call":
            ran.add(frame.f_code.co_filename)

    sys.setprofile(profile)
    try:
        texts = c_sources.sources()
    finally:
        sys.setprofile(None)
    ran = {Path(f).resolve() for f in ran if f.startswith(str(package))}
    assert ran and ran <= listed, sorted(map(str, ran - listed))
    for module in ("rollplan.planners.geometric.c_sources", "rollplan.core.c_functions"):
        path = Path(importlib.import_module(module).__file__)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.level:   # from .x import y, from . import x
                base = path.parents[node.level - 1].joinpath(*(node.module.split(".") if node.module else []))
                for stem in ([base] if node.module else [base / a.name for a in node.names]):
                    file = stem.with_suffix(".py") if stem.with_suffix(".py").is_file() else stem / "__init__.py"
                    assert file.resolve() in listed, (module, str(file))
    assert not [p for p in listed if p.parts[len(package.parts)] in ("plots", "cli", "cli.py", "studies", "execution",
                                                                      "codegen", "io.py")]
    assert set(c_sources.STATIC_FILES) <= set(texts) and (package / "csrc").resolve() in {p.parent for p in listed}


def test_the_test_run_has_its_own_cache_directory(request):
    """conftest gives the run a cache folder that is not the user's: the build cache of this package content, or
    a new one with ROLLPLAN_TEST_FRESH_CACHE or pytest's cache disabled; the same in every worker and
    subprocess."""
    import conftest

    folder = cmod.cache_dir()
    if conftest.fresh_cache(request.config):
        assert folder.name.startswith("rollplan-test-cache-")
    else:
        assert folder.name == conftest._package_digest() and folder.parent.name == "rollplan-build"
    assert folder != Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rollplan"
    run = subprocess.run([sys.executable, "-c", "from rollplan.core.compiled import cache_dir; print(cache_dir())"],
                         capture_output=True, text=True, check=True, timeout=120)
    assert run.stdout.strip() == str(folder)


def test_the_build_cache_of_the_tests_changes_with_any_byte_of_the_package(tmp_path):
    """The run-to-run build cache is keyed by every file of the package: a copy has the same key, a copy with one
    byte changed in a C source, a header or a Python module has another (so no run loads what another content
    built)."""
    import conftest

    package = Path(cmod.__file__).parents[1]
    copy = tmp_path / "rollplan"
    shutil.copytree(package, copy, ignore=shutil.ignore_patterns("__pycache__"))
    same = conftest._package_digest(copy)
    assert same == conftest._package_digest(package)
    seen = {same}
    for path in (next(copy.rglob("*.c")), copy / "core" / "model.py", next(copy.rglob("*.h"))):
        original = path.read_bytes()
        path.write_bytes(original[:-1] + bytes([original[-1] ^ 1]))
        seen.add(conftest._package_digest(copy))
        path.write_bytes(original)
    assert len(seen) == 4 and conftest._package_digest(copy) == same


# ----------------------------------------------------------------------------- a cache other users can write


def _stest(src):
    import ctypes

    write = lambda: {"f.c": "int f(int x) { return 3 * x + 1; }"}
    return cmod.shared_library("stest", write, lambda p: ctypes.CDLL(p).f, "python", memo=[src])


@pytest.mark.parametrize("mode", [0o777, 0o757, 0o1777])
def test_a_cache_directory_others_can_write_is_refused_by_the_command(tmp_path, mode):
    """With ROLLPLAN_CACHE_DIR on a folder others may write, another user could plant a library under its
    predictable name with a matching digest, and the next plan loaded and ran it: one line, exit 2."""
    folder = tmp_path / "shared"
    folder.mkdir()
    folder.chmod(mode)
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0", "1", "--k", "2.5"],
                       capture_output=True, text=True, timeout=300, check=False,
                       env={**os.environ, "ROLLPLAN_CACHE_DIR": str(folder)})
    assert r.returncode == 2, (r.returncode, r.stderr[-2000:])
    assert len(r.stderr.strip().splitlines()) == 1 and "Traceback" not in r.stderr
    assert str(folder) in r.stderr and "writable by group or others" in r.stderr
    assert not list(folder.iterdir())   # nothing loaded, built or written there


def test_the_cache_directory_is_created_private(tmp_path, monkeypatch):
    monkeypatch.setenv("ROLLPLAN_CACHE_DIR", str(tmp_path / "new" / "cache"))
    monkeypatch.delenv("ROLLPLAN_NO_COMPILE", raising=False)
    src = tmp_path / "src.txt"
    src.write_text("v1")
    f = _stest(src)
    assert (tmp_path / "new" / "cache").stat().st_mode & 0o777 == 0o700
    if f is not None:   # with a compiler: the library and its digest are writable by this user only
        for p in (tmp_path / "new" / "cache").iterdir():
            assert p.stat().st_mode & 0o022 == 0, p


@pytest.mark.parametrize("damage", ["dir 0777", "dir 0757", "dir owner", "lib 0666", "lib 0646", "lib owner"])
def test_a_library_or_directory_others_control_is_refused_by_the_api(cache, damage):
    """A library another user owns or may write (or one in such a folder) is never loaded:
    UnsafeCacheError (an InputError), whatever its digest says."""
    from rollplan import InputError, UnsafeCacheError

    src = cache / "src.txt"
    src.write_text("v1")
    assert _stest(src)(4) == 13
    (lib,) = cache.glob("stest-*.so")
    what, how = damage.split()
    target = cache if what == "dir" else lib
    if how == "owner":
        if os.geteuid() != 0:
            pytest.skip("changing a file's owner needs root")
        os.chown(target, 12345, -1)
    else:
        target.chmod(int(how, 8))
    with pytest.raises(UnsafeCacheError, match="refusing") as err:
        _stest(src)
    assert isinstance(err.value, InputError) and str(target) in str(err.value)
    if what == "dir":
        with pytest.raises(UnsafeCacheError):
            cmod.compiled(_fn())


def test_a_leaf_table_others_may_write_is_refused(tmp_path, monkeypatch):
    """The reference enumeration's leaf tables live in the same cache directory and are refused on the same terms."""
    from rollplan import UnsafeCacheError

    from reference_enumerate import rho_table

    monkeypatch.setenv("ROLLPLAN_CACHE_DIR", str(tmp_path / "cache"))
    first = rho_table.__wrapped__(3.3)   # built and stored (the cache of this process is bypassed)
    (table,) = (tmp_path / "cache").glob("rho_table_*.npz")
    assert rho_table.__wrapped__(3.3).eps == first.eps
    table.chmod(0o666)
    with pytest.raises(UnsafeCacheError, match="writable by group or others"):
        rho_table.__wrapped__(3.3)


def _session_cache_copied_to(folder, capsys):
    """Copy this test run's cache (compiled functions and leaf tables of ``rollplan plan --to 0.3 0.2``, planned
    here first) into ``folder``, so that a command run with it loads them instead of compiling them again."""
    from conftest import run

    assert run(capsys, "plan", "--to", "0.3", "0.2")[0] == 0
    for path in Path(os.environ["ROLLPLAN_CACHE_DIR"]).iterdir():
        if path.is_file() and not path.name.startswith("."):
            shutil.copy2(path, folder / path.name)


@pytest.mark.parametrize("how", ["inside", pytest.param("link", marks=pytest.mark.slow)])
def test_a_cache_directory_under_a_folder_others_can_write_is_refused(tmp_path, how, capsys):
    """A private cache folder inside a folder others may write (no sticky bit), or reached by a link that lives in
    one, can be swapped for another user's: one line, exit 2, nothing written. With the sticky bit it is used (it
    holds a copy of this run's cache: the check is the same for a load as for a build)."""
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o777)
    if how == "inside":
        folder = shared / "mine"
        folder.mkdir(mode=0o700)
    else:
        target = tmp_path / "own"
        target.mkdir(mode=0o700)
        folder = shared / "link"
        folder.symlink_to(target)
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0.3", "0.2"], capture_output=True,
                       text=True, timeout=300, check=False, env={**os.environ, "ROLLPLAN_CACHE_DIR": str(folder)})
    assert r.returncode == 2 and len(r.stderr.strip().splitlines()) == 1, r.stderr
    assert str(shared) in r.stderr and "sticky" in r.stderr
    assert not list(folder.iterdir())
    shared.chmod(0o1777)   # with the sticky bit (as /tmp) others cannot rename or remove the folder
    _session_cache_copied_to(folder, capsys)
    r = subprocess.run([sys.executable, "-m", "rollplan.cli", "plan", "--to", "0.3", "0.2"], capture_output=True,
                       text=True, timeout=300, check=False, env={**os.environ, "ROLLPLAN_CACHE_DIR": str(folder)})
    assert r.returncode == 0, r.stderr


def test_clear_cache_removes_the_libraries_and_the_stored_leaf_tables(tmp_path, monkeypatch):
    from rollplan.core.compiled import clear_cache
    monkeypatch.setenv("ROLLPLAN_CACHE_DIR", str(tmp_path))
    names = ["c_planner_search_triangle-ab12.so", "c_planner_search_triangle-ab12-table-0x1.8p+0.bin"]
    for name in names + ["notes.txt"]:
        (tmp_path / name).write_bytes(b"x")
    assert clear_cache() == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["notes.txt"]
