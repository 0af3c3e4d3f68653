"""The C search for every k the planner accepts (sigma graphs below k = 1/2, the graph over x above;
docs/design/enumeration.md): the Python planner's plans through it against the numpy reference search
(tests/reference_enumerate.py), and its roots
against the 2-D brute force of tests/test_enumerate.py (scipy's brentq and bounded minimiser on the level set)."""

import ctypes
import fcntl
import math
import os
import pty
import re
import struct
import subprocess
import sys
import tempfile
import termios
import threading

import numpy as np
import pytest
from conftest import READY, require_c_search
from test_enumerate import brute_roots_2d, same_sets
from test_interrupts import run_and_interrupt

from rollplan import NoPlanError, Problem
from rollplan.core.curves import A_MAX
from rollplan.core.plane import wrap_exact
from rollplan.planners.geometric import GeometricPhasePlanner, compiled_search, leafmap

from reference_enumerate import ReferencePlanner


def _gamma_tol(a, b):
    """Tolerance of gamma of the same root from the two searches: 1e-12 times 1 + s^-3 (s = sqrt(1 - 2 r^2) of the
    larger radius r): gamma turns the step's shift, whose derivative in r grows like s^-3 (docs/design/leaf-map.md),
    so the last bit of a polished radius (the two polishes start from the two searches' roots) moves gamma by
    ~1e-14 s^-3."""
    r = max(a, b)
    return 1e-12 * (1.0 + (1.0 - 2.0 * r * r) ** -1.5)


def _targets(seed, ks, count, steps=None):
    """Random targets ((u, v, psi), steps, k): k from ``ks(rng)``, psi within the reach of the turns of the leaves."""
    rng = np.random.default_rng(seed)
    for _ in range(count):
        k, n = float(ks(rng)), int(rng.integers(1, 4)) if steps is None else steps
        e = leafmap.turn(np.linspace(0.0, A_MAX, 2001), k)
        span = float(e.max() - min(e.min(), 0.0))
        d, th = rng.uniform(0.02, 0.5), rng.uniform(-np.pi, np.pi)
        psi = rng.uniform(-1.0, 1.0) * min(np.pi, 0.9 * n * span)
        yield (float(d * np.cos(th)), float(d * np.sin(th)), float(psi)), n, k


def _solve(planner, target, steps, k, **kw):
    try:
        return planner.solve(Problem(target, k=k, steps=steps), **kw)
    except NoPlanError:
        return None


def _check_same_plans(seed, ks, count):
    """The planner with the compiled search and with the numpy search: the same outcome and, where there is a plan,
    the same branch, (a, b) to 1e-12 and gamma to :func:`_gamma_tol` (both polished by the same solver); returns
    how many plans."""
    fast, slow = GeometricPhasePlanner(), ReferencePlanner()
    plans = 0
    for target, steps, k in _targets(seed, ks, count):
        p, q = _solve(fast, target, steps, k), _solve(slow, target, steps, k)
        assert (p is None) == (q is None), (target, steps, k)
        if p is None:
            continue
        plans += 1
        assert p.stats.details["search"] == "compiled" and q.stats.details["search"] == "numpy"
        assert p.branch == q.branch, (target, steps, k)
        assert np.allclose([p.a, p.b], [q.a, q.b], rtol=0, atol=1e-12), (target, steps, k)
        assert abs(p.gamma - q.gamma) <= _gamma_tol(q.a, q.b), (target, steps, k)
    return plans


def _check_same_lists(seed, ks, count, fixed_steps=None):
    """all_solutions with the compiled and the numpy search: as many plans, and the same ones (branch, (a, b) to
    1e-12, gamma to :func:`_gamma_tol`), paired in the order of (branch, a, b); returns how many lists were not
    empty."""
    fast, slow = GeometricPhasePlanner(), ReferencePlanner()
    listed = 0
    for target, steps, k in _targets(seed, ks, count, fixed_steps):
        p, q = (_solve(pl, target, steps, k, all_solutions=True) for pl in (fast, slow))
        assert (p is None) == (q is None), (target, steps, k)
        if p is None:
            continue
        listed += 1
        got, want = (sorted((r.branch, r.a, r.b, r.gamma) for r in (x, *x.alternatives)) for x in (p, q))
        assert len(got) == len(want), (target, steps, k, len(got), len(want))
        for x, y in zip(got, want):
            assert x[0] == y[0] and np.allclose(x[1:3], y[1:3], rtol=0, atol=1e-12), (target, steps, k, x, y)
            assert abs(x[3] - y[3]) <= _gamma_tol(y[1], y[2]), (target, steps, k, x, y)
        assert p.stats.details["search"] == "compiled"
    return listed


