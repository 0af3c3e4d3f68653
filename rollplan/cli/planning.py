"""What ``plan`` and ``route`` share: checks before any work, progress stages, the timed motion and the outputs."""

from __future__ import annotations

from ..errors import InputError, check_whole
from ..io import save_figure
from ..planners.geometric import Plan, as_composed
from ..problem import check_steps
from ..progress import report
from ..robot import default_robot
from .arguments import number, whole
from .common import NORM, check_outputs, emit_json, k_or_robot
from .format import num

__all__ = ["add_timing_options", "is_timed", "check_timing_outputs", "most_pieces", "check_samples", "plan_inputs",
           "stage", "write_results"]


def add_timing_options(parser) -> None:
    """--duration, --timing, --samples and --timing-plot of ``plan`` and ``route``."""
    from ..execution.actuation import MAX_SAMPLES
    from ..execution.timing import LAWS

    parser.add_argument("--duration", type=number, default=None, metavar="T",
                        help="time the motion over T seconds (by default rest-to-rest per piece: leaf, roll; "
                             "--timing min-jerk) and compute the rotor rates, angles and torques (uses the default "
                             "robot unless --robot is given); refused if it would exceed the robot's "
                             "max_rotor_rate or max_rotor_torque")
    parser.add_argument("--timing", choices=list(LAWS), default=None, metavar="NAME",
                        help="timing law: " + "; ".join(f"{n}: {law.summary}" for n, law in LAWS.items())
                             + ". Every law rests at the corners of the contact path (where a roll meets the figure "
                               "eights). Without --duration: the law's shortest duration within the robot's limits")
    parser.add_argument("--samples", type=whole, default=None,
                        help=f"samples of the trajectory in --json and --plot, in all, in [2, {MAX_SAMPLES}], "
                             "more than the pieces the motion may have (4 n + 2 for n figure eights per leg, a "
                             "route the sum over its legs); default 2000, or that + 1 when more; with --duration "
                             "or --timing also the least number of time samples (at "
                             "least 400 per piece for min-jerk, 3000 for the other laws)")
    parser.add_argument("--timing-plot", metavar="FILE.png",
                        help="with --duration or --timing: rotor rates and torques in time with the robot's limits, "
                             "and the phase plane (s, s') with the maximum velocity curve")


def is_timed(args) -> bool:
    return args.duration is not None or args.timing is not None


def check_timing_outputs(args, inputs=()) -> None:
    """--timing-plot of ``plan`` and ``route``: a figure path, and a timed motion to draw."""
    if args.timing_plot is not None:
        check_outputs(figure=args.timing_plot, inputs=inputs)
        if not is_timed(args):
            raise InputError("--timing-plot needs a timed motion: give --duration T or --timing NAME")


def _robot_for_duration(args, k, robot):
    """The robot of ``--duration`` / ``--timing`` (the default robot unless --robot is given), with the timing
    law's needs (limits, duration) checked before planning."""
    if not is_timed(args):
        return robot
    if robot is None:
        if k is not None:
            raise InputError("--duration and --timing need the robot's inertias, not only k: give --robot FILE "
                             "(or drop --k to use the default robot)")
        robot = default = default_robot()
    else:
        default = None
    from ..execution.limits import Limits
    from ..execution.timing import get_law

    get_law(args.timing or "min-jerk").check(Limits.of(robot), args.duration)
    if default is not None:
        print("rollplan: no --robot given: using the default robot (rollplan/data/default_robot.toml); "
              "lengths in m")
    return robot


def most_pieces(legs: str, steps: int) -> int:
    """The most pieces of a plan of ``steps`` figure eights per leg: two legs of two leaves per figure eight
    (one leg with ``--legs one``), and the rolls to and from the pole."""
    return (2 if legs == "one" else 4) * steps + 2


def check_samples(args, pieces: int) -> None:
    """``--samples`` before any work: within [2, MAX_SAMPLES] and, with --json or --plot (the path sampled at
    the end of each piece), more than the ``pieces`` the plan may have; by default 2000, or pieces + 1."""
    from ..execution.actuation import DEFAULT_SAMPLES, MAX_SAMPLES

    sampled = bool(args.json or args.plot)
    if args.samples is None:
        args.samples = max(DEFAULT_SAMPLES, pieces + 1) if sampled else DEFAULT_SAMPLES
        if args.samples > MAX_SAMPLES:
            raise InputError(f"--json and --plot sample the end of each of the up to {pieces} pieces of this "
                             f"motion: more than the {MAX_SAMPLES} samples allowed; plan fewer steps or legs")
        return
    check_whole("samples", args.samples, 2, MAX_SAMPLES)
    if sampled and args.samples < pieces + 1:
        raise InputError(f"--samples {args.samples} is not allowed with --steps {args.steps}: the motion may have "
                         f"up to {pieces} pieces (figure-eight leaves and rolls), and --json and --plot sample the "
                         f"end of each: give --samples >= {pieces + 1}, or leave it out")


