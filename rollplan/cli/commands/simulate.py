"""``rollplan simulate``: the plan file's own motion on a plant (the model's equations or MuJoCo), open or closed
loop."""

from __future__ import annotations

from ...errors import InputError, check_finite, check_whole
from ...inputs import show_path
from ...io import save_figure
from ...problem import STATE_NAMES
from ...progress import report
from ...robot import load_robot
from ..arguments import JSON_HELP, number, whole
from ..common import EXIT_OK, NORM, check_outputs, emit_json
from ..format import num


def _noise(args):
    from ...execution.plants import disturbance

    sigma = check_finite("--noise", args.noise)
    if sigma < 0 or sigma > 0.1:
        raise InputError(f"--noise {args.noise!r} is not allowed: it must lie in [0, 0.1] (R and rad per sample)")
    return (disturbance("measurement", sigma_length=sigma, sigma_angle=sigma, seed=args.seed),) if sigma > 0 else ()


def _check_simulate_options(args) -> None:
    """simulate's own options, every one whatever the mode (a seed is checked without --noise too); the closed
    loop's own options are refused without --closed-loop (they would do nothing)."""
    check_whole("--seed", args.seed, 0, 2**63 - 1)
    if not args.closed_loop:
        for flag, value in (("--average", args.average), ("--tolerance", args.tolerance),
                            ("--corrections", args.corrections)):
            if value is not None:
                raise InputError(f"{flag} applies to --closed-loop only")
    args.average = 1 if args.average is None else args.average
    args.tolerance = 1e-6 if args.tolerance is None else args.tolerance
    args.corrections = 3 if args.corrections is None else args.corrections
    check_whole("--average", args.average, 1, 1_000_000)
    check_whole("--corrections", args.corrections, 0, 100)
    tol = check_finite("--tolerance", args.tolerance)
    if not 0 < tol <= 1:
        raise InputError(f"--tolerance {args.tolerance!r} is not allowed: it must lie in (0, 1] (R and rad)")


def _file_samples(rp, args, plant):
    """The plan file's own motion as samples, its piece duration and figure eights (for ``plant``)."""
    import numpy as np

    from ...execution.feedback import Samples

    if plant in ("torques", "mujoco") and rp.rotor_torques is None:
        raise InputError(f"plan file {str(args.plan_file)!r} has no key 'rotor_torques': the {plant} plant replays "
                         "the plan's torques (make it with: rollplan plan ... --duration T --json FILE)")
    if args.closed_loop and rp.steps is None:
        raise InputError(f"plan file {str(args.plan_file)!r} has no key 'steps': the closed loop re-plans the figure "
                         "eights left (make it with: rollplan plan ... --duration T --json FILE)")
    torques = rp.rotor_torques if rp.rotor_torques is not None else np.zeros_like(rp.rotor_rates)
    segment = rp.segment if rp.segment is not None else np.zeros(rp.time.size, int)
    pieces = max(len(rp.kinds), int(np.unique(segment).size))
    samples = Samples(rp.time, rp.rotor_rates, torques, segment, rp.kinds, "linear")
    return samples, float(rp.time[-1] - rp.time[0]) / pieces, rp.steps or 1


def _position(error_r: float, robot) -> str:
    """A position error given in units of R, in metres and in R."""
    return f"{error_r * robot.radius:.3e} m ({error_r:.3e} R)"


