"""The ``rollplan`` command. Exit codes: 0 success, 2 bad input, 3 no plan, 4 solver failure."""

from __future__ import annotations

import argparse
import logging
import sys

from .core.curves import A_MAX
from .errors import InputError, NoPlanError, SolverError, check_finite, check_whole
from .io import check_figure_path, check_writable, composed_to_dict, route_to_dict, save_figure, write_json
from .planners import geometric
from .planners.geometric import as_composed
from .problem import STATE_NAMES
from .robot import default_robot, load_robot
from .waypoints import read_waypoints

EXIT_OK, EXIT_INPUT, EXIT_NOPLAN, EXIT_SOLVER = 0, 2, 3, 4
#: k of ``plan`` and ``compare`` when neither --k nor --robot is given (the paper's case study).
DEFAULT_K = 2.5


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad input in one line with exit code 2."""

    def error(self, message):
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message}\n")


def _number(text: str) -> float:
    try:
        return check_finite("value", float(text))
    except (ValueError, InputError):
        raise argparse.ArgumentTypeError(f"{text!r} is not a finite number") from None


def _whole(text: str) -> int:
    try:
        return int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None


def _check_outputs(json=None, figure=None) -> None:
    """Refuse unwritable output paths and unknown figure formats before any computation."""
    if json is not None:
        check_writable(json)
    if figure is not None:
        check_figure_path(figure)


def _k_or_robot(args):
    """(k, robot) from --k / --robot."""
    if args.robot is not None:
        return None, load_robot(args.robot)
    return args.k, None


def _fmt_plan(p, unit) -> str:
    lines = [
        f"  figure eight  a = {p.a:.9g} {unit}   b = {p.b:.9g} {unit}   gamma = {p.gamma:.9g} rad"
        f"   (branch m = {p.branch})",
        f"  one step      h = {p.h:.9g} {unit}   eta = {p.eta:.9g} rad",
        f"  path length   {p.path_length:.9g} {unit}",
        f"  final         u_a = {p.final.u_a:.12g}  v_a = {p.final.v_a:.12g}  psi = {p.final.psi:.12g}"
        f"  u_o = {p.final.u_o:.3g}  v_o = {p.final.v_o:.3g}",
        f"  residual      {p.residual:.2e} ({p.certificate.method}, independent of the planner)",
    ]
    return "\n".join(lines)


def _fmt_state(x) -> str:
    return "(" + ", ".join(f"{float(v):.9g}" for v in x) + ")"


def _fmt_composed(p, unit) -> str:
    """The lines of a composed plan (rollplan.planners.geometric.composed.ComposedPlan)."""
    R = p.radius
    what = {"empty": "the start is the goal: no motion", "rolls": "the approach and departure rolls alone",
            "one": "one leg of figure eights", "turn": "turn in place by pairs of equal circles",
            "two": "two legs of figure eights through an intermediate pole state"}[p.mode]
    lines = [f"  mode          {p.mode}: {what}"]
    if p.approach is not None:
        lines.append(f"  approach      roll of {p.approach.sigma * R:.9g} {unit} to the pole along the great circle "
                     f"(direction beta = {p.approach.beta:.6g} rad)")
    if p.legs or p.turn is not None:
        t = p.target
        lines.append(f"  eights do     (u_a, v_a, psi) = ({t[0] * R:.9g}, {t[1] * R:.9g}, {t[2]:.9g}) "
                     "from rest at the pole")
    for i, leg in enumerate(p.legs, 1):
        s = R / leg.radius
        lines.append(f"  leg {i}         {leg.steps} x figure eight a = {leg.a * s:.9g} {unit}   b = {leg.b * s:.9g} "
                     f"{unit}   gamma = {leg.gamma:.9g} rad   (branch m = {leg.branch})")
    if p.turn is not None:
        tr = p.turn
        lines.append(f"  turn          {tr.steps} pair(s) of circles b = {tr.b * R:.9g} {unit} "
                     f"({'+y' if tr.side == 0 else '-y'} side), eta = {tr.eta:.9g} rad each")
    if p.departure is not None:
        lines.append(f"  departure     roll of {p.departure.sigma * R:.9g} {unit} from the pole along the great "
                     f"circle (direction beta = {p.departure.beta:.6g} rad)")
    lines += [f"  path length   {p.path_length:.9g} {unit} in {len(p.pieces)} pieces",
              f"  final         {_fmt_state(p.final)}",
              f"  residual      {p.residual:.2e} ({p.certificate.method}, the whole motion from the start state)"]
    return "\n".join(lines)


def _is_timed(args) -> bool:
    return args.duration is not None or args.timing is not None


def _check_timing_outputs(args) -> None:
    """--timing-plot of ``plan`` and ``route``: a figure path, and a timed motion to draw."""
    if args.timing_plot is not None:
        check_figure_path(args.timing_plot)
        if not _is_timed(args):
            raise InputError("--timing-plot needs a timed motion: give --duration T or --timing NAME")


def _robot_for_duration(args, k, robot):
    """The robot of ``--duration`` / ``--timing`` (the default robot unless --robot is given), with the timing
    law's needs (limits, duration) checked before planning."""
    if not _is_timed(args):
        return robot
    if robot is None:
        if k is not None:
            raise InputError("--duration and --timing need the robot's inertias, not only k: give --robot FILE "
                             "(or drop --k to use the default robot)")
        robot = default_robot()
        print("rollplan: no --robot given: using the default robot (rollplan/data/default_robot.toml); "
              "lengths in m")
    from .execution.limits import Limits
    from .execution.timing import get_law

    get_law(args.timing or "min-jerk").check(Limits.of(robot), args.duration)
    return robot


