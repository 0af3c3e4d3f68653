"""Full reconfiguration in numbers: writes results/reconfiguration.md, reconfiguration.json and composed.png.

Every number is a measurement of this run:

* the approach/departure roll: its closed form against CVODES on the model's curve ODE and against
  scipy's DOP853 on the printed (15), (16), (20) (``tests/references.py``), down to and past the margin;
* random start/goal pairs (contact points anywhere in the region): modes, lengths, the certificate's
  residual, the residual of the independent DOP853 integration of the whole composed motion, time,
  the corners of the contact path at the joints, and how much ``legs="shortest"`` saves over the
  default ``"fallback"``;
* turning in place for several psi and k;
* a route of five waypoints;
* the JSON trajectory replayed by DOP853 along its sampled contact path, for several sample counts;
* the figure of a composed plan, results/composed.png;
* lengths against optimal control: for the issue's two pairs and random pairs (contact points up to 60 deg from
  the pole, k in [1.5, 8]), today's pole plan, one leg at any base point (``base="any"``), ``--refine``
  (``refine=True``) and a multi-start optimal-control reference solved on the printed (15), (16), (20) by
  ``tests/references.py`` (multiple shooting, RK4; not the project's collocation), with times.

Run: ``python scripts/reconfiguration.py [--out-dir results] [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from quick_runs import refuse_quick_into_results  # noqa: E402


def parse_args(argv=None):
    """The command line; ``--quick`` without ``--out-dir`` exits 2 with one line (before the slow imports below)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", help="default results; with --quick, required (results/ keeps the full run)")
    ap.add_argument("--quick", action="store_true", help="a few cases only, every section (for the tests of this "
                                                         "script)")
    args = ap.parse_args(argv)
    refuse_quick_into_results(args, "reconfiguration.py")
    return args


if __name__ == "__main__":
    parse_args()

import numpy as np  # noqa: E402

import rollplan  # noqa: E402
from rollplan.core.paths import PathIntegrator  # noqa: E402
from rollplan.io import save_figure, tagged, write_atomic, write_json  # noqa: E402
from rollplan.planners.geometric import ComposedPlanner, as_composed  # noqa: E402
from rollplan.planners.geometric.maneuvers import StraightRoll  # noqa: E402
from rollplan.plots.composed import plot_composed  # noqa: E402
from rollplan.problem import N3Z_MIN, Problem  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import references as ref  # noqa: E402  (the independent references of the tests)

SIGMA_MAX = math.acos(N3Z_MIN)


contact_at = ref.polar_contact
reference_final = ref.composed_final


def residual(final, goal):
    d = np.asarray(final, float) - np.asarray(goal, float)
    d[2] = ref.wrap(d[2])
    return float(np.linalg.norm(d))


def dop853_residual(p):
    c = as_composed(p)
    pr = c.problem
    return residual(reference_final(c.pieces, pr.scaled(pr.start), c.k), pr.scaled(pr.goal))


def corners(pieces):
    """Angles [deg] between the contact path's tangents at the end of each piece and the start of the next:
    ``{"leaf-leaf": [...], "other": [...]}`` (joints between the leaves of one leg of figure eights, and
    the rest: rolls to leaves, leg to leg, circle to circle).

    The map from the sphere's tangent plane at the contact point to the plane's ((15)-(16)) preserves
    angles, so these are the corners of the path on the plane too. Tangents are chords of length 1e-7 rad
    in the piece parameter.
    """
    out = {"leaf-leaf": [], "other": []}
    h = 1e-7
    for a, b in zip(pieces[:-1], pieces[1:]):
        end = ref.contact_point(*a.contact([2 * np.pi - h, 2 * np.pi]).T)
        begin = ref.contact_point(*b.contact([0.0, h]).T)
        t1, t2 = end[1] - end[0], begin[1] - begin[0]
        c = np.dot(t1, t2) / (np.linalg.norm(t1) * np.linalg.norm(t2))
        same_leg = a.kind == b.kind == "leaf" and (a.params, a.gamma) == (b.params, b.gamma)
        key = "leaf-leaf" if same_leg else "other"
        out[key].append(math.degrees(math.acos(max(-1.0, min(1.0, c)))))
    return out


