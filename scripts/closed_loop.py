"""Closed-loop execution under model error: writes results/closed_loop.md, .json and closed_loop.png.

1. The issue's case: a robot built from the issue's numbers (k = 4.2107) and the same robot with
   +5.5 % total mass and +7.5 % rotor inertia (k = 4.3607); four figure eights to (0.2, 0.25, 0.8 rad);
   open and closed loop on the rate and the torque plant, the requirement, the replay of the applied
   rotor rates, the estimates, and measurement noise of several sizes (Monte Carlo over seeds).
2. Monte Carlo over random goals: arrival error against the error of k (1, 2, 5, 10 %) and of J_r,
   open against closed loop, with and without measurement noise (median and 95th percentile).
3. The torque-driven plant against the rate-driven one on the same plans.
4. The issue's case on the torque plant and on MuJoCo (when mujoco imports): closed loop with 1 and 4 figure
   eights, without noise and with measurement noise (Monte Carlo over seeds; on the torque plant also with the
   state at rest averaged over readings).
5. Beyond the paper's equations, on MuJoCo: a centre of mass off the centre, rolling resistance; open and
   closed loop.

Run: ``python scripts/closed_loop.py [--out-dir results] [--seeds 10] [--workers 2] [--scheduler ADDRESS] [--quick]
[--report-only] [--mujoco-seeds 8] [--mujoco-only]``; ``--mujoco-only`` runs sections 4 and 5 alone and merges
them into the existing closed_loop.json before writing the page again.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from tqdm import tqdm

import rollplan
from rollplan.execution.estimate import FRICTION_SIGNIFICANCE
from rollplan.execution.feedback import execute, joints
from rollplan.execution.plants import disturbance, run_rates, run_torques, simulate_rotors
from rollplan.io import save_figure, write_atomic, write_json
from rollplan.plots.closed_loop import plot_closed_loop
from rollplan.problem import arrival_error, arrival_residual
from rollplan.studies.closed_loop import (
    ISSUE_MODEL,
    issue_real_robot,
    robot_with_error,
    run_cases,
    summarize,
)
from rollplan.studies.executor import map_in_order

# tqdm's monitor thread would make the process pools spawn their workers (rollplan.studies.executor.start_method:
# fork only while this process runs no other thread), each importing and building everything again
tqdm.monitor_interval = 0

GOAL = (0.2, 0.25, 0.8)
STEPS = 4
PIECE = 2.5          # s per leaf: 5 s per figure eight
ERRORS = (0.01, 0.02, 0.05, 0.10)
NOISE = 1e-3         # measurement noise of the Monte Carlo [R and rad]
NOISE_LEVELS = (1e-4, 1e-3, 1e-2)
MUJOCO_STEPS = (1, 4)
MUJOCO_NOISE = 1e-3  # measurement noise of section 4 [R and rad]
AVERAGE = 16         # section 4, torque plant: readings averaged at rest in the extra rows
BEYOND = [  # section 5: MuJoCo settings beyond the paper's equations (com offset [m] in the shell's frame)
    ("centre of mass 0.01 mm below the centre", {"com_offset": (0.0, 0.0, -1e-5)}),
    ("centre of mass 0.1 mm below the centre", {"com_offset": (0.0, 0.0, -1e-4)}),
    ("centre of mass 1 mm below the centre", {"com_offset": (0.0, 0.0, -1e-3)}),
    ("centre of mass 0.1 mm off the axis (x)", {"com_offset": (1e-4, 0.0, 0.0)}),
    ("rolling resistance 1e-6 m", {"rolling": 1e-6}),
    ("rolling resistance 1e-5 m", {"rolling": 1e-5}),
    ("rolling resistance 1e-4 m", {"rolling": 1e-4}),
]
BEYOND_STEPS = 1
MUJOCO_SETTINGS = {}  # sections 4 and 5: MuJoCo settings of every run (mujoco_engine.Settings; {}: the defaults)
TORQUE_CASES = [  # the three plans of results/sensitivity.md: target [m, rad], steps, duration [s]
    ((0.0, 0.1, 0.0), 1, 10.0),
    ((0.05, 0.08, 0.5), 2, 10.0),
    ((0.2, 0.1, 1.0), 3, 20.0),
]


def e(x) -> str:
    return "-" if x is None else f"{x:.2e}"


def bar(label):
    b = tqdm(desc=label, file=sys.stderr)

    def progress(done, total):
        b.total = total
        b.update(done - b.n)
    return b, progress


def replay_gap(replay, run, radius) -> float:
    """Largest difference of the replay's final state from the run's [R, rad] (psi wrapped)."""
    return float(np.abs(arrival_error(rollplan.State(*replay.series.state[-1]), run.final, radius)).max())


def issue_case(seeds, workers):
    model, real = ISSUE_MODEL, issue_real_robot()
    p = rollplan.plan(GOAL, STEPS, robot=model)
    rows = []
    setups = [("rates", "rate plant", {}), ("torques", "torque plant (feed-forward)", {}),
              ("torques", "torque plant, bearing friction c = 2e-5 N m s/rad, rate servo K = 1e-3 N m s/rad",
               {"disturbances": (disturbance("friction", c=2e-5),), "servo_gain": 1e-3})]
    runs = {}
    for plant, label, kw in tqdm(setups, desc="issue case", file=sys.stderr):
        t0 = time.perf_counter()
        ol = execute(p, model, real, PIECE, plant=plant, closed_loop=False, **kw)
        cl = execute(p, model, real, PIECE, plant=plant, **kw)
        replay = simulate_rotors(real, cl.series.time, cl.series.rotor_rates, x0=p.problem.start.array())
        rows.append({"plant": label, "open": ol.arrival_error, "open_position": ol.position_error,
                     "closed": cl.arrival_error, "required": max(1e-3, 0.05 * ol.arrival_error),
                     "replay": replay_gap(replay, cl, real.radius),
                     "samples": int(cl.series.time.size), "duration": float(cl.series.time[-1]),
                     "seconds": time.perf_counter() - t0, "estimates": cl.estimates})
        runs[label] = cl
    p1 = rollplan.plan(GOAL, 1, robot=model)
    t0 = time.perf_counter()
    ol = execute(p1, model, real, PIECE, closed_loop=False)
    cl = execute(p1, model, real, PIECE)
    replay = simulate_rotors(real, cl.series.time, cl.series.rotor_rates, x0=p1.problem.start.array())
    rows.append({"plant": "rate plant, 1 figure eight", "open": ol.arrival_error, "open_position": ol.position_error,
                 "closed": cl.arrival_error, "required": max(1e-3, 0.05 * ol.arrival_error),
                 "replay": replay_gap(replay, cl, real.radius),
                 "samples": int(cl.series.time.size), "duration": float(cl.series.time[-1]),
                 "seconds": time.perf_counter() - t0, "estimates": cl.estimates})
    noise = []
    for sigma in NOISE_LEVELS:
        b, prog = bar(f"issue case, noise {sigma:g}")
        res = []
        for seed in range(seeds):
            dist = (disturbance("measurement", sigma_length=sigma, sigma_angle=sigma, seed=seed),)
            cl = execute(p, model, real, PIECE, disturbances=dist)
            one = execute(p1, model, real, PIECE, disturbances=dist)
            res.append({"closed": cl.arrival_error, "k": cl.estimates[-1]["k"], "one": one.arrival_error})
            prog(seed + 1, seeds)
        b.close()
        noise.append({"sigma": sigma, **summarize(res, "closed"), "one_median": summarize(res, "one")["median"],
                      "k_error_median": float(np.median([abs(r["k"] / real.k - 1) for r in res]))})
    return {"model_k": model.k, "real_k": real.k, "goal": GOAL, "steps": STEPS, "rows": rows, "noise": noise}


def monte_carlo(seeds, workers, plant="rates", errors=ERRORS, noises=(0.0, NOISE), scheduler=None):
    cases = [{"kind": kind, "error": err, "seed": s, "noise": nz, "plant": plant, "steps": STEPS,
              "piece_duration": PIECE}
             for kind in ("k", "J_r") for err in errors for nz in noises for s in range(seeds)]
    b, prog = bar(f"Monte Carlo, {plant} plant")
    try:
        results = run_cases(cases, workers, prog, scheduler=scheduler)
    finally:
        b.close()
    rows = []
    for kind in ("k", "J_r"):
        for err in errors:
            row = {"kind": kind, "error": err}
            for nz in noises:
                sel = [r for r in results if r["kind"] == kind and r["error"] == err and r["noise"] == nz]
                tag = "" if nz == 0 else "_noise"
                row["open" + tag] = summarize(sel, "open")
                row["closed" + tag] = summarize(sel, "closed")
            rows.append(row)
    return rows, results


def mujoco_available():
    try:
        import mujoco
    except ImportError:
        return None
    return mujoco.__version__


def issue_run(case: dict) -> dict:
    """One run of the issue's case (the plan for ``ISSUE_MODEL``, executed on ``issue_real_robot()``): ``case`` holds
    ``goal``, ``steps``, ``piece_duration``, ``plant``, ``noise``, ``seed``, ``average`` (readings at rest, 0: the
    last sample), ``settings`` (MuJoCo settings, or None) and ``open`` (also run open loop)."""
    t0 = time.perf_counter()
    model, real = ISSUE_MODEL, issue_real_robot()
    dist = (disturbance("measurement", sigma_length=case["noise"], sigma_angle=case["noise"], seed=case["seed"]),) \
        if case["noise"] > 0 else ()
    kw = {"plant": case["plant"], "disturbances": dist, "rest_readings": case["average"]}
    if case["settings"] is not None:
        from rollplan.execution import mujoco_engine

        kw["mujoco_model"] = mujoco_engine.compile_model(mujoco_engine.mjcf(real, mujoco_engine.Settings(
            **case["settings"])))
    p = rollplan.plan(tuple(case["goal"]), case["steps"], robot=model)
    out = dict(case)
    if case["open"]:
        out["open"] = execute(p, model, real, case["piece_duration"], closed_loop=False, **kw).arrival_error
    run = execute(p, model, real, case["piece_duration"], **kw)
    fed = [d["friction"] for d in run.estimates if "friction" in d]
    out.update(closed=run.arrival_error, closed_position=run.position_error, estimated_k=run.estimates[-1].get("k"),
               real_k=real.k, samples=int(run.series.time.size), duration=run.series.duration,
               stopped=run.stopped, friction_fed=bool(fed) and any(any(c != 0 for c in f) for f in fed),
               corrections=sum(sg["mode"] == "correction" for sg in run.segments),
               seconds=time.perf_counter() - t0)
    return out


def issue_cases(seeds):
    """Section 4's runs: torque plant and (when mujoco imports) MuJoCo, 1 and 4 figure eights, no noise and noise."""
    cases = []
    for plant in ("torques", "mujoco") if mujoco_available() else ("torques",):
        base = {"goal": list(GOAL), "piece_duration": PIECE, "open": False,
                "settings": (dict(MUJOCO_SETTINGS) or None) if plant == "mujoco" else None}
        for n in MUJOCO_STEPS:
            cases.append({**base, "plant": plant, "steps": n, "noise": 0.0, "seed": 0, "average": 0})
            cases += [{**base, "plant": plant, "steps": n, "noise": MUJOCO_NOISE, "seed": s, "average": 0}
                      for s in range(seeds)]
            if plant == "torques":
                cases += [{**base, "plant": plant, "steps": n, "noise": MUJOCO_NOISE, "seed": s, "average": AVERAGE}
                          for s in range(seeds)]
    return cases


