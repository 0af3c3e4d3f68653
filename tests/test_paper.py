"""The paper's case study (Section III.C) reproduced (rollplan.studies.paper): against the paper's
printed numbers, the closed form (36), an independent integrator (scipy DOP853 on the printed
(28)-(30)), and brute-force geometry."""

import json
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from rollplan.cli import main
from rollplan.errors import InputError
from rollplan.studies.paper import run_case_study, write_reproduction
from rollplan.studies.paper.stages import CaseStudy, count_self_intersections, refine_root
from rollplan.studies.paper.values import PAPER, agrees

import references

eq36 = references.shift_36
A0 = brentq(lambda a: eq36(a) - 1.0, 0.45, 0.53, xtol=1e-15)  # independent of rollplan


@pytest.fixture(scope="module")
def dop853():
    """(a, k, leaves) -> state (u_a, v_a, psi) after the given leaves of the symmetric figure eight, by DOP853
    on the printed (28)-(30), (35)."""

    def trace(a, k, leaves=2):
        x = np.zeros(3)
        for side in (1.0, -1.0)[:leaves]:
            x = references.leaf_end(a, side, k, 0.0, x, rtol=1e-13, atol=1e-15)
        return x

    return trace


@pytest.fixture(scope="module")
def study():
    return CaseStudy()


@pytest.fixture(scope="module")
def reduced(study):
    """A reduced reproduction: coarse sweeps, one self-intersection probe per interval (about 4 s: the tests that
    use it are in the full tier; the building blocks below check the main path in the unit tier)."""
    return run_case_study(k_points=71, a_points=300, samples=200, crossing_samples=1000, crossings_per_interval=1,
                          study=study)


def find(result, start):
    hits = [r for r in result.rows if r.quantity.startswith(start)]
    assert len(hits) == 1, start
    return hits[0]


# ----------------------------------------------------------------------------- the reduced reproduction


@pytest.mark.slow
@pytest.mark.parametrize("start,key", [
    ("gamma [rad] pointing the shift along +v_a, k = 0", "gamma_k0"),
    ("h/R at k = 2.5", "h_k2.5"), ("h/R at k = 5", "h_k5"),
    ("gamma [rad] at k = 2.5", "gamma_k2.5"), ("gamma [rad] at k = 5", "gamma_k5"),
    ("zero k_1", "k1"), ("zero k_2", "k2"), ("zero k_3", "k3"), ("zero k_4", "k4"),
    ("a_1/R", "a1"), ("a_2/R", "a2"), ("a_3/R", "a3"), ("a_4/R", "a4"),
    ("gamma [rad] for a_1", "gamma_a1"), ("gamma [rad] for a_2", "gamma_a2"),
])
def test_reduced_rows_match_paper_digits(reduced, start, key):
    row = find(reduced, start)
    d = len(PAPER[key].split(".")[1])
    assert row.paper == float(PAPER[key])
    assert abs(row.computed - float(PAPER[key])) <= 0.5 * 10.0 ** -d
    assert row.status == "reproduced"


@pytest.mark.slow
def test_printed_radius_is_a_discrepancy_against_closed_form_36(reduced):
    row = find(reduced, "a/R with h/R = 1 at k = 0")
    assert row.status == "discrepancy" and row.paper == 0.533681
    assert abs(row.computed - A0) < 1e-11           # root of (36) = 1 by scipy brentq
    printed = find(reduced, "h/R at k = 0 for the printed a")
    assert printed.status == "discrepancy"
    assert abs(printed.computed - eq36(0.533681)) < 1e-11
    assert round(eq36(0.533681), 5) == 1.17636


@pytest.mark.slow
def test_k5_is_a_discrepancy_and_the_computed_zero_is_a_zero(reduced, dop853):
    row = find(reduced, "zero k_5")
    assert row.status == "discrepancy"
    u, v, _ = dop853(A0, row.computed)
    assert math.hypot(u, v) < 1e-9                      # a zero by an independent integrator
    u, v, _ = dop853(A0, 10.9801)
    assert math.hypot(u, v) > 1.0                       # the printed k_5 is far from a zero