def _plan_inputs(args):
    """The checks of ``plan`` and ``route`` before any work: outputs, samples, the robot and the timing law's
    needs; returns ``(k, robot)``."""
    _check_outputs(json=args.json, figure=args.plot)
    _check_timing_outputs(args)
    check_whole("samples", args.samples, 2, 10**7)
    k, robot = _k_or_robot(args)
    return k, _robot_for_duration(args, k, robot)


def cmd_plan(args) -> int:
    k, robot = _plan_inputs(args)
    goal = (args.to[0], args.to[1], args.psi, args.contact[0], args.contact[1])
    p = geometric.plan(goal, args.steps, k, robot, args.radius, args.all, args.method, start=args.start,
                       legs=args.legs)
    unit = "m" if robot is not None else ("R" if args.radius is None else "units")
    g = p.goal
    composed = hasattr(p, "pieces")
    if composed or tuple(p.problem.start) != (0.0,) * 5:
        print(f"rollplan: k = {p.k:.9g}, R = {p.radius:g}, steps = {p.steps}, from (u_a, v_a, psi, u_o, v_o) = "
              f"{_fmt_state(p.problem.start)} to {_fmt_state(g)}")
    else:
        print(f"rollplan: k = {p.k:.9g}, R = {p.radius:g}, steps = {p.steps}, target (u_a, v_a, psi) = "
              f"({g.u_a:g}, {g.v_a:g}, {g.psi:g})")
    print(_fmt_composed(p, unit) if composed else _fmt_plan(p, unit))
    details = p.stats.details
    found = (f"{details['candidates']} brackets, {details['solves']} solves, " if "candidates" in details else "")
    print(f"  solver        {p.stats.method}: {p.stats.status}, {p.stats.iterations} iterations, {found}"
          f"{p.stats.time_s * 1e3:.1f} ms")
    for i, alt in enumerate(p.alternatives, 1):
        print(f"alternative {i}:")
        print(_fmt_composed(alt, unit) if composed else _fmt_plan(alt, unit))
    _write_results(args, p, robot, unit, composed_to_dict)
    return EXIT_OK


