"""Generated C library (rollplan.codegen): compiled with gcc, compared with its symbolic twins and
independent references."""

from __future__ import annotations

import contextlib
import ctypes
import math
import re
import shutil
import subprocess

import casadi as ca
import numpy as np
import pytest
from conftest import one_line
from conftest import run as run_cli
from scipy.optimize import brentq, minimize_scalar
from test_enumerate import b_of, leaf_gap, repeated

from rollplan import Problem, codegen
from rollplan.cli import main
from rollplan.codegen.c_library import (
    CERT_TOL,
    DEFAULT_K_MAX,
    FLOAT_CERT_TOL,
    PSI_MAX,
    certificate_functions,
    generated_functions,
)
from rollplan.core import model
from rollplan.core.curves import A_MAX, figure_eight
from rollplan.core.integrate import CvodesIntegrator, spectral_step
from rollplan.core.rewrite import algebraic
from rollplan.errors import InputError, NoPlanError
from rollplan.inputs import show_path
from rollplan.planners.geometric import GeometricPhasePlanner

import references
from reference_enumerate import ReferencePlanner, reference_plan

pytestmark = pytest.mark.skipif(shutil.which("make") is None or shutil.which("cc") is None,
                                reason="needs make and a C compiler")

STEPS = codegen.DEFAULT_STEPS_PER_LEAF
DEGREE = STEPS // (len(figure_eight().pieces[0].breaks) - 1)


@pytest.fixture(scope="module")
def built(generated_c):
    run = subprocess.run(["make", "-C", str(generated_c.out), "plan_demo", "librollplan.so"], check=False,
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return generated_c


@pytest.fixture(scope="module")
def twins():
    return {f.name(): f for f in generated_functions()}


#: A compiler in front of the real one (argv: real compiler, object store, the compiler's arguments): a compile of
#: one C file (``-c -o OUT FILE.c``) whose compiler, arguments, file and headers of its folder were compiled before
#: gets the stored object (and the ``.su`` of -fstack-usage); any other call, and a compile that wrote to stderr
#: or failed, runs the real compiler alone and is not stored.
_OBJECT_CACHE_CC = """import hashlib, os, shutil, subprocess, sys
real, store, args = sys.argv[1], sys.argv[2], sys.argv[3:]
sources = [a for a in args if a.endswith(".c")]
if "-c" not in args or "-o" not in args or len(sources) != 1:
    sys.exit(subprocess.run([real, *args]).returncode)
out, source = args[args.index("-o") + 1], sources[0]
key = hashlib.sha256(subprocess.run([real, "--version"], capture_output=True).stdout)
for a in args:
    key.update((os.path.basename(a) if a == out else a).encode() + b"\\0")
folder = os.path.dirname(os.path.abspath(source))
for name in sorted(os.listdir(folder)):
    if name.endswith(".h") or name == os.path.basename(source):
        with open(os.path.join(folder, name), "rb") as fh:
            key.update(name.encode() + b"\\0" + fh.read() + b"\\0")
kept = os.path.join(store, key.hexdigest())
su = os.path.splitext(out)[0] + ".su"
if os.path.exists(kept + ".o"):
    if os.path.exists(kept + ".su"):
        shutil.copyfile(kept + ".su", su)
    shutil.copyfile(kept + ".o", out)
    sys.exit(0)
run = subprocess.run([real, *args], stderr=subprocess.PIPE)
sys.stderr.buffer.write(run.stderr)
if run.returncode == 0 and not run.stderr:
    for made, ext in ((su, ".su"), (out, ".o")):
        if os.path.exists(made):
            shutil.copyfile(made, kept + f".{os.getpid()}{ext}")
            os.replace(kept + f".{os.getpid()}{ext}", kept + ext)
sys.exit(run.returncode)
"""


def object_store_tools() -> dict:
    """The make variables that put the object store of the run's cache directory (``ROLLPLAN_CACHE_DIR``: the
    run-to-run build cache of this package content, or a fresh one) in front of the host compiler (``CC``) and the
    ARM cross compiler (``ARM``, a prefix): an object that an earlier build compiled from the same compiler, flags and
    sources is copied instead of compiled again (:data:`_OBJECT_CACHE_CC`)."""
    import os
    import sys
    from pathlib import Path

    root = Path(os.environ["ROLLPLAN_CACHE_DIR"]) / "test-object-cache"
    (root / "objects").mkdir(parents=True, exist_ok=True)
    script = root / "cc.py"
    if not script.exists() or script.read_text() != _OBJECT_CACHE_CC:
        script.with_suffix(f".{os.getpid()}").write_text(_OBJECT_CACHE_CC)
        script.with_suffix(f".{os.getpid()}").replace(script)
    tools = root / "bin"
    tools.mkdir(exist_ok=True)
    front = {"cc": shutil.which("cc"), "arm-none-eabi-gcc": shutil.which("arm-none-eabi-gcc")}
    for name, real in front.items():
        if real and not (tools / name).exists():
            tmp = tools / f".{name}.{os.getpid()}"
            tmp.write_text(f"#!/bin/sh\nexec {sys.executable} {script} {real} {root / 'objects'} \"$@\"\n")
            tmp.chmod(0o755)
            tmp.replace(tools / name)
    for name in ("ar", "nm", "size", "objdump"):
        real = shutil.which(f"arm-none-eabi-{name}")
        if real and not (tools / f"arm-none-eabi-{name}").exists():
            with contextlib.suppress(FileExistsError):
                (tools / f"arm-none-eabi-{name}").symlink_to(real)
    return {"CC": str(tools / "cc"), **({"ARM": f"{tools}/arm-none-eabi-"} if front["arm-none-eabi-gcc"] else {})}


def make(*argv, **kwargs):
    """``subprocess.run(["make", *argv])`` (text output captured, no check) with the host and ARM compilers behind
    the run's object store (:func:`object_store_tools`). The Makefile's rules, flags, links and checks run as they
    are."""
    tools = object_store_tools()
    return subprocess.run(["make", *(f"{k}={v}" for k, v in tools.items()), *argv], capture_output=True, text=True,
                          check=False, **kwargs)


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


@pytest.mark.parametrize("name", ["rollplan_omega_z", "rollplan_rotor_rates", "rollplan_montana", "rollplan_rhs0",
                                  "rollplan_rhs1", "rollplan_rk8_0", "rollplan_rk8_1"])
def test_model_functions_match_symbolic_twin(built, twins, name):
    rng = np.random.default_rng(1)
    c_fun, twin = external(built, name), twins[name]
    for _ in range(5):
        args = [rng.uniform(-1, 1, twin.size1_in(i)) for i in range(twin.n_in())]
        args = [a + 2.0 if twin.name_in(i) in ("j_xx", "j_zz", "j_r", "k") else a for i, a in enumerate(args)]
        args = [0.3 + 0.3 * a if twin.name_in(i) == "p" else a for i, a in enumerate(args)]   # leaf radii
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


def test_algebraic_form_of_the_certificate_is_the_piece_rhs():
    """The certificate's right side in algebraic form (no trig of inverse trig) against the curve ODE
    (28)-(30) as the model writes it, and against the printed equations."""
    from rollplan.core.integrate import DOP853_C, piece_rhs, rk8_step

    curve = figure_eight()
    rng = np.random.default_rng(4)
    for i, f in enumerate(certificate_functions()[:2]):
        ops = {f.instruction_id(j) for j in range(f.n_instructions())}
        assert not ops & {ca.OP_ASIN, ca.OP_ATAN2, ca.OP_TAN}
        plain = piece_rhs(curve, i)
        for _ in range(5):
            phi, x, p, k, gamma = rng.uniform(0, 6.28), rng.uniform(-1, 1, 3), rng.uniform(0.01, A_MAX, 2), \
                rng.uniform(0.5, 5), rng.uniform(-3, 3)
            got = np.array(f(phi, x, p, k, gamma)).ravel()
            np.testing.assert_allclose(got, np.array(plain(phi, x, p, k, gamma)).ravel(), rtol=1e-13, atol=1e-14)
    # the RK8 steps take cos and sin of phi at the stages and of gamma: the step of rk8_step of the plain right side
    for i, step in enumerate(certificate_functions()[2:4]):
        ref = rk8_step(piece_rhs(curve, i))
        for _ in range(3):
            t, h, x, p, k, gamma = rng.uniform(0, 6.28), rng.uniform(0.01, 0.5), rng.uniform(-1, 1, 3), \
                rng.uniform(0.01, A_MAX, 2), rng.uniform(0.5, 5), rng.uniform(-3, 3)
            phis = t + h * np.array(DOP853_C)
            got = np.array(step(x, np.cos(phis), np.sin(phis), h, p, k, np.cos(gamma), np.sin(gamma))).ravel()
            np.testing.assert_allclose(got, np.array(ref(x, t, h, p, k, gamma)).ravel(), rtol=1e-13, atol=1e-14)
    # the turn rates that set the certificate's steps: psi' of the plain right side at k = 0 and at k, at rest
    for i, rates in enumerate(certificate_functions()[4:6]):
        plain = piece_rhs(curve, i)
        for _ in range(3):
            phi, p, k, gamma = rng.uniform(0, 6.28), rng.uniform(0.01, A_MAX, 2), rng.uniform(0.5, 5), \
                rng.uniform(-3, 3)
            want = [float(plain(phi, np.zeros(3), p, kk, gamma)[2]) for kk in (0.0, k)]
            got = np.array(rates(np.cos(phi), np.sin(phi), p, k, np.cos(gamma), np.sin(gamma))).ravel()
            np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-14)
    g = ca.Function("g", [y := ca.SX.sym("y"), z := ca.SX.sym("z")],
                    [ca.cos(ca.atan2(y, z)) + ca.tan(ca.asin(y / 3)) * ca.sin(ca.atan2(y, z))])
    h = algebraic(g)
    assert not {h.instruction_id(j) for j in range(h.n_instructions())} & {ca.OP_ASIN, ca.OP_ATAN2, ca.OP_TAN}
    for y0, z0 in ((0.3, -0.7), (-1.2, 0.4), (2.0, 2.0)):
        t = np.arctan2(y0, z0)
        assert abs(float(h(y0, z0)) - (np.cos(t) + np.tan(np.arcsin(y0 / 3)) * np.sin(t))) < 1e-14