@pytest.mark.slow
def test_self_intersection_claim_and_path_length_claim(reduced):
    for i in range(6):
        row = find(reduced, f"self-intersections of the half-step plane path, k in [k_{i}, k_{i + 1}]")
        assert row.computed == i and row.status == "reproduced"
    assert find(reduced, "a_1 contact path shorter").status == "reproduced"
    p1, traj1 = reduced.plans["a1"]
    p0, traj0 = reduced.plans["k0"]
    # the sampled plane path is as long as the path on the sphere, 4 pi a (rolling without slip)
    assert abs(traj1.path_length() - 4 * math.pi * p1.a) < 1e-3
    assert abs(traj0.path_length() - 4 * math.pi * A0) < 1e-3
    assert p1.residual < 1e-9 and p0.residual < 1e-9


@pytest.mark.slow
def test_roots_count_is_stable_on_doubled_grid(reduced):
    assert reduced.k_sweep.roots_double_grid == len(reduced.k_sweep.roots)
    assert len(reduced.k_sweep.roots) == 6
    assert np.allclose(reduced.k_sweep.roots, reduced.k_sweep.roots_cvodes, atol=1e-9)


@pytest.mark.slow
def test_json_schema(reduced, tmp_path):
    write_reproduction(reduced, tmp_path, figures=False)
    doc = json.loads((tmp_path / "reproduction.json").read_text())
    assert list(doc) == ["version", "units", "rows"] and len(doc["rows"]) == len(reduced.rows)
    assert doc["units"]["length"] == "R"
    for r in doc["rows"]:
        assert list(r) == ["quantity", "paper", "computed", "status", "note"]
        assert isinstance(r["quantity"], str) and isinstance(r["note"], str) and r["note"]
        assert isinstance(r["paper"], float) and isinstance(r["computed"], float)
        assert r["status"] in ("reproduced", "discrepancy")
    assert "discrepancy" in (tmp_path / "REPRODUCTION.md").read_text()


# ----------------------------------------------------------------------------- building blocks


def test_paper_gamma_and_shift_by_an_independent_integrator(dop853):
    # at the root of (36) = 1 (not at the printed 0.533681) DOP853 gives the printed h and gammas
    for k, h_key, g_key in ((0.0, None, "gamma_k0"), (2.5, "h_k2.5", "gamma_k2.5"), (5.0, "h_k5", "gamma_k5")):
        u, v, _ = dop853(A0, k)
        gamma = math.remainder(math.pi / 2 - math.atan2(v, u), 2 * math.pi)
        assert agrees(gamma, PAPER[g_key])
        if h_key:
            assert agrees(math.hypot(u, v), PAPER[h_key])


def test_signed_shift_is_twice_the_first_leaf_shift(study, dop853):
    # the symmetry behind the signed shift: one step shifts twice as far as its first half-step
    for k in (0.0, 1.7, 6.3):
        full, half = dop853(A0, k), dop853(A0, k, leaves=1)
        assert np.allclose(full[:2], 2 * half[:2], atol=1e-10)
        out = study.spectral(A0, k)
        assert abs(out[4] - (full[0] * math.cos(half[2] / 2) - full[1] * math.sin(half[2] / 2))) < 1e-10
        assert abs(abs(out[4]) - math.hypot(*full[:2])) < 1e-10


def test_batch_equals_pointwise_dop853(study, dop853):
    ks = np.array([0.3, 2.5, 7.0])
    out = study.batch(A0, ks)
    for j, k in enumerate(ks):
        assert np.allclose(out[:3, j], dop853(A0, k), atol=1e-10)


@pytest.mark.parametrize("f,lo,hi", [(math.cos, 0.0, 3.0), (lambda x: x**3 - 2 * x - 5, 2.0, 3.0),
                                     (lambda x: math.exp(x) - 10.0, 0.0, 5.0),
                                     (lambda x: math.tanh(x - 1.3) - 0.2, 0.0, 3.0)])
def test_refine_root_matches_brentq(f, lo, hi):
    assert abs(refine_root(f, lo, hi) - brentq(f, lo, hi, xtol=1e-15)) < 1e-10


def test_refine_root_evaluates_each_point_once():
    """The root's function (a CVODES run in the case study) is evaluated once at each point, values already
    known are not computed again, and the root is the one scipy's brentq finds."""
    calls = []

    def f(x):
        calls.append(x)
        return math.cos(x) - x

    root = refine_root(f, 0.0, 1.0)
    assert len(calls) == len(set(calls))
    assert abs(root - brentq(f, 0.0, 1.0, xtol=1e-15)) < 1e-14
    calls.clear()
    assert refine_root(f, 0.0, 1.0, known={0.0: f(0.0), 1.0: f(1.0)}) == root
    assert calls.count(0.0) == calls.count(1.0) == 1   # only the two calls above