def beyond_cases():
    """Section 5's runs: MuJoCo with each of ``BEYOND``'s settings, open and closed loop, no noise."""
    return [{"goal": list(GOAL), "piece_duration": PIECE, "plant": "mujoco", "steps": BEYOND_STEPS, "noise": 0.0,
             "seed": 0, "average": 0,
             "settings": {k: list(v) if isinstance(v, tuple) else v for k, v in {**MUJOCO_SETTINGS, **st}.items()},
             "label": label, "open": True} for label, st in BEYOND]


def mujoco_section(seeds, workers, scheduler=None):
    """Sections 4 and 5: the issue's case closed loop on the torque plant and MuJoCo, and beyond the paper."""
    t0 = time.perf_counter()
    cases = issue_cases(seeds)
    beyond = beyond_cases() if mujoco_available() else []
    b, prog = bar("issue case, torque plant and MuJoCo")
    try:
        runs = map_in_order(issue_run, cases + beyond, jobs=workers, scheduler=scheduler,
                            progress=lambda label, done, total: prog(done, total), label="closed-loop runs")
    finally:
        b.close()
    runs, beyond_runs = runs[:len(cases)], runs[len(cases):]
    rows = []
    for plant in dict.fromkeys(r["plant"] for r in runs):
        for n in MUJOCO_STEPS:
            exact = next(r for r in runs if r["plant"] == plant and r["steps"] == n and r["noise"] == 0)
            row = {"plant": plant, "steps": n, "closed": exact["closed"], "estimated_k": exact["estimated_k"],
                   "samples": exact["samples"], "duration": exact["duration"], "seconds": exact["seconds"],
                   "noise": MUJOCO_NOISE}
            for avg, tag in ((0, "noise"), (AVERAGE, "average")):
                vals = np.array([r["closed"] for r in runs if r["plant"] == plant and r["steps"] == n
                                 and r["noise"] > 0 and r["average"] == avg], float)
                if vals.size:
                    row.update({f"{tag}_median": float(np.median(vals)), f"{tag}_p90": float(np.percentile(vals, 90)),
                                f"{tag}_max": float(vals.max()), f"{tag}_runs": int(vals.size)})
            fed = [r["friction_fed"] for r in runs if r["plant"] == plant and r["steps"] == n and r["noise"] > 0]
            row["friction_fed"] = int(sum(fed))
            rows.append(row)
    return {"mujoco_version": mujoco_available(), "seeds": seeds, "rows": rows, "runs": runs, "average": AVERAGE,
            "settings": dict(MUJOCO_SETTINGS),
            "beyond": beyond_runs, "wall_seconds": time.perf_counter() - t0, "workers": workers, "commit": commit()}


