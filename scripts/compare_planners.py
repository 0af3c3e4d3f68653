"""Geometric phase versus direct collocation on a set of targets; writes results/comparison.md.

Usage: python scripts/compare_planners.py [--out results] [--quick] [--figures-only]

For every target: the geometric-phase plan (fewest steps in 1..3 that give a
plan), and collocation (N = 100, Legendre d = 3, T = 1) with two costs
(path_length, angular_velocity), each from the warm start and from the naive
straight-line guess. Both collocation solves steer psi to the same final value
(the plan's branch), so they solve the same problem. Then the IPOPT time
against N, and the budget measurement (N = 100, d = 3, warm start).
"""

from __future__ import annotations

import argparse
import logging
import platform
import statistics
import time
from pathlib import Path

import numpy as np

from rollplan import NoPlanError, Problem, SolverError, plan
from rollplan.io import save_figure, write_atomic
from rollplan.planners.collocation import CollocationPlanner
from rollplan.plots.compare import plot_comparison, plot_scaling
from rollplan.studies.comparison import compare, comparison_series, measure_plan

import bench_collocation

K = 2.5
TARGETS = [(0.3, 0.0, 0.0), (0.0, 0.5, 0.0), (0.5, 0.3, 0.4), (-0.4, 0.4, 1.0), (0.8, -0.2, -0.5),
           (1.0, 1.0, 0.0), (0.2, 0.1, 2.0), (-0.6, -0.6, -1.5), (1.5, 0.0, 0.3), (0.1, -0.3, 3.0),
           (0.7, 0.7, -2.5), (-1.2, 0.5, 0.8)]
COSTS = ("path_length", "angular_velocity")


def gp(target):
    for n in (1, 2, 3):
        try:
            return plan(target, n, k=K, legs="one")   # one leg of figure eights: the paper's plan
        except NoPlanError:
            continue
    return None


def run_targets(planners, targets):
    rows = []
    for tgt in targets:
        p = gp(tgt)
        if p is None:
            rows.append({"target": tgt, "plan": None})
            continue
        g, _ = measure_plan(p)
        row = {"target": tgt, "plan": p, "gp": g, "coll": {}}
        for cost in COSTS:
            for guess in ("warm", "naive"):
                try:
                    r = planners[cost].solve(Problem(tgt, k=K), guess=guess, turns=p.branch, warm_start=p)
                    row["coll"][cost, guess] = r
                except SolverError as exc:
                    row["coll"][cost, guess] = exc
        rows.append(row)
        logging.info("target %s done", tgt)
    return rows


def fmt(x, f=".4g"):
    return format(x, f) if isinstance(x, (int, float)) else str(x)


def _status(r):
    return r.status if isinstance(r, Exception) else "ok"


def target_table(rows):
    out = ["| target (u_a, v_a, psi) | n | GP length | GP effort | GP peak w | coll. length (path cost) "
           "| coll. effort (energy cost) | coll. peak w (path cost) | residual GP / coll. "
           "| naive guess (path / energy) |",
           "|---|---|---|---|---|---|---|---|---|---|"]
    for row in rows:
        t = row["target"]
        if row["plan"] is None:
            out.append(f"| {t} | - | no plan in 1..3 steps | | | | | | | |")
            continue
        g = row["gp"]
        rl = row["coll"]["path_length", "warm"]
        re = row["coll"]["angular_velocity", "warm"]
        cl = fmt(rl.measures.path_length) if not isinstance(rl, Exception) else f"failed ({rl.status})"
        pk = fmt(rl.measures.peak_omega) if not isinstance(rl, Exception) else "-"
        ce = fmt(re.measures.effort) if not isinstance(re, Exception) else f"failed ({re.status})"
        res = max((r.residual for r in (rl, re) if not isinstance(r, Exception)), default=float("nan"))
        out.append(f"| ({t[0]:g}, {t[1]:g}, {t[2]:g}) | {row['plan'].steps} | {g.path_length:.4g} | "
                   f"{g.effort:.4g} | {g.peak_omega:.4g} | {cl} | {ce} | {pk} | {row['plan'].residual:.1e} / "
                   f"{res:.1e} | "
                   f"{_status(row['coll']['path_length', 'naive'])} / "
                   f"{_status(row['coll']['angular_velocity', 'naive'])} |")
    return out