def rolls(quick):
    rows = []
    integ = PathIntegrator()
    for n3z in (0.5, N3Z_MIN, 0.01) if not quick else (N3Z_MIN,):
        sigma = math.acos(n3z)
        worst_cv = worst_dop = 0.0
        for beta in np.linspace(-3.0, 3.0, 7 if not quick else 3):
            u, v = contact_at(sigma, beta)
            for k in (0.0, 2.5, 10.0, 100.0):
                for kind in ("approach", "departure"):
                    roll = StraightRoll.make(u, v, kind)
                    start = np.array([0, 0, 0, u, v]) if kind == "approach" else np.zeros(5)
                    cv = integ.ends([roll.piece()], start, k)[-1, :3]
                    ends = (sigma, 0.0) if kind == "approach" else (0.0, sigma)
                    dop = ref.integrate_contact_path(ref.great_circle_path(roll.beta, *ends), np.zeros(3), (0, 1),
                                                     k).y[:, -1]
                    worst_cv = max(worst_cv, residual(cv, roll.element()))
                    worst_dop = max(worst_dop, residual(dop, roll.element()))
        rows.append({"n3z": n3z, "cvodes": worst_cv, "dop853": worst_dop})
    return rows


def random_pairs(quick):
    rng = np.random.default_rng(2024)
    fallback, shortest = ComposedPlanner(), ComposedPlanner(legs="shortest")
    fallback.solve(Problem((0.0, 1.0, 0.0), k=2.5))   # build once
    rows = []
    for i in range(1 if quick else 30):
        start = (*rng.uniform(-1.5, 1.5, 2), rng.uniform(-4, 4),
                 *contact_at(rng.uniform(0, SIGMA_MAX), rng.uniform(-np.pi, np.pi)))
        goal = (*rng.uniform(-1.5, 1.5, 2), rng.uniform(-4, 4),
                *contact_at(rng.uniform(0, SIGMA_MAX), rng.uniform(-np.pi, np.pi)))
        k, steps = float(rng.uniform(0.5, 12.0)), int(rng.integers(1, 4))
        problem = Problem(goal, start=start, k=k, steps=steps)
        row = {"case": i, "k": k, "steps": steps}
        try:
            t0 = time.perf_counter()
            p = fallback.solve(problem)
            row.update(time_s=time.perf_counter() - t0, mode=p.mode, length=p.path_length,
                       rolls=sum(q.length for q in p.pieces if q.kind in ("approach", "departure")),
                       certificate=p.residual, dop853=dop853_residual(p), corners=corners(p.pieces))
            t0 = time.perf_counter()
            q = shortest.solve(problem)
            row.update(shortest_time_s=time.perf_counter() - t0, shortest_mode=q.mode, shortest_length=q.path_length,
                       shortest_dop853=dop853_residual(q))
        except rollplan.NoPlanError as exc:
            row["no_plan"] = str(exc)
        rows.append(row)
        print(f"pair {i}: {row.get('mode')} {row.get('length', float('nan')):.4f} -> "
              f"{row.get('shortest_length', float('nan')):.4f}", file=sys.stderr)
    return rows


def turns(quick):
    rows = []
    planner = ComposedPlanner()
    for k in (0.0, 2.5, 10.0, 30.0) if not quick else (2.5,):
        for psi in (0.3, 1.0, 3.0) if not quick else (1.0,):
            t0 = time.perf_counter()
            p = planner.solve(Problem((0.0, 0.0, psi), k=k))
            dt = time.perf_counter() - t0
            rows.append({"k": k, "psi": psi, "b": p.turn.b, "length": p.path_length, "time_s": dt,
                         "certificate": p.residual, "dop853": dop853_residual(p)})
    return rows


