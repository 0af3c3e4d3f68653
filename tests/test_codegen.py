"""Generated C library (rollplan.codegen): compiled with gcc, compared with its symbolic twins and
independent references."""

from __future__ import annotations

import re
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest

from rollplan import codegen
from rollplan.cli import main
from rollplan.codegen.c_library import TABLE_STEPS_PER_LEAF, generated_functions, reference_plan, table_radii
from rollplan.core import model
from rollplan.core.curves import figure_eight
from rollplan.core.integrate import CvodesIntegrator, spectral_step

import references

pytestmark = pytest.mark.skipif(shutil.which("make") is None or shutil.which("cc") is None,
                                reason="needs make and a C compiler")

STEPS = codegen.DEFAULT_STEPS_PER_LEAF
DEGREE = STEPS // (len(figure_eight().pieces[0].breaks) - 1)


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    out = tmp_path_factory.mktemp("c") / "planner"
    g = codegen.generate(out)
    run = subprocess.run(["make", "-C", str(out), "plan_demo", "librollplan.so"], check=False, capture_output=True,
                         text=True)
    assert run.returncode == 0, run.stderr
    return g


@pytest.fixture(scope="module")
def twins():
    return {f.name(): f for f in generated_functions()}


def external(built, name):
    return ca.external(name, str(built.out / "librollplan.so"))


def demo(built, *args):
    return subprocess.run([str(built.out / "plan_demo"), *map(str, args)], check=False, capture_output=True, text=True)


def test_build_uses_strict_c99_flags_and_no_malloc(built):
    makefile = (built.out / "Makefile").read_text()
    assert "-std=c99 -Wall -Wextra -Werror -O2" in makefile
    assert (built.out / "plan_demo").exists()
    for path in built.out.glob("*.c"):
        assert not re.search(r"\b(malloc|calloc|realloc|free)\s*\(", path.read_text()), path
    assert built.code_bytes == sum(p.stat().st_size for p in built.out.glob("*.[ch]"))


def _values(f, args):
    return [np.array(x) for x in f.call(list(args))]


@pytest.mark.parametrize("name", ["rollplan_omega_z", "rollplan_rotor_rates", "rollplan_montana"])
def test_model_functions_match_symbolic_twin(built, twins, name):
    rng = np.random.default_rng(1)
    c_fun, twin = external(built, name), twins[name]
    for _ in range(5):
        args = [rng.uniform(-1, 1, twin.size1_in(i)) for i in range(twin.n_in())]
        args = [a + 2.0 if twin.name_in(i) in ("j_xx", "j_zz", "j_r", "k") else a for i, a in enumerate(args)]
        for got, want in zip(_values(c_fun, args), _values(twin, args)):
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-14)
        # Jacobian of the compiled function by central differences against the symbolic Jacobian
        ins = twin.mx_in()
        out = twin(*ins)
        for i in range(twin.n_in()):
            jac = np.array(ca.Function("j", ins, [ca.jacobian(out, ins[i])])(*args))
            fd = np.zeros_like(jac)
            for j in range(twin.size1_in(i)):
                hi, lo = [x.copy() for x in args], [x.copy() for x in args]
                hi[i][j] += 1e-6
                lo[i][j] -= 1e-6
                fd[:, j] = (np.array(c_fun(*hi)) - np.array(c_fun(*lo))).ravel() / 2e-6
            np.testing.assert_allclose(fd, jac, rtol=1e-6, atol=1e-7)


def test_omega_z_satisfies_realizability(built):
    """Independent identity: the generated spin makes the left side of (13) vanish."""
    f = external(built, "rollplan_omega_z")
    rng = np.random.default_rng(2)
    for _ in range(5):
        wxy, (u, v, psi), k = rng.uniform(-1, 1, 2), rng.uniform(-1, 1, 3), rng.uniform(0, 5)
        wz = float(f(wxy, u, v, psi, k))
        assert abs(float(model.realizability_residual(ca.DM([*wxy, wz]), u, v, psi, k))) < 1e-13


def test_rotor_rates_invert_omega_from_rotor_rates(built):
    """Independent identity: (11) solved for omega and mapped back gives the rotor rates."""
    f = external(built, "rollplan_rotor_rates")
    rng = np.random.default_rng(3)
    for _ in range(5):
        phi_dot, (u, v, psi) = rng.uniform(-5, 5, 2), rng.uniform(-1, 1, 3)
        j_xx, j_zz, j_r = 3.0, 1.2, 0.1
        w = model.omega_from_rotor_rates(ca.DM(phi_dot), u, v, psi, j_xx, j_zz, j_r)
        np.testing.assert_allclose(np.array(f(w, u, v, psi, j_xx, j_zz, j_r)).ravel(), phi_dot, rtol=1e-12)


