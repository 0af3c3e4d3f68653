"""The fair comparison of geometric phase and collocation on a set of targets; writes results/comparison.md.

Usage: python scripts/compare_planners.py [--out results] [--quick]

Every number and every conclusion of comparison.md is computed here from the runs
(rollplan.studies.comparison.compare: one problem, rest to rest, acceleration-level
controls for both, the same contact bound, the GP path with its optimal timing, the
collocation from several starts over m). Also: the collocation's optimum against N, and
the rotor-energy comparison with the default robot. Writes comparison.md, comparison.json
and comparison_paths.png. The peer (rockit's transcription of the same OCP) needs the ``peer`` extra.
"""

from __future__ import annotations

import argparse
import logging
import math
import os
import platform
import statistics
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from rollplan import default_robot
from rollplan.errors import NoPlanError, SolverError
from rollplan.io import save_figure, write_atomic, write_json
from rollplan.plots.compare import plot_comparison
from rollplan.studies.comparison import CONTACT_BOUND, compare, minimum_time

K = 2.5
TARGETS = [(0.3, 0.0, 0.0), (0.5, 0.3, 0.4), (-0.4, 0.4, 1.0), (0.8, -0.2, -0.5), (0.2, 0.1, 2.0),
           (-0.6, -0.6, -1.5)]
#: Targets of the path_length cost (a subset: every run is a multistart of IPOPT solves).
LENGTH_TARGETS = TARGETS[:4]
ROBOT_TARGETS = [(0.05, 0.03, 0.4), (0.02, 0.01, 2.0)]
N = 100
#: Relative difference of two starts' costs counted as a tie (the same optimum reached from both).
TIE = 1e-9
CONVERGENCE_N = (20, 40, 80, 160, 320)


def polar_max(motion):
    s = motion.state
    return float(np.degrees(np.arccos(np.clip(np.cos(s[:, 3]) * np.cos(s[:, 4]), -1, 1)).max()))


def run(target, cost, robot=None, intervals=N):
    t0 = time.perf_counter()
    try:
        c = compare(target, 1, k=None if robot else K, robot=robot, cost=cost, intervals=intervals)
    except (NoPlanError, SolverError) as exc:
        logging.info("%s %s: %s", target, cost, exc)
        return {"target": target, "cost": cost, "error": str(exc)}
    g, o = c.gp, c.collocation
    rest = max(float(np.abs(m.omega[[0, -1]]).max()) for m in (g.motion, o.motion))
    not_worse = [s.cost <= s.start_cost * (1 + 1e-9) for s in c.starts if s.start_cost is not None and s.cost]
    row = {"target": target, "cost": cost, "gp_branch": c.plan.branch, "gp_a": c.plan.a, "gp_b": c.plan.b,
           "gp_turns": round((c.plan.final.psi - c.problem.goal.psi) / (2 * math.pi)), "ocp_turns": c.result.turns,
           "gp": g.costs, "ocp": o.costs, "bound": c.bound, "gp_residual": g.residual, "ocp_residual": o.residual,
           "gp_time": g.solve_time_s, "ocp_time": o.solve_time_s, "winner": c.result.guess,
           "winners": [s.name for s in c.starts if s.cost is not None and s.cost <= o.costs[cost] * (1 + TIE)],
           "starts": [(s.name, s.status, s.cost) for s in c.starts], "rest": rest,
           "polar_gp": polar_max(g.motion), "polar_ocp": polar_max(o.motion),
           "bound_deg": math.degrees(c.contact_bound), "ocp_not_worse": all(not_worse), "n_checked": len(not_worse),
           "wall": time.perf_counter() - t0}
    logging.info("%s %s: GP %.4g, OCP %.4g (%.0f s)", target, cost, g.costs[cost], o.costs[cost], row["wall"])
    return row, c


def fmt(x, f=".4g"):
    return "n/a" if x is None else format(x, f)


def kind(name):
    return "naive" if name.startswith("naive") else ("GP, psi bent to another m" if "->" in name else "GP branch")