def torque_vs_rate():
    robot = rollplan.default_robot()
    rows = []
    for target, steps, duration in tqdm(TORQUE_CASES, desc="torque vs rate plant", file=sys.stderr):
        p = rollplan.plan(target, steps, robot=robot)
        m = rollplan.actuate(p, robot, duration)
        t0 = time.perf_counter()
        a = run_rates(robot, m.series.time, m.series.rotor_rates)
        t1 = time.perf_counter()
        b = run_torques(robot, m.series.time, m.series.rotor_torques, breaks=joints(m.series))
        t2 = time.perf_counter()
        one = run_torques(robot, m.series.time, m.series.rotor_torques)
        R = robot.radius
        rows.append({"target": target, "steps": steps, "samples": int(m.series.time.size),
                     "position": float(np.abs(a.series.state[:, :2] - b.series.state[:, :2]).max() / R),
                     "angles": float(np.abs(a.series.state[:, 2:] - b.series.state[:, 2:]).max()),
                     "one_spline": float(np.abs(a.series.state[:, :2] - one.series.state[:, :2]).max() / R),
                     "arrival_rates": arrival_residual(a.series.state[-1], p.goal, R),
                     "arrival_torques": arrival_residual(b.series.state[-1], p.goal, R),
                     "seconds_rates": t1 - t0, "seconds_torques": t2 - t1})
    # the same plan on the issue's mismatched robot, open loop, fed rates or torques
    model, real = ISSUE_MODEL, issue_real_robot()
    p = rollplan.plan(GOAL, STEPS, robot=model)
    mismatch = {}
    for kind in ("k", "J_r"):
        rob = robot_with_error(model, kind, 0.10)
        mismatch[kind] = {pl: execute(p, model, rob, PIECE, plant=pl, closed_loop=False).arrival_error
                          for pl in ("rates", "torques")}
    mismatch["issue"] = {pl: execute(p, model, real, PIECE, plant=pl, closed_loop=False).arrival_error
                         for pl in ("rates", "torques")}
    return rows, mismatch