def test_refine_root_rejects_non_bracket():
    with pytest.raises(InputError, match="does not bracket"):
        refine_root(math.cos, 0.0, 1.0)


def brute_crossings(p):
    def orient(o, e, q):
        return np.sign((e[0] - o[0]) * (q[1] - o[1]) - (e[1] - o[1]) * (q[0] - o[0]))

    n = len(p) - 1
    return sum(1 for i in range(n) for j in range(i + 2, n)
               if orient(p[i], p[i + 1], p[j]) * orient(p[i], p[i + 1], p[j + 1]) < 0
               and orient(p[j], p[j + 1], p[i]) * orient(p[j], p[j + 1], p[i + 1]) < 0)


def test_self_intersections_of_known_curves():
    t = np.linspace(0.05, 2 * np.pi - 0.05, 701)
    assert count_self_intersections(np.cos(t), np.sin(t)) == 0                 # open circle
    assert count_self_intersections(np.cos(t), np.sin(t) * np.cos(t)) == 1     # Gerono's lemniscate
    r = 0.5 + np.cos(t)                                                        # limacon with an inner loop
    assert count_self_intersections(r * np.cos(t), r * np.sin(t)) == 1
    s = np.linspace(-np.pi, 5 * np.pi, 3001)                                   # prolate cycloid, 3 loops
    assert count_self_intersections(s - 2 * np.sin(s), 1 - 2 * np.cos(s)) == 3
    rng = np.random.default_rng(1)
    for n in (5, 40, 90):
        p = rng.normal(size=(n, 2))
        assert count_self_intersections(*p.T) == brute_crossings(p)


def test_bad_input():
    with pytest.raises(InputError, match="k_points"):
        run_case_study(k_points=3)


def test_cli_rejects_file_as_out(tmp_path, capsys):
    f = tmp_path / "file"
    f.write_text("x")
    assert main(["reproduce", "--out", str(f)]) == 2
    assert "is a file" in capsys.readouterr().err


@pytest.mark.slow
def test_cli_reproduce_writes_everything(tmp_path, capsys, monkeypatch, reduced):
    """The command writes every figure, the table and the report. Its computation is the reduced one (the numbers
    are checked above; the full-size run is the documented command of docs/results.md, run by
    tests/test_readme_commands.py)."""
    import dataclasses

    from rollplan.studies.paper import run

    asked = []

    def reduced_run(**options):
        asked.append(options)
        return dataclasses.replace(reduced, timings=dict(reduced.timings))

    monkeypatch.setattr(run, "run_case_study", reduced_run)
    out = tmp_path / "paper"
    assert main(["reproduce", "--out", str(out)]) == 0
    assert list(asked[0]) == ["progress"]            # the defaults: the command passes no sizes of its own
    names = {p.name for p in out.iterdir()}
    assert {f"fig{i:02d}.png" for i in range(6, 13)} <= names
    assert {"reproduction.json", "REPRODUCTION.md"} <= names
    rows = json.loads((out / "reproduction.json").read_text())["rows"]
    status = {r["quantity"]: r["status"] for r in rows}
    assert sum(s == "reproduced" for s in status.values()) >= 20
    assert "reproduced" in capsys.readouterr().out


def test_batches_report_progress(study):
    calls = []
    study.batch(A0, np.linspace(0.0, 3.0, 2 * study.chunk + 7), progress=lambda *c: calls.append(c))
    assert [c[1] for c in calls] == [study.chunk, 2 * study.chunk, 2 * study.chunk + 7]


@pytest.mark.slow
def test_reproduction_onto_a_full_disk_is_one_line(reduced, full_disk):
    """Regression: reproduce onto a full disk was a traceback; now OutputError (the CLI exits 2), no
    temporary left."""
    from rollplan.errors import OutputError

    with pytest.raises(OutputError, match="disk is full") as err:
        write_reproduction(reduced, full_disk, figures=False)
    assert "\n" not in str(err.value)
    assert sorted(p.name for p in full_disk.iterdir()) == ["filler"]