ROUTE = [(0, 0, 0), (1.0, 0.5, 0.3), (1.0, 0.5, 1.3), (1.2, 0.4, 1.5, 0.3, -0.2), (0, 0, 0, 0, 0)]


def route():
    t0 = time.perf_counter()
    r = rollplan.plan_route(ROUTE, k=2.5)
    dt = time.perf_counter() - t0
    x, worst = np.asarray(rollplan.State.of(ROUTE[0]), float), 0.0
    for p, w in zip(r.plans, ROUTE[1:]):
        x = reference_final(as_composed(p).pieces, x, 2.5)
        worst = max(worst, residual(x, rollplan.State.of(w)))
    return {"modes": r.stats.details["modes"], "length": r.path_length, "time_s": dt, "certificate": r.residual,
            "waypoint_residuals": [float(v) for v in r.waypoint_residuals], "dop853_worst_waypoint": worst}


#: The issue's two pairs (start, goal, k): the README example and a second one.
ISSUE_PAIRS = [((0.0, 0.0, 0.0, 0.5, -0.3), (0.8, 0.2, 1.0, -0.4, 0.4), 2.5),
               ((0.3, -0.2, 0.5, -0.3, 0.2), (-0.5, 0.6, -0.7, 0.35, 0.25), 4.0)]


def timed(f):
    t0 = time.perf_counter()
    out = f()
    return out, time.perf_counter() - t0


def random_full_pairs(seed, count):
    """``count`` random (start, goal, k): positions in [-1, 1]^2 R, psi in [-pi, pi], both contact points up to
    60 deg from the pole, k in [1.5, 8]."""
    rng = np.random.default_rng(seed)
    pairs = []
    for _ in range(count):
        start = (*rng.uniform(-1.0, 1.0, 2), rng.uniform(-np.pi, np.pi),
                 *contact_at(rng.uniform(0, math.radians(60.0)), rng.uniform(-np.pi, np.pi)))
        goal = (*rng.uniform(-1.0, 1.0, 2), rng.uniform(-np.pi, np.pi),
                *contact_at(rng.uniform(0, math.radians(60.0)), rng.uniform(-np.pi, np.pi)))
        pairs.append((tuple(float(v) for v in start), tuple(float(v) for v in goal), float(rng.uniform(1.5, 8.0))))
    return pairs


def ocp_turns(quick) -> dict:
    """The turns of the optimal-control reference: m = -2..2, or with ``quick`` its default m = -1, 0, 1 (left to the
    default, so that a process that asked for the same reference before finds it computed)."""
    return {} if quick else {"turns": (-2, -1, 0, 1, 2)}


def warm_default(problem, repeats: int = 3):
    """The new default (``polish="fast"``) of ``problem``, and its wall time: the median of ``repeats`` solves (after
    one that builds what it needs)."""
    fast = ComposedPlanner(polish="fast")
    fast.solve(problem)
    times = []
    for _ in range(repeats):
        q, dt = timed(lambda: fast.solve(problem))
        times.append(dt)
    return q, float(np.median(times))