@pytest.mark.slow
def test_same_plan_as_the_numpy_search_below_one_half():
    """k in [0.1, 1/2) (E not monotone or increasing: the C sigma graphs)."""
    require_c_search()
    assert _check_same_plans(31, lambda rng: rng.uniform(0.1, 0.5), 16) >= 4


def test_same_lists_as_the_numpy_search_below_one_half():
    require_c_search()
    assert _check_same_lists(32, lambda rng: rng.uniform(0.1, 0.5), 6) >= 2


@pytest.mark.slow
def test_same_plan_as_the_numpy_search_for_every_k():
    """k log-uniform in [0.1, 30]: both graphs of the C search (sigma graphs below 1/2, the graph over x above)."""
    require_c_search()
    ks = lambda rng: math.exp(rng.uniform(math.log(0.1), math.log(30.0)))   # noqa: E731
    assert _check_same_plans(33, ks, 16) >= 8
    assert _check_same_lists(34, ks, 4, fixed_steps=1) >= 2


@pytest.mark.parametrize("k", [0.0, *(pytest.param(k, marks=pytest.mark.slow) for k in (0.45, 0.1, 0.3))])
def test_c_roots_against_the_2d_brute_force(k):
    """Every root of the C search (rollplan_plan_all, uncertified) is one of the brute force's and none is missed;
    the shortest root (rollplan_plan_with) is the brute force's shortest. Targets with psi = 0 have the branch
    eta = 0 (a = b, and a != b with E(a) = E(b) where E is not monotone)."""
    require_c_search()
    rng = np.random.default_rng(int(k * 1000) + 41)
    targets = [((0.3, 0.2, 0.0), 1), ((0.05, -0.1, 0.0), 2)]
    targets += [((rng.uniform(-0.6, 0.6), rng.uniform(-0.6, 0.6), rng.uniform(-np.pi, np.pi)), int(rng.integers(1, 4)))
                for _ in range(2)]
    for target, steps in targets:
        brute = brute_roots_2d(target, steps, k)
        turns = wrap_exact(target[2])[1]
        listed = compiled_search.all_roots(*target, steps, k)
        got = [(r.m - turns, r.a, r.b) for r in listed]
        assert same_sets(brute, got) == ([], []), (target, steps)
        first = compiled_search.shortest_root(*target, steps, k)
        if not brute:
            assert math.isnan(first.a) and math.isnan(first.b)
            continue
        shortest = min(a + b for _, a, b in brute)
        assert first.a + first.b == pytest.approx(shortest, abs=1e-9), (target, steps)


@pytest.mark.slow
def test_ctrl_c_during_a_long_c_search_exits_130():
    """`plan --all --k 99` spends minutes in one call of the C search (every root of 511 branches, after its table of
    k = 99 is built); a SIGINT 1.5 s after the command's modules are imported (``conftest.READY``), during that call,
    exits 130 within two seconds (the call runs in a helper thread, the main thread acts on the signal), one line,
    no traceback."""
    require_c_search()
    code, elapsed, _, err = run_and_interrupt(["plan", "--to", "0", "1", "--k", "99", "--all"], 1.5, wait_for="ready",
                                              command=[sys.executable, "-c", READY])
    assert code == 130, err
    assert elapsed < 2.0
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "rollplan: interrupted"