def plan_inputs(args, inputs=(), samples=True):
    """The checks of ``plan`` and ``route`` before any work: outputs (never one of ``inputs`` or the robot
    file), steps, samples (those of a plan; ``route`` checks them once it knows its legs), the robot and the
    timing law's needs; returns ``(k, robot)``."""
    inputs = [*inputs, args.robot]
    check_outputs(json=args.json, figure=args.plot, inputs=inputs)
    check_timing_outputs(args, inputs)
    check_steps(args.steps)
    if samples:
        based = 2 * (args.steps + 1) + 2 if getattr(args, "base", "pole") == "any" else 0   # rolls, steps + 1 eights
        check_samples(args, max(most_pieces(args.legs, args.steps), based))
    k, robot = k_or_robot(args)
    return k, _robot_for_duration(args, k, robot)


def stage(args, command: str, name: str) -> None:
    """Report the stage ``name`` of ``plan`` or ``route`` as progress (so long work is never silent)."""
    stages = ["planning"] + ["timing"] * is_timed(args) + ["sampling"] * bool(args.json or args.plot) + \
        ["writing JSON"] * bool(args.json) + ["drawing"] * bool(args.plot or args.timing_plot) + ["done"]
    report(command, stages.index(name), len(stages) - 1, stage=name)


def write_results(args, p, robot, unit, to_dict, command) -> None:
    """--duration/--timing, --json, --plot and --timing-plot of ``plan`` and ``route``: ``args.samples``
    trajectory samples in all; each stage reported as progress."""
    if is_timed(args):
        stage(args, command, "timing")
    motion, extra = _timed(args, p, robot) if is_timed(args) else (None, {})
    if args.json or args.plot:
        stage(args, command, "sampling")
    traj = as_composed(p).sample(args.samples) if (args.json or args.plot) else None
    if args.json:
        stage(args, command, "writing JSON")
        emit_json(args, {**to_dict(p, traj), **extra}, unit)
    if args.plot or args.timing_plot:
        stage(args, command, "drawing")
    if args.plot and motion is not None:
        from ..plots.motion import plot_motion

        save_figure(plot_motion(motion, p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot and isinstance(p, Plan):
        from ..plots.plan import plot_plan

        save_figure(plot_plan(p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot:
        from ..plots.composed import plot_composed

        save_figure(plot_composed(p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    if args.timing_plot:
        from ..execution.timing import velocity_limit
        from ..plots.timing import plot_timing

        moving = motion.path is not None and motion.limits.any
        limit = velocity_limit(motion.path, motion.limits, motion.profile) if moving else None
        save_figure(plot_timing(motion, limit), args.timing_plot)
        print(f"wrote {args.timing_plot}")


def _timed(args, p, robot):
    """``--duration`` / ``--timing``: rotor rates, angles and torques, checked by the rotor-only simulation
    from the plan's start state."""
    from ..execution.actuation import actuate, certify_motion
    from ..execution.timing import round_up
    from ..io import motion_to_dict

    timing = args.timing or "min-jerk"
    motion = actuate(p, robot, args.duration, args.samples, timing)
    sim = certify_motion(motion)
    lim = motion.limits
    shortest = motion.minimum_duration
    at_shortest = shortest is not None and motion.duration == shortest
    print(f"  motion        T = {num(motion.duration)} s{' (the shortest feasible)' if at_shortest else ''}, "
          f"{motion.series.time.size} samples, timing {timing}"
          f"{' (rest-to-rest per piece: leaf, roll)' if timing == 'min-jerk' else ''}")
    if motion.path is None:
        print("  limits        none needed: the plan is the empty motion (at rest)")
    elif lim.any:   # the shortest rounded up to 6 digits is the least printed value --duration accepts
        print(f"  limits        {lim.describe()}: the shortest feasible duration with timing {timing} is "
              f"{num(shortest)} s (as --duration: {num(round_up(shortest))} s or more)")
    else:
        print("  limits        none in the robot file (add max_rotor_rate [rad/s] and max_rotor_torque [N m] "
              "to keep the motors within them)")
    rate, torque = abs(motion.series.rotor_rates).max(), abs(motion.series.rotor_torques).max()
    use_rate = f" ({rate / lim.max_rotor_rate:.1%} of the limit)" if lim.max_rotor_rate is not None else ""
    use_torque = f" ({torque / lim.max_rotor_torque:.1%} of the limit)" if lim.max_rotor_torque is not None else ""
    print(f"  rotors        max |rate| = {num(rate)} rad/s{use_rate}   max |torque| = {num(torque)} N m{use_torque}")
    print(f"  rotor-only    arrival error {sim.arrival_error:.2e} ({NORM}), position error "
          f"{sim.position_error * robot.radius:.2e} m (spline through the rotor rates, (11) and (6)-(10) by CVODES)")
    if not args.json:   # the JSON's lists of samples only for --json
        return motion, {}
    extra = motion_to_dict(motion)
    extra["rotor_simulation"] = {"arrival_error": sim.arrival_error, "position_error": sim.position_error,
                                 "final": [float(v) for v in sim.final]}
    return motion, extra