def against_optimal_control(quick):
    """Lengths and times of the pole plan, the new default, base="any", refine=True and the optimal-control
    reference."""
    pairs = list(ISSUE_PAIRS[:1] if quick else ISSUE_PAIRS) + random_full_pairs(25, 0 if quick else 5)
    pole, based, refined = ComposedPlanner(), ComposedPlanner(base="any"), ComposedPlanner(refine=True)
    pole.solve(Problem((0.0, 1.0, 0.0), k=2.5))   # build once
    rows = []
    for i, (start, goal, k) in enumerate(pairs):
        problem = Problem(goal, start=start, k=k)
        row = {"start": start, "goal": goal, "k": k}
        p, row["pole_time_s"] = timed(lambda: pole.solve(problem))
        row["pole"] = p.path_length
        q, row["default_time_s"] = warm_default(problem, 1 if quick else 3)
        row.update(default=q.path_length, default_polished=q.mode == "refined", default_certificate=q.residual)
        try:
            q, row["based_time_s"] = timed(lambda: based.solve(problem))
            row.update(based=q.path_length, based_mode=q.mode)
        except rollplan.NoPlanError as exc:
            row["based_error"] = str(exc)
        r, row["refine_time_s"] = timed(lambda: refined.solve(problem))
        row.update(refine=r.path_length, refine_certificate=r.residual, refined=r.mode == "refined",
                   refine_note=r.stats.details.get("refine"))
        if r.mode == "refined":
            tr = r.sample(4001)
            out = ref.replay(tr.u_o, tr.v_o, tr.segment, tr.state[0, :3], k)
            row["refine_replay"] = residual(np.r_[out[-1], tr.state[-1, 3:]], problem.goal)
        (best, per_turn), row["ocp_time_s"] = timed(
            lambda: ref.optimal_control_length(start, goal, k, **ocp_turns(quick)))
        row.update(ocp=best, ocp_turns={str(m): v for m, v in per_turn.items()})
        rows.append(row)
        print(f"optimal control pair {i}: pole {row['pole']:.4f}, default {row['default']:.4f}, any base "
              f"{row.get('based', float('nan')):.4f}, refined {row['refine']:.4f}, reference {best:.4f}",
              file=sys.stderr)
    return rows


def default_against_reference(quick):
    """The new default against the pole plan and the optimal-control reference on more random pairs; with ``quick``
    on the README example's pair, whose reference :func:`against_optimal_control` computed (a check that the section
    runs)."""
    rows = []
    pole = ComposedPlanner()
    for i, (start, goal, k) in enumerate(ISSUE_PAIRS[:1] if quick else random_full_pairs(2525, 24)):
        problem = Problem(goal, start=start, k=k)
        row = {"start": start, "goal": goal, "k": k}
        p, row["pole_time_s"] = timed(lambda: pole.solve(problem))
        q, row["default_time_s"] = warm_default(problem, 1 if quick else 3)
        row.update(pole=p.path_length, pole_mode=p.mode, default=q.path_length, polished=q.mode == "refined",
                   certificate=q.residual)
        if q.mode == "refined":
            tr = q.sample(4001)
            out = ref.replay(tr.u_o, tr.v_o, tr.segment, tr.state[0, :3], k)
            row["replay"] = residual(np.r_[out[-1], tr.state[-1, 3:]], problem.goal)
        (row["ocp"], _), row["ocp_time_s"] = timed(
            lambda: ref.optimal_control_length(start, goal, k, **ocp_turns(quick)))
        rows.append(row)
        print(f"random pair {i}: pole {row['pole']:.4f}, default {row['default']:.4f} ({row['default_time_s']:.3f} s), "
              f"reference {row['ocp']:.4f}", file=sys.stderr)
    return rows


def replay(p, samples):
    """Max |replayed - sampled| of (u_a, v_a, psi) and |replayed end - goal| (DOP853 along splines of the samples)."""
    tr = p.sample(samples)
    out = ref.replay(tr.u_o, tr.v_o, tr.segment, tr.state[0, :3], p.k)
    err = tr.state[:, :3] - out
    err[:, 2] = ref.wrap(err[:, 2])
    return float(np.abs(err).max()), residual(np.r_[out[-1], tr.state[-1, 3:]], p.goal)