def _simulate_executed(args, rp, robot, plant=None, **engine) -> int:
    """``rollplan simulate`` with ``--closed-loop``, ``--plant torques`` or ``--noise``: the file's own motion on
    the chosen plant (``plant``, default ``--plant``; ``engine``: more arguments of the execution, e.g. the MuJoCo
    model), open loop, and in closed loop that motion corrected."""
    from ...execution.feedback import execute_samples

    plant = plant or args.plant
    dist = _noise(args)
    first, piece, steps = _file_samples(rp, args, plant)
    timing = rp.timing or "min-jerk"
    common = {"plant": plant, "disturbances": dist, "timing": timing, "rest_readings": args.average,
              "tolerance": args.tolerance, "corrections": args.corrections, "progress": report}
    segments = rp.data.get("segments") if isinstance(rp.data.get("segments"), list) else []
    families = {p.get("curve") for p in segments if isinstance(p, dict)} - {None, "figure_eight", "great_circle"}
    runs = [execute_samples(first, rp.start, rp.goal, steps, rp.robot, robot, piece, closed_loop=closed,
                            replan=not families, **common, **engine)
            for closed in (False, True)[:1 + bool(args.closed_loop)]]
    opened, run = runs[0], runs[-1]
    f, g, e = run.final, rp.goal, run.error
    n_corr = sum(s["mode"] == "correction" for s in run.segments)
    print(f"rollplan simulate: {plant} plant, {'closed' if args.closed_loop else 'open'} loop, the file's motion "
          f"({first.time.size} samples over {num(first.time[-1] - first.time[0])} s, timing {timing}), robot k = "
          f"{num(robot.k)} (planned k = {num(rp.robot.k)}){', measurement noise ' + num(args.noise) if dist else ''}")
    print(f"  final         u_a = {num(f[0])} m  v_a = {num(f[1])} m  psi = {num(f[2])} rad"
          f"  u_o = {num(f[3])} rad  v_o = {num(f[4])} rad")
    print(f"  target        u_a = {num(g.u_a)} m  v_a = {num(g.v_a)} m  psi = {num(g.psi)} rad")
    print(f"  arrival error {run.arrival_error:.3e} ({NORM}): position {_position(run.position_error, robot)}, "
          f"psi {e[2]:.3e} rad" + (f"; open loop {opened.arrival_error:.3e}, position "
                                    f"{_position(opened.position_error, robot)}" if args.closed_loop else ""))
    if args.closed_loop:
        print(f"  corrections   {n_corr} after the plan (tolerance {num(args.tolerance)}, at most {args.corrections}; "
              f"re-plans and corrections timed {timing}, {num(piece)} s a piece or the shortest within the limits; "
              f"state at rest: mean of {args.average} reading{'s' if args.average > 1 else ''})")
        if run.stopped:
            print(f"  stopped       {run.stopped}")
        print("  estimated k   " + ", ".join(num(d["k"]) for d in run.estimates if "k" in d))
    if args.json:
        d = run.to_dict()
        d.update({"open_loop_arrival_error": opened.arrival_error, "robot": robot.as_dict(),
                  "model_robot": rp.robot.as_dict(), "noise": args.noise, "seed": args.seed,
                  "corrections": n_corr, "tolerance": args.tolerance, "average": args.average})
        emit_json(args, d, "m")
    if args.plot:
        title = (f"{plant} plant, {'closed' if args.closed_loop else 'open'} loop on {args.plan_file}: arrival "
                 f"error {run.arrival_error:.2e} ({NORM})" + (f", open loop {opened.arrival_error:.2e}"
                                                            if args.closed_loop else ""))
        _plot_simulation(args, rp, run.series, robot, title)
    return EXIT_OK


def _planned_states(rp, time=None):
    """The plan file's planned states at ``time`` (default: its sample times; after its end, its last state),
    (N, 5), or None if it has none usable."""
    import numpy as np

    try:
        state = np.asarray(rp.data.get("state"), float)
    except (TypeError, ValueError):
        return None
    ok = state.shape == (rp.time.size, 5) and np.all(np.isfinite(state))
    if not ok:
        return None
    if time is None:
        return state
    keep = rp.distinct
    return np.column_stack([np.interp(time, rp.time[keep], state[keep, i]) for i in range(5)])


def _plot_simulation(args, rp, series, robot, title) -> None:
    from ...plots.motion import plot_simulation

    save_figure(plot_simulation(series, rp.goal, _planned_states(rp, series.time), robot, title), args.plot)
    print(f"wrote {args.plot}")