@pytest.mark.slow
def test_ctrl_c_while_a_long_list_is_certified_exits_130_within_a_second():
    """`plan --all` at k = 12, n = 4 certifies 1864 roots (seconds): its progress shows on stderr, and a SIGINT
    during the certificates exits 130 within a second (the machine may be loaded: 1.5 s), one line, no
    traceback."""
    require_c_search()
    code, elapsed, _, err = run_and_interrupt(["-v", "plan", "--to", "0", "1", "--k", "12", "--steps", "4", "--all"],
                                              0.5, wait_for="certifying 1864 roots in C")
    assert code == 130, err
    assert elapsed < 1.5, elapsed
    assert "Traceback" not in err and err.strip().splitlines()[-1] == "rollplan: interrupted"


#: ``python -c`` program: the command line (argv after the program) with every progress display shown at once
#: (the command line shows one only after 5 s of work: tests/test_progress.py checks the delay on a terminal); it
#: prints the delays asked for on stdout.
_AT_ONCE = """import sys
import rollplan.progress
init = rollplan.progress.Progress.__init__
def sooner(self, *args, **kwargs):
    print("delay", kwargs.get("delay"), flush=True)
    kwargs["delay"] = 0.0
    init(self, *args, **kwargs)
rollplan.progress.Progress.__init__ = sooner
from rollplan.cli import main
sys.exit(main(sys.argv[1:]))
"""


def _run_on_a_terminal(argv, columns=120):
    """``rollplan argv`` with stderr on a pseudo-terminal of ``columns`` columns, its progress shown at once
    (:data:`_AT_ONCE`): (exit code, stderr text, stdout text)."""
    main, side = pty.openpty()
    fcntl.ioctl(side, termios.TIOCSWINSZ, struct.pack("HHHH", 24, columns, 0, 0))
    out = tempfile.TemporaryFile()  # noqa: SIM115 (read after the process ends, closed on return)
    proc = subprocess.Popen([sys.executable, "-c", _AT_ONCE, *argv], stdout=out, stderr=side)
    os.close(side)
    got = []

    def read():
        while True:
            try:
                data = os.read(main, 65536)
            except OSError:   # the terminal closed with the process
                return
            if not data:
                return
            got.append(data)

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    code = proc.wait(timeout=600)
    reader.join(10)
    os.close(main)
    out.seek(0)
    with out:
        return code, b"".join(got).decode(errors="replace"), out.read().decode()


@pytest.mark.slow
def test_a_long_list_shows_a_progress_bar_on_a_terminal():
    """`plan --all` on a terminal: a bar of the certificates that ends at the count of roots. The command line shows
    a bar only after 5 s of work (checked: the delay it asks for); here the bar shows at once
    (:data:`_AT_ONCE`), so that a list of tens of roots (k = 4, n = 2) shows it instead of thousands
    certified for more than 5 s."""
    require_c_search()
    code, err, out = _run_on_a_terminal(["plan", "--to", "0", "1", "--k", "4", "--steps", "2", "--all"])
    assert code == 0, err
    assert out.splitlines()[0] == "delay 5.0", out[:200]
    listed = re.search(r"all plans: (\d+)", err) or re.search(r"certify \(k = 4, (\d+) roots\)", err)
    assert listed, err[-2000:]
    n = listed.group(1)
    bars = [line for line in err.replace("\r", "\n").splitlines() if line.startswith(f"certify (k = 4, {n} roots)")]
    assert len(bars) >= 2 and "%|" in bars[0] and f"{n}/{n}" in bars[-1], bars[-3:]


def test_two_threads_certify_as_one():
    """certify_roots with two threads (the second on its own instance of the C library, a copy of the file loaded
    again) gives exactly the certificates of one thread, in the same order."""
    require_c_search()
    roots = compiled_search.listed_roots(0.3, -0.2, 0.5, 2, 1.5)
    assert len(roots) >= 10
    one = compiled_search.certify_roots(roots, 0.3, -0.2, 0.5, 2, 1.5, threads=1)
    two = compiled_search.certify_roots(roots, 0.3, -0.2, 0.5, 2, 1.5, threads=2)
    assert two == one and all(c.residual + c.bound <= 1e-9 for c in one)
    second = compiled_search._second_certify()
    assert second is not None and second[0]._handle != ctypes.CDLL(compiled_search.library().path)._handle