def section(rows, cost, unit):
    ok = [r for r in rows if "error" not in r]
    out = [f"| target (u_a, v_a, psi) | GP branch (a, b) | m GP / OCP | length GP / OCP | {cost} GP / bound / OCP "
           f"| ratio OCP/GP | peak rotor rate GP / OCP | residual GP / OCP | time GP / OCP [s] | best start |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if "error" in r:
            out.append(f"| {r['target']} | {r['error']} |||||||||")
            continue
        g, o = r["gp"], r["ocp"]
        out.append(f"| {r['target']} | {r['gp_branch']} ({r['gp_a']:.3f}, {r['gp_b']:.3f}) | {r['gp_turns']} / "
                   f"{r['ocp_turns']} | {g['path_length']:.4g} / {o['path_length']:.4g} | {g[cost]:.4g} / "
                   f"{fmt(r['bound'])} / {o[cost]:.4g} | {o[cost] / g[cost]:.3f} | {g['peak_rotor_rate']:.4g} / "
                   f"{o['peak_rotor_rate']:.4g} | {r['gp_residual']:.1e} / {r['ocp_residual']:.1e} | "
                   f"{r['gp_time']:.2f} / {r['ocp_time']:.2f} | {', '.join(r['winners'])} |")
    ratios = [r["ocp"][cost] / r["gp"][cost] for r in ok]
    lratios = [r["ocp"]["path_length"] / r["gp"]["path_length"] for r in ok]
    lines = []
    if ok:
        better = sum(x < 1 for x in ratios)
        lines.append(f"- The collocation's {cost} is below the GP plan's on {better}/{len(ok)} targets; ratio "
                     f"OCP/GP median {statistics.median(ratios):.3f} (range {min(ratios):.3f}-{max(ratios):.3f}); "
                     f"path-length ratio median {statistics.median(lratios):.3f} "
                     f"(range {min(lratios):.3f}-{max(lratios):.3f}).")
        if cost == "angular_velocity":
            over = [r["gp"][cost] / r["bound"] - 1 for r in ok]
            lines.append(f"- The GP path's optimal rest-to-rest timing is within {100 * max(over):.2f} % of the timing "
                         f"bound of its path on every target (median {100 * statistics.median(over):.2f} %; "
                         f"{sum(x <= 0.02 for x in over)}/{len(ok)} within 2 %).")
        diff_m = sum(r["ocp_turns"] != r["gp_turns"] for r in ok)
        lines.append(f"- The best collocation optimum has another number of whole turns m of psi than the GP plan on "
                     f"{diff_m}/{len(ok)} targets.")
        wins = {}
        for r in ok:
            for k in {kind(name) for name in r["winners"]}:
                wins[k] = wins.get(k, 0) + 1
        conv = {}
        for r in ok:
            for name, status, _ in r["starts"]:
                n_ok, n = conv.get(kind(name), (0, 0))
                conv[kind(name)] = (n_ok + (status == "ok"), n + 1)
        lines.append(f"- Best start (every start within {TIE:g} relative of the best cost counts: starts reaching the "
                     "same optimum tie): " + ", ".join(f"{k} {v}/{len(ok)}" for k, v in sorted(wins.items())) +
                     "; converged: " + ", ".join(f"{k} {a}/{b}" for k, (a, b) in sorted(conv.items())) + ".")
        checked = sum(r["n_checked"] for r in ok)
        lines.append(f"- Every collocation started from a GP branch ends no worse than that branch: "
                     f"{'yes' if all(r['ocp_not_worse'] for r in ok) else 'NO'} ({checked} warm starts).")
        lines.append(f"- Both motions start and end at rest (largest |omega| at t = 0, T: "
                     f"{max(r['rest'] for r in ok):.1e} rad/s) and stay within the contact bound "
                     f"{ok[0]['bound_deg']:.4g} deg (largest polar angle GP {max(r['polar_gp'] for r in ok):.3f} deg, "
                     f"collocation {max(r['polar_ocp'] for r in ok):.3f} deg). Residuals: GP at most "
                     f"{max(r['gp_residual'] for r in ok):.1e}, collocation at most "
                     f"{max(r['ocp_residual'] for r in ok):.1e}.")
        gt, ot = [r["gp_time"] for r in ok], [r["ocp_time"] for r in ok]
        lines.append(f"- Solve time (whole side, shared machine): GP median {statistics.median(gt):.2f} s, "
                     f"collocation (every start) median {statistics.median(ot):.2f} s.")
    return out, lines


def convergence(target=(0.5, 0.3, 0.4)):
    rows = []
    for n in CONVERGENCE_N:
        c = compare(target, 1, k=K, intervals=n, branches=1, naive=False)
        rows.append((n, c.collocation.costs["angular_velocity"], c.gp.costs["angular_velocity"], c.bound,
                     c.collocation.residual))
        logging.info("convergence N = %d done", n)
    diffs = [rows[i][1] - rows[i + 1][1] for i in range(len(rows) - 1)]
    orders = [math.log2(diffs[i] / diffs[i + 1]) if diffs[i] * diffs[i + 1] > 0 else float("nan")
              for i in range(len(diffs) - 1)]
    gp_over = [(r[2] / r[3] - 1) for r in rows]
    per_doubling = statistics.median([gp_over[i] / gp_over[i + 1] for i in range(len(gp_over) - 1)])
    table = ["| N | collocation int|omega|^2 dt | J(N/2) - J(N) | empirical order | GP (optimal timing) | "
             "GP over its bound | collocation residual |", "|---|---|---|---|---|---|---|"]
    for i, (n, o, g, b, res) in enumerate(rows):
        table.append(f"| {n} | {o:.8f} | {fmt(diffs[i - 1] if i else None, '.3e')} | "
                     f"{fmt(orders[i - 2] if i >= 2 else None, '.2f')} | {g:.6f} | {100 * (g / b - 1):.3f} % | "
                     f"{res:.1e} |")
    monotone = all(x > 0 for x in diffs)
    text = ("Empirical order of the collocation optimum J(N) in N, log2((J(N/4) - J(N/2)) / (J(N/2) - J(N))) "
            "from successive doublings (no reference value): " + ", ".join(f"{x:.2f}" for x in orders) +
            f"; J(N) decreases {'monotonically' if monotone else 'NOT monotonically'} with N. ")
    if abs(orders[-1] - 1) < 0.2:
        text += ("The optimum converges at first order, not at the transcription's order 2d (which its states have "
                 "with the controls held fixed, tests/test_compare.py): the cost does not involve the "
                 "accelerations, so the continuous problem's infimum has the rates jumping at both ends and is not "
                 "attained, and the discrete optimum ramps the rates from and to rest within about one interval at "
                 "each end. ")
    text += (f"The GP timing's excess over its bound falls from {100 * gp_over[0]:.2f} % at N = {rows[0][0]} to "
             f"{100 * gp_over[-1]:.3f} % at N = {rows[-1][0]} (median ratio per doubling of N {per_doubling:.2f}).")
    return table, text, rows


#: The peer's case: a target of the angular_velocity table, N and d of the comparison, from its warm start gp0.
PEER_TARGET = (0.5, 0.3, 0.4)
PEER_REPEATS = 5


def peer_section(quick, data):
    """rockit's transcription of the same rest-to-rest OCP (rollplan.studies.comparison_peer) against rollplan's."""
    from rollplan import Problem
    from rollplan.errors import InputError
    from rollplan.studies.comparison_peer import peer_rest_to_rest

    head = [f"## Peer: the same OCP in rockit (target {PEER_TARGET}, cost angular_velocity, N = {N}, Legendre d = 3)",
            ""]
    repeats = 1 if quick else PEER_REPEATS
    try:
        r = peer_rest_to_rest(Problem(PEER_TARGET, k=K), "gp", intervals=N, degree=3, repeats=repeats).row()
    except (InputError, SolverError, NoPlanError) as exc:
        data["peer"] = {"error": str(exc)}
        return [*head, f"- Not run: {exc}", ""]
    data["peer"] = r
    agree = r["relative_difference"] <= 1e-6
    ratio = r["peer_solve_median_s"] / r["solve_median_s"]
    lines = [
        "rockit (`rockit-meco`, the `peer` extra) transcribes the OCP of `rollplan.planners.collocation.rest` by its "
        "own code (`rockit.DirectCollocation`, one polynomial per control interval): the same dynamics (the model's "
        "CasADi function passed to `ocp.set_der`), cost (`ocp.integral` of the same running cost), boundary "
        "conditions at rest, contact bound (on the control grid and at the collocation points), piecewise-constant "
        "accelerations on the same N intervals, the same collocation points, IPOPT with the same options, from the "
        f"same guess ({r['guess']}: the shortest GP branch with its optimal timing). Solve times: wall time of a "
        f"solve from that guess with the solver built, median of {repeats + 1} (rollplan) and {repeats} (rockit, "
        "after its first solve); rockit's include its per-solve bookkeeping.", "",
        f"- The optima {'agree' if agree else 'DO NOT agree'} to 1e-6: relative difference "
        f"{r['relative_difference']:.1e}; largest difference of the accelerations {r['control_difference']:.1e} "
        f"rad/s^2; both certified by CVODES (residuals {r['residual']:.1e} / {r['peer_residual']:.1e}).",
        f"- Solve time median rollplan {r['solve_median_s']:.3f} s, rockit {r['peer_solve_median_s']:.3f} s (rockit/"
        f"rollplan {ratio:.2f}; iterations {r['iterations']} / {r['peer_iterations']}). Construction: rollplan's NLP "
        f"and solver {r['build_s']:.2f} s; rockit's first solve (transcription, solver, solve) {r['peer_first_s']:.2f} "
        "s.", "",
        "| side | optimum int|omega|^2 dt | iterations | solve median [s] | per iteration [ms] | construction [s] | "
        "residual |", "|---|---|---|---|---|---|---|",
        f"| rollplan (`RestToRestPlanner`) | {r['objective']:.12f} | {r['iterations']} | {r['solve_median_s']:.3f} | "
        f"{1e3 * r['solve_median_s'] / r['iterations']:.1f} | {r['build_s']:.2f} | {r['residual']:.1e} |",
        f"| rockit (`DirectCollocation`) | {r['peer_objective']:.12f} | {r['peer_iterations']} | "
        f"{r['peer_solve_median_s']:.3f} | {1e3 * r['peer_solve_median_s'] / r['peer_iterations']:.1f} | "
        f"{r['peer_first_s']:.2f} (with the first solve) | {r['peer_residual']:.1e} |", ""]
    return [*head, *lines]


def min_time_section(quick, data):
    robot = replace(default_robot(), max_rotor_rate=300.0, max_rotor_torque=0.05)
    rows, table = [], ["| target [m, rad] | GP time-optimal [s] | collocation minimum time [s] | ratio | peak rate "
                       "GP / coll. [rad/s] | peak torque GP / coll. [N m] | residual GP / coll. |",
                       "|---|---|---|---|---|---|---|"]
    for tgt in (ROBOT_TARGETS[:1] if quick else ROBOT_TARGETS):
        try:
            mt = minimum_time(tgt, robot)
        except (NoPlanError, SolverError) as exc:
            table.append(f"| {tgt} | {exc} ||||||")
            continue
        g, o = mt.gp.costs, mt.collocation.costs
        rows.append({"target": tgt, "gp": mt.gp_duration, "ocp": mt.duration, "gp_costs": g, "ocp_costs": o})
        table.append(f"| {tgt} | {mt.gp_duration:.4f} | {mt.duration:.4f} | {mt.duration / mt.gp_duration:.3f} | "
                     f"{g['peak_rotor_rate']:.4g} / {o['peak_rotor_rate']:.4g} | {g['peak_rotor_torque']:.5f} / "
                     f"{o['peak_rotor_torque']:.5f} | {mt.gp.residual:.1e} / {mt.collocation.residual:.1e} |")
        logging.info("minimum time %s done", tgt)
    data["minimum_time"] = rows
    lines = []
    if rows:
        ratios = [r["ocp"] / r["gp"] for r in rows]
        over = max(max(r["ocp_costs"]["peak_rotor_torque"] / robot.max_rotor_torque,
                       r["ocp_costs"]["peak_rotor_rate"] / robot.max_rotor_rate) for r in rows)
        lines = [f"- Minimum-time ratio collocation/GP median {statistics.median(ratios):.3f} "
                 f"(range {min(ratios):.3f}-{max(ratios):.3f}) on {len(rows)} targets.",
                 f"- The collocation's NLP holds the limits at its collocation points; where the certified samples "
                 f"exceeded them it was solved again with the limits backed off. On the certified samples its largest "
                 f"use of a limit is {over:.5f} of it" + (" (ABOVE 1 between the collocation points)." if over > 1
                                                           else ".")]
    return [f"## Minimum time under the rotor limits (default robot, max_rotor_rate = {robot.max_rotor_rate:g} rad/s, "
            f"max_rotor_torque = {robot.max_rotor_torque:g} N m; collocation N = 60)", "", *lines, "", *table, ""]


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="results")
    ap.add_argument("--quick", action="store_true", help="three targets, no convergence table")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(message)s")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t_all = time.perf_counter()
    load_start = os.getloadavg()[0]
    targets = TARGETS[:3] if args.quick else TARGETS
    md = ["# Geometric phase versus collocation: one problem, rest to rest", "",
          f"Generated by `scripts/compare_planners.py` on {platform.node()} ({platform.machine()}); k = {K}, "
          f"T = 1 s, N = {N} intervals for both, collocation Legendre d = 3, contact bound "
          f"{math.degrees(CONTACT_BOUND):.4g} deg for both, start at rest at the origin, goal at rest at the pole.", "",
          "Both motions solve the same problem (`rollplan.studies.comparison`): the same start and goal, the same "
          "contact bound (the GP planner keeps the branches with leaves a, b <= sin(bound / 2) R), rest to rest with "
          "accelerations constant on N intervals (the collocation controls the contact accelerations; the GP path is "
          "timed by the rest-to-rest timing of its path that minimises the compared cost), psi an angle (the "
          "collocation is solved from the GP branches, the best branch's motion with psi bent to m +- 1 and 0, and a "
          "naive straight line; the best certified optimum is kept). Every cost is measured by "
          "`rollplan.measures.measure` on the sampled motion of each side. 'bound' is the least int |omega|^2 dt of "
          "any timing of the GP path, (int |W| ds)^2 / T. For the path_length cost both minimise the energy form "
          "int |v|^2 dt (the GP path's length does not depend on its timing) and the length is reported.", ""]
    data = {"k": K, "intervals": N, "contact_bound": CONTACT_BOUND, "sections": {}}
    figure = None
    for cost in ("angular_velocity", "path_length"):
        rows = []
        for tgt in (targets if cost == "angular_velocity" else [t for t in targets if t in LENGTH_TARGETS]):
            res = run(tgt, cost)
            if isinstance(res, tuple):
                rows.append(res[0])
                if figure is None and tgt == (0.2, 0.1, 2.0) and cost == "angular_velocity":
                    figure = res[1]
            else:
                rows.append(res)
        table, lines = section(rows, cost, "")
        md += [f"## Cost {cost}", "", *lines, "", *table, ""]
        data["sections"][cost] = rows
    robot = default_robot()
    rows = []
    for tgt in (ROBOT_TARGETS[:1] if args.quick else ROBOT_TARGETS):
        res = run(tgt, "rotor_energy", robot=robot)
        rows.append(res[0] if isinstance(res, tuple) else res)
    table, lines = section(rows, "rotor_energy", "N^2 m^2 s")
    md += ["## Cost rotor_energy (int |tau|^2 dt), the default robot (R = 0.1 m, targets in m)", "", *lines, "",
           *table, ""]
    data["sections"]["rotor_energy"] = rows
    if not args.quick:
        table, text, conv = convergence()
        md += ["## Convergence in N (target (0.5, 0.3, 0.4), cost angular_velocity)", "", text, "", *table, ""]
        data["convergence"] = conv
    md += min_time_section(args.quick, data)
    md += peer_section(args.quick, data)
    if figure is not None:
        save_figure(plot_comparison(figure), out / "comparison_paths.png")
        md += ["![paths and time series, (0.2, 0.1, 2)](comparison_paths.png)", ""]
    load = ", ".join(f"{x:.2f}" for x in (load_start, os.getloadavg()[0]))
    md.insert(3, f"Total run time {time.perf_counter() - t_all:.0f} s; times are wall times on a shared machine "
                 f"({os.cpu_count()} cores; load average over 1 min at start and end: {load}).")
    write_atomic(out / "comparison.md", "\n".join(md).encode())
    write_json(out / "comparison.json", _jsonable(data))
    print(f"wrote {out / 'comparison.md'}")


def _jsonable(x):
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, np.integer)):
        return x.item()
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


if __name__ == "__main__":
    main()