TARGETS = [(0.0, 1.0, 0.0, 1, 2.5), (0.3, -0.2, 0.5, 1, 2.5), (2.0, 1.0, 1.0, 3, 2.5)]
SLOW_TARGETS = [(0.5, 0.5, -2.0, 2, 2.5), (0.0, 1.0, 0.0, 1, 0.5), (-0.4, 0.8, 0.3, 1, 1.5), (1.0, 0.5, 0.2, 2, 4.0),
                (0.0, 2.8, 0.0, 1, 2.5), (1.0, 2.0, 0.3, 1, 2.5),   # leaves near A_MAX
                (1.5, 0.0, 0.0, 3, 2.5),                            # psi = 0, n > 1: the limit h_des / n (34)
                (0.1, -0.3, 3.0, 2, 5.0), (0.0, 1.0, 3.0, 1, 5.0),  # the examples (k = 10 is above K_MAX)
                (0.0621, 0.0847, 2.4915, 5, 2.5), (-0.2724, 0.1488, -2.9291, 3, 2.5), (0.3, 0.2, 20.0, 2, 3.0),
                (-0.017225508301479647, 0.0249278638274345, 20.41012902950338, 5, 0.5),   # b near A_MAX, k = 1/2
                (-0.32010604239559476, 0.45238485573887033, -28.48818775189438, 6, 1.5)]  # rejected root after a plan


def _parse(run):
    a, b, gamma, residual, bound, m = run.stdout.split()
    return float(a), float(b), float(gamma), float(residual), float(bound), int(m)


def _same_plan(c, q):
    """C plan (a, b, gamma, ..., m) and Python plan q: the same branch and (a, b, gamma) to 1e-8. gamma turns the
    n-step shift onto the target, so for a target closer than 1 R it is compared by the arrival it sets,
    |target| |d gamma| (for a target at 1e-7 R, radii equal to 1e-15 give gammas 4e-8 apart, both exact)."""
    scale = min(1.0, float(np.hypot(q.problem.goal.u_a, q.problem.goal.v_a)))
    turn = abs(float(references.wrap(q.gamma - c[2]))) * scale
    gap = max(abs(q.a - c[0]), abs(q.b - c[1]), turn)
    return c[5] == q.branch and gap < 1e-8


def _check_plan(built, planner, target, branch=None):
    u, v, psi, n, k = target
    run = demo(built, u, v, psi, n, k, *(() if branch is None else (branch,)))
    assert run.returncode == 0, run.stderr
    c = _parse(run)
    a, b, gamma, residual, bound, m = c
    assert residual + bound <= 1e-9 and (branch is None or m == branch)
    # exact when integrated accurately (CVODES, independent of both planners' leaf maps)
    final = planner.certifier.final(a, b, k, gamma, n)
    err = [final.u_a - u, final.v_a - v, float(references.wrap(final.psi - psi)), final.u_o, final.v_o]
    assert np.linalg.norm(err) < 1e-9
    # and by the printed (28)-(30) integrated by DOP853
    x = references.trace(a, b, k, gamma, n)
    assert np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)]) < 1e-9 + 1e-11 * n
    # the same plan as the Python planner: the shortest over all branches, or the one of the branch asked for
    q = reference_plan((u, v, psi), n, k, branch=branch)
    assert q is not None and _same_plan(c, q), (c, q and (q.a, q.b, q.gamma, q.branch))


@pytest.mark.parametrize("target", TARGETS)
def test_plan_demo_matches_python_plan(built, planner, target):
    _check_plan(built, planner, target)


@pytest.mark.slow
@pytest.mark.parametrize("target", SLOW_TARGETS)
def test_plan_demo_matches_python_plan_more(built, planner, target):
    _check_plan(built, planner, target)


@pytest.mark.parametrize("target, branch", [((0.1, -0.3, 3.0, 2, 5.0), -2), ((0.0, 1.0, 0.0, 1, 2.5), -1),
                                            ((0.3, 0.2, 20.0, 2, 3.0), -5)])
def test_plan_demo_on_a_branch_matches_python(built, planner, target, branch):
    _check_plan(built, planner, target, branch)