def convergence_table(rows):
    out = ["| cost | guess | converged | median iterations | median IPOPT time [s] | same optimum as warm |",
           "|---|---|---|---|---|---|"]
    summary = {}
    for cost in COSTS:
        for guess in ("warm", "naive"):
            rs = [row["coll"][cost, guess] for row in rows if row["plan"] is not None]
            ok = [r for r in rs if not isinstance(r, Exception) and r.residual < 1e-6]
            same = ""
            if guess == "naive":
                pairs = [(row["coll"][cost, "warm"], row["coll"][cost, "naive"]) for row in rows
                         if row["plan"] is not None]
                pairs = [(a, b) for a, b in pairs if not isinstance(a, Exception) and not isinstance(b, Exception)]
                obj = lambda r: r.solution.objective  # noqa: E731
                n_same = sum(abs(obj(a) - obj(b)) <= 1e-6 * max(1.0, abs(obj(a))) for a, b in pairs)
                n_lower = sum(obj(b) < obj(a) - 1e-6 * max(1.0, abs(obj(a))) for a, b in pairs)
                same = f"{n_same}/{len(pairs)} (naive lower in {n_lower})"
            fails = [f"{r.status}" for r in rs if isinstance(r, Exception)]
            summary[cost, guess] = (len(ok), len(rs))
            it = statistics.median([r.stats.iterations for r in ok]) if ok else float("nan")
            tm = statistics.median([r.stats.time_s for r in ok]) if ok else float("nan")
            fail_txt = f" (failed: {', '.join(sorted(set(fails)))})" if fails else ""
            out.append(f"| {cost} | {guess} | {len(ok)}/{len(rs)}{fail_txt} | {it:g} | {tm:.3f} | {same} |")
    return out, summary


