"""Geometric phase versus collocation (rollplan.studies.comparison), `rollplan compare`, and the
measurements behind it.

References: the figure eight's length ``2 pi n (a + b)`` (closed form), finite differences of the
sampled motions inverted through Montana's (6), (7), (10) as printed in the paper
(``references.omega_from_rates``), and the JSON schema of the issue.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from rollplan import Problem
from rollplan.cli import main
from rollplan.studies.comparison import compare

import references

K = 2.5
TARGET = (0.5, 0.3, 0.4)


@pytest.fixture(scope="module")
def comp():
    return compare(TARGET, 1, k=K, intervals=40)


def _fd_energy(traj):
    """int |omega|^2 dt from finite differences of the samples (a Trajectory timed in t), omega by
    inverting (6), (7), (10)."""
    assert traj.parameter == "t"
    t, x = traj.s, traj.state
    xdot = np.gradient(x, t, axis=0, edge_order=2)
    sq = (references.omega_from_rates(x, xdot, traj.radius) ** 2).sum(axis=1)
    speed = np.hypot(xdot[:, 0], xdot[:, 1])
    trap = lambda y: float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(t)))  # noqa: E731
    return trap(sq), trap(speed)


def test_comparison_holds_both_results_of_one_problem(comp):
    assert comp.problem == Problem(TARGET, k=K) == comp.plan.problem == comp.result.problem
    assert comp.horizon == 1.0 and comp.effort_kind == "angular_velocity"
    assert comp.effort(comp.plan_measures) == comp.plan_measures.effort
    assert comp.result.turns == comp.plan.branch and comp.result.guess == "warm"


def test_geometric_side_measurements(comp):
    g, p = comp.plan_measures, comp.plan
    tr = comp.plan_trajectory
    assert g.path_length == pytest.approx(2 * math.pi * (p.a + p.b), rel=1e-12)
    energy, length = _fd_energy(tr)
    assert length == pytest.approx(g.path_length, rel=1e-3)
    assert energy == pytest.approx(comp.effort(g), rel=2e-2)  # FD across the leaf junctions is crude
    assert tr.s[0] == 0 and tr.s[-1] == pytest.approx(comp.horizon) and np.all(np.diff(tr.s) > 0)


def test_collocation_side_measurements(comp):
    r = comp.result
    o = r.measures
    energy, length = _fd_energy(r.trajectory)
    assert length == pytest.approx(o.path_length, rel=1e-3)
    assert energy == pytest.approx(comp.effort(o), rel=2e-2)
    assert r.residual < 1e-7 and comp.plan.residual < 1e-9
    # the optimum of the path-length cost is shorter than the figure eight
    assert o.path_length < comp.plan_measures.path_length


def test_cli_compare_json_and_plot(tmp_path, capsys):
    js, png = tmp_path / "c.json", tmp_path / "c.png"
    rc = main(["compare", "--to", "0.5", "0.3", "--psi", "0.4", "--k", "2.5", "--intervals", "40",
               "--json", str(js), "--plot", str(png)])
    out = capsys.readouterr().out
    assert rc == 0
    for row in ("contact path length [R]", "effort", "peak |omega|", "residual (CVODES, Euclidean norm)", "solve time",
                "iterations"):
        assert row in out
    d = json.loads(js.read_text())
    for side in ("geometric_phase", "collocation"):
        s = d[side]
        for key in ("path_length", "effort", "residual", "solve_time_s", "trajectory"):
            assert key in s
        tr = s["trajectory"]
        assert set(tr) == {"t", "u_o", "v_o", "u_a", "v_a", "psi"}
        assert len({len(v) for v in tr.values()}) == 1 and len(tr["t"]) >= 1000
        assert tr["u_a"][-1] == pytest.approx(0.5, abs=1e-6) and tr["psi"][-1] == pytest.approx(0.4, abs=1e-6)
    assert png.stat().st_size > 1000


@pytest.mark.parametrize("argv, msg", [
    (["compare", "--to", "0.5", "0.3", "--k", "-1"], "k = -1"),
    (["compare", "--to", "0.5", "0.3", "--cost", "rotor_effort"], "needs robot"),
    (["compare", "--to", "0.5", "0.3", "--intervals", "0"], "intervals"),
    (["compare", "--to", "0.5", "0.3", "--json", "/nonexistent/dir/x.json"], "not writable"),
])
def test_cli_compare_bad_input(argv, msg, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert msg in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_cli_compare_robot(tmp_path, capsys):
    toml = tmp_path / "r.toml"
    toml.write_text("radius = 0.1\nmass_total = 1.2\nmass_shell = 0.4\nrotor_inertia_axial = 2.0e-4\n"
                    "rotor_inertia_transverse = 1.2e-4\n")
    js = tmp_path / "c.json"
    rc = main(["compare", "--to", "0.05", "0.03", "--psi", "0.4", "--robot", str(toml), "--cost", "rotor_effort",
               "--intervals", "30", "--json", str(js)])
    assert rc == 0
    d = json.loads(js.read_text())
    assert d["geometric_phase"]["effort_kind"] == "rotor" == d["collocation"]["effort_kind"]
    # the rotor-effort optimum costs less rotor effort than the figure eight
    assert d["collocation"]["effort"] < d["geometric_phase"]["effort"]


def test_cli_compare_solver_failure_exit_4(monkeypatch, capsys):
    """A failing IPOPT solve maps to exit 4 with its status, no traceback."""
    import rollplan.studies.comparison as cmp
    from rollplan.errors import SolverError

    def failing(*args, **kwargs):
        raise SolverError("IPOPT did not solve the collocation problem; hint: try guess='warm'",
                          "Maximum_Iterations_Exceeded")

    monkeypatch.setattr(cmp, "collocate", failing)
    assert main(["compare", "--to", "0.5", "0.3"]) == 4
    err = capsys.readouterr().err
    assert "Maximum_Iterations_Exceeded" in err and "hint" in err and "Traceback" not in err
    assert "try --guess warm" in err and "guess='warm'" not in err   # the hint in command-line syntax