# found by an independent review: small shifts, roots near A_MAX, tangencies of the C table that are no roots
REVIEW_PLANS = [((0.0009285391486776204, -0.0006994135967995514, -0.04186188760954446, 3, 0.7736122083112522), None),
                ((0.0, 1e-7, 0.0, 1, 2.5), -1), ((0.0, 1e-7, 0.0, 1, 2.5), -3), ((0.0, 1e-7, 0.0, 1, 2.5), -5),
                # the shortest plan at a = b = 0.0166 (Python's numpy search once lost it: a table tangency at a = 0)
                ((0.0009695511170914938, -0.0006893752926909919, 1.0268242372426444e-06, 5, 3.111167772746886), None),
                # a table tangency at a = 1.7e-14 polished into no root; the branch's next root is its first real one
                ((-1.85929096078532e-06, 1.0656708586409496e-06, 1.2970035739289984e-05, 4, 0.6605612544811826), None),
                ((0.00010992864487406656, 0.00013240113551447741, -5.394669467275043e-09, 4, 4.461494692913729), None),
                # one leaf of 6.7e-7 to 1.5e-5 R: the accurate g has the other sign on the whole tangency of the table,
                # the root is beyond it (outward); a table root 8e-6 off, where Newton overshoots (bracketed)
                ((-0.19774984652120803, 0.21937835536955066, -1.6527334493900014, 4, 4.059753730381), None),
                ((0.014448772925918646, 0.7212378574110099, 2.440174018234638, 6, 2.018660631794008), -1),
                ((-0.5091073505949908, -0.16823626107740713, -1.3412188729766725, 2, 1.7705457308787267), 0),
                ((-0.0015830671749122464, 0.008561782905277567, -2.7727023192855853, 4, 2.2192607383692886), None),
                # the shorter of a close pair just past a fold, below the table's tangency
                ((0.19438362775550225, -0.07499852746717327, -0.47758477038764546, 6, 2.0319688742180233), 3),
                # one leaf of 4.5e-7 to 1.8e-6 R, where |g| is within the table's floor at the cell's end: the accurate
                # map's sign there (once missed by C, or by Python)
                ((-0.0004356814508162583, -0.0022958110047663466, -0.03690756050478427, 1, 4.07202986478338), None),
                ((-0.23514667333733408, 0.25769256035036836, -2.1730042745002818, 5, 4.341183060122573), None),
                ((0.6362094470948114, 0.3987371288935435, -2.295412544033408, 1, 3.0086624896465706), None)]
REVIEW_NO_PLANS = [(-0.00018479813435709692, 0.0006503651028485891, 0.09195336625285222, 1, 0.7426881607174539),
                   (-1.5656e-08, 2.8743e-08, -0.79272, 3, 2.2974)]


@pytest.mark.parametrize("target, branch", REVIEW_PLANS)
def test_plan_demo_small_shifts_near_a_max_match_python(built, planner, target, branch):
    """A shift of 1e-3 R or 1e-7 R with roots near A_MAX: the C polish (Newton on |S| - h, not on g = |S|^2 - h^2,
    whose root error grows like 1 / h) gives the exact root, certified, and Python's choice."""
    _check_plan(built, planner, target, branch)


@pytest.mark.parametrize("target", REVIEW_NO_PLANS)
def test_plan_demo_tangency_of_the_table_is_no_plan(built, target):
    """Targets without a plan (Python's numpy search finds no root) where the C table's g has tangencies within its
    error: no plan (exit 3), not a failed certificate (exit 5); uncertified, the C search returns no root either."""
    run = demo(built, *map(repr, target))
    assert run.returncode == 3 and run.stdout == "" and "no plan" in run.stderr, (run.returncode, run.stderr)
    assert reference_plan(target[:3], target[3], target[4]) is None
    clib = ctypes.CDLL(str(built.out / "librollplan.so"))
    plan = _Plan()
    options = _Options(0, 0, 0)
    status = clib.rollplan_plan_with(*(ctypes.c_double(x) for x in target[:3]), ctypes.c_int(target[3]),
                                     ctypes.c_double(target[4]), ctypes.byref(options), ctypes.byref(plan))
    assert status == 3


@pytest.mark.parametrize("target, branch", [((0.1, -0.3, 3.0, 2, 5.0), 0), ((0.3, 0.2, 20.0, 2, 3.0), -6)])
def test_plan_demo_branch_without_plan_agrees_with_python(built, target, branch):
    run = demo(built, *target, branch)
    assert run.returncode == 3 and run.stdout == "" and "no plan" in run.stderr
    assert reference_plan(target[:3], target[3], target[4], branch=branch) is None


@pytest.mark.slow
def test_random_targets_same_plan_as_python(built):
    """Random targets, k in [1/2, K_MAX] (and a few in [0, 1/2), close to the pole, where there are plans): the C
    planner and the Python planner give the same outcome, and where there is a plan, the same branch and
    (a, b, gamma) to 1e-8."""
    rng = np.random.default_rng(11)
    plans = 0
    for i in range(36):
        u, v = rng.uniform(-2, 2, 2)
        psi, n, k = rng.uniform(-4, 4), int(rng.integers(1, 5)), float(rng.uniform(0.5, DEFAULT_K_MAX))
        if i >= 30:
            u, v, psi, k = 0.2 * u, 0.2 * v, 0.1 * psi, float(rng.uniform(0.0, 0.5))
        run = demo(built, repr(float(u)), repr(float(v)), repr(float(psi)), n, repr(k))
        q = reference_plan((u, v, psi), n, k)
        assert (run.returncode == 0) == (q is not None), (u, v, psi, n, k, run.stderr)
        if q is not None:
            plans += 1
            assert _same_plan(_parse(run), q), (u, v, psi, n, k)
    assert plans >= 20


def _parse_all(run):
    """The plans of ``plan_demo --all`` (each as _parse gives it) and the count on its last line."""
    lines = run.stdout.splitlines()
    count, word = lines[-1].split()
    assert word == "plans"
    return [_parse(subprocess.CompletedProcess((), 0, line)) for line in lines[:-1]], int(count)


def _reference_all(target):
    """Every certified plan of the numpy reference search (``--all``), shortest first; [] if none."""
    u, v, psi, n, k = target
    try:
        best = ReferencePlanner().solve(Problem((u, v, psi), k=k, steps=n), all_solutions=True)
    except NoPlanError:
        return []
    return [best, *best.alternatives]


def _check_all(built, target, checked=3, traced=None):
    """``plan_demo --all``: as many plans as the numpy search lists, each the same (branch and (a, b, gamma) to
    1e-8), sorted by a + b; the first ``checked`` and the last integrated by DOP853 on the printed equations
    (or, given a list ``traced``, put there as ``(target, plan)`` for :func:`_check_traced`)."""
    u, v, psi, n, k = target
    run = demo(built, "--all", *(repr(float(x)) for x in (u, v, psi)), n, repr(float(k)))
    want = _reference_all(target)
    if not want:
        assert run.returncode == 3 and run.stdout == "" and "no plan" in run.stderr, (target, run.stderr)
        return 0
    assert run.returncode == 0, (target, run.stderr)
    got, count = _parse_all(run)
    assert count == len(got) == len(want), (target, count, len(want))
    lengths = [c[0] + c[1] for c in got]
    assert lengths == sorted(lengths)
    # paired by branch and radii (plans of nearly equal length may come in either order)
    for c, q in zip(sorted(got, key=lambda c: (c[5], c[0], c[1])), sorted(want, key=lambda q: (q.branch, q.a, q.b))):
        assert _same_plan(c, q), (target, c, (q.a, q.b, q.gamma, q.branch))
    mine = []
    for a, b, gamma, residual, bound, _ in got[:checked] + got[-1:]:
        assert residual + bound <= CERT_TOL
        mine.append((target, (a, b, k, gamma, n)))
    if traced is None:
        _check_traced(mine)
    else:
        traced.extend(mine)
    return count


def _check_traced(traced):
    """Each ``(target, plan)`` lands on its target when integrated by DOP853 (all at once, :func:`_traces`)."""
    for ((u, v, psi, n, _), plan), x in zip(traced, _traces([p for _, p in traced])):
        assert np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)]) < 1e-9 + 1e-11 * n, (u, v, psi, plan)


@pytest.mark.parametrize("target", [(0.0, 1.0, 0.0, 1, 2.5),
                                    pytest.param((0.3, -0.2, 0.5, 2, 1.5), marks=pytest.mark.slow),
                                    (0.0, 1.0, 0.0, 1, 0.5), (0.3, 0.2, 0.5, 2, 0.1), (0.3, 0.2, 0.0, 1, 0.45)])
