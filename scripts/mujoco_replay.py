"""Plans replayed on MuJoCo (an independent rigid-body contact simulator): writes results/mujoco_replay.md, .json.

1. Min-jerk and time-optimal plans of the default robot (limits 300 rad/s, 0.05 N m for time-optimal) to
   (0, 0.1 m, 0): their torques at the plan file's sampling, at ten times it, and for time-optimal with the
   exact torque switches (every break of the time profile a repeated sample time, left and right values):
   MuJoCo's arrival error, slip, penetration and the rotors' rates at the end, beside the paper's torque
   plant fed the same samples interpolated the same way (linearly).
2. The contact and integrator settings: solref time constant, solimp, timestep (min-jerk, fine samples).
3. What the paper's equations do not model (options of `rollplan mjcf`): centre of mass off the centre,
   softer floor, rolling resistance.
4. The closed loop on MuJoCo: a 2-step plan executed on a robot with k 4.86 -> 5.03, open and closed loop.

Run: ``python scripts/mujoco_replay.py [--out-dir results] [--quick]`` (about 5 min; --quick: a 2 s plan).
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import rollplan
from rollplan.execution import mujoco_engine as engine
from rollplan.execution.actuation import actuate
from rollplan.execution.feedback import execute
from rollplan.execution.plants import run_torques
from rollplan.io import write_atomic, write_json
from rollplan.outputs import make_folder
from rollplan.problem import arrival_residual

GOAL = (0.0, 0.1, 0.0)
LIMITS = {"max_rotor_rate": 300.0, "max_rotor_torque": 0.05}


def exact_switches(motion):
    """The motion's torques sampled uniformly plus, at every break of its time profile, the left and the
    right value (a repeated time): ``(t, torques)``."""
    prof, path = motion.profile, motion.path
    b = prof.breaks[1:-1]
    keep = np.min(np.abs(motion.series.time[:, None] - b[None, :]), axis=1) > 1e-12 * motion.duration
    t_u = motion.series.time[keep]

    def torques(t, piece, side):
        s, sd, sdd = prof.evaluate(t, piece)
        ps = path.evaluate(np.clip(s, 0.0, path.length), side)
        return ps.A * sdd[:, None] + ps.B * sd[:, None] ** 2

    k = np.arange(1, prof.breaks.size - 1)
    rows = [(t_u, motion.series.rotor_torques[keep], np.zeros(t_u.size)),
            (b, torques(b, k - 1, "left"), np.ones(b.size)),
            (b, torques(b, k, "right"), 2 * np.ones(b.size))]
    t = np.concatenate([r[0] for r in rows])
    tau = np.vstack([r[1] for r in rows])
    order = np.lexsort((np.concatenate([r[2] for r in rows]), t))
    return t[order], tau[order]


def replay(robot, t, tau, goal, settings=engine.DEFAULT_SETTINGS, servo=0.0, rates=None):
    model = engine.compile_model(engine.mjcf(robot, settings))
    t0 = time.perf_counter()
    r = engine.replay(model, t, tau, goal=goal, rates=rates, servo_gain=servo)
    return {"arrival_error": r.arrival_error, "position_error": r.position_error, "psi_error": float(r.error[2]),
            "slip": r.slip, "max_penetration": r.max_penetration,
            "final_rotor_rate": float(np.abs(r.final_rotor_rates).max()), "final_speed": r.final_speed,
            "steps": r.steps, "seconds": time.perf_counter() - t0}


def model_plant(robot, t, tau, goal):
    """The paper's torque plant fed the same samples, interpolated linearly (strictly increasing times: a repeated
    time is moved by 1e-12 of the span, a step of that width)."""
    t = np.array(t, float)
    for i in range(1, t.size):
        if t[i] <= t[i - 1]:
            t[i] = t[i - 1] + 1e-12 * (t[-1] - t[0])
    run = run_torques(robot, t, tau, interpolation="linear")
    return arrival_residual(run.series.state[-1], goal, robot.radius)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out-dir", default="results")
    ap.add_argument("--quick", action="store_true", help="a 2 s min-jerk plan, fewer settings (a test of the script)")
    ap.add_argument("--report-only", action="store_true", help="only write mujoco_replay.md again from the .json")
    args = ap.parse_args()
    out = Path(args.out_dir)
    make_folder(out, parents=True)
    if args.report_only:
        data = json.loads((out / "mujoco_replay.json").read_text())
        write_atomic(out / "mujoco_replay.md", report(data, data["duration"]).encode())
        return
    duration = 2.0 if args.quick else 10.0
    mujoco = engine.require()
    robot = rollplan.default_robot()
    limited = replace(robot, **LIMITS)
    plan = rollplan.plan(GOAL, robot=robot)
    data = {"robot": robot.as_dict(), "goal": list(GOAL), "mujoco": mujoco.__version__, "duration": duration,
            "settings": engine.DEFAULT_SETTINGS.as_dict(), "machine": platform.machine()}

    # 1. plans at several samplings
    series = []
    for samples in (2001, 20001):
        m = actuate(plan, robot, duration, samples=samples)
        series.append((f"min-jerk, {m.series.time.size} samples", robot, m.series.time, m.series.rotor_torques, m.goal))
    m = actuate(rollplan.plan(GOAL, robot=limited), limited, timing="time-optimal")
    series.append((f"time-optimal, {m.series.time.size} samples", limited, m.series.time, m.series.rotor_torques,
                   m.goal))
    if not args.quick:
        m10 = actuate(rollplan.plan(GOAL, robot=limited), limited, timing="time-optimal", samples=60000)
        series.append((f"time-optimal, {m10.series.time.size} samples", limited, m10.series.time,
                       m10.series.rotor_torques, m10.goal))
    t_b, tau_b = exact_switches(m)
    series.append((f"time-optimal, exact switches ({t_b.size} samples)", limited, t_b, tau_b, m.goal))
    data["plans"] = []
    for name, rob, t, tau, goal in series:
        r = replay(rob, t, tau, goal)
        r.update(name=name, duration=float(t[-1]), model_plant=model_plant(rob, t, tau, goal))
        data["plans"].append(r)
        print(name, r["arrival_error"], r["model_plant"])

    # 2. contact and integrator settings (min-jerk, fine samples)
    fine = actuate(plan, robot, duration, samples=20001)
    d = engine.DEFAULT_SETTINGS
    trials = [("solref 0.02 1 (MuJoCo's default), default solimp", replace(d, solref=(0.02, 1.0),
                                                                          solimp=(0.9, 0.95, 0.001, 0.5, 2.0)))]
    for tc in ((0.02, 0.005, 0.002, 0.001, 5e-4, 2e-4) if not args.quick else (0.02, 2e-4)):
        trials.append((f"solref {tc:g} 1", replace(d, solref=(tc, 1.0))))
    trials += [("solref 2e-4 0.5 (underdamped)", replace(d, solref=(2e-4, 0.5))),
               ("solimp 0.9 0.95 0.001 (MuJoCo's default)", replace(d, solimp=(0.9, 0.95, 0.001, 0.5, 2.0))),
               ("timestep 5e-5, solref 1e-4 1", replace(d, timestep=5e-5, solref=(1e-4, 1.0)))]
    data["settings_trials"] = []
    for name, s in trials:
        r = replay(robot, fine.series.time, fine.series.rotor_torques, fine.goal, s)
        r.update(name=name, settings=s.as_dict())
        data["settings_trials"].append(r)
        print(name, r["arrival_error"], r["max_penetration"])

    # 3. what the paper does not model
    coarse = actuate(plan, robot, duration)
    options = [("the paper's robot (default settings)", d),
               ("centre of mass 1 mm below the centre", replace(d, com_offset=(0.0, 0.0, -0.001))),
               ("centre of mass 1 mm to the side (x)", replace(d, com_offset=(0.001, 0.0, 0.0))),
               ("softer floor, solref 0.02 1", replace(d, solref=(0.02, 1.0))),
               ("rolling resistance 1e-5 m", replace(d, rolling=1e-5)),
               ("rolling resistance 1e-4 m", replace(d, rolling=1e-4))]
    data["options"] = []
    for name, s in options:
        r = replay(robot, coarse.series.time, coarse.series.rotor_torques, coarse.goal, s)
        r.update(name=name)
        rr = replay(robot, coarse.series.time, coarse.series.rotor_torques, coarse.goal, s, servo=0.05,
                    rates=coarse.series.rotor_rates)
        r["servo_arrival_error"] = rr["arrival_error"]
        data["options"].append(r)
        print(name, r["arrival_error"], rr["arrival_error"])

    # 4. closed loop on MuJoCo
    real = replace(robot, mass_total=1.266, rotor_inertia_axial=2.15e-4, rotor_inertia_transverse=1.29e-4)
    cl_plan = rollplan.plan((0.02, 0.025, 0.8), steps=2, robot=robot)
    data["closed_loop"] = {"real_k": real.k, "model_k": robot.k}
    for plant in ("torques", "mujoco"):
        for closed in (False, True):
            e = execute(cl_plan, robot, real, duration / 4, plant=plant, closed_loop=closed)
            data["closed_loop"][f"{plant}_{'closed' if closed else 'open'}"] = {
                "arrival_error": e.arrival_error, "k": [x.get("k") for x in e.estimates]}
    print(data["closed_loop"])
    write_json(out / "mujoco_replay.json", data)
    write_atomic(out / "mujoco_replay.md", report(data, duration).encode())
    print(f"wrote {out / 'mujoco_replay.md'}")


def report(data, duration) -> str:
    e = "{:.2e}".format
    L = ["# Plans replayed on MuJoCo", "",
         f"`python scripts/mujoco_replay.py` (MuJoCo {data['mujoco']}, {data['machine']}). The default robot "
         "(k = 4.86266) to (u_a, v_a, psi) = (0, 0.1 m, 0), one figure eight; the model of `rollplan mjcf` "
         f"(settings {data['settings']}); the plan's motor torques applied feed-forward, interpolated linearly "
         "between samples, each RK4 step getting the interpolant's mean. Arrival error: the Euclidean norm of "
         "(u_a/R, v_a/R, psi, u_o, v_o) (R and rad). Slip: the distance slid at the contact [m]; penetration: "
         "the deepest the sphere sank into the floor [m].", "",
         "## 1. Plans", "",
         "The model column is the paper's torque plant (CVODES) fed the same samples, interpolated the same way: "
         "where MuJoCo and it agree, the error is the samples', not the engine's.", "",
         "| plan | MuJoCo arrival error | paper's torque plant | slip [m] | penetration [m] | rotor rate at end "
         "[rad/s] | centre speed at end [m/s] | RK4 steps |", "|---|---|---|---|---|---|---|---|"]
    for r in data["plans"]:
        L.append(f"| {r['name']} ({r['duration']:.4g} s) | {e(r['arrival_error'])} | {e(r['model_plant'])} | "
                 f"{e(r['slip'])} | {e(r['max_penetration'])} | {e(r['final_rotor_rate'])} | {e(r['final_speed'])} "
                 f"| {r['steps']} |")
    L += ["", "Uniform samples blur the time-optimal law's bang-bang switches (an O(h) error: ten times the "
          "samples, a tenth of the error, the rotors still turning at the end); with the switches as repeated "
          "sample times (left and right values) the replay converges like the min-jerk one.", "",
          f"## 2. Contact and integrator settings (min-jerk, {duration:g} s, 20001 samples)", "",
          "| setting | arrival error | psi error [rad] | slip [m] | penetration [m] |", "|---|---|---|---|---|"]
    for r in data["settings_trials"]:
        L.append(f"| {r['name']} | {e(r['arrival_error'])} | {e(r['psi_error'])} | {e(r['slip'])} | "
                 f"{e(r['max_penetration'])} |")
    L += ["", "The error falls with the contact's time constant (the soft contact lets the sphere slip and sink "
          "in proportion to it); the default is the stiffest MuJoCo allows at the step, two steps.", "",
          "## 3. What the paper's equations do not model (options of `rollplan mjcf`; min-jerk, 2001 samples)", "",
          "| model | arrival error, torques alone | with a rate loop, gain 0.05 N m s/rad | slip [m] |"
          " penetration [m] |", "|---|---|---|---|---|"]
    for r in data["options"]:
        L.append(f"| {r['name']} | {e(r['arrival_error'])} | {e(r['servo_arrival_error'])} | {e(r['slip'])} | "
                 f"{e(r['max_penetration'])} |")
    L += ["", "A centre of mass 1 mm off the centre (1 % of R) turns the sphere into a pendulum: gravity's moment "
          "about the contact point, which (11) assumes zero, changes the angular momentum, and the plan misses by "
          "about 2 (R and rad). Rolling resistance of 1e-5 m (a hard floor) already costs 0.1, 1e-4 m about 1. A "
          "rotor-rate loop around the planned rates does not help: the rotors follow their rates, the shell "
          "does not. The closed loop of section 4 was not run on these: its estimator models inertias only.",
          ]
    c = data["closed_loop"]
    L += ["", "## 4. Closed loop on MuJoCo", "",
          f"Two figure eights to (0.02 m, 0.025 m, 0.8 rad), planned for k = {c['model_k']:.6g}, executed on a "
          f"robot with +5.5 % mass and +7.5 % rotor inertia (k = {c['real_k']:.6g}); min-jerk, "
          f"{duration / 4:g} s per leaf. `rollplan simulate --engine mujoco --closed-loop` runs this.", "",
          "| plant | open loop | closed loop | estimated k (before each figure eight) |", "|---|---|---|---|"]
    for plant in ("torques", "mujoco"):
        o, cl = c[f"{plant}_open"], c[f"{plant}_closed"]
        L.append(f"| {plant} | {e(o['arrival_error'])} | {e(cl['arrival_error'])} | "
                 f"{', '.join(f'{k:.6g}' for k in cl['k'] if k is not None)} |")
    return "\n".join(L) + "\n"


if __name__ == "__main__":
    main()
