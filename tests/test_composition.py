"""The composition law (C) of rollplan.core.plane against a direct integration of the printed (15), (16), (20)
by DOP853 (references.integrate_contact_path), on contact paths off the south pole."""

import numpy as np
import pytest

from rollplan.core.plane import compose, inverse, relative

import references as ref


def random_path(rng):
    """A smooth contact path in the chart starting off the pole, t in [0, 1]."""
    u0, v0 = rng.uniform(-0.6, 0.6, 2)
    return ref.chart_path(u0, v0, rng.normal(0, 0.15, 3), rng.normal(0, 0.15, 3))


@pytest.mark.parametrize("seed", range(4))
def test_a_start_state_acts_on_any_path_as_a_rigid_motion(seed):
    """From (p0, psi0) along any contact path: p0 + Rot(-psi0) p_c and psi0 + Psi, at every point of the path."""
    rng = np.random.default_rng(seed)
    path, k = random_path(rng), rng.uniform(0.0, 12.0)
    s0 = np.array([rng.normal(), rng.normal(), rng.uniform(-6, 6)])
    t = np.linspace(0.0, 1.0, 21)
    direct = ref.integrate_contact_path(path, s0, (0.0, 1.0), k, t).y
    from_zero = ref.integrate_contact_path(path, np.zeros(3), (0.0, 1.0), k, t).y
    assert np.abs(direct - compose(s0, from_zero)).max() < 1e-10
    assert np.abs(direct[:, -1] - compose(s0, from_zero[:, -1])).max() < 1e-10


def test_chaining_and_reversal():
    """g of c1 then c2 is g_c1 * g_c2 (each from zero, c2 starting where c1 ends); c backwards gives g_c^-1."""
    path, k = random_path(np.random.default_rng(7)), 2.5
    whole = ref.integrate_contact_path(path, np.zeros(3), (0.0, 1.0), k).y[:, -1]
    g1 = ref.integrate_contact_path(path, np.zeros(3), (0.0, 0.37), k).y[:, -1]
    g2 = ref.integrate_contact_path(path, np.zeros(3), (0.37, 1.0), k).y[:, -1]
    assert np.abs(whole - compose(g1, g2)).max() < 1e-10
    back = ref.integrate_contact_path(path, np.zeros(3), (1.0, 0.0), k).y[:, -1]
    assert np.abs(back - inverse(whole)).max() < 1e-10


def test_figure_eight_from_a_pole_state_is_turned_by_minus_psi0_and_shifted():
    k, s0 = 5.0, np.array([1.5, -0.4, -2.2])
    pieces = [ref.circle_path(0.31, 1.0, 0.7), ref.circle_path(0.42, -1.0, 0.7)]
    ends = []
    for x in (np.zeros(3), s0):
        for path in pieces:
            x = ref.integrate_contact_path(path, x, (0.0, 2 * np.pi), k).y[:, -1]
        ends.append(x)
    expect = np.concatenate([s0[:2] + ref.rotate(-s0[2], ends[0][:2]), [s0[2] + ends[0][2]]])
    assert np.abs(ends[1] - expect).max() < 1e-10


def test_group_axioms_and_the_target_of_the_figure_eights():
    rng = np.random.default_rng(3)
    g, h, e, a = (np.array([rng.normal(), rng.normal(), rng.uniform(-4, 4)]) for _ in range(4))
    assert np.allclose(compose(compose(g, h), e), compose(g, compose(h, e)), atol=1e-14)
    assert np.allclose(compose(g, inverse(g)), 0, atol=1e-14) and np.allclose(compose(inverse(g), g), 0, atol=1e-14)
    assert np.allclose(compose(g, relative(g, h)), h, atol=1e-14)
    # (F) of rollplan.planners.geometric.composed: start * g_A * g_F * g_B = goal
    f = compose(compose(inverse(a), relative(g, h)), inverse(e))
    assert np.allclose(compose(compose(compose(g, a), f), e), h, atol=1e-13)
    cols = np.stack([h, e], axis=1)   # the law acts on columns of states alike
    assert np.allclose(compose(g, cols), np.stack([compose(g, h), compose(g, e)], axis=1), atol=1e-15)