def test_plan_demo_all_lists_the_plans_of_python_all(built, target):
    """plan_demo --all (every root on every branch, certified on board) against the numpy search's --all list; the
    paper's case k = 2.5, h = 1 R has its smallest solution a = b = 0.300429 R first; k < 1/2 (sigma graphs of the
    C search; psi = 0: the branch eta = 0 where E is not monotone)."""
    assert _check_all(built, target) >= 3
    if target == (0.0, 1.0, 0.0, 1, 2.5):
        first = _parse_all(demo(built, "--all", *target))[0][0]
        assert abs(first[0] - 0.300429) < 5e-7 and abs(first[1] - 0.300429) < 5e-7


@pytest.mark.slow
def test_plan_demo_all_random_targets_match_python(built):
    """Random targets, k in [1/2, K_MAX], n in 1..4: the same list of plans as the numpy search. Five of the first six
    draws (950 roots, each certified by the reference): the fifth (n = 3, 552 roots) and the seventh and eighth
    (n = 4, 1374 roots) take no line or branch of rollplan_planner.c that these five do not (gcov)."""
    rng = np.random.default_rng(12)
    listed, traced = 0, []
    for draw in range(6):
        u, v = rng.uniform(-1.5, 1.5, 2)
        target = (float(u), float(v), float(rng.uniform(-4, 4)), int(rng.integers(1, 5)),
                  float(rng.uniform(0.5, DEFAULT_K_MAX)))
        if draw == 4:
            continue
        listed += _check_all(built, target, checked=1, traced=traced) > 0
    _check_traced(traced)
    assert listed >= 4


def test_plan_all_capacity_and_bad_arguments(built):
    """rollplan_plan_all into a smaller array: status TOO_MANY (6), the full count, and the shortest plans of the
    full list; count NULL or a negative capacity are bad input; a target without a plan is NO_PLAN (3)."""
    clib = ctypes.CDLL(str(built.out / "librollplan.so"))
    d = ctypes.c_double
    clib.rollplan_plan_all.argtypes = [d, d, d, ctypes.c_int, d, ctypes.POINTER(_Options), ctypes.POINTER(_Plan),
                                       ctypes.c_int, ctypes.POINTER(ctypes.c_int)]

    def plan_all(target, capacity, count=True):
        plans, n = (_Plan * max(capacity, 1))(), ctypes.c_int(-1)
        status = clib.rollplan_plan_all(*target[:3], target[3], target[4], None, plans, capacity,
                                        ctypes.byref(n) if count else None)
        return status, n.value, [(p.a, p.b, p.gamma, p.m) for p in plans[:max(0, min(n.value, capacity))]]

    target = (0.3, -0.2, 0.5, 2, 1.5)
    status, total, full = plan_all(target, 1000)
    assert status == 0 and total == len(full) >= 3
    status, count, part = plan_all(target, 2)
    assert status == 6 and count == total and part == full[:2]
    assert plan_all(target, 2, count=False)[0] == 2 and plan_all(target, -1)[0] == 2
    assert plan_all((0.0, 0.0, 0.5, 1, 2.5), 4)[0] == 2 and plan_all((0.3, 0.2, 0.5, 1, -0.1), 4)[0] == 2
    assert plan_all((2.0, 2.0, 0.0, 1, 5.0), 4)[:2] == (3, 0)


#: The compiler command of a test build of planner.c: not optimized (a third of the -O2 compile's time); without
#: -ffast-math both compute the same IEEE doubles.
TEST_BUILD = ["cc", "-std=c99", "-O0", "-Wall", "-Wextra", "-Werror"]


@pytest.mark.slow
def test_search_falls_back_to_certifying_every_root(built, tmp_path):
    """The search's fallback: when the shortest root fails its certificate, the search runs again certifying every
    root, so the plan is the shortest certified one. A test build (planner.c with RP_TEST_REJECT_BELOW = L,
    linked with the fixture's objects) rejects every plan with a + b < L: for L just above the shortest plan it
    returns the shortest of the Python planner's certified plans with a + b >= L; for L beyond every plan it
    reports the best rejected root with status NOT_CERTIFIED."""
    target = (0.0, 1.0, 0.0, 1, 2.5)
    best = GeometricPhasePlanner().solve(Problem(target[:3], k=target[4], steps=target[3]), all_solutions=True)
    plans = sorted((best,) + best.alternatives, key=lambda q: q.a + q.b)   # every certified plan of the target
    assert len(plans) >= 2
    cut = plans[0].a + plans[0].b + 1e-6
    out = built.out
    for limit, exe in ((cut, "fallback"), (100.0, "reject_all")):
        subprocess.run([*TEST_BUILD,
                        f"-DRP_TEST_REJECT_BELOW={limit!r}",
                        "-I", str(out), "-o", str(tmp_path / exe), str(out / "plan_demo.o"),
                        str(out / "rollplan_planner.c"), str(out / "rollplan_model.o"), "-lm"], check=True)
    run = subprocess.run([str(tmp_path / "fallback"), *map(str, target)], capture_output=True, text=True, check=False)
    assert run.returncode == 0, run.stderr
    want = min((q for q in plans if q.a + q.b >= cut), key=lambda q: q.a + q.b)
    assert _same_plan(_parse(run), want), (run.stdout, want)
    run = subprocess.run([str(tmp_path / "reject_all"), *map(str, target)], capture_output=True, text=True,
                         check=False)
    assert run.returncode == 5 and "not certified" in run.stderr, (run.returncode, run.stderr)


def test_close_pair_hidden_by_the_table_is_split_in_c(built, tmp_path):
    """The close pair of tests/test_enumerate.py that the table shows as one tangency (k = 5, one step, eta = 0.3,
    h = sqrt(q_min) (1 + 1e-8), two roots 2.4e-8 apart): a test build that rejects every plan shorter than the pair
    makes the C search return the pair's first root, which is brentq's root on the complex step map to 1e-10 (before
    tangency() decided on the accurate map, the C search returned a point between the two, 1.2e-8 away)."""
    k, eta = 5.0, 0.3
    res = minimize_scalar(lambda a: leaf_gap(a, eta, 0.0, k), bounds=(0.5716, 0.5816), method="bounded",
                          options={"xatol": 1e-14})
    h = math.sqrt(res.fun) * (1.0 + 1e-8)
    first = brentq(leaf_gap, res.x - 1e-6, res.x, args=(eta, h, k), xtol=1e-16, rtol=1e-15)
    out = built.out
    limit = first + float(b_of(np.array([first]), eta, k)[0]) - 1e-6
    subprocess.run([*TEST_BUILD, f"-DRP_TEST_REJECT_BELOW={limit!r}",
                    "-I", str(out), "-o", str(tmp_path / "pair"), str(out / "plan_demo.o"),
                    str(out / "rollplan_planner.c"), str(out / "rollplan_model.o"), "-lm"], check=True)
    run = subprocess.run([str(tmp_path / "pair"), repr(h), "0", repr(eta), "1", repr(k), "0"], capture_output=True,
                         text=True, check=False)
    assert run.returncode == 0, run.stderr
    a, b, gamma, residual, bound, m = _parse(run)
    assert m == 0 and abs(a - first) < 1e-10, (a, first)
    x = references.trace(a, b, k, gamma, 1)
    assert np.linalg.norm([x[0] - h, x[1], references.wrap(x[2] - eta)]) < 1e-9


def test_plan_demo_reproduces_paper_radius(built):
    """Paper, Section IV: k = 2.5, h/R = 1 has the smallest solution a1 = 0.300429 R (a = b, n = 1)."""
    run = demo(built, 0, 1, 0, 1, 2.5)
    a, b = (float(x) for x in run.stdout.split()[:2])
    assert abs(a - 0.300429) < 5e-7 and abs(b - 0.300429) < 5e-7


