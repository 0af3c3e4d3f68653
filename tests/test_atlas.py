"""The reachability atlas (rollplan.studies.atlas): the step map over the admissible square, its n-step
totals and fold, against the planner's step map, the printed (28)-(30) integrated by DOP853
(``references.trace``), CVODES over n steps, finite differences and the mirror symmetry."""

import json

import numpy as np
import pytest

from rollplan import cli
from rollplan.core.curves import A_MAX
from rollplan.errors import InputError
from rollplan.planners import geometric
from rollplan.studies.atlas import compute_atlas, n_step_totals

import references


@pytest.fixture(scope="module")
def atlas():
    return compute_atlas(2.5, steps=2, resolution=6)


def test_grid_is_the_admissible_square(atlas):
    assert atlas.a[0] > 0 and atlas.a[-1] == pytest.approx(A_MAX)
    assert atlas.h.shape == atlas.eta.shape == atlas.det.shape == (6, 6)


@pytest.mark.parametrize("i,j", [(0, 0), (1, 4), (5, 2), (3, 3), (5, 5)])
def test_values_match_the_step_map(atlas, i, j):
    s = geometric.step(atlas.a[i], atlas.b[j], k=2.5)
    assert atlas.h[i, j] == pytest.approx(s.h, rel=1e-12, abs=1e-14)
    assert atlas.eta[i, j] == pytest.approx(s.eta, rel=1e-12, abs=1e-14)


def test_one_point_matches_scipy(atlas):
    x = references.trace(atlas.a[2], atlas.b[4], 2.5)
    assert atlas.h[2, 4] == pytest.approx(np.hypot(x[0], x[1]), abs=1e-9)
    assert atlas.eta[2, 4] == pytest.approx(x[2], abs=1e-9)


def test_n_step_totals_match_an_n_step_cvodes_trace(atlas, planner):
    for i, j in [(1, 3), (4, 0)]:
        final = planner.certifier.final(atlas.a[i], atlas.b[j], 2.5, 0.0, 2)
        assert atlas.shift_total[i, j] == pytest.approx(np.hypot(final.u_a, final.v_a), abs=1e-9)
        assert atlas.turn_total[i, j] == pytest.approx(final.psi, abs=1e-9)


def test_mirror_symmetry(atlas):
    # swapping the leaves mirrors the figure eight: same shift, opposite turn
    assert np.allclose(atlas.h, atlas.h.T, rtol=1e-10, atol=1e-13)
    assert np.allclose(atlas.eta, -atlas.eta.T, rtol=1e-10, atol=1e-13)


def test_fold_determinant_matches_finite_differences(atlas):
    def he(a, b):
        s = geometric.step(a, b, k=2.5)
        return np.array([s.h, s.eta])

    for i, j in [(1, 4), (2, 2), (4, 1)]:
        a, b, d = atlas.a[i], atlas.b[j], 1e-6
        jac = np.column_stack([(he(a + d, b) - he(a - d, b)) / (2 * d), (he(a, b + d) - he(a, b - d)) / (2 * d)])
        assert atlas.det[i, j] == pytest.approx(np.linalg.det(jac), rel=1e-5, abs=1e-7)


def test_n_step_totals_limit():
    h, psi = n_step_totals(np.array([0.5]), np.array([0.0]), 3)
    assert h[0] == pytest.approx(1.5) and psi[0] == 0.0


def test_n_step_totals_follow_33(atlas):
    for i, j in [(0, 5), (2, 3), (5, 1)]:
        gain = references.n_step_gain(atlas.eta[i, j], 2)
        assert atlas.shift_total[i, j] == pytest.approx(atlas.h[i, j] * gain, rel=1e-12, abs=1e-15)
        assert atlas.turn_total[i, j] == pytest.approx(2 * atlas.eta[i, j], rel=1e-15)


def test_bad_input():
    with pytest.raises(InputError, match="k = -1"):
        compute_atlas(-1.0)
    with pytest.raises(InputError, match="resolution"):
        compute_atlas(1.0, resolution=1)
    with pytest.raises(InputError, match="steps = 0"):
        compute_atlas(1.0, steps=0)


@pytest.mark.slow
def test_cli_atlas(tmp_path):
    png, js = tmp_path / "atlas.png", tmp_path / "atlas.json"
    assert cli.main(["atlas", "--k", "2.5", "--steps", "2", "--resolution", "6", "--out", str(png),
                     "--json", str(js)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    d = json.loads(js.read_text())
    s = geometric.step(d["a"][1], d["b"][3], k=2.5)
    assert d["h"][1][3] == pytest.approx(s.h, rel=1e-12)
    assert cli.main(["atlas", "--k", "-2", "--out", str(png)]) == 2
    assert cli.main(["atlas", "--k", "1", "--out", str(tmp_path / "no" / "a.png")]) == 2


@pytest.mark.parametrize("curve", ["viviani", *(pytest.param(c, marks=pytest.mark.slow)
                                                for c in ("triangle", "square"))])
def test_atlas_of_a_curve_family_matches_scipy(tmp_path, curve):
    """`rollplan atlas --curve NAME`: h and eta of the family's figure eight on the grid against DOP853 on the
    printed (28)-(30) along the leaves as typed in tests/references.py; the fold determinant against finite
    differences of that reference; the JSON names the curve."""
    png, js = tmp_path / "atlas.png", tmp_path / "atlas.json"
    assert cli.main(["atlas", "--curve", curve, "--k", "2.5", "--resolution", "4", "--out", str(png),
                     "--json", str(js)]) == 0
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    d = json.loads(js.read_text())
    assert d["curve"] == curve

    def he(a, b):
        x = references.family_trace(curve, a, b, 2.5)
        return np.array([np.hypot(x[0], x[1]), x[2]])

    for i, j in [(0, 3), (2, 1)]:
        a, b = d["a"][i], d["b"][j]
        assert [d["h"][i][j], d["eta"][i][j]] == pytest.approx(he(a, b), abs=1e-8)
    a, b, step = d["a"][1], d["b"][2], 1e-5
    jac = np.column_stack([(he(a + step, b) - he(a - step, b)) / (2 * step),
                           (he(a, b + step) - he(a, b - step)) / (2 * step)])
    assert d["det"][1][2] == pytest.approx(np.linalg.det(jac), rel=1e-5, abs=1e-7)


def test_the_atlas_takes_the_method_geometric_of_the_registry(atlas):
    """The step map of the registry's method "geometric" (given as a method or as its pole-to-pole planner)
    is the default's; anything else is one clear line."""
    from rollplan.planners import METHODS

    method = METHODS["geometric"](nodes=24)
    for planner in (method, method.planner):
        other = compute_atlas(2.5, steps=2, resolution=6, planner=planner)
        assert np.allclose(other.h, atlas.h, rtol=1e-9, atol=1e-12)
        assert np.allclose(other.eta, atlas.eta, rtol=1e-9, atol=1e-12)
    with pytest.raises(InputError, match="planner") as err:
        compute_atlas(2.5, resolution=6, planner="geometric")
    assert "\n" not in str(err.value)