POINTS = [(0.3, 0.2, 2.5), (0.69, 0.69, 2.5), (0.1, 0.5, 0.0), (0.5, 0.69, 5.0), (0.05, 0.6, 1.0)]


def test_step_map_matches_twin_and_foundation(built, twins):
    step, step_jac = external(built, "rollplan_step"), external(built, "rollplan_step_jac")
    ref = spectral_step(figure_eight(), DEGREE)   # same quadrature, unrolled SX implementation
    ab, k = ca.SX.sym("ab", 2), ca.SX.sym("k")
    xf = ref(ca.DM.zeros(3), ab, k, 0)
    ref_jac = ca.Function("rj", [ab, k], [xf, ca.jacobian(xf, ab)])
    for a, b, kk in POINTS:
        c_out = _values(step, ([a, b], kk))
        for got, want in zip(c_out, _values(twins["rollplan_step"], ([a, b], kk))):
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-13)
        cj = _values(step_jac, ([a, b], kk))
        for got, want in zip(cj, _values(twins["rollplan_step_jac"], ([a, b], kk))):
            np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-12)
        x, jac = (np.array(v) for v in ref_jac([a, b], kk))
        np.testing.assert_allclose(np.concatenate([c_out[0].ravel(), c_out[1].ravel()]), x.ravel(), atol=1e-12)
        np.testing.assert_allclose(cj[3][:3], jac, rtol=1e-9, atol=1e-10)
        assert abs(c_out[2].item() - np.arctan2(x[1, 0], x[0, 0])) < 1e-12
        # direction row of the Jacobian by finite differences of the compiled step map
        for col, e in enumerate(np.eye(2) * 1e-6):
            hi, lo = (float(step(np.array([a, b]) + s * e, kk)[2]) for s in (1, -1))  # direction
            assert abs((hi - lo) / 2e-6 - cj[3][3, col]) < 1e-5 * (1 + abs(cj[3][3, col]))


def test_step_map_matches_cvodes(built):
    """Independent integrator: the default steps per leaf are accurate to 1e-9 for k <= 5."""
    step = external(built, "rollplan_step")
    cv = CvodesIntegrator(figure_eight(), reltol=1e-13, abstol=1e-14)
    ints = cv.integrators(1)
    for a, b, k in POINTS:
        _, xs = cv.trace([a, b], k, 0.0, 1, integrators=ints)
        shift, eta, _ = _values(step, ([a, b], k))
        np.testing.assert_allclose([*shift.ravel(), eta.item()], xs[-1], atol=1e-9)


def test_leaf_table_matches_twin_and_single_leaves(built, twins):
    table = external(built, "rollplan_leaf_table")
    got = _values(table, (2.5,))
    for g, w in zip(got, _values(twins["rollplan_leaf_table"], (2.5,))):
        np.testing.assert_allclose(g, w, rtol=1e-13, atol=1e-13)
    radii = table_radii()
    degree = TABLE_STEPS_PER_LEAF // (len(figure_eight().pieces[0].breaks) - 1)
    for i in range(2):
        leaf = spectral_step(figure_eight(), degree, pieces=(i,))
        for j in (0, len(radii) // 2, len(radii) - 1):
            p = [radii[j], radii[j]]
            np.testing.assert_allclose(got[i][:, j], np.array(leaf(ca.DM.zeros(3), p, 2.5, 0)).ravel(), atol=1e-12)


TARGETS = [(0.0, 1.0, 0.0, 1, 2.5), (0.3, -0.2, 0.5, 1, 2.5), (2.0, 1.0, 1.0, 3, 2.5)]
SLOW_TARGETS = [(0.5, 0.5, -2.0, 2, 2.5), (0.0, 1.0, 0.0, 1, 0.0), (-0.4, 0.8, 0.3, 1, 1.5), (1.0, 0.5, 0.2, 2, 4.0),
                (0.0, 2.8, 0.0, 1, 2.5), (1.0, 2.0, 0.3, 1, 2.5),   # leaves near A_MAX
                (1.5, 0.0, 0.0, 3, 2.5)]                            # psi = 0, n > 1: the limit h_des / n (34)


def _check_plan(built, planner, target):
    u, v, psi, n, k = target
    run = demo(built, u, v, psi, n, k)
    assert run.returncode == 0, run.stderr
    a, b, gamma, residual = (float(x) for x in run.stdout.split())
    assert residual < 1e-10
    # exact when integrated accurately (CVODES, independent of the step map)
    final = planner.certifier.final(a, b, k, gamma, n)
    err = [final.u_a - u, final.v_a - v, float(references.wrap(final.psi - psi)), final.u_o, final.v_o]
    assert np.linalg.norm(err) < 1e-7
    # and by the printed (28)-(30) integrated by DOP853
    x = references.trace(a, b, k, gamma, n)
    assert np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)]) < 1e-7
    # the same plan as the Python planner on branch m = 0
    q = reference_plan((u, v, psi), n, k, near=(a, b))
    assert q is not None and q.branch == 0, "Python planner found no plan on branch m = 0"
    assert max(abs(q.a - a), abs(q.b - b), abs(float(references.wrap(q.gamma - gamma)))) < 1e-8