@pytest.mark.parametrize("args, status", [
    (("x", 1, 0, 1, 2.5), 2), ((0, 1, 0, 0, 2.5), 2), ((0, 1, 0, 1.5, 2.5), 2), ((0, 1, 0, 1, -1), 2),
    ((0, 0, 0, 1, 2.5), 2), ((0, 1, 0, 1), 2), ((0, 1, "nan", 1, 2.5), 2),
    ((0, 2, 0, 1, 50), 2), ((0, 1, 0, 1, 5.000001), 2), ((0, 1, 0, 1001, 2.5), 2), ((0, 1, 0, 1, "inf"), 2),
    ((0, 1, 0, 1, -0.01), 2),       # below K_MIN = 0
    ((0, 1, 1e7, 1, 2.5), 2), ((0, 1, 0, 1, 2.5, 0.5), 2), (("--all", 0, 1, 0, 1), 2), (("--all", 0, 0, 0, 1, 2.5), 2),
    (("--all", 2, 2, 0, 1, 5), 3),
    ((30, 0, 0, 1, 2.5), 3),        # farther than any figure eight reaches in one step
    ((0, 1, 6.2, 2, 2.5, 0), 3),    # sin(psi/2) small: branch m = 0 needs h = 24 R
])
def test_plan_demo_reports_bad_input_and_no_plan(built, args, status):
    run = demo(built, *args)
    assert run.returncode == status
    assert run.stdout == "" and run.stderr.count("\n") == 1


@pytest.mark.parametrize("args, needle", [
    (("0", "0x10", "0", "1", "2.5"), "usage"),          # hexadecimal is not a decimal number (strtod reads 16)
    (("0", "1", "0", "1", "1e308"), "K = 1e308"),       # beyond K_MAX: bad input, not "no convergence"
    (("0", "1", "0", "1", "100.5"), f"[0.0, {DEFAULT_K_MAX!r}]"),   # the k range fixed at generation
    (("0", "1", "0", "1", "-0.25"), "K = -0.25"), (("0", "1", "2e6", "1", "2.5"), f"at most {PSI_MAX!r}"),
    (("0", "1", "0", "1001", "2.5"), "[1, 1000]"),
    (("0", "1", "0", "1", "inf"), "usage"), ((" 0", "1", "0", "1", "2.5"), "usage"),
    (("0", "1_0", "0", "1", "2.5"), "usage"), (("0", "1e400", "0", "1", "2.5"), "usage"),
])
def test_plan_demo_reads_numbers_as_rollplan_does(built, args, needle):
    """Regression: plan_demo read "0x10" as 16 and exited 4 for K = 1e308; now the command line's rules."""
    run = demo(built, *args)
    assert run.returncode == 2 and needle in run.stderr and run.stderr.count("\n") == 1 and run.stdout == ""


def test_plan_demo_accepts_exponents(built):
    run = demo(built, "-1e-3", "1e0", "0", "1", "2.5e0")
    assert run.returncode == 0, run.stderr


def test_codegen_limits_and_read_only_targets(tmp_path, capsys):
    """--steps-per-leaf 1e9 (MemoryError) and a 5000-character --prefix (a traceback) are refused in one
    line before anything is written."""
    for argv in (["--steps-per-leaf", "1000000000"], ["--prefix", "a" * 5000]):
        assert main(["codegen", "--out", str(tmp_path / "c"), *argv]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "Traceback" not in err
    assert not (tmp_path / "c").exists()


def test_cli_codegen(tmp_path, capsys):
    assert main(["codegen", "--out", str(tmp_path / "c"), "--prefix", "rp", "--k-max", "2.5"]) == 0
    assert (tmp_path / "c" / "rp.h").exists() and (tmp_path / "c" / "rp_model.c").exists()
    assert "bytes" in capsys.readouterr().out
    assert main(["codegen", "--out", str(tmp_path / "d"), "--steps-per-leaf", "33"]) == 2
    assert main(["codegen", "--out", str(tmp_path / "d"), "--steps-per-leaf", "100"]) == 2   # inaccurate near A_MAX
    with pytest.raises(SystemExit, match="2"):
        main(["codegen", "--out", str(tmp_path / "d"), "--k-max", "nan"])
    assert main(["codegen", "--out", str(tmp_path / "d"), "--prefix", "9x"]) == 2
    assert main(["codegen", "--out", str(tmp_path / "d"), "--prefix", "rollplan_planner"]) == 2
    assert not (tmp_path / "d").exists()   # a refused run leaves no empty folder behind
    assert main(["codegen", "--out", str(tmp_path / "no" / "such")]) == 2
    assert "not allowed" in capsys.readouterr().err


def _codegen(capsys, *argv):
    """``rollplan codegen argv`` in this process (:func:`conftest.run`), as a finished process."""
    code, out, err = run_cli(capsys, "codegen", *argv)
    return subprocess.CompletedProcess(("rollplan", "codegen", *argv), code, out, err)


def _contents(folder):
    return {p.relative_to(folder).as_posix(): (p.read_bytes() if p.is_file() else None) for p in folder.rglob("*")}


def _package_csrc():
    """``{file name: bytes}`` of the C sources of the installed package (``rollplan/csrc``)."""
    from importlib.resources import files

    folder = files("rollplan") / "csrc"
    return {f.name: f.read_bytes() for f in folder.iterdir() if f.name.endswith((".c", ".h"))}


#: The options of :func:`prefixed`'s generation.
PREFIXED = ("--prefix", "rp_2", "--k-max", "16")


@pytest.fixture(scope="module")
def prefixed(tmp_path_factory):
    """`rollplan codegen --prefix rp_2 --k-max 16` (another prefix; the step map sized automatically for a k_max
    above the default) built by its Makefile (``make``: plan_demo and librp_2.a): one build for the tests of the
    prefix, of the automatic size and of the copied C search. ``out`` the folder, ``said`` what the command
    printed."""
    import io
    from types import SimpleNamespace

    out = tmp_path_factory.mktemp("prefixed") / "rp"
    said = io.StringIO()
    with contextlib.redirect_stdout(said):
        assert main(["codegen", "--out", str(out), *PREFIXED]) == 0
    run = make("-C", str(out))
    assert run.returncode == 0, run.stderr
    return SimpleNamespace(out=out, said=said.getvalue())


#: The options of the generation for another curve: those of tests/test_plan_curves.py's Viviani planner, so that
#: the object store of :func:`make` gives one run's second build of these sources the first one's objects.
VIVIANI = ("--curve", "viviani", "--k-max", "6.5")


@pytest.mark.slow
@pytest.mark.parametrize("argv", [(), ("--real", "float"), PREFIXED, VIVIANI])
def test_codegen_copies_the_package_c_search_unchanged(tmp_path, argv, request, capsys):
    """One copy of the C search: the files that `rollplan codegen` writes for it are byte for byte the files of the
    installed package, for a double and a float build, another prefix with a larger step map, and another curve
    (what varies by generation is in the generated rollplan_config.h, which has no template token left); the build
    compiles them as they are. The default and the float generation are the module's builds (codegen.generate,
    which `rollplan codegen` calls with its options), the prefixed one :func:`prefixed`: their plan_demo is made by
    the same Makefile rule."""
    package = _package_csrc()
    assert {"rollplan_planner.c", "rollplan_planner.h"} <= set(package)
    prebuilt = {(): "built", ("--real", "float"): "built_float", PREFIXED: "prefixed"}.get(argv)
    if prebuilt:
        out = request.getfixturevalue(prebuilt).out
    else:
        out = tmp_path / "c"
        r = _codegen(capsys, "--out", str(out), *argv)
        assert r.returncode == 0, r.stderr
    for name, data in package.items():
        assert (out / name).read_bytes() == data, name
        assert b"@" not in re.sub(rb"/\*.*?\*/", b"", data, flags=re.S), name   # no template token in the code
    config = (out / "rollplan_config.h").read_text()
    prefix = argv[argv.index("--prefix") + 1] if "--prefix" in argv else "rollplan"
    assert f"#define RP_NAME(x) {prefix}_##x" in config and "@" not in config
    if not prebuilt:
        run = make("-C", str(out), "plan_demo")
        assert run.returncode == 0, run.stderr
    run = subprocess.run([str(out / "plan_demo"), "0", "1", "0", "1", "2.5"], capture_output=True, text=True,
                         check=False)
    assert run.returncode == 0 and len(run.stdout.split()) == 6, run.stderr


@pytest.mark.slow
def test_codegen_never_overwrites_files_it_did_not_write(tmp_path, capsys):
    """`codegen --out DIR` replaced the user's Makefile and plan_demo.c in DIR without asking. Now a folder that
    holds files codegen did not write (or wrote and were changed since) is refused in one line naming it and
    --overwrite; with --overwrite the files of codegen's names are replaced and the others kept. A folder codegen
    wrote, with the products of its Makefile in it, is generated again without asking."""
    user = tmp_path / "project"
    user.mkdir()
    (user / "Makefile").write_text("all:\n\techo mine\n")
    (user / "plan_demo.c").write_text("int main(void) { return 0; }\n")
    before = _contents(user)
    r = _codegen(capsys, "--out", str(user))
    assert r.returncode == 2 and one_line(r.stderr), r.stderr
    assert show_path(user) in r.stderr and "--overwrite" in r.stderr and "Makefile" in r.stderr
    assert _contents(user) == before
    (user / "notes.txt").write_text("keep me\n")
    r = _codegen(capsys, "--out", str(user), "--overwrite")
    assert r.returncode == 0, r.stderr
    assert "Builds the generated C99 planner" in (user / "Makefile").read_text()
    assert (user / "notes.txt").read_text() == "keep me\n" and (user / "rollplan_model.c").exists()

    fresh = tmp_path / "fresh"
    assert _codegen(capsys, "--out", str(fresh)).returncode == 0
    (fresh / "plan_demo").write_bytes(b"\x7fELF")            # what `make` leaves
    (fresh / "build" / "arm-m7").mkdir(parents=True)
    r = _codegen(capsys, "--out", str(fresh), "--real", "float")
    assert r.returncode == 0, r.stderr
    assert "#define casadi_real float" in (fresh / "rollplan_model.h").read_text()   # generated again
    (fresh / "plan_demo.c").write_text("/* edited */\n")
    r = _codegen(capsys, "--out", str(fresh))
    assert r.returncode == 2 and one_line(r.stderr) and "plan_demo.c" in r.stderr, r.stderr
    assert (fresh / "plan_demo.c").read_text() == "/* edited */\n"


def test_plan_demo_no_plan_agrees_with_python(built):
    """k = 5, (2, 2) in one step: no branch has a root (the Python planner finds none either)."""
    run = demo(built, 2, 2, 0, 1, 5)
    assert run.returncode == 3 and run.stdout == "" and "no plan" in run.stderr
    assert reference_plan((2.0, 2.0, 0.0), 1, 5.0) is None


@pytest.mark.slow
def test_generated_prefix_builds_and_plans(prefixed):
    """A planner generated for k <= 16 (:func:`prefixed`): other prefix, and certified plans at k = 10."""
    out = prefixed.out
    assert (out / "librp_2.a").exists()
    run = subprocess.run([str(out / "plan_demo"), "0", "1", "0", "1", "2.5"], check=False, capture_output=True,
                         text=True)
    a, b = (float(x) for x in run.stdout.split()[:2])
    assert abs(a - 0.300429) < 5e-7 and abs(b - 0.300429) < 5e-7
    for u, v, psi, n in ((0.0, 2.0, 0.0, 1), (0.5, -0.3, 1.0, 2)):
        run = subprocess.run([str(out / "plan_demo"), *map(str, (u, v, psi, n, 10))], check=False,
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        a, b, gamma = (float(x) for x in run.stdout.split()[:3])
        x = references.trace(a, b, 10.0, gamma, n)
        q = reference_plan((u, v, psi), n, 10.0)
        assert q is not None and _same_plan(_parse(run), q)
        assert np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)]) <= CERT_TOL
    run = subprocess.run([str(out / "plan_demo"), "0", "2", "0", "1", "16.5"], check=False, capture_output=True)
    assert run.returncode == 2
    run = subprocess.run([str(out / "plan_demo"), "0", "2", "0", "1", "-0.1"], check=False, capture_output=True)
    assert run.returncode == 2