def main(argv=None) -> int:
    args = parse_args(argv)
    args.out_dir = args.out_dir or "results"
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    data = {"load_average_at_start": os.getloadavg()[0], "rolls": rolls(args.quick), "pairs": random_pairs(args.quick),
            "turns": turns(args.quick), "route": route(), "optimal_control": against_optimal_control(args.quick),
            "default_random": default_against_reference(args.quick)}
    if args.quick:      # the full run's JSON keeps its keys (the default's time: the median of three)
        data["default_repeats"] = 1
        data["quick"] = True
    fig_plan = rollplan.plan((0.0, 0.0, 1.5, -0.4, 0.4), k=2.5, start=(0.0, 0.0, 0.0, 0.5, -0.3), polish="off")
    data["figure"] = {"mode": fig_plan.mode, "length": fig_plan.path_length, "residual": fig_plan.residual,
                      "lengths": fig_plan.lengths()}
    data["replay"] = [{"samples": n, **dict(zip(("max_error", "end_error"), replay(fig_plan, n)))}
                      for n in ((501,) if args.quick else (501, 2001, 8001))]
    save_figure(plot_composed(fig_plan, fig_plan.sample(4000)), out / "composed.png")
    data["total_time_s"] = time.perf_counter() - t0
    write_json(out / "reconfiguration.json", tagged(data, "R"))
    write_atomic(out / "reconfiguration.md", report(data).encode())
    print(f"wrote {out / 'reconfiguration.md'}, reconfiguration.json, composed.png "
          f"({data['total_time_s']:.0f} s)", file=sys.stderr)
    return 0