def cmd_simulate(args) -> int:
    from ...execution.plants import simulate_rotors
    from ...io import load_rotor_plan

    check_outputs(json=args.json, figure=args.plot, inputs=[args.plan_file, args.robot])
    _check_simulate_options(args)
    _noise(args)   # the options before the files
    gain = _servo_gain(args)
    other = load_robot(args.robot) if args.robot else None
    rp = load_rotor_plan(args.plan_file)
    robot = other or rp.robot
    if args.engine == "mujoco":
        return _simulate_mujoco(args, rp, robot, gain)
    if args.closed_loop or args.plant != "rates" or args.noise:
        return _simulate_executed(args, rp, robot)
    keep = rp.distinct
    sim = simulate_rotors(robot, rp.time[keep], rp.rotor_rates[keep], rp.goal, x0=rp.start.array())
    e = sim.error
    f, g = sim.final, rp.goal
    print(f"rollplan simulate: {keep.size} samples over {num(rp.time[-1] - rp.time[0])} s, robot k = {num(robot.k)}"
          f"{' (planned k = %s)' % num(rp.robot.k) if args.robot else ''}, R = {num(robot.radius)} m")
    print(f"  final         u_a = {num(f[0])} m  v_a = {num(f[1])} m  psi = {num(f[2])} rad"
          f"  u_o = {f[3]:.3g} rad  v_o = {f[4]:.3g} rad")
    print(f"  target        u_a = {num(g.u_a)} m  v_a = {num(g.v_a)} m  psi = {num(g.psi)} rad")
    print(f"  arrival error {sim.arrival_error:.3e} ({NORM}): position {_position(sim.position_error, robot)}, "
          f"psi {e[2]:.3e} rad, u_o {e[3]:.1e} rad, v_o {e[4]:.1e} rad")
    if args.json:
        emit_json(args, {"final": dict(zip(STATE_NAMES, map(float, sim.final))),
                          "arrival_error": sim.arrival_error, "position_error": sim.position_error,
                          "position_error_m": sim.position_error * robot.radius,
                          "error": dict(zip(STATE_NAMES, map(float, e))),
                          "error_units": "u_a, v_a and position_error in R; psi (wrapped), u_o, v_o in rad",
                          "robot": robot.as_dict()}, "m")
    if args.plot:
        title = (f"rotor-driven simulation of {args.plan_file}: arrival error {sim.arrival_error:.2e} ({NORM}),\n"
                 f"position error {sim.position_error * robot.radius:.2e} m")
        _plot_simulation(args, rp, sim.series, robot, title)
    return EXIT_OK


def _servo_gain(args) -> float:
    """The rate loop's gain of ``--servo`` (0 without it); ``--servo`` and ``--mjcf`` need ``--engine mujoco``."""
    if args.engine != "mujoco":
        for flag, value in (("--servo", args.servo), ("--mjcf", args.mjcf)):
            if value is not None:
                raise InputError(f"{flag} applies to --engine mujoco only")
        return 0.0
    gain = 0.0 if args.servo is None else check_finite("--servo", args.servo)
    if not 0.0 <= gain <= 1e3:
        raise InputError(f"--servo {args.servo!r} is not allowed: the rate loop's gain must lie in [0, 1000] N m s/rad")
    return gain


