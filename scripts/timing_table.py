#!/usr/bin/env python
"""Shortest durations of the timing laws under the motors' limits: writes results/timing.md and timing.json.

For a few robots (with ``max_rotor_rate`` and ``max_rotor_torque``) and targets, the
shortest duration of every law of ``rollplan.execution.timing`` within the limits: the
time-optimal timing against the min-jerk law that respects the same limits (and the
non-stop laws); the time-optimal duration against the independent phase-plane
integration (``tests/references.py``) on a fine grid, and the three solvers of the
discrete problem against each other on one grid (numpy passes, the TOPP-RA library
where installed, CasADi/IPOPT); how much of the time one limit is active; the excess
over the limits on the samples; the rotor-only simulation's miss. A convergence table in
the grid size, and figures: ``timing_laws.png`` (the four laws on one plan, limits
dashed, and the phase plane) and ``timing_rate_limited.png``.

Run from the repository root (``pip install -e '.[toppra]'`` for the TOPP-RA column):

    python scripts/timing_table.py [--quick] [--out-dir results]
"""

from __future__ import annotations

import argparse
import datetime
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path


def parse_args(argv=None):
    """The command line, read before the slow imports below (a bad option is refused at once)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true",
                    help="one row, coarse reference, one solve per grid size, no figures (smoke test)")
    ap.add_argument("--out-dir", default="results")
    return ap.parse_args(argv)


if __name__ == "__main__":
    parse_args()

import numpy as np  # noqa: E402

import rollplan  # noqa: E402
from rollplan.errors import NoPlanError  # noqa: E402
from rollplan.execution.actuation import sample_motion  # noqa: E402
from rollplan.execution.limits import Limits  # noqa: E402
from rollplan.execution.path import ContactPath  # noqa: E402
from rollplan.execution.plants import simulate_rotors  # noqa: E402
from rollplan.execution.timing import LAWS, velocity_limit  # noqa: E402
from rollplan.execution.topp import solve_topp, toppra_available  # noqa: E402
from rollplan.io import save_figure, tagged, write_atomic, write_json  # noqa: E402
from rollplan.plots.timing import plot_timing  # noqa: E402
from rollplan.progress import Progress  # noqa: E402

from benchmark import command_line, git_commit, machine  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))
import references  # noqa: E402

_DEFAULT = rollplan.Robot()
#: name -> robot with its motors' limits [rad/s, N m].
ROBOTS = {
    "default": replace(_DEFAULT, max_rotor_rate=300.0, max_rotor_torque=0.05),
    "k2.5": rollplan.Robot(radius=0.1, mass_total=1.0, mass_shell=0.8, rotor_inertia_axial=5e-4,
                           rotor_inertia_transverse=5e-4 / 1.2, max_rotor_rate=150.0, max_rotor_torque=0.03),
    "large": rollplan.Robot(radius=0.25, mass_total=8.0, mass_shell=2.0, rotor_inertia_axial=4e-3,
                            rotor_inertia_transverse=2.5e-3, max_rotor_rate=200.0, max_rotor_torque=0.5),
    "default, slow motor": replace(_DEFAULT, max_rotor_rate=40.0, max_rotor_torque=0.05),
}
#: (target (u_a [R], v_a [R], psi [rad]), steps).
TARGETS = [((0.0, 1.0, 0.0), 1), ((0.5, 0.8, 0.5), 2), ((1.5, -0.5, 1.0), 3), ((0.0, 2.0, 0.0), 2)]
#: The plan of the figures and of the convergence table.
FIGURE_CASE = ((0.5, 0.8, 0.5), 2)
GRID = 2000          # intervals of the solver comparison (the time-optimal law's own grid)
REFERENCE_GRID = 32000


def timed(f, *args, **kwargs):
    t0 = time.perf_counter()
    out = f(*args, **kwargs)
    return out, time.perf_counter() - t0


def phase_plane(path, limits, n):
    grid = path.grid(n)
    return references.phase_plane_topp(grid, limits.max_rotor_rate, limits.max_rotor_torque)


def row(name, robot, target, steps, settings):
    """One row of the table (None when the target has no plan with these steps)."""
    R = robot.radius
    try:
        plan = rollplan.plan((target[0] * R, target[1] * R, target[2]), steps, robot=robot)
    except NoPlanError:
        return None
    lim = Limits.of(robot)
    path = ContactPath.of_plan(plan, robot)
    r = {"robot": name, "k": robot.k, "max_rotor_rate": lim.max_rotor_rate, "max_rotor_torque": lim.max_rotor_torque,
         "target_R": list(target), "steps": steps, "a_R": plan.a / R, "b_R": plan.b / R, "L_R": path.length}
    profiles = {}
    for law_name, law in LAWS.items():
        profiles[law_name], r[f"{law_name}_s"] = timed(law.profile, path, lim)
        r[law_name] = profiles[law_name].duration
    grid = path.grid(GRID)
    base = solve_topp(grid, lim)
    r["numpy_T"], r["numpy_solve_s"] = base.duration, base.solve_time
    for backend in settings["backends"]:
        prof = solve_topp(grid, lim, backend=backend)
        r[f"{backend}_vs_numpy"] = prof.duration / base.duration - 1
        r[f"{backend}_solve_s"] = prof.solve_time
    pp, r["phase_plane_s"] = timed(phase_plane, path, lim, settings["reference_grid"])
    r["phase_plane_T"] = pp["duration"]
    r["time-optimal_vs_phase_plane"] = r["time-optimal"] / pp["duration"] - 1
    to = profiles["time-optimal"]
    m = sample_motion(path, to, 4, plan.goal, LAWS["time-optimal"].samples_per_piece)
    rate = np.abs(m.series.rotor_rates).max(axis=1) / lim.max_rotor_rate
    torque = np.abs(m.series.rotor_torques).max(axis=1) / lim.max_rotor_torque
    r["samples"] = int(m.series.time.size)
    r["max_utilisation"] = float(max(rate.max(), torque.max()))
    r["active_rate"], r["active_torque"] = float(np.mean(rate > 0.99)), float(np.mean(torque > 0.99))
    r["active_any"] = float(np.mean(np.maximum(rate, torque) > 0.99))
    sim = simulate_rotors(robot, m.series.time, m.series.rotor_rates, plan.goal)
    r["sim_position_error_R"], r["sim_arrival_error"] = sim.position_error, sim.arrival_error
    figure = (target, steps) == FIGURE_CASE and name in ("default", "default, slow motor")
    if settings["figures"] is not None and figure:
        motions = [sample_motion(path, profiles[n], 4000, plan.goal, 1000) for n in LAWS]
        fine = path.grid(settings["reference_grid"])
        ref = ("phase-plane integration (reference)", fine.s, np.sqrt(pp["x"]))
        title = (f"{name} robot (k = {robot.k:.3g}, {lim.describe()}), target ({target[0]:g} R, {target[1]:g} R, "
                 f"{target[2]:g} rad), {steps} steps: each law at its shortest duration")
        fig = plot_timing(motions, velocity_limit(path, lim, to), title, ref)
        settings["figures"][name] = fig
    return r


def convergence(settings):
    """The time-optimal duration against the grid size, every solver, on the figure case of the default robot."""
    robot = ROBOTS["default"]
    lim = Limits.of(robot)
    (u, v, psi), steps = FIGURE_CASE
    plan = rollplan.plan((u * robot.radius, v * robot.radius, psi), steps, robot=robot)
    path = ContactPath.of_plan(plan, robot)
    rows = []
    for n in settings["convergence_grids"]:
        grid = path.grid(n)
        d = {"N": n}
        for backend in ("numpy", *settings["backends"]):
            if backend == "casadi" and n > 4000:
                continue
            times = []
            for _ in range(settings["repeats"] if n <= 8000 else 1):
                prof = solve_topp(grid, lim, backend=backend)
                times.append(prof.solve_time)
            d[f"{backend}_T"], d[f"{backend}_s_min"], d[f"{backend}_s_median"] = \
                prof.duration, min(times), statistics.median(times)
        pp, d["phase_plane_s"] = timed(references.phase_plane_topp, grid, lim.max_rotor_rate, lim.max_rotor_torque)
        d["phase_plane_T"] = pp["duration"]
        d["numpy_vs_phase_plane"] = d["numpy_T"] / pp["duration"] - 1
        rows.append(d)
    return rows


def _e(v):
    return "-" if v is None else f"{v:+.1e}"


def to_markdown(report) -> str:
    m, rows = report["machine"], report["rows"]
    ratio = [r["time-optimal"] / r["min-jerk"] for r in rows]
    cruise = [r["smooth-cruise"] / r["time-optimal"] - 1 for r in rows]
    pp = [r["time-optimal_vs_phase_plane"] for r in rows]
    out = [
        "# Shortest durations of the timing laws under the motors' limits", "",
        f"- date: {report['date']}; commit `{report['commit']}`; command `{report['command']}`",
        f"- machine: {m['cpu']}, {m['cores']} cores, load average at start "
        f"{', '.join(f'{x:.2f}' for x in m['load_average'] or [])} (solve times are noisy)",
        f"- toppra: {'installed' if report['toppra'] else 'not installed (column left out)'}", "",
        "Every law's shortest duration within `max_rotor_rate` and `max_rotor_torque` "
        "(`rollplan plan --robot R.toml --timing NAME`), in s. min-jerk is today's law (rest-to-rest per "
        "half-step); time-optimal is the TOPP-RA profile on a grid of 2000 intervals, stretched to meet the "
        "limits between its nodes. Robots: `default` is rollplan's default robot, `k2.5` R 0.1 m, M 1.0 kg, "
        "m_o 0.8 kg, J_r 5e-4, J_p 4.17e-4 kg m^2 (the paper's k), `large` R 0.25 m, M 8 kg, m_o 2 kg, "
        "J_r 4e-3, J_p 2.5e-3 kg m^2.", "",
        f"**The time-optimal timing takes {min(ratio):.2f}-{max(ratio):.2f} of the shortest min-jerk duration under "
        f"the same limits**; smooth-cruise (non-stop, C3) is {min(cruise):.0%}-{max(cruise):.0%} longer than "
        f"time-optimal. Against the phase-plane integration on {report['settings']['reference_grid']} intervals "
        f"the time-optimal duration is {min(pp):+.1e} to {max(pp):+.1e} (conservative: the grid profile meets the "
        "limits at its nodes and is stretched to meet them in between).", "",
        "| robot (k) | limits [rad/s, N m] | target (u, v [R], psi) | n | L [R] | min-jerk | nonstop-min-jerk | "
        "smooth-cruise | time-optimal | TO / min-jerk | T* phase plane | TO vs phase plane | toppra vs numpy | "
        "casadi vs numpy | active (rate / torque / either) | max sample / limit | rotor-only miss [R] |",
        "|" + "---|" * 17]
    for r in rows:
        out.append(
            f"| {r['robot']} ({r['k']:.3g}) | {r['max_rotor_rate']:g}, {r['max_rotor_torque']:g} | "
            f"({r['target_R'][0]:g}, {r['target_R'][1]:g}, {r['target_R'][2]:g}) | {r['steps']} | {r['L_R']:.4f} | "
            f"{r['min-jerk']:.4f} | {r['nonstop-min-jerk']:.4f} | {r['smooth-cruise']:.4f} | {r['time-optimal']:.4f} | "
            f"{r['time-optimal'] / r['min-jerk']:.3f} | {r['phase_plane_T']:.5f} | "
            f"{r['time-optimal_vs_phase_plane']:+.1e} | {_e(r.get('toppra_vs_numpy'))} | "
            f"{_e(r.get('casadi_vs_numpy'))} | {r['active_rate']:.2f} / {r['active_torque']:.2f} / "
            f"{r['active_any']:.2f} | {r['max_utilisation']:.7f} | {r['sim_position_error_R']:.1e} |")
    out += ["", "Columns: *active* is the share of the time samples (3000 per half-step) at which a rotor rate, "
            "a torque, or either is above 99 % of its limit; *max sample / limit* the largest ratio over the "
            "samples; *rotor-only miss* the distance of the arrival of the rotor-only simulation "
            "(`rollplan.simulate_rotors`: a cubic spline through the sampled rates, (11) and (6)-(10) by CVODES) "
            "from the target. *toppra vs numpy* and *casadi vs numpy* compare the solvers on the same grid of "
            f"{GRID} intervals (relative difference of the durations, before the stretch).", "",
            "## Convergence in the grid size", "",
            f"Default robot, target {FIGURE_CASE[0]}, {FIGURE_CASE[1]} steps; solve times min / median of "
            f"{report['settings'].get('repeats', 3)} [s] "
            "(one run above 8000 intervals).", ""]
    conv = report["convergence"]
    backends = ["numpy", *report["settings"]["backends"]]
    out.append("| N | " + " | ".join(f"{b} T [s]" for b in backends) + " | phase plane T [s] | numpy vs phase plane | "
               + " | ".join(f"{b} s" for b in backends) + " | phase plane s |")
    out.append("|" + "---|" * (2 * len(backends) + 4))
    for d in conv:
        cells = [f"{d[b + '_T']:.7f}" if b + "_T" in d else "-" for b in backends]
        secs = [f"{d[b + '_s_min']:.3f} / {d[b + '_s_median']:.3f}" if b + "_T" in d else "-" for b in backends]
        out.append(f"| {d['N']} | " + " | ".join(cells) + f" | {d['phase_plane_T']:.7f} | "
                   f"{d['numpy_vs_phase_plane']:+.2e} | " + " | ".join(secs) + f" | {d['phase_plane_s']:.3f} |")
    out += ["", "Figures: `timing_laws.png` (default robot) and `timing_rate_limited.png` (slow motor): each law "
            "at its shortest duration, rotor rates and torques in time with the limits dashed, and the phase "
            "plane (s, s') with the maximum velocity curve and the phase-plane reference.", ""]
    return "\n".join(out)


def main(argv=None):
    args = parse_args(argv)
    backends = (["toppra"] if toppra_available() else []) + ["casadi"]
    settings = {"backends": backends, "reference_grid": 2000 if args.quick else REFERENCE_GRID,
                "convergence_grids": [250, 500] if args.quick else [500, 1000, 2000, 4000, 8000, 16000, 32000],
                "repeats": 1 if args.quick else 3,
                "figures": {} if not args.quick else None}
    cases = [(n, rob, tg, st) for n, rob in ROBOTS.items() for tg, st in TARGETS]
    if args.quick:   # every line of row() and convergence() runs once
        cases = cases[:1]
    mach = machine()
    report = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
              "commit": git_commit(), "machine": mach, "command": command_line(argv, __file__),
              "toppra": "toppra" in backends, "settings": {k: v for k, v in settings.items() if k != "figures"},
              "rows": []}
    try:
        with Progress(unit="rows") as progress:   # a bar on a terminal, plain lines in a log
            for i, case in enumerate(cases):
                progress("rows", i, len(cases))
                r = row(*case, settings)
                if r is not None:
                    report["rows"].append(r)
            progress("rows", len(cases), len(cases))
        report["convergence"] = convergence(settings)
    except KeyboardInterrupt:
        print("interrupted: nothing written", file=sys.stderr)
        return 130
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "timing.md", to_markdown(report).encode())
    write_json(out / "timing.json", tagged(report, "R"))
    for name, file in (("default", "timing_laws.png"), ("default, slow motor", "timing_rate_limited.png")):
        if settings["figures"] is not None and name in settings["figures"]:
            save_figure(settings["figures"][name], out / file)
    print(f"wrote {out / 'timing.md'} and {out / 'timing.json'}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