# ----------------------------------------------------------------------------- the on-board certificate

@pytest.fixture(scope="module")
def clib(built):
    lib = ctypes.CDLL(str(built.out / "librollplan.so"))
    d, p = ctypes.c_double, ctypes.POINTER(ctypes.c_double)
    lib.rollplan_certify.argtypes = [d, d, d, ctypes.c_int, d, d, d, d, p, p, p]
    lib.rollplan_certify.restype = ctypes.c_int
    return lib


def certify(clib, a, b, gamma, steps, k, target):
    final, residual, bound = (ctypes.c_double * 3)(), ctypes.c_double(), ctypes.c_double()
    status = clib.rollplan_certify(a, b, gamma, steps, k, *target, final, ctypes.byref(residual), ctypes.byref(bound))
    return status, np.array(final), residual.value, bound.value


@pytest.mark.parametrize("a, b, gamma, steps, k", [
    (0.3004288061954572, 0.3004288061954572, 0.93188347081455891, 1, 2.5), (0.69, 0.69, 0.3, 1, DEFAULT_K_MAX),
    (0.05, 0.69, -2.0, 2, DEFAULT_K_MAX), (0.2, 0.45, 1.0, 3, 0.0), (0.6, 0.1, 3.0, 1, 1.5),
    (0.685, 0.2, 0.0, 1, 1.0),    # near A_MAX at small k: certified only after the steps are doubled again
    (0.69, 0.01, 1.0, 2, 0.5), (0.5, 0.6, 0.7, 4, 2.5), (0.4, 0.4, 0.0, 1, DEFAULT_K_MAX), (0.1, 0.1, 0.0, 3, 2.5),
    (0.66, 0.62, -1.0, 2, 3.7), (0.66, 0.66, 0.2, 3, 1.0), (0.69, 0.2, 1.0, 4, 1.5), (0.68, 0.05, 0.0, 6, 2.0),
    (0.6597467940923643, 0.03704584696412159, 0.5035557975055616, 6, 1.5)])   # too few steps once: bound < error
def test_certificate_final_state_is_within_its_bound(clib, a, b, gamma, steps, k):
    """The RK8 certificate's final state against DOP853 on the printed (28)-(30) (rtol 1e-13)."""
    ref = references.trace(a, b, k, gamma, steps)
    status, final, residual, bound = certify(clib, a, b, gamma, steps, k, ref)
    assert status == 0
    err = np.linalg.norm(final - ref)
    assert err <= bound + 1e-11 * steps          # DOP853's own error at rtol 1e-13
    assert abs(residual - err) <= 1e-11 * steps and bound < CERT_TOL


def test_certificate_refuses_a_wrong_plan_and_bad_arguments(clib):
    a, gamma = 0.3004288061954572, 0.93188347081455891
    assert certify(clib, a, a, gamma, 1, 2.5, (0.0, 1.0, 0.0))[0] == 0
    status, _, residual, _ = certify(clib, a + 1e-7, a, gamma, 1, 2.5, (0.0, 1.0, 0.0))
    assert status == 5 and residual > CERT_TOL
    assert certify(clib, a, a, gamma + 1e-8, 1, 2.5, (0.0, 1.0, 0.0))[0] == 5
    for args in ((0.7, a, gamma, 1, 2.5), (a, 0.0, gamma, 1, 2.5), (a, a, gamma, 0, 2.5), (a, a, gamma, 1, 5.5),
                 (a, a, float("nan"), 1, 2.5), (a, a, gamma, 1001, 2.5)):
        assert certify(clib, *args, (0.0, 1.0, 0.0))[0] == 2


