"""The speed-ups of issue 7 keep the numbers: bracketing, Adams verification, one-pass spectral map."""

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from rollplan.curves import A_MAX, figure_eight
from rollplan.geometric import GeometricPhasePlanner, _target_shift, _rot
from rollplan.integrate import CvodesIntegrator, spectral_step

from printed_rhs import trace

CASES = [(0.3, 0.3, 2.5, 0.1, 1), (A_MAX, A_MAX, 2.5, -1.0, 1), (A_MAX, 0.05, 10.0, 2.0, 2), (0.5, 0.2, 0.0, 0.3, 3),
         (0.12, 0.61, 5.0, -2.5, 1)]


@pytest.fixture(scope="module")
def planner():
    return GeometricPhasePlanner()


def _err(x, ref):
    e = np.asarray(x[:3], float) - ref
    e[2] = (e[2] + np.pi) % (2 * np.pi) - np.pi
    return np.abs(e).max()


@pytest.mark.parametrize("a,b,k,gamma,steps", CASES)
def test_adams_verifier_matches_scipy(planner, a, b, k, gamma, steps):
    ref = trace(a, b, k, gamma, steps)
    assert _err(planner.verify(a, b, k, gamma, steps), ref) < 2e-10


def test_bdf_still_available_and_agrees():
    curve = figure_eight()
    bdf = CvodesIntegrator(curve, 1e-13, 1e-14, multistep="bdf")
    adams = CvodesIntegrator(curve, 1e-13, 1e-14)
    for a, b, k, gamma, steps in CASES[:3]:
        x1 = bdf.trace([a, b], k, gamma, steps)[1][-1]
        x2 = adams.trace([a, b], k, gamma, steps)[1][-1]
        assert np.abs(x1 - x2).max() < 2e-10


@pytest.mark.parametrize("a,b,k,gamma,steps", CASES)
def test_one_pass_spectral_step_matches_scipy(a, b, k, gamma, steps):
    f = spectral_step(figure_eight())
    x = np.zeros(3)
    for _ in range(steps):
        x = np.array(f(x, [a, b], k, gamma)).ravel()
    assert _err(x, trace(a, b, k, gamma, steps)) < 1e-11


def _brackets_full_grid(planner, k, h_des, psi, steps):
    """The bracketing test applied to every cell of the grid (the foundation's algorithm, written out)."""
    t = planner._leaf_tables(k)
    r, d0, eta0, d1, eta1 = t[0], t[1:3], t[3], t[4:6], t[6]
    eta = eta0[:, None] + eta1[None, :]
    shift = _rot(eta0, d0)[:, :, None] + d1[:, None, :]
    h = np.hypot(shift[0], shift[1])
    rows = []
    n = r.size - 1
    corners = lambda z: np.stack([z[:-1, :-1], z[1:, :-1], z[:-1, 1:], z[1:, 1:]])
    ec, hc = corners(eta), corners(h)
    emin, emax, hmin, hmax = ec.min(0), ec.max(0), hc.min(0), hc.max(0)
    for i in range(n):
        lo = np.ceil((steps * emin[i] - psi) / (2 * np.pi)).astype(int)
        hi = np.floor((steps * emax[i] - psi) / (2 * np.pi)).astype(int)
        for j in np.nonzero(hi >= lo)[0]:
            for m in range(lo[j], hi[j] + 1):
                eta_m = (psi + 2 * np.pi * m) / steps
                h_m = float(_target_shift(h_des, eta_m, steps))
                if np.isfinite(h_m) and hmin[i, j] <= h_m <= hmax[i, j]:
                    rows.append((r[i] + r[j], i * n + j, m))
    rows.sort(key=lambda x: (x[0], x[1], x[2]))
    return [(c, m) for _, c, m in rows]


@pytest.mark.parametrize("k,h_des,psi,steps", [(0.0, 1.0, 0.0, 1), (1.0, 0.7, 0.4, 2), (2.5, 1.3, -2.0, 3),
                                                (2.5, 0.2, 3.0, 1)])
def test_bracket_index_finds_the_same_cells_as_the_full_grid(planner, k, h_des, psi, steps):
    br = planner._brackets(k, h_des, psi, steps)
    r = planner._leaf_tables(k)[0]
    n = r.size - 1
    ii = np.searchsorted(r, br[:, 1]) - 1
    jj = np.searchsorted(r, br[:, 2]) - 1
    got = list(zip((ii * n + jj).tolist(), br[:, 5].astype(int).tolist()))
    assert got == _brackets_full_grid(planner, k, h_des, psi, steps)


@pytest.mark.slow
def test_benchmark_script_runs(tmp_path):
    script = Path(__file__).resolve().parent.parent / "scripts" / "benchmark.py"
    subprocess.run([sys.executable, str(script), "--quick", "--no-jit", "--no-cold",
                    "--out-dir", str(tmp_path)], check=True, capture_output=True, timeout=600)
    text = (tmp_path / "benchmarks.md").read_text()
    assert "evaluations/s" in text and "commit" in text and "speed-up" in text and "Profile" in text
    assert "## Budgets" in text and "Collocation planner" in text and "C planner" in text
    assert "load average at start" in text
    assert (tmp_path / "benchmarks.json").stat().st_size > 0