def table_mc(rows, noise):
    out = ["| real robot | open median | open 95 % | closed median | closed 95 % |"
           + (" open median (noise) | closed median (noise) | closed 95 % (noise) | failed |" if noise else
              " failed |"),
           "|---|---:|---:|---:|---:|" + ("---:|---:|---:|---:|" if noise else "---:|")]
    for r in rows:
        fails = r["closed"]["failed"] + (r["closed_noise"]["failed"] if noise else 0)
        line = (f"| {r['kind']} {100 * r['error']:g} % | {e(r['open']['median'])} | {e(r['open']['p95'])} | "
                f"{e(r['closed']['median'])} | {e(r['closed']['p95'])} |")
        if noise:
            line += (f" {e(r['open_noise']['median'])} | {e(r['closed_noise']['median'])} | "
                     f"{e(r['closed_noise']['p95'])} |")
        out.append(line + f" {fails} |")
    return out


def figure_title(seeds) -> str:
    return (f"rate plant, {STEPS} figure eights, random goals 1.5-3 R away, {seeds} seeds a point; "
            f"noise: {NOISE:g} R / rad per sample")


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True,
                              cwd=Path(__file__).parent, check=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default=str(Path(__file__).resolve().parents[1] / "results"))
    ap.add_argument("--seeds", type=int, default=10, help="Monte Carlo runs per row (default 10)")
    ap.add_argument("--torque-seeds", type=int, default=5, help="runs per row of the torque plant (default 5)")
    ap.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    ap.add_argument("--scheduler", default=None, metavar="ADDRESS",
                    help="run the Monte Carlo on this Dask distributed scheduler (pip install 'rollplan[distributed]')")
    ap.add_argument("--quick", action="store_true", help="2 seeds, errors 1 and 10 %% only (a smoke test)")
    ap.add_argument("--report-only", action="store_true",
                    help="only write closed_loop.md and .png again from closed_loop.json")
    ap.add_argument("--mujoco-seeds", type=int, default=8,
                    help="noisy runs per row of section 4 (torque plant and MuJoCo; default 8)")
    ap.add_argument("--mujoco-only", action="store_true",
                    help="run only sections 4 and 5 and merge them into the existing closed_loop.json")
    args = ap.parse_args()
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if args.report_only or args.mujoco_only:
        data = json.loads((out / "closed_loop.json").read_text())
        if args.mujoco_only:
            if mujoco_available() is None:
                sys.exit("scripts/closed_loop.py: --mujoco-only needs mujoco (pip install 'rollplan[mujoco]')")
            print("sections 4 and 5: torque plant and MuJoCo", file=sys.stderr)
            data["mujoco"] = mujoco_section(args.mujoco_seeds, args.workers, args.scheduler)
            write_json(out / "closed_loop.json", data)
        report(data, out)
        return
    errors = (0.01, 0.10) if args.quick else ERRORS
    seeds = 2 if args.quick else args.seeds
    tseeds = 1 if args.quick else args.torque_seeds
    t0 = time.perf_counter()
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    issue = issue_case(seeds, args.workers)
    mc_rows, mc_runs = monte_carlo(seeds, args.workers, errors=errors, scheduler=args.scheduler)
    ends = tuple(dict.fromkeys((errors[0], errors[-1])))   # the smallest and largest error, once each
    tq_rows, tq_runs = monte_carlo(tseeds, args.workers, "torques", errors=ends, noises=(0.0,),
                                   scheduler=args.scheduler)
    tvr, mismatch = torque_vs_rate()
    mj = mujoco_section(args.mujoco_seeds, args.workers, args.scheduler)
    data = {"issue_case": issue, "monte_carlo_rates": mc_rows, "monte_carlo_torques": tq_rows, "runs_rates": mc_runs,
            "runs_torques": tq_runs, "torque_vs_rate": tvr, "open_loop_by_plant": mismatch, "seeds": seeds,
            "torque_seeds": tseeds, "mujoco": mj, "wall_seconds": time.perf_counter() - t0, "commit": commit(),
            "host": platform.node(), "load": load, "workers": args.workers, "quick": args.quick}
    write_json(out / "closed_loop.json", data)
    report(data, out)