@pytest.mark.slow
def test_k_max_is_checked_at_generation(tmp_path, monkeypatch):
    """A k_max out of range, or beyond what the step map serves, is refused before the library's functions are
    built (seconds of symbolic work that a refusal wasted)."""
    def not_now(*args, **kwargs):
        raise AssertionError("the library's functions were built before k_max was checked")

    monkeypatch.setattr(codegen.c_library, "generated_functions", not_now)
    with pytest.raises(InputError, match="k_max = 10 is not allowed with 240 steps per leaf"):
        codegen.generate(tmp_path / "a", k_max=10)
    for bad in (-1, 101, float("nan"), "5", True):
        with pytest.raises(InputError, match="k_max"):
            codegen.generate(tmp_path / "b", k_max=bad)
    assert main(["codegen", "--out", str(tmp_path / "c"), "--k-max", "30", "--steps-per-leaf", "240"]) == 2


@pytest.mark.slow
def test_codegen_k_max_16_sizes_its_step_map_itself(prefixed, tmp_path, capsys):
    """`codegen --k-max 16` without --steps-per-leaf (auto, :func:`prefixed`): the smallest size whose step map is
    accurate to 1e-10 up to k = 16 (400; 320 is refused for it), and its plan_demo plans a k = 16 target as the
    Python planner does and lands on it when integrated by DOP853 on the printed equations."""
    out = prefixed.out
    assert "400 steps per leaf" in prefixed.said
    assert main(["codegen", "--out", str(tmp_path / "small"), "--k-max", "16", "--steps-per-leaf", "320"]) == 2
    assert "320 steps per leaf" in capsys.readouterr().err
    for u, v, psi, n in ((0.5, -0.3, 1.0, 2), (0.0, 1.0, 0.0, 1)):
        run = subprocess.run([str(out / "plan_demo"), *map(str, (u, v, psi, n, 16))], check=False,
                             capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        c = _parse(run)
        q = reference_plan((u, v, psi), n, 16.0)
        assert q is not None and _same_plan(c, q), (c, q and (q.a, q.b, q.gamma, q.branch))
        x = references.trace(c[0], c[1], 16.0, c[2], n)
        assert np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)]) <= CERT_TOL