def _simulate_mujoco(args, rp, robot, gain: float) -> int:
    """``rollplan simulate --engine mujoco``: the plan's torques replayed on MuJoCo's rigid-body model, with a rate
    loop of gain ``gain`` (:func:`_servo_gain`)."""
    import math

    import numpy as np

    from ...execution import mujoco_engine as engine
    from ...inputs import read_text

    mujoco = engine.require()
    if args.mjcf:
        where = f"MJCF file {show_path(args.mjcf)}"
        model = engine.compile_model(read_text(args.mjcf, "MJCF file", 1 << 24), where)
        if not math.isclose(engine.radius_of(model), robot.radius, rel_tol=1e-9):
            raise InputError(f"{where}: its sphere's radius {engine.radius_of(model):g} m is not the plan's "
                             f"{robot.radius:g} m (the plan's lengths are on that sphere)")
    else:
        model = engine.compile_model(engine.mjcf(robot))
    if args.closed_loop or args.noise:
        return _simulate_executed(args, rp, robot, "mujoco", mujoco_model=model, servo_gain=gain)
    where = f"plan file {show_path(args.plan_file)}"
    if "rotor_torques" not in rp.data:
        raise InputError(f"{where} has no key 'rotor_torques' (make it with: rollplan plan ... --duration T --json "
                         "FILE)")
    t, tau = engine.torque_samples(rp.data["time"], rp.data["rotor_torques"], where)
    rates = np.asarray(rp.data["rotor_rates"], float) if gain > 0 else None
    if rates is not None and rates.shape != tau.shape:
        raise InputError(f"{where}: 'rotor_rates' and 'rotor_torques' must have the same shape for --servo")
    run = engine.replay(model, t, tau, rp.start, rp.goal, rates=rates, servo_gain=gain)
    e, f, g = run.error, run.final, rp.goal
    print(f"rollplan simulate: MuJoCo {mujoco.__version__}, {run.steps} RK4 steps of {num(run.timestep)} s, "
          f"robot k = {num(robot.k)}{' (planned k = %s)' % num(rp.robot.k) if args.robot else ''}, "
          f"R = {num(robot.radius)} m{', rate loop gain %s N m s/rad' % num(gain) if gain else ''}"
          f"{', model ' + show_path(args.mjcf) if args.mjcf else ''}")
    print(f"  final         u_a = {num(f[0])} m  v_a = {num(f[1])} m  psi = {num(f[2])} rad"
          f"  u_o = {f[3]:.3g} rad  v_o = {f[4]:.3g} rad")
    print(f"  target        u_a = {num(g.u_a)} m  v_a = {num(g.v_a)} m  psi = {num(g.psi)} rad")
    print(f"  arrival error {run.arrival_error:.3e} ({NORM}): position {run.position_error * robot.radius:.3e} m, "
          f"psi {e[2]:.3e} rad, u_o {e[3]:.1e} rad, v_o {e[4]:.1e} rad")
    print(f"  contact       slip {run.slip:.3e} m, max penetration {run.max_penetration:.3e} m; at the end: rotor "
          f"rates {run.final_rotor_rates[0]:.2e}, {run.final_rotor_rates[1]:.2e} rad/s, centre speed "
          f"{run.final_speed:.2e} m/s")
    if args.json:
        d = run.summary()
        d.update({"engine": "mujoco", "mujoco_version": mujoco.__version__,
                  "final": dict(zip(STATE_NAMES, map(float, f))), "error": dict(zip(STATE_NAMES, map(float, e))),
                  "position_error_m": run.position_error * robot.radius,
                  "error_units": "u_a, v_a and position_error in R; psi (wrapped), u_o, v_o in rad; slip, "
                                 "max_penetration in m",
                  "servo_gain": gain, "robot": robot.as_dict(),
                  "mjcf": args.mjcf if args.mjcf else engine.DEFAULT_SETTINGS.as_dict()})
        emit_json(args, d, "m")
    if args.plot:
        from ...plots.motion import plot_simulation

        title = (f"MuJoCo replay of {args.plan_file}: arrival error {run.arrival_error:.2e} ({NORM}),\n"
                 f"slip {run.slip:.2e} m, max penetration {run.max_penetration:.2e} m")
        save_figure(plot_simulation(run.series, g, _planned_states(rp), robot, title), args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


def register(sub) -> None:
    """The ``simulate`` command's options."""
    m = sub.add_parser("simulate", help="drive the robot by the plan file's own motion (its rotor rates, or its "
                       "torques) and report the arrival error; optionally in closed loop")
    m.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    m.add_argument("--robot", metavar="FILE.toml", help="simulate this (real) robot instead of the planned one")
    m.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the simulated final state and errors"))
    m.add_argument("--plot", metavar="FILE.png", help="the simulated motion against the plan: paths, psi, deviation "
                   "in time, and the rotor rates that drove it")
    m.add_argument("--closed-loop", action="store_true",
                   help="run the file's motion, measure after each figure eight where it rests, estimate the robot, "
                        "re-plan the rest (with the file's timing law), then correct from the measured state until "
                        "--tolerance or --corrections")
    m.add_argument("--plant", choices=("rates", "torques"), default="rates",
                   help="drive the robot by the file's rotor rates (default) or by its motor torques (linear "
                        "between samples, a step at a time given twice)")
    m.add_argument("--noise", type=number, default=0.0, metavar="SIGMA",
                   help="measurement noise: standard deviation on u_a, v_a [R] and the angles [rad], "
                        "at most 0.1 (default 0)")
    m.add_argument("--seed", type=whole, default=0, help="seed of the noise, in [0, 2^63 - 1] (default 0)")
    m.add_argument("--engine", choices=("model", "mujoco"), default="model",
                   help="model: the paper's equations (default); mujoco: the plan's motor torques replayed on "
                        "MuJoCo's rigid-body model of the robot (pip install 'rollplan[mujoco]')")
    m.add_argument("--mjcf", metavar="FILE.xml", help="with --engine mujoco: this model (written by rollplan mjcf, "
                   "maybe edited) instead of the robot's own with the default settings")
    m.add_argument("--servo", type=number, default=None, metavar="GAIN",
                   help="with --engine mujoco: add a rotor-rate loop around the planned rates, gain in [0, 1000] "
                        "N m s/rad (default none: torques alone); --closed-loop and --noise also work with "
                        "--engine mujoco (the state measured from MuJoCo's pose)")
    m.add_argument("--average", type=whole, default=None, metavar="N",
                   help="closed loop: the state at rest is the mean of N sensor readings, N in [1, 10^6] (default 1)")
    m.add_argument("--tolerance", type=number, default=None, metavar="TOL",
                   help="closed loop: no correction once the measured arrival error is below TOL, in (0, 1] (R and "
                        "rad; default 1e-6)")
    m.add_argument("--corrections", type=whole, default=None, metavar="N",
                   help="closed loop: at most N correcting motions after the plan, N in [0, 100] (default 3)")
    m.set_defaults(func=cmd_simulate)