def _write_results(args, p, robot, unit, to_dict) -> None:
    """--duration/--timing, --json, --plot and --timing-plot of ``plan`` and ``route``: ``args.samples``
    trajectory samples in all."""
    motion, extra = _timed(args, p, robot) if _is_timed(args) else (None, {})
    traj = as_composed(p).sample(args.samples) if (args.json or args.plot) else None
    if args.json:
        write_json(args.json, {**to_dict(p, traj), **extra})
        print(f"wrote {args.json}")
    if args.plot and motion is not None:
        from .plots.motion import plot_motion

        save_figure(plot_motion(motion, p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot and not hasattr(p, "pieces"):
        from .plots.plan import plot_plan

        save_figure(plot_plan(p, traj, unit or "R"), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot:
        from .plots.composed import plot_composed

        save_figure(plot_composed(p, traj, unit or "R"), args.plot)
        print(f"wrote {args.plot}")
    if args.timing_plot:
        from .execution.timing import velocity_limit
        from .plots.timing import plot_timing

        moving = motion.path is not None and motion.limits.any
        limit = velocity_limit(motion.path, motion.limits, motion.profile) if moving else None
        save_figure(plot_timing(motion, limit), args.timing_plot)
        print(f"wrote {args.timing_plot}")


def cmd_route(args) -> int:
    k, robot = _plan_inputs(args)
    waypoints = read_waypoints(args.waypoints)
    progress = _Progress()
    print(f"rollplan route: {len(waypoints)} waypoints from {args.waypoints}", file=sys.stderr)
    try:
        r = geometric.plan_route(waypoints, args.steps, k, robot, args.radius, args.legs, args.method,
                                 progress=lambda done, total: progress("legs", done, total))
    except KeyboardInterrupt:
        progress.close()
        print("\nrollplan: interrupted", file=sys.stderr)
        return 130
    progress.close()
    unit = "m" if robot is not None else ("R" if args.radius is None else "units")
    print(f"rollplan route: k = {r.k:.9g}, R = {r.radius:g}, {len(r.plans)} legs, default steps = {r.steps}")
    for i, (p, w, res) in enumerate(zip(r.plans, r.waypoints[1:], r.waypoint_residuals), 1):
        label = f" {w.label!r}" if w.label else ""
        print(f"  leg {i} to waypoint {i + 1}{label} {_fmt_state(w.state)}: {getattr(p, 'mode', 'one')}, "
              f"{p.path_length:.6g} {unit}, waypoint residual {res:.2e}")
    print(f"  path length   {r.path_length:.9g} {unit} in {len(r.pieces)} pieces")
    print(f"  final         {_fmt_state(r.final)}")
    print(f"  residual      {r.residual:.2e} ({r.certificate.method}, the whole route from the first waypoint)")
    print(f"  time          {r.stats.time_s:.2f} s")
    _write_results(args, r, robot, unit, route_to_dict)
    return EXIT_OK


def _timed(args, p, robot):
    """``--duration`` / ``--timing``: rotor rates, angles and torques, checked by the rotor-only simulation
    from the plan's start state."""
    from .execution.actuation import actuate
    from .execution.plants import simulate_rotors
    from .execution.timing import round_up
    from .io import motion_to_dict

    timing = args.timing or "min-jerk"
    motion = actuate(p, robot, args.duration, args.samples, timing)
    sim = simulate_rotors(robot, motion.time, motion.rotor_rates, p.goal, x0=p.problem.start.array())
    lim = motion.limits
    print(f"  motion        T = {motion.duration:g} s, {motion.time.size} samples, timing {timing}"
          f"{' (rest-to-rest per piece: leaf, roll)' if timing == 'min-jerk' else ''}")
    if motion.path is None:
        print("  limits        none needed: the plan is the empty motion (at rest)")
    elif lim.any:
        print(f"  limits        {lim.describe()}: the shortest feasible duration with timing {timing} is "
              f"{round_up(motion.minimum_duration):.6g} s")
    else:
        print("  limits        none in the robot file (add max_rotor_rate [rad/s] and max_rotor_torque [N m] "
              "to keep the motors within them)")
    rate, torque = abs(motion.rotor_rates).max(), abs(motion.rotor_torques).max()
    use_rate = f" ({rate / lim.max_rotor_rate:.1%} of the limit)" if lim.max_rotor_rate is not None else ""
    use_torque = f" ({torque / lim.max_rotor_torque:.1%} of the limit)" if lim.max_rotor_torque is not None else ""
    print(f"  rotors        max |rate| = {rate:.4g} rad/s{use_rate}   max |torque| = {torque:.4g} N m{use_torque}")
    print(f"  rotor-only    arrival error {sim.arrival_error:.2e} (position {sim.position_error:.2e} R; "
          "spline through the rotor rates, (11) and (6)-(10) by CVODES)")
    extra = motion_to_dict(motion)
    extra["rotor_simulation"] = {"arrival_error": sim.arrival_error, "position_error": sim.position_error,
                                 "final": [float(v) for v in sim.final]}
    return motion, extra


def cmd_step(args) -> int:
    if args.json is not None:
        check_writable(args.json)
    r = geometric.step(args.a, args.b, k=args.k, gamma=args.gamma)
    u, v = r.shift
    # final psi of one step equals eta
    print(f"rollplan step: a = {r.a:g} R, b = {r.b:g} R, k = {r.k:g}, gamma = {r.gamma:g} rad")
    print(f"  h = {r.h:.12g} R   eta = {r.eta:.12g} rad   direction = {r.direction:.12g} rad")
    print(f"  final u_a = {u:.12g} R   v_a = {v:.12g} R   psi = {r.eta:.12g} rad")
    if args.json:
        write_json(args.json, {"a": r.a, "b": r.b, "k": r.k, "gamma": r.gamma, "h": r.h, "eta": r.eta,
                               "direction": r.direction, "final": {"u_a": float(u), "v_a": float(v), "psi": r.eta}})
        print(f"wrote {args.json}")
    return EXIT_OK


class _Progress:
    """``progress(label, done, total)`` drawn as one tqdm bar per label on stderr."""

    def __init__(self) -> None:
        from tqdm import tqdm

        self._tqdm = tqdm
        self._bars: dict = {}

    def __call__(self, label: str, done: int, total: int) -> None:
        bar = self._bars.get(label)
        if bar is None:
            bar = self._bars[label] = self._tqdm(total=total, desc=label, file=sys.stderr)
        bar.total = total
        bar.update(done - bar.n)

    def close(self) -> None:
        for bar in self._bars.values():
            bar.close()
        self._bars.clear()


def cmd_reproduce(args) -> int:
    import time

    from .studies.paper import reproduce

    t0 = time.perf_counter()
    progress = _Progress()
    print(f"rollplan reproduce: Section III.C of the paper into {args.out}", file=sys.stderr)
    try:
        result = reproduce(args.out, progress=progress)
    finally:
        progress.close()
    width = max(len(r.quantity) for r in result.rows)
    for r in result.rows:
        print(f"  {r.quantity:<{width}}  paper {r.paper:<11.9g} computed {r.computed:<16.12g} {r.status}")
    n_ok = sum(r.status == "reproduced" for r in result.rows)
    print(f"{n_ok} of {len(result.rows)} reproduced, {len(result.rows) - n_ok} discrepancies "
          f"(evidence in {args.out}/REPRODUCTION.md); {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def cmd_simulate(args) -> int:
    from .execution.plants import simulate_rotors
    from .io import load_rotor_plan

    if args.json is not None:
        check_writable(args.json)
    rp = load_rotor_plan(args.plan_file)
    robot = load_robot(args.robot) if args.robot else rp.robot
    sim = simulate_rotors(robot, rp.time, rp.rotor_rates, rp.goal, x0=rp.start.array())
    e = sim.error
    f, g = sim.final, rp.goal
    print(f"rollplan simulate: {rp.time.size} samples over {rp.time[-1] - rp.time[0]:g} s, robot k = {robot.k:.9g}"
          f"{' (planned k = %.9g)' % rp.robot.k if args.robot else ''}")
    print(f"  final         u_a = {f[0]:.12g} m  v_a = {f[1]:.12g} m  psi = {f[2]:.12g} rad"
          f"  u_o = {f[3]:.3g}  v_o = {f[4]:.3g}")
    print(f"  target        u_a = {g.u_a:.12g} m  v_a = {g.v_a:.12g} m  psi = {g.psi:.12g} rad")
    print(f"  arrival error {sim.arrival_error:.3e} (position {sim.position_error:.3e} R = "
          f"{sim.position_error * robot.radius:.3e} m, psi {e[2]:.3e} rad, u_o {e[3]:.1e}, v_o {e[4]:.1e})")
    if args.json:
        write_json(args.json, {"final": dict(zip(STATE_NAMES, map(float, sim.final))),
                               "arrival_error": sim.arrival_error, "position_error": sim.position_error,
                               "error": dict(zip(STATE_NAMES, map(float, e))),
                               "robot": robot.as_dict()})
        print(f"wrote {args.json}")
    return EXIT_OK


def cmd_animate(args) -> int:
    from .execution.plants import simulate_rotors
    from .io import load_rotor_plan
    from .plots.animation import make_animation

    check_writable(args.out)
    if not 2 <= args.frames <= 2000:
        raise InputError(f"--frames {args.frames} is not allowed: it must lie in [2, 2000]")
    if not 1 <= args.fps <= 100:
        raise InputError(f"--fps {args.fps} is not allowed: it must lie in [1, 100]")
    rp = load_rotor_plan(args.plan_file)
    sim = simulate_rotors(rp.robot, rp.time, rp.rotor_rates, rp.goal, x0=rp.start.array())
    make_animation(rp.time, sim.state, rp.rotor_rates, rp.robot, rp.goal, args.out, args.frames, args.fps)
    print(f"wrote {args.out}")
    return EXIT_OK


def _fmt_row(name, a, b, fmt):
    return f"  {name:<30s} {format(a, fmt):>20s} {format(b, fmt):>20s}"


def cmd_compare(args) -> int:
    from .studies import comparison

    _check_outputs(json=args.json, figure=args.plot)
    k, robot = _k_or_robot(args)
    c = comparison.compare((args.to[0], args.to[1], args.psi), args.steps, k, robot, args.radius, args.horizon,
                           args.cost, args.intervals, args.degree, args.scheme, args.contact_bound, args.branches)
    p, r, prob = c.plan, c.result, c.problem
    unit = "m" if robot is not None else ("R" if args.radius is None else "units")
    g, tr = prob.goal, r.transcription
    print(f"rollplan compare: k = {prob.k:.9g}, R = {prob.radius:g}, T = {c.horizon:g} s, target (u_a, v_a, psi) = "
          f"({g.u_a:g}, {g.v_a:g}, {g.psi:g}), cost {c.cost}, contact bound {c.contact_bound:.6g} rad, rest to rest")
    print(f"  geometric phase: {prob.steps} figure eight(s), a = {p.a:.6g}, b = {p.b:.6g}, gamma = {p.gamma:.6g}, "
          f"branch {p.branch}, optimal timing ({len(c.branches)} branch(es) timed)")
    wins = sum(s.status == "ok" for s in c.starts)
    print(f"  collocation: contact accelerations, {tr.scheme} d = {tr.degree}, N = {tr.intervals}, best of "
          f"{len(c.starts)} starts ({wins} converged): {r.guess}, psi turns m = {r.turns}")
    print(f"  {'':<32s} {'geometric phase':>20s} {'collocation':>20s}")
    gc, oc = c.gp.costs, c.collocation.costs
    print(_fmt_row(f"contact path length [{unit}]", gc["path_length"], oc["path_length"], ".6g"))
    print(_fmt_row("effort int|omega|^2 dt [rad^2/s]", gc["angular_velocity"], oc["angular_velocity"], ".6g"))
    print(_fmt_row("torque energy int|tau|^2 dt", gc["rotor_energy"], oc["rotor_energy"], ".6g"))
    print(_fmt_row("peak rotor rate [rad/s]", gc["peak_rotor_rate"], oc["peak_rotor_rate"], ".6g"))
    print(_fmt_row("peak rotor torque [N m]", gc["peak_rotor_torque"], oc["peak_rotor_torque"], ".6g"))
    print(_fmt_row("final residual (CVODES)", c.gp.residual, c.collocation.residual, ".2e"))
    print(_fmt_row("solve time [s]", c.gp.solve_time_s, c.collocation.solve_time_s, ".3f"))
    if robot is None:
        print("  (without --robot, torques are those of a robot with this k and J_zz = 1)")
    if args.json:
        write_json(args.json, comparison.comparison_to_dict(c))
        print(f"wrote {args.json}")
    if args.plot:
        from .plots.compare import plot_comparison

        save_figure(plot_comparison(c, unit), args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


def _add_target_options(parser, to_default, steps_help) -> None:
    """--to, --psi, --steps, --k | --robot, --radius: the target and the robot, as in ``plan``."""
    if to_default is None:
        parser.add_argument("--to", nargs=2, type=_number, metavar=("U", "V"), required=True,
                            help="target contact point (u_a, v_a) on the plane")
    else:
        parser.add_argument("--to", nargs=2, type=_number, metavar=("U", "V"), default=to_default,
                            help="target contact point (u_a, v_a) on the plane (default %g %g)" % tuple(to_default))
    parser.add_argument("--psi", type=_number, default=0.0, help="target contact angle [rad] (default 0)")
    parser.add_argument("--steps", type=_whole, default=1, help=steps_help)
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--k", type=_number, default=None, help="inertia ratio k >= 0 (default %g)" % DEFAULT_K)
    g.add_argument("--robot", metavar="FILE.toml", help="robot parameters (k from eq. 14; lengths in metres)")
    parser.add_argument("--radius", type=_number, default=None, help="sphere radius R (default 1, or the robot's)")


def _add_compare_parser(sub) -> None:
    from .planners import collocation
    from .studies.comparison import COMPARED_COSTS, CONTACT_BOUND

    c = sub.add_parser("compare", help="geometric-phase plan versus collocation optimum on one problem, rest to rest")
    _add_target_options(c, to_default=None, steps_help="figure eights n >= 1 of the geometric plan (default 1)")
    c.add_argument("--cost", choices=COMPARED_COSTS, default="angular_velocity",
                   help="the cost compared, minimised by both (default angular_velocity; rotor_energy needs --robot)")
    c.add_argument("--horizon", type=_number, default=1.0, help="time horizon T [s] of both motions (default 1)")
    c.add_argument("--intervals", type=_whole, default=100, help="intervals N of both motions (default 100)")
    c.add_argument("--degree", type=_whole, default=3, help="collocation degree d (default 3)")
    c.add_argument("--scheme", choices=collocation.SCHEMES, default="legendre", help="collocation points")
    c.add_argument("--branches", type=_whole, default=2,
                   help="geometric-phase branches timed and used as warm starts (default 2)")
    c.add_argument("--contact-bound", type=_number, default=CONTACT_BOUND, metavar="RAD",
                   help="both planners: largest polar angle of the contact point from the south pole "
                        "(default %.4g rad = 80 deg)" % CONTACT_BOUND)
    c.add_argument("--json", metavar="FILE", help="write both results as JSON")
    c.add_argument("--plot", metavar="FILE.png", help="both contact paths and their omega, rotor rates, torques")
    c.set_defaults(func=cmd_compare)


def cmd_codegen(args) -> int:
    from . import codegen

    g = codegen.generate(args.out, args.steps_per_leaf, args.prefix)
    print(f"rollplan codegen: wrote {len(g.files)} files to {g.out} (prefix {g.prefix!r}, "
          f"{g.steps_per_leaf} steps per leaf)")
    print(f"  C code      {g.code_bytes} bytes ({g.model_bytes} generated by CasADi)")
    print(f"  work memory {g.work_doubles} doubles (static)")
    print(f"  build       make -C {g.out}   then   {g.out}/plan_demo U V PSI STEPS K")
    return EXIT_OK


def cmd_batch(args) -> int:
    import os

    from .studies.batch import run_batch

    try:
        jobs = args.jobs if args.jobs is not None else (os.cpu_count() or 1)
        r = run_batch(args.targets, args.out, jobs, args.resume, args.overwrite, args.method,
                      progress=not args.quiet)
    except KeyboardInterrupt:
        print(f"\nrollplan: interrupted; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return 130
    print(f"rollplan batch: {r.total} targets, {r.skipped} already done, {r.planned} planned "
          f"({r.failed} failed) in {r.time_s:.1f} s; wrote {args.out}")
    return EXIT_OK


def cmd_atlas(args) -> int:
    from .plots.atlas import plot_atlas
    from .studies.atlas import atlas_to_dict, compute_atlas

    _check_outputs(json=args.json, figure=args.out)
    at = compute_atlas(args.k, args.steps, args.resolution)
    save_figure(plot_atlas(at), args.out)
    print(f"rollplan atlas: k = {at.k:g}, steps = {at.steps}, {at.a.size} x {at.b.size} grid on (0, {at.a[-1]:g}]^2")
    print(f"  shift per step h in [{at.h.min():.6g}, {at.h.max():.6g}] R, holonomy eta in "
          f"[{at.eta.min():.6g}, {at.eta.max():.6g}] rad, {at.fold_cells} grid cells on the fold det = 0")
    print(f"wrote {args.out}")
    if args.json:
        write_json(args.json, atlas_to_dict(at))
        print(f"wrote {args.json}")
    return EXIT_OK


def _add_timing_options(parser) -> None:
    """--duration, --timing, --samples and --timing-plot of ``plan`` and ``route``."""
    from .execution.timing import LAWS

    parser.add_argument("--duration", type=_number, default=None, metavar="T",
                        help="time the motion over T seconds (by default rest-to-rest per piece: leaf, roll; "
                             "--timing min-jerk) and compute the rotor rates, angles and torques (uses the default "
                             "robot unless --robot is given); refused if it would exceed the robot's "
                             "max_rotor_rate or max_rotor_torque")
    parser.add_argument("--timing", choices=list(LAWS), default=None, metavar="NAME",
                        help="timing law: " + "; ".join(f"{n}: {law.summary}" for n, law in LAWS.items())
                             + ". Every law rests at the corners of the contact path (where a roll meets the figure "
                               "eights). Without --duration: the law's shortest duration within the robot's limits")
    parser.add_argument("--samples", type=_whole, default=2000,
                        help="samples of the trajectory in --json and --plot, in all (default 2000); with "
                             "--duration or --timing also the least number of time samples (at least 400 per "
                             "piece for min-jerk, 3000 for the other laws)")
    parser.add_argument("--timing-plot", metavar="FILE.png",
                        help="with --duration or --timing: rotor rates and torques in time with the robot's limits, "
                             "and the phase plane (s, s') with the maximum velocity curve")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rollplan", description=__doc__)
    parser.add_argument("-v", "--verbose", action="store_true", help="log the planner's progress")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    p = sub.add_parser("plan", help="plan a motion between two states by figure eights (and rolls, turns, legs)")
    _add_target_options(p, to_default=(0.0, 1.0), steps_help="number of figure eights n >= 1 per leg (default 1)")
    p.add_argument("--from", dest="start", nargs=5, type=_number, default=(0.0,) * 5,
                   metavar=("U_A", "V_A", "PSI", "U_O", "V_O"),
                   help="start state (default 0 0 0 0 0: at rest at the origin, contact at the south pole); "
                        "off the pole psi is the contact angle of (2), not a yaw")
    p.add_argument("--contact", nargs=2, type=_number, default=(0.0, 0.0), metavar=("U_O", "V_O"),
                   help="goal contact point on the sphere [rad] (default 0 0, the south pole); "
                        "cos(u_o) cos(v_o) >= 0.05")
    p.add_argument("--legs", choices=geometric.LEGS, default="fallback",
                   help="figure eights: one leg, with a turn in place or two legs only where one leg has no plan "
                        "(fallback, default); also search two legs and keep the shorter (shortest); one; two")
    p.add_argument("--all", action="store_true", help="also list every other verified solution branch (one leg)")
    p.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    p.add_argument("--json", metavar="FILE", help="write the plan as JSON")
    p.add_argument("--plot", metavar="FILE.png", help="draw the contact path on the sphere and the plane "
                   "(with --duration: omega, rotor rates and torques in time)")
    _add_timing_options(p)
    p.set_defaults(func=cmd_plan)

    w = sub.add_parser("route", help="plan a route through waypoints (a CSV file), leg by leg, certified as one")
    w.add_argument("waypoints", metavar="WAYPOINTS.csv",
                   help="header u_a,v_a,psi[,u_o,v_o][,steps][,label]; one waypoint a row, the first is the start")
    w.add_argument("--steps", type=_whole, default=1, help="figure eights per leg where a row does not say (default 1)")
    g = w.add_mutually_exclusive_group()
    g.add_argument("--k", type=_number, default=None, help="inertia ratio k >= 0 (default %g)" % DEFAULT_K)
    g.add_argument("--robot", metavar="FILE.toml", help="robot parameters (k from eq. 14; lengths in metres)")
    w.add_argument("--radius", type=_number, default=None, help="sphere radius R (default 1, or the robot's)")
    w.add_argument("--legs", choices=geometric.LEGS, default="fallback", help="as for plan (default fallback)")
    w.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    w.add_argument("--json", metavar="FILE", help="write the route as JSON")
    w.add_argument("--plot", metavar="FILE.png", help="draw the route's contact path")
    _add_timing_options(w)
    w.set_defaults(func=cmd_route)

    s = sub.add_parser("step", help="what one figure eight does: shift h and holonomy eta")
    s.add_argument("--a", type=_number, required=True, help="first leaf radius [R], 0 < a <= %g" % A_MAX)
    s.add_argument("--b", type=_number, default=None, help="second leaf radius [R] (default a)")
    s.add_argument("--k", type=_number, required=True, help="inertia ratio k >= 0")
    s.add_argument("--gamma", type=_number, default=0.0, help="rotation about OZ [rad] (default 0)")
    s.add_argument("--json", metavar="FILE", help="write the result as JSON")
    s.set_defaults(func=cmd_step)

    r = sub.add_parser("reproduce", help="regenerate the paper's case study (Figs 6-12, table, report)")
    r.add_argument("--out", required=True, metavar="DIR",
                   help="folder for fig06.png..fig12.png, reproduction.json, REPRODUCTION.md (created if missing)")
    r.set_defaults(func=cmd_reproduce)

    m = sub.add_parser("simulate", help="drive the robot by the plan's rotor rates alone and report the arrival error")
    m.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    m.add_argument("--robot", metavar="FILE.toml", help="simulate this (real) robot instead of the planned one")
    m.add_argument("--json", metavar="FILE", help="write the simulated final state and errors as JSON")
    m.set_defaults(func=cmd_simulate)

    a = sub.add_parser("animate", help="animate the sphere rolling under the plan's rotor rates (GIF)")
    a.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    a.add_argument("--out", metavar="FILE.gif", required=True, help="output animation (GIF)")
    a.add_argument("--frames", type=_whole, default=100, help="number of frames (default 100)")
    a.add_argument("--fps", type=_whole, default=20, help="frames per second (default 20)")
    a.set_defaults(func=cmd_animate)

    _add_compare_parser(sub)

    c = sub.add_parser("codegen", help="write a self-contained C99 planner (CasADi code generation)")
    c.add_argument("--out", required=True, metavar="DIR", help="output folder (created if missing)")
    c.add_argument("--steps-per-leaf", type=_whole, default=200,
                   help="node intervals per leaf of the step map, a multiple of 10 (default 200)")
    c.add_argument("--prefix", default="rollplan", help="prefix of the C symbols and files (default rollplan)")
    c.set_defaults(func=cmd_codegen)

    b = sub.add_parser("batch", help="plan every target of a CSV file (u_a, v_a, psi, steps, k) in parallel")
    b.add_argument("targets", metavar="TARGETS.csv", help="CSV with header u_a, v_a, psi, steps, k")
    b.add_argument("--out", required=True, metavar="PLANS.jsonl", help="output: one JSON line per target")
    b.add_argument("--jobs", type=_whole, default=None, help="worker processes (default: number of cores)")
    b.add_argument("--resume", action="store_true", help="keep the lines in --out and plan only the missing rows")
    b.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    b.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    b.add_argument("--quiet", action="store_true", help="no progress bar on stderr")
    b.set_defaults(func=cmd_batch)

    t = sub.add_parser("atlas", help="maps of h(a, b) and eta(a, b) with contours and the fold of the step map")
    t.add_argument("--k", type=_number, required=True, help="inertia ratio k >= 0")
    t.add_argument("--steps", type=_whole, default=1, help="also map what n figure eights reach (default 1)")
    t.add_argument("--resolution", type=_whole, default=81, help="grid points per axis (default 81)")
    t.add_argument("--out", required=True, metavar="FILE.png", help="figure")
    t.add_argument("--json", metavar="FILE", help="write the maps as JSON")
    t.set_defaults(func=cmd_atlas)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.ERROR, format="%(name)s: %(message)s")
    if (getattr(args, "command", None) in ("plan", "compare", "route") and args.k is None and args.robot is None
            and getattr(args, "duration", None) is None and getattr(args, "timing", None) is None):
        args.k = DEFAULT_K
    try:
        return args.func(args)
    except InputError as exc:
        print(f"rollplan: error: {exc}", file=sys.stderr)
        return EXIT_INPUT
    except NoPlanError as exc:
        print(f"rollplan: no plan: {exc}", file=sys.stderr)
        return EXIT_NOPLAN
    except SolverError as exc:
        print(f"rollplan: solver failed ({exc.status}): {exc}", file=sys.stderr)
        return EXIT_SOLVER
    except KeyboardInterrupt:
        print("\nrollplan: interrupted", file=sys.stderr)
        return 130
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