def scaling(Ns, repeats, target=(0.5, 0.3, 0.4)):
    p = plan(target, 1, k=K, legs="one")
    res = {}
    for cost in COSTS:
        times, builds, iters, objs, resid = [], [], [], [], []
        for N in Ns:
            t0 = time.perf_counter()
            P = CollocationPlanner(N, 3, "legendre", cost)
            builds.append(time.perf_counter() - t0)
            ts = []
            for _ in range(repeats):
                r = P.solve(Problem(target, k=K), warm_start=p)
                ts.append(r.stats.time_s)
            times.append(statistics.median(ts))
            iters.append(r.stats.iterations)
            objs.append(r.measures.path_length if cost == "path_length" else r.measures.effort)
            resid.append(r.residual)
        res[cost] = (np.array(times), np.array(builds), iters, np.array(objs), np.array(resid))
    return res


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", default="results")
    ap.add_argument("--quick", action="store_true", help="fewer targets and repeats")
    ap.add_argument("--figures-only", action="store_true", help="only the two comparison figures (no timings)")
    args = ap.parse_args()
    logging.basicConfig(level=logging.INFO, format="%(message)s")
    logging.getLogger("rollplan").setLevel(logging.ERROR)
    out = Path(args.out)
    out.mkdir(exist_ok=True)
    targets = TARGETS[:4] if args.quick else TARGETS
    t_start = time.perf_counter()
    ex = compare((0.5, 0.3, 0.4), 1, k=K)
    save_figure(plot_comparison(ex, "R", comparison_series(ex)), out / "comparison_paths.png")
    ex2 = compare((-0.4, 0.4, 1.0), 1, k=K, cost="angular_velocity")
    save_figure(plot_comparison(ex2, "R", comparison_series(ex2)), out / "comparison_paths_energy.png")
    if args.figures_only:
        print(f"wrote {out / 'comparison_paths.png'} and {out / 'comparison_paths_energy.png'}")
        return
    planners = {c: CollocationPlanner(100, 3, "legendre", c) for c in COSTS}
    rows = run_targets(planners, targets)

    Ns = [25, 50, 100, 200] if args.quick else [25, 50, 100, 200, 400]
    sc = scaling(Ns, 3 if args.quick else 5)
    save_figure(plot_scaling(Ns, [sc[c][0] for c in COSTS], [f"{c}, Legendre d = 3, warm" for c in COSTS]),
                out / "comparison_scaling.png")
    bt = bench_collocation.measure(repeats=3 if args.quick else 5, targets=targets[:6], k=K, naive=False)["times_s"]
    med = statistics.median(bt)

    # which is shorter / cheaper
    valid = [r for r in rows if r["plan"] is not None]
    shorter = sum(1 for r in valid if not isinstance(r["coll"]["path_length", "warm"], Exception)
                  and r["coll"]["path_length", "warm"].measures.path_length < r["gp"].path_length)
    cheaper = sum(1 for r in valid if not isinstance(r["coll"]["angular_velocity", "warm"], Exception)
                  and r["coll"]["angular_velocity", "warm"].measures.effort < r["gp"].effort)
    ratio_l = [r["coll"]["path_length", "warm"].measures.path_length / r["gp"].path_length for r in valid
               if not isinstance(r["coll"]["path_length", "warm"], Exception)]
    coll_res = [r["coll"]["path_length", "warm"].residual for r in valid
                if not isinstance(r["coll"]["path_length", "warm"], Exception)] or [float("nan")]
    ratio_e = [r["coll"]["angular_velocity", "warm"].measures.effort / r["gp"].effort for r in valid
               if not isinstance(r["coll"]["angular_velocity", "warm"], Exception)]
    gp_times = [r["plan"].stats.time_s for r in valid]
    conv, _ = convergence_table(rows)
    slope = {c: np.polyfit(np.log(Ns), np.log(sc[c][0]), 1)[0] for c in COSTS}

    md = [
        "# Geometric phase versus direct collocation",
        "",
        f"Generated by `scripts/compare_planners.py` on {platform.node()} ({platform.processor() or 'cpu'}), "
        f"k = {K}, T = 1 s, collocation N = 100, Legendre d = 3, piecewise-constant contact rates. "
        f"Total run time {time.perf_counter() - t_start:.0f} s. Times are wall times on a shared machine.",
        "",
        "Geometric-phase plans are timed with t proportional to theta (each circle at constant speed). "
        "Effort is int |omega|^2 dt [rad^2/s]. The collocation's `path_length` cost is the energy form "
        "int |v|^2 dt, whose minimizers are the shortest paths traversed at constant speed "
        "(Cauchy-Schwarz); the `angular_velocity` cost is int |omega|^2 dt. All residuals are from an "
        "independent CVODES integration of the model with the planned inputs.",
        "",
        "## Which is shorter, which is cheaper",
        "",
        f"- Collocation (path-length cost, warm start) is shorter than the figure-eight plan on {shorter}/{len(valid)} "
        f"targets; length ratio collocation/GP median {statistics.median(ratio_l):.3f} "
        f"(range {min(ratio_l):.3f}-{max(ratio_l):.3f})." if ratio_l else "- no collocation solution",
        f"- Collocation (angular-velocity cost, warm start) needs less int |omega|^2 dt than the plan on "
        f"{cheaper}/{len(valid)} targets; effort ratio median {statistics.median(ratio_e):.3f} "
        f"(range {min(ratio_e):.3f}-{max(ratio_e):.3f})." if ratio_e else "- no collocation solution",
        f"- The geometric-phase planner takes {statistics.median(gp_times):.3f} s median (bracketing, root solve and "
        f"CVODES verification); its residual is at most {max(r['plan'].residual for r in valid):.1e}, the "
        f"collocation's at most {max(coll_res):.1e} (path-length cost, warm start), bounded by the transcription "
        "error and IPOPT's tolerance. The plan is exact in structure (any timing of the same "
        "curve is realizable); the collocation result is optimal only for its cost, horizon and discretization.",
    ]
    md += ["", "## Per target", ""] + target_table(rows)
    md += ["", "## Convergence from the naive guess versus the warm start", "",
           "Naive: every state linear in time from 0 to the target with u_o = v_o = 0 and zero rates. "
           "Warm: the geometric-phase plan, theta mapped to t / T. Both steer psi to the plan's branch.", ""] + conv
    md += ["", "Why the naive guess fails: it sits at rest on the south pole (u_o = v_o = 0, zero rates), where "
           "the system is driftless and its linearization is not controllable. There the collocation "
           "equations' Jacobian is rank deficient (N = 10, d = 3: rank 197 of 200 rows for the target "
           "(0.3, 0, 0), 199 of 200 for (0.5, 0.3, 0.4), whose psi guess is not zero): to first order "
           "the rates only move (u_o, v_o) and, through (6)-(7), (u_a, v_a) by amounts that must cancel "
           "since u_o and v_o return to 0; the displacement and the turn of psi come only from Lie "
           "brackets (second order). IPOPT then reports a locally infeasible problem, as it does here for "
           "the targets with psi = 0; for others the first steps leave the singular point by chance. This "
           "is the sensitivity to the initial guess the paper attributes to optimal control; the "
           "geometric-phase plan is a feasible, non-singular guess. The problem is non-convex: warm and "
           "naive runs that both converge may end in different local optima (last column)."]
    md += ["", "## Time against N (Legendre d = 3, warm start, target (0.5, 0.3, 0.4))", "",
           "Per cost: IPOPT time, iterations, NLP build time, the verified optimum (path length for "
           "`path_length`, int |omega|^2 dt for `angular_velocity`) and the verified residual.", "",
           "| N | " + " | ".join(f"{c}: IPOPT [s] | iter. | build [s] | optimum | residual" for c in COSTS) + " |",
           "|---|" + "---|---|---|---|---|" * len(COSTS)]
    for i, N in enumerate(Ns):
        md.append(f"| {N} | " + " | ".join(f"{sc[c][0][i]:.3f} | {sc[c][2][i]} | {sc[c][1][i]:.2f} | "
                                           f"{sc[c][3][i]:.8f} | {sc[c][4][i]:.1e}" for c in COSTS) + " |")
    md += ["", "The optimum changes by O(N^-2) as N doubles: the contact rates are constant on each interval, "
           "and a piecewise-constant approximation of a smooth optimal control costs O(h^2) in the cost "
           "(first-order optimality makes the O(h) control error enter quadratically). The residual sits at "
           "the level of IPOPT's tolerance (1e-10) for d = 3, where the Gauss method's O(h^6) error is smaller."]
    md += ["", "Fitted exponent of IPOPT time ~ N^p: " + ", ".join(f"{c}: p = {slope[c]:.2f}" for c in COSTS) + ".",
           "", "![time vs N](comparison_scaling.png)", "",
           "## Budget: N = 100, d = 3, warm start", "",
           f"IPOPT time over {len(bt)} solves (path_length, {len(targets[:6])} targets): median {med:.3f} s, "
           f"max {max(bt):.3f} s. Budget < 1 s: {'met' if med < 1.0 else 'NOT met'}.", "",
           "## Figures", "", "![paths](comparison_paths.png)", "", "![paths, energy cost](comparison_paths_energy.png)",
           ""]
    write_atomic(out / "comparison.md", "\n".join(md).encode())
    print(f"wrote {out / 'comparison.md'}; budget median {med:.3f} s")


if __name__ == "__main__":
    main()