@pytest.mark.parametrize("target", TARGETS)
def test_plan_demo_matches_python_plan(built, planner, target):
    _check_plan(built, planner, target)


@pytest.mark.slow
@pytest.mark.parametrize("target", SLOW_TARGETS)
def test_plan_demo_matches_python_plan_more(built, planner, target):
    _check_plan(built, planner, target)


def test_plan_demo_reproduces_paper_radius(built):
    """Paper, Section IV: k = 2.5, h/R = 1 has the smallest solution a1 = 0.300429 R (a = b, n = 1)."""
    run = demo(built, 0, 1, 0, 1, 2.5)
    a, b = (float(x) for x in run.stdout.split()[:2])
    assert abs(a - 0.300429) < 5e-7 and abs(b - 0.300429) < 5e-7


@pytest.mark.parametrize("args, status", [
    (("x", 1, 0, 1, 2.5), 2), ((0, 1, 0, 0, 2.5), 2), ((0, 1, 0, 1.5, 2.5), 2), ((0, 1, 0, 1, -1), 2),
    ((0, 0, 0, 1, 2.5), 2), ((0, 1, 0, 1), 2), ((0, 1, "nan", 1, 2.5), 2),
    ((30, 0, 0, 1, 2.5), 3),        # farther than any figure eight reaches in one step
    ((0, 1, 6.2, 2, 2.5), 3),       # sin(psi/2) small: branch m = 0 needs h = 24 R
])
def test_plan_demo_reports_bad_input_and_no_plan(built, args, status):
    run = demo(built, *args)
    assert run.returncode == status
    assert run.stdout == "" and run.stderr.count("\n") == 1


def test_cli_codegen(tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path / "c"), "--prefix", "rp", "--steps-per-leaf", "100"]) == 0
    assert (tmp_path / "c" / "rp.h").exists() and (tmp_path / "c" / "rp_model.c").exists()
    assert "bytes" in capsys.readouterr().out
    assert main(["codegen", "--out", str(tmp_path / "d"), "--steps-per-leaf", "33"]) == 2
    assert main(["codegen", "--out", str(tmp_path / "d"), "--prefix", "9x"]) == 2
    assert not (tmp_path / "d").exists()   # a refused run leaves no empty folder behind
    assert main(["codegen", "--out", str(tmp_path / "no" / "such")]) == 2
    assert "not allowed" in capsys.readouterr().err


def test_plan_demo_no_convergence_is_nonzero(built):
    """k = 5, h = 2.8 R in one step: the coarse table brackets cells, but branch m = 0 has no root
    (the Python planner finds none either); the demo says so and exits with 4."""
    run = demo(built, 2, 2, 0, 1, 5)
    assert run.returncode == 4 and run.stdout == "" and "no convergence" in run.stderr
    assert reference_plan((2.0, 2.0, 0.0), 1, 5.0) is None


@pytest.mark.slow
def test_generated_prefix_builds_and_plans(tmp_path):
    out = tmp_path / "rp"
    codegen.generate(out, 160, "rp")
    run = subprocess.run(["make", "-C", str(out)], check=False, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert (out / "librp.a").exists()
    run = subprocess.run([str(out / "plan_demo"), "0", "1", "0", "1", "2.5"], check=False, capture_output=True,
                         text=True)
    a, b = (float(x) for x in run.stdout.split()[:2])
    assert abs(a - 0.300429) < 5e-7 and abs(b - 0.300429) < 5e-7