def test_codegen_refuses_k_max_beyond_the_largest_automatic_size(tmp_path, capsys, monkeypatch):
    """With the automatic sizes capped at 240 steps per leaf, k_max = 10 (which needs 320) is refused in one line
    naming the cap, exit 2, before anything is written; a bad --steps-per-leaf names auto."""
    monkeypatch.setattr(codegen.c_library, "AUTO_STEPS_PER_LEAF", (240,))
    assert main(["codegen", "--out", str(tmp_path / "c"), "--k-max", "10"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "k_max = 10 is not allowed" in err and "240 steps per leaf" in err
    assert not (tmp_path / "c").exists()
    with pytest.raises(SystemExit, match="2"):
        main(["codegen", "--out", str(tmp_path / "c"), "--steps-per-leaf", "many"])
    assert "auto" in capsys.readouterr().err


def _fuzz_inputs(rng, count, many_steps):
    special = {"u": [0.0, 1e-300, -1e-9, 1e3, 3.0], "psi": [0.0, 1e-300, np.pi, -np.pi, 50.0, 1e6],
               "steps": [1, 2, many_steps], "k": [0.0, 1e-300, 0.5, 0.4999999, DEFAULT_K_MAX, 2.5]}
    for _ in range(count):
        u, v = (rng.choice(special["u"]) if rng.random() < 0.2 else rng.uniform(-3, 3) for _ in range(2))
        psi = rng.choice(special["psi"]) if rng.random() < 0.2 else rng.uniform(-4, 4)
        steps = int(rng.choice(special["steps"])) if rng.random() < 0.2 else int(rng.integers(1, 5))
        k = rng.choice(special["k"]) if rng.random() < 0.2 else rng.uniform(0.0, DEFAULT_K_MAX)
        yield float(u), float(v), float(psi), steps, float(k)


def _fuzz(built, seed, count, many_steps, tol=CERT_TOL):
    """No wrong plan with exit 0: every plan the C planner returns lands within the tolerance when
    integrated by DOP853 on the printed equations (all plans at once, :func:`_traces`); every other outcome is a
    documented status."""
    rng = np.random.default_rng(seed)
    outcomes, planned = [], []
    for u, v, psi, steps, k in _fuzz_inputs(rng, count, many_steps):
        run = demo(built, repr(u), repr(v), repr(psi), steps, repr(k))
        assert run.returncode in (0, 2, 3, 4, 5), (u, v, psi, steps, k, run.stderr)
        outcomes.append(run.returncode)
        if run.returncode:
            assert run.stdout == "" and run.stderr.count("\n") == 1
            continue
        a, b, gamma, residual, bound, _ = _parse(run)
        assert 0 < a <= A_MAX and 0 < b <= A_MAX and residual + bound <= tol
        planned.append(((u, v, psi, steps, k), (a, b, k, gamma, steps)))
    for ((u, v, psi, steps, k), _), x in zip(planned, _traces([p for _, p in planned])):
        miss = np.linalg.norm([x[0] - u, x[1] - v, references.wrap(x[2] - psi)])
        assert miss <= tol + 1e-11 * steps, (u, v, psi, steps, k, miss)
    return outcomes


def _traces(plans):
    """:func:`references.trace` of many plans ``(a, b, k, gamma, steps)`` at once. The first figure eight of every
    plan by DOP853 from zero, leaf by leaf as one system (:func:`references.curve_leaf_ends`; fewer than
    :data:`_BATCHED` plans one by one); the later ones by the symmetry of the printed equations
    (:func:`test_enumerate.repeated`). Checked against :func:`references.trace` (DOP853 over every step) by
    test_traces_are_the_trace_of_each_plan. Final states, shape (len(plans), 3)."""
    if not plans:
        return np.zeros((0, 3))
    a, b, k, gamma, steps = (np.array(c, float) for c in zip(*plans))
    x = np.zeros((3, a.size))
    for r, side in ((a, 1.0), (b, -1.0)):
        if a.size < _BATCHED:
            for i in range(a.size):
                x[:, i] = references.leaf_end(r[i], side, k[i], gamma[i], x[:, i])
        else:
            x = references.curve_leaf_ends(_rotated_circles(r, side, gamma), x, k)
    return repeated(x.T, steps)


#: Fewer plans than this are traced one by one (a call of the batched right side costs that of a few alone).
_BATCHED = 4


def _rotated_circles(r, side, gamma):
    """The circles (35) of radii ``r`` on ``side``, each turned by its own gamma (31): a curve for
    :func:`references.curve_leaf_ends`."""
    cg, sg = np.cos(gamma), np.sin(gamma)
    d = np.sqrt(1.0 - r * r)
    ad, aa, dd = side * r * d, r * r, d * d   # (35): x = a sin phi, y = side a d (1 - cos phi)

    def curve(phi):
        s, c = math.sin(phi), math.cos(phi)
        x, y, dx, dy = r * s, ad * (1.0 - c), r * c, ad * s
        return (np.array([cg * x - sg * y, sg * x + cg * y, -aa * c - dd]),
                np.array([cg * dx - sg * dy, sg * dx + cg * dy, aa * s]))

    return curve


@pytest.mark.slow
def test_traces_are_the_trace_of_each_plan():
    """The traces of the fuzz tests (batched, and one by one for fewer than _BATCHED plans; later figure eights by
    the symmetry) against DOP853 over every step, plan by plan (other steps, k, gamma, radii)."""
    plans = [(0.3, 0.2, 2.5, 0.7, 1), (0.69, 0.05, DEFAULT_K_MAX, -2.0, 2), (0.1, 0.6, 0.3, 3.0, 2),
             (0.45, 0.45, 0.0, 0.0, 1), (0.2, 0.65, 1.5, 1.0, 1), (0.6, 0.3, 4.0, -1.0, 1), (0.01, 0.02, 0.5, 0.2, 1),
             (0.3, 0.2, 2.5, 0.7, 5), (0.5, 0.1, 6.0, -0.4, 4)]
    for batch in (plans, plans[-3:-1]):
        for plan, x in zip(batch, _traces(batch)):
            alone = references.trace(*plan)
            assert np.abs(x - alone).max() < 1e-11, (plan, x, alone)


def test_fuzz_no_wrong_plan_with_exit_0(built):
    """Fast subset: extreme u, v, psi, k; few steps (DOP853 checks every plan, at ~50 ms per leaf)."""
    assert 0 in _fuzz(built, 5, 10, 3)


@pytest.mark.slow
def test_fuzz_no_wrong_plan_with_exit_0_more(built):
    outcomes = _fuzz(built, 6, 80, 40)
    assert outcomes.count(0) >= 10


@pytest.fixture(scope="module")
def built_float(generated_c_float):
    run = make("-C", str(generated_c_float.out), "plan_demo")
    assert run.returncode == 0, run.stderr
    return generated_c_float


@pytest.mark.slow
def test_float_build_has_no_double_and_certifies_to_its_tolerance(built_float, built):
    """Single precision: the same plan as the double build to float accuracy, and a fuzz test at 1e-4."""
    text = (built_float.out / "rollplan_model.c").read_text() + (built_float.out / "rollplan_planner.c").read_text()
    code = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    assert "#define casadi_real float" in text
    assert not re.search(r"\b(sin|cos|sqrt|atan2|hypot|fabs|fmod)\s*\(", code)
    assert "ROLLPLAN_CERT_TOL 0.0001f" in (built_float.out / "rollplan.h").read_text()
    for target in TARGETS:
        f32, f64 = (demo(b, *target) for b in (built_float, built))
        assert f32.returncode == f64.returncode == 0
        assert np.max(np.abs(np.array(f32.stdout.split()[:3], float) - np.array(f64.stdout.split()[:3], float))) < 1e-4
    assert 0 in _fuzz(built_float, 7, 10, 3, FLOAT_CERT_TOL)


# ----------------------------------------------------------------------------- the time law in C

class _Options(ctypes.Structure):
    _fields_ = [("use_branch", ctypes.c_int), ("branch", ctypes.c_long), ("certify", ctypes.c_int)]


class _Plan(ctypes.Structure):
    _fields_ = [("a", ctypes.c_double), ("b", ctypes.c_double), ("gamma", ctypes.c_double), ("eta", ctypes.c_double),
                ("h", ctypes.c_double), ("m", ctypes.c_long), ("residual", ctypes.c_double),
                ("bound", ctypes.c_double), ("predicted", ctypes.c_double), ("branches", ctypes.c_int),
                ("roots", ctypes.c_long)]


@pytest.mark.parametrize("target, steps, duration", [((0.3, -0.2, 0.5), 2, 7.0), ((0.0, 1.0, 0.0), 1, 2.0)])
def test_sample_is_the_python_min_jerk_law(clib, target, steps, duration):
    """rollplan_sample at random times against rollplan.execution.actuation (the min-jerk law of
    rollplan.execution.timing, rotor rates from the model's (11), angles and state integrated by CVODES):
    rates to 1e-10, state and rotor angles to 1e-10 of their size (the accuracy of the Python side's
    integration); its angles' time derivative is its rates; and at the end the state is the target (to the
    certificate's tolerance; DOP853 on the printed equations certifies the plan's end state)."""
    from rollplan import Problem, default_robot
    from rollplan.execution.actuation import actuate
    from rollplan.planners.geometric import GeometricPhasePlanner

    robot = default_robot()
    R, k = robot.radius, robot.k
    plan = GeometricPhasePlanner().solve(Problem(tuple(x * R if i < 2 else x for i, x in enumerate(target)),
                                                 robot=robot, steps=steps))
    motion = actuate(plan, robot, duration=duration, samples=200)
    d = ctypes.c_double
    clib.rollplan_sample.argtypes = [ctypes.POINTER(_Plan), ctypes.c_int, d, d, d, d, d, d, ctypes.POINTER(d),
                                     ctypes.POINTER(d), ctypes.POINTER(d)]
    p = _Plan(plan.a / R, plan.b / R, plan.gamma)
    args = (steps, k, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, duration)

    def sample(t):
        rates, angles, state = (d * 2)(), (d * 2)(), (d * 5)()
        assert clib.rollplan_sample(ctypes.byref(p), *args, t, rates, angles, state) == 0
        return np.array(rates), np.array(angles), np.array(state)

    rng = np.random.default_rng(5)
    size = max(1.0, float(np.abs(motion.series.rotor_angles).max()))
    for i in rng.choice(motion.series.time.size, 12, replace=False):
        rates, angles, state = sample(motion.series.time[i])
        assert np.abs(rates - motion.series.rotor_rates[i]).max() <= 1e-10
        assert np.abs(angles - motion.series.rotor_angles[i]).max() <= 1e-10 * size
        want = motion.series.state[i]
        assert np.all(np.abs(state * [R, R, 1, 1, 1] - want) <= 1e-10 * (1 + np.abs(want)))
    for t in rng.uniform(0.05, 0.95, 3) * duration:
        fd = (sample(t + 1e-6)[1] - sample(t - 1e-6)[1]) / 2e-6
        np.testing.assert_allclose(fd, sample(t)[0], rtol=1e-6, atol=1e-6)
    rates, angles, state = sample(duration)
    end = references.trace(plan.a / R, plan.b / R, k, plan.gamma, steps)
    assert np.abs(rates).max() == 0.0 and np.linalg.norm(state[:3] - end) <= 1e-9
    assert np.linalg.norm(state[:2] - target[:2]) + abs(references.wrap(state[2] - target[2])) <= 1e-9
    rates = (d * 2)()
    for bad in ((steps, k, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, duration, duration * 1.01),
                (steps, k, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, 0.0, 0.0),
                (0, k, robot.j_xx, robot.j_zz, robot.rotor_inertia_axial, duration, 0.0)):
        assert clib.rollplan_sample(ctypes.byref(p), *bad, rates, None, None) == 2


def test_generated_model_code_does_not_depend_on_the_process_print_precision():
    """CasADi writes the constant matrices of an MX function into the comments of its C at the process's print
    precision, which another library may change for the whole process (rockit sets 14 digits): the same planner
    then gave other files (and missed every build cache keyed by their content). ``model_code`` writes at a fresh
    process's precision and leaves the caller's as it was."""
    from rollplan.core import c_functions

    x = ca.MX.sym("x", 2)
    f = ca.Function("f", [x], [ca.DM([1 / 3, 2 / 3]) * x + ca.sin(x)])
    before = ca.DM.get_precision()
    try:
        ca.DM.set_precision(c_functions.DM_PRECISION)
        fresh = c_functions.model_code([f], "p")
        ca.DM.set_precision(14)
        raw = ca.CodeGenerator("p.c")
        raw.add(f)
        assert "0.33333333333333" in raw.dump()     # the premise: 14 digits reach the comments
        assert c_functions.model_code([f], "p") == fresh
        assert ca.DM.get_precision() == 14
    finally:
        ca.DM.set_precision(before)