def report(d) -> str:
    repeats = "one" if d.get("default_repeats") == 1 else "three"   # warm solves of the default per pair
    L = ["# Full reconfiguration: measurements", "",
         "Written by `scripts/reconfiguration.py` (rerun it to regenerate). Residuals are Euclidean norms over "
         "(u_a, v_a in R, psi wrapped, u_o, v_o); *certificate* is the planner's CVODES integration of the whole "
         "composed motion from the start state, *DOP853* an independent integration of the printed (15), (16), (20) "
         "along the same contact path (`tests/references.py`). Times are wall times on a shared 2-core machine "
         f"(load average {d['load_average_at_start']:.1f} at the start): upper bounds.", "",
         "## Approach and departure rolls: closed form against integration", "",
         "Worst difference over directions beta, k in {0, 2.5, 10, 100}, approach and departure:", "",
         "| n3z of the off-pole end | CVODES (model's curve ODE) | DOP853 (printed equations) |", "|---|---|---|"]
    L += [f"| {r['n3z']:g} | {r['cvodes']:.1e} | {r['dop853']:.1e} |" for r in d["rolls"]]
    pairs = [r for r in d["pairs"] if "mode" in r]
    modes = {}
    for r in pairs:
        modes[r["mode"]] = modes.get(r["mode"], 0) + 1
    times = np.array([r["time_s"] for r in pairs])
    stimes = np.array([r["shortest_time_s"] for r in pairs])
    saving = np.array([1 - r["shortest_length"] / r["length"] for r in pairs])
    corner = np.concatenate([r["corners"]["other"] for r in pairs])
    smooth = np.concatenate([r["corners"]["leaf-leaf"] for r in pairs])
    L += ["", "## Random start and goal states", "",
          f"{len(d['pairs'])} pairs (seed 2024): positions in [-1.5, 1.5]^2 R, psi in [-4, 4], both contact points "
          "uniform in direction and polar angle up to the margin (n3z >= 0.05), k in [0.5, 12], n in {1, 2, 3}.", "",
          f"* planned and certified: {len(pairs)} of {len(d['pairs'])}; modes (default `legs=\"fallback\"`): "
          + ", ".join(f"{m} {c}" for m, c in sorted(modes.items())),
          f"* worst certificate residual {max(r['certificate'] for r in pairs):.1e}; worst DOP853 residual "
          f"{max(r['dop853'] for r in pairs):.1e}; worst DOP853 residual of the `shortest` plans "
          f"{max(r['shortest_dop853'] for r in pairs):.1e} (tolerance 1e-9)",
          f"* path length {min(r['length'] for r in pairs):.3g} to {max(r['length'] for r in pairs):.3g} R, "
          f"of which rolls {min(r['rolls'] for r in pairs):.3g} to {max(r['rolls'] for r in pairs):.3g} R",
          f"* time per plan (default): median {np.median(times):.3g} s, max {times.max():.3g} s; with "
          f"`legs=\"shortest\"`: median {np.median(stimes):.3g} s, max {stimes.max():.3g} s",
          f"* `shortest` found a shorter (two-leg) plan in {int((saving > 1e-9).sum())} of {len(pairs)} pairs; "
          f"saving median {np.median(saving) * 100:.1f} %, max {saving.max() * 100:.1f} %",
          f"* corners of the contact path at the joints (angle between the tangents before and after): where a "
          f"roll meets a leaf or one leg the next, median {np.median(corner):.0f} deg, max {corner.max():.0f} deg "
          f"over {corner.size} joints; between the leaves of one leg at most {smooth.max():.1e} deg over "
          f"{smooth.size} joints (the figure eights of a leg join smoothly). The time law rests at every joint."]
    L += ["", "## Turning in place", "", "| k | psi | circle b [R] | path [R] | certificate | DOP853 | time [s] |",
          "|---|---|---|---|---|---|---|"]
    L += [f"| {r['k']:g} | {r['psi']:g} | {r['b']:.6f} | {r['length']:.4f} | {r['certificate']:.1e} | "
          f"{r['dop853']:.1e} | {r['time_s']:.3f} |" for r in d["turns"]]
    r = d["route"]
    L += ["", "## A route of five waypoints", "",
          f"`{ROUTE}` at k = 2.5: leg modes {', '.join(r['modes'])}; {r['length']:.4f} R; one-pass certificate "
          f"{r['certificate']:.1e}, worst waypoint residual {max(r['waypoint_residuals']):.1e}; DOP853 through the "
          f"whole route, worst waypoint {r['dop853_worst_waypoint']:.1e}; {r['time_s']:.2f} s."]
    oc = d["optimal_control"]
    L += ["", "## Lengths against optimal control", "",
          "Contact path lengths [R] and wall times [s] of: the pole plan (*pole*, `polish=\"off\"`: every leg of "
          "figure eights at the south pole), the new default (*default*: `rollplan.plan`, the pole plan and the fast "
          "polish, N = 8 from the straight line, the shorter certified kept; time: the median of "
          f"{repeats} warm solves), one leg at any base point along the arc from the start to "
          "the goal contact point "
          "(`base=\"any\"`), `--refine` (`refine=True`: the rest-to-rest collocation warm-started by the default "
          "plan and by straight lines, N = 60, polar angle <= 80 deg, certified by CVODES), and a multi-start "
          "optimal-control reference "
          "(`tests/references.py`: (15), (16), (20) as printed, multiple shooting with RK4, N = 60, rest to rest, "
          "polar angle <= 80 deg, minimum path energy, IPOPT from the straight line on each whole number of turns "
          f"m in {{{', '.join(oc[0]['ocp_turns'])}}} of psi, the shortest kept). Pairs 1 and 2 are the issue's; the "
          "others random (seed 25): positions in [-1, 1]^2 R, psi in [-pi, pi], both contact points up to 60 deg "
          "from the pole, k in [1.5, 8]. *ratio* is the length over the reference's.", "",
          "| pair | k | pole [R] | time | default [R] | time | any base [R] | time | --refine [R] | time | "
          "reference [R] | time | pole ratio | default ratio | any-base ratio | --refine ratio | --refine certificate "
          "| --refine DOP853 replay |",
          "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for i, r in enumerate(oc, 1):
        b = r.get("based", float("nan"))
        L.append(f"| {i} | {r['k']:.3g} | {r['pole']:.4f} | {r['pole_time_s']:.2f} | {r['default']:.4f}"
                 f"{'' if r['default_polished'] else ' (pole)'} | {r['default_time_s']:.3f} | {b:.4f} | "
                 f"{r.get('based_time_s', float('nan')):.2f} | {r['refine']:.4f}{'' if r['refined'] else ' (kept)'} | "
                 f"{r['refine_time_s']:.1f} | {r['ocp']:.4f} | {r['ocp_time_s']:.1f} | {r['pole'] / r['ocp']:.3f} | "
                 f"{r['default'] / r['ocp']:.3f} | {b / r['ocp']:.3f} | {r['refine'] / r['ocp']:.3f} | "
                 f"{r['refine_certificate']:.1e} | "
                 f"{r.get('refine_replay', float('nan')):.1e} |")
    worst = max(r["refine"] / r["ocp"] for r in oc)
    L += ["", f"* `--refine` is at most {worst:.3f} x the reference's length over these pairs; it takes "
          f"{min(r['refine_time_s'] for r in oc):.1f} to {max(r['refine_time_s'] for r in oc):.1f} s (the plan "
          "included: IPOPT from the plan on its whole turns m of psi and on 0, and from the straight line on "
          "m = -1, 0, 1, then the Gauss-Newton correction and the CVODES certificate of the best).",
          "* *DOP853 replay*: the refined motion's 4001 samples, (15), (16), (20) integrated by DOP853 along cubic "
          "splines of the sampled (u_o, v_o) alone, distance of the end to the goal."]
    notes = [f"pair {i}: {r['refine_note']}" for i, r in enumerate(oc, 1) if not r["refined"]]
    if notes:
        L += ["* kept (not refined): " + "; ".join(notes)]
    dr = d["default_random"]
    pairs = "--quick: the README example's, not random" if d.get("quick") else "seed 2525, drawn as above"
    ratios = np.array([r["default"] / r["ocp"] for r in dr])
    one = [r["default_time_s"] for r in dr if r["pole_mode"] == "one"]
    L += ["", "### The new default on more random pairs", "",
          f"{len(dr)} pairs ({pairs}): the pole plan, the new default and the reference. The default "
          f"is at most {ratios.max():.3f} x the reference's length (median {np.median(ratios):.3f} x), never longer "
          f"than the pole plan ({sum(r['default'] <= r['pole'] for r in dr)} of {len(dr)}); polished "
          f"{sum(r['polished'] for r in dr)} of {len(dr)}; worst certificate "
          f"{max(r['certificate'] for r in dr):.1e}, worst DOP853 replay of the polished motions "
          f"{max((r['replay'] for r in dr if 'replay' in r), default=float('nan')):.1e}. Warm time of the default "
          f"(median of {repeats} solves per pair): median "
          f"{np.median([r['default_time_s'] for r in dr]):.3f} s, max "
          f"{max(r['default_time_s'] for r in dr):.3f} s; over the {len(one)} pairs whose pole plan is one leg, "
          f"median {np.median(one) if one else float('nan'):.3f} s.", "",
          "| pair | k | pole [R] | pole mode | default [R] | time [s] | reference [R] | default ratio | pole ratio |",
          "|---|---|---|---|---|---|---|---|---|"]
    L += [f"| {i} | {r['k']:.3g} | {r['pole']:.4f} | {r['pole_mode']} | {r['default']:.4f}"
          f"{'' if r['polished'] else ' (pole)'} | {r['default_time_s']:.3f} | {r['ocp']:.4f} | "
          f"{r['default'] / r['ocp']:.3f} | {r['pole'] / r['ocp']:.3f} |" for i, r in enumerate(dr, 1)]
    f = d["figure"]
    L += ["", "## The figure and the trajectory replay", "",
          "`composed.png`: contact (0.5, -0.3) to (-0.4, 0.4), psi 0 to 1.5 at the same plane point, k = 2.5: "
          f"mode {f['mode']}, {f['length']:.4f} R ("
          + ", ".join(f"{k} {v:.3f}" for k, v in f["lengths"].items()) + f"), residual {f['residual']:.1e}.", "",
          "(15), (16), (20) integrated by DOP853 along cubic splines of the sampled (u_o, v_o) alone "
          "(one spline per segment) against the sampled (u_a, v_a, psi):", "",
          "| samples | max difference | end to goal |", "|---|---|---|"]
    L += [f"| {r['samples']} | {r['max_error']:.1e} | {r['end_error']:.1e} |" for r in d["replay"]]
    L += ["", f"Total run time {d['total_time_s']:.0f} s.", ""]
    return "\n".join(L)


if __name__ == "__main__":
    sys.exit(main())