def mujoco_report(mj) -> list:
    """The lines of sections 4 and 5 (section 4 as it was when the JSON is of an older run)."""
    L = ["## 4. The issue's robot closed loop on the torque plant and on MuJoCo", ""]
    if not mj:
        return L + ["Not run.", ""]
    old = "plant" not in mj["rows"][0]
    L += [f"The real robot of section 1 (+5.5 % total mass, +7.5 % rotor inertias): the project's torque plant, and "
          f"MuJoCo {mj['mujoco_version']} (`rollplan.execution.mujoco_engine`, "
          + (f"settings {mj['settings']}" if mj.get("settings") else "default settings: RK4, 1e-4 s, stiff "
             "sphere-plane contact") + "; no bearing friction in either). The plan for the model robot, the same "
          "goal, 2.5 s a piece; the plan's motor torques fed forward, no servo; the state measured at rest; closed "
          "loop with the corrections (as `rollplan simulate PLAN --robot REAL.toml [--engine mujoco] --closed-loop "
          "[--noise S]`). "
          "Arrival error of the true final state (the plant's, not the measured one). Noise: "
          f"{mj['rows'][0]['noise']:g} (R and rad) per sample, {mj['seeds']} seeds a row; the state used for a "
          "re-plan or correction is the last sample of the motion (one reading)"
          + ("" if old else f", or in the 'average' columns the mean of {mj['average']} readings at rest "
             "(`--average`)")
          + f". Section computed in {mj['wall_seconds'] / 60:.1f} min with {mj['workers']} workers, commit "
          f"{mj['commit']}.", ""]
    if old:
        L += ["| figure eights | closed loop, no noise | final k estimate | samples | motion [s] | wall [s] "
              "| noise: median | noise: max | runs |", "|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
        for r in mj["rows"]:
            L.append(f"| {r['steps']} | **{e(r['closed'])}** | {r['estimated_k']:.6f} | {r['samples']} | "
                     f"{r['duration']:.1f} | {r['seconds']:.0f} | **{e(r['noise_median'])}** | {e(r['noise_max'])} | "
                     f"{r['noise_runs']} |")
        return L + [""]
    L += ["| plant | figure eights | closed loop, no noise | final k estimate | motion [s] | wall [s] "
          "| noise: median | noise: 90 % | noise: max | average: median | average: 90 % |",
          "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    names = {"torques": "torque plant", "mujoco": "MuJoCo"}
    for r in mj["rows"]:
        k = "-" if r["estimated_k"] is None else f"{r['estimated_k']:.6f}"
        L.append(f"| {names[r['plant']]} | {r['steps']} | **{e(r['closed'])}** | {k} | {r['duration']:.1f} | "
                 f"{r['seconds']:.0f} | **{e(r.get('noise_median'))}** | {e(r.get('noise_p90'))} | "
                 f"{e(r.get('noise_max'))} | {e(r.get('average_median'))} | {e(r.get('average_p90'))} |")
    fed = sum(r["friction_fed"] for r in mj["rows"])
    L += ["", f"Real k {issue_real_robot().k:.6f}. The issue asks for 1e-3 without noise and 5e-3 (median) with noise "
          "1e-3. One reading with noise sigma on each of the five coordinates misses by sqrt(5) sigma = "
          f"{np.sqrt(5) * mj['rows'][0]['noise']:.2e} rms, and a correction driven by it cannot do better: the noisy "
          "rows sit at that floor, and averaging N readings lowers it by sqrt(N). On the torque plant and MuJoCo "
          "the loop also estimates a bearing friction (there is none); a friction is fed forward only when it is "
          f"positive and more than {FRICTION_SIGNIFICANCE:g} standard errors from zero "
          "(`rollplan.execution.estimate.established_friction`), because a feed-forward `c phi_dot` with an error "
          "dc leaves the rotors the momentum dc Phi after a motion that turned them by Phi, and without real "
          "friction the robot then never comes to rest. Noisy runs in which a friction was fed forward: "
          f"{fed} of {sum(r.get('noise_runs', 0) + r.get('average_runs', 0) for r in mj['rows'])}.", ""]
    beyond = mj.get("beyond") or []
    L += ["## 5. Beyond the paper's equations (MuJoCo)", ""]
    if not beyond:
        return L + ["Not run: mujoco is not installed (pip install 'rollplan[mujoco]').", ""]
    L += ["The real robot of section 4 on MuJoCo with what the paper's equations leave out (options of `rollplan "
          f"mjcf`: `--com-offset`, `--rolling-resistance`); {BEYOND_STEPS} figure eight, no noise, open loop and "
          "closed loop with the corrections (the controller still plans with the paper's model and estimates only its "
          "inertias). Arrival error of the true final state.", "",
          "| real robot on MuJoCo | open loop | closed loop | final k estimate | corrections | stopped |",
          "|---|---:|---:|---:|---:|---|"]
    for r in beyond:
        k = "-" if r["estimated_k"] is None else f"{r['estimated_k']:.4f}"
        L.append(f"| {r['label']} | {e(r['open'])} | **{e(r['closed'])}** | {k} | {r['corrections']} | "
                 f"{(r['stopped'] or '-').replace('|', chr(92) + '|')} |")
    try:
        import mujoco
        floor = f"{mujoco.mjMINMU:g}"
    except ImportError:
        floor = "a minimum"
    return L + ["", f"Real k {issue_real_robot().k:.4f} (the paper's model of the real robot). The open-loop column "
                "includes the model's error in k (the real robot is the mismatched one); the closed loop removes "
                "that part. Its estimator models inertias only: a centre of mass off the centre makes the sphere "
                "a pendulum (gravity's moment about the contact point, zero in (11)), so the robot is not at rest "
                "where the plan rests and the estimate of k drifts: even 0.01 mm leaves the closed loop short of "
                "the issue's 1e-3 (the corrections end at their budget), and from 1 mm below, or 0.1 mm to the "
                "side, it ends further off than the open loop. Rolling resistance brakes every motion by a share "
                "the plans do not know: the closed loop reduces the miss at 1e-5 m, but not to 1e-3, and fails at "
                "1e-4 m (the contact point leaves the hemisphere plans start from). MuJoCo raises every friction "
                f"coefficient below {floor} to {floor}: "
                f"a rolling resistance below {floor} m acts as {floor} m, and with rolling resistance (condim 6) the "
                f"torsional friction, 0 in the model, is {floor} m too; so the rows 1e-6 m and 1e-5 m are one "
                "model.", ""]


def report(data, out):
    """closed_loop.png and closed_loop.md from the study's data (the JSON)."""
    issue, mc_rows, tq_rows = data["issue_case"], data["monte_carlo_rates"], data["monte_carlo_torques"]
    tvr, mismatch = data["torque_vs_rate"], data["open_loop_by_plant"]
    seeds, tseeds = data["seeds"], data["torque_seeds"]
    save_figure(plot_closed_loop(mc_rows, figure_title(seeds)), out / "closed_loop.png")
    m = ISSUE_MODEL
    L = ["# Closed-loop execution under model error",
         "",
         f"Generated by `scripts/closed_loop.py` (commit {data['commit']}, {data['host']}, load average at start "
         f"{data['load']:.1f}, {data['wall_seconds'] / 60:.1f} min with {data['workers']} workers"
         f"{', --quick' if data['quick'] else ''}). "
         "Units: arrival errors are the norm of (u_a, v_a in R; psi, u_o, v_o in rad) to the goal "
         "(`rollplan.problem.arrival_error`).",
         "",
         "Controller (`rollplan.execution.feedback.execute`): the plan's figure eights are applied one at a time; "
         "after each the full state is measured at rest, the robot's inertia ratios are estimated from all the "
         "motion seen (rates: Jxx/J_r, Jzz/J_r; torques: Jxx, Jzz, J_r and the bearing friction; least squares "
         "of the momentum integral (11) over windows, `rollplan.execution.estimate`), and the rest is re-planned "
         "from the measured state with the estimated robot by the composed planner (approach roll + the "
         "remaining figure eights), timed min-jerk, 2.5 s a piece. After the last figure eight, correcting "
         "motions (a composed plan of one figure eight from the measured state to the goal, with the estimated "
         "robot) follow while the measured arrival error exceeds 1e-6, at most 3 "
         "(`rollplan.execution.feedback.DEFAULT_TOLERANCE`, `DEFAULT_CORRECTIONS`): with one figure eight the "
         "closed loop is no longer the open loop.",
         "",
         f"## 1. The issue's robot: k {issue['model_k']:.4f} (model) against {issue['real_k']:.4f} (real)",
         "",
         f"Model: R = {m.radius} m, M = {m.mass_total} kg, m_o = {m.mass_shell} kg, J_r = {m.rotor_inertia_axial} "
         f"kg m^2, J_p = {m.rotor_inertia_transverse} kg m^2 (the issue's robot is not in the repository; this one "
         "has its k). Real: +5.5 % total mass, +7.5 % rotor inertias (axial and transverse). Goal (u_a, v_a, psi) "
         f"= ({GOAL[0]} m, {GOAL[1]} m, {GOAL[2]} rad), {STEPS} figure eights of 5 s. No noise. 'Replay': the "
         "applied rotor rates alone drive `simulate_rotors` of the real robot; the largest difference from the "
         "reported final state [R, rad].",
         "",
         "| plant | open loop | closed loop | required max(1e-3, 5 % open) | replay | samples | motion [s] "
         "| wall [s] |",
         "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in issue["rows"]:
        L.append(f"| {r['plant']} | {e(r['open'])} | **{e(r['closed'])}** | {e(r['required'])} | {e(r['replay'])} | "
                 f"{r['samples']} | {r['duration']:.1f} | {r['seconds']:.1f} |")
    est = issue["rows"][0]["estimates"]
    L += ["", "Estimated k before each figure eight (rate plant): "
          + ", ".join(f"{d['k']:.10f}" for d in est if "k" in d) + f" (real {issue['real_k']:.10f}).", "",
          f"With measurement noise (white, per sample, sigma on u_a, v_a in R and on the angles in rad; rate plant; "
          f"{seeds} seeds):", "",
          "| sigma | closed loop median | closed loop 95 % | median relative error of the final k estimate "
          "| 1 figure eight: closed loop median |",
          "|---:|---:|---:|---:|---:|"]
    for r in issue["noise"]:
        L.append(f"| {r['sigma']:g} | {e(r['median'])} | {e(r['p95'])} | {e(r['k_error_median'])} "
                 f"| {e(r.get('one_median'))} |")
    L += ["", "## 2. Monte Carlo over goals: open against closed loop", "",
          f"Random goals 1.5-3 R away in any direction, psi in [-1, 1] rad, {STEPS} figure eights, model = the "
          "robot above; real robot: k off by the error through the total mass (Jzz, J_r unchanged), or the axial "
          f"rotor inertia J_r off by the error; random sign. {seeds} seeds a row; noise = measurement noise "
          f"{NOISE:g} (R and rad) per sample. Rate plant. Figure: `closed_loop.png`.", ""]
    L += table_mc(mc_rows, True)
    noisy = [r["closed_noise"]["median"] for r in mc_rows if r["closed_noise"]["median"] is not None]
    gain = [r["open_noise"]["median"] / r["closed_noise"]["median"] for r in mc_rows
            if r["closed_noise"]["median"] and r["open_noise"]["median"] is not None]
    if noisy and gain:
        L += ["", "Without noise the closed loop removes the model error to the integrators' accuracy (the estimate "
              "is exact after one figure eight). With noise it sits at a floor, "
              f"{min(noisy):.2e} to {max(noisy):.2e} (median), that does not depend on the size of the model "
              "error (the same seeds give the same floor in every row): it comes from the noise, through the measured "
              "states of the re-plans and the noisy estimate used for the last, uncorrected figure eight (the two "
              f"are not separated here). Feedback then buys a factor {min(gain):.0f} to {max(gain):.0f} "
              "(open / closed median)."]
    L += ["", f"Torque plant (torques of the plan fed forward), no noise, {tseeds} seeds a row:", ""]
    L += table_mc(tq_rows, False)
    L += ["", "## 3. Torque-driven against rate-driven plant on the same plan", "",
          "Default robot, the plans of `results/sensitivity.md`, timed min-jerk: the plan's rotor rates drive the "
          "rate plant, its torques (T) the torque plant (not-a-knot splines split at the joints of the path; "
          "'one spline' = a single spline across them). Largest difference of the whole state history.", "",
          "| target [m, rad], steps | samples | max diff u_a, v_a [R] | max diff angles [rad] | one spline [R] | "
          "arrival, rates | arrival, torques | wall rates / torques [s] |",
          "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in tvr:
        L.append(f"| {tuple(r['target'])}, {r['steps']} | {r['samples']} | {e(r['position'])} | {e(r['angles'])} | "
                 f"{e(r['one_spline'])} | {e(r['arrival_rates'])} | {e(r['arrival_torques'])} | "
                 f"{r['seconds_rates']:.2f} / {r['seconds_torques']:.2f} |")
    L += ["", "Open loop on mismatched robots, the plan of section 1, fed rates or torques:", "",
          "| real robot | rates | torques |", "|---|---:|---:|"]
    for name, label in (("k", "k +10 %"), ("J_r", "J_r +10 %"), ("issue", "the issue's robot")):
        L.append(f"| {label} | {e(mismatch[name]['rates'])} | {e(mismatch[name]['torques'])} |")
    L += ["", "Fed torques, the rotors' absolute momenta are those planned, and J_r enters (11) only through "
          "J_r (I - n_3 n_3^T) next to Jxx - J_r; fed rates, omega scales with J_r phi_dot directly. So a rotor "
          "inertia error costs far less on the torque plant, while a k error costs both alike.", ""]
    L += mujoco_report(data["mujoco"]) if "mujoco" in data else []
    write_atomic(out / "closed_loop.md", "\n".join(L).encode())
    print(f"wrote {out / 'closed_loop.md'}, closed_loop.json, closed_loop.png ({data['wall_seconds']:.0f} s)")


if __name__ == "__main__":
    main()
