"""The rollplan command: exact motion planning for a spherical robot driven by two internal rotors.

Exit codes: 0 success, 2 bad input, 3 no plan, 4 solver failure, 130 interrupted (Ctrl-C), 143 terminated
(SIGTERM, stopped as for Ctrl-C); batch: 1 when some rows failed, 3 when every row failed. `--json -` writes
the JSON document to stdout and the summary to stderr.
Lengths are printed in the unit in use (R, or m with --robot or --radius), summaries with 6
significant digits (JSON files in full precision); long work shows its progress on stderr.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import logging
import os
import re
import sys
from contextlib import ExitStack
from dataclasses import replace

from . import (
    interrupts,
    threads,  # noqa: F401  (before anything that loads numpy: one BLAS thread per process)
)
from .core.curves import A_MAX
from .errors import (
    SHOW_WIDTH,
    InputError,
    NoPlanError,
    SolverError,
    check_finite,
    check_whole,
    show,
    show_limit,
)
from .inputs import parse_number, parse_whole, show_path
from .io import check_figure_path, check_writable, composed_to_dict, route_to_dict, save_figure, tagged, write_json
from .outputs import WRITE_FAILURES, claim, make_folder, write_all
from .planners import geometric
from .planners.geometric import as_composed
from .problem import DEFAULT_K, K_MAX, MAX_STEPS, STATE_NAMES, State, check_contact, check_reach, check_steps
from .progress import Progress, report, reporting
from .robot import ROBOT_KEYS, default_robot, load_robot
from .version import __version__
from .waypoints import read_waypoints

#: The limits of ``--radius``: those of a robot file's radius.
_RADIUS = next(key for key in ROBOT_KEYS if key.name == "radius")
EXIT_OK, EXIT_SOME_FAILED, EXIT_INPUT, EXIT_NOPLAN, EXIT_SOLVER, EXIT_INTERRUPTED = 0, 1, 2, 3, 4, 130
EXIT_TERMINATED = 143   # SIGTERM: stopped as for Ctrl-C (128 + 15, the shell's status of a terminated command)
#: What a residual is (printed next to every residual and arrival error).
NORM = "Euclidean norm; lengths in R, angles in rad"
#: Numbers as argparse should see them: also in exponent form (-1e-3) and -inf/-nan (refused later by the
#: number check, with a clear message, instead of being taken for an option).
_NEGATIVE_NUMBER = re.compile(r"^-([0-9]+\.?[0-9]*|\.[0-9]+)([eE][-+]?[0-9]+)?$|^-(inf|infinity|nan)$", re.IGNORECASE)


#: A value argparse echoes in a message, quoted or not, longer than a message shows (:func:`rollplan.errors.show`).
_QUOTED_LONG = re.compile(r"'([^'\s]{%d,})'" % SHOW_WIDTH)
_BARE_LONG = re.compile(r"(?<![\S])[^\s']{%d,}" % (SHOW_WIDTH + 1))


class _Parser(argparse.ArgumentParser):
    """argparse that takes negative numbers in any form and reports bad input in one line with exit code 2.

    ``builder(parser)``, if given, adds the arguments when the parser is first used (a command whose options
    need heavy modules loads them only when it runs or shows its help).
    """

    def __init__(self, *args, builder=None, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self._negative_number_matcher = _NEGATIVE_NUMBER
        self._builder = builder

    def _build(self) -> None:
        if self._builder is not None:
            build, self._builder = self._builder, None
            build(self)

    def parse_known_args(self, args=None, namespace=None):
        self._build()
        return super().parse_known_args(args, namespace)

    def format_help(self):
        self._build()
        return super().format_help()

    def format_usage(self):
        self._build()
        return super().format_usage()

    def error(self, message):
        message = _QUOTED_LONG.sub(lambda m: show(m.group(1)), message)   # argparse echoes values in full
        message = _BARE_LONG.sub(lambda m: m.group(0)[:SHOW_WIDTH - 3] + "...", message)
        self.exit(EXIT_INPUT, f"{self.prog}: error: {message} (see: {self.prog} --help)\n")


def _number(text: str) -> float:
    try:
        return parse_number(text, "value")
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value = ")) from None


def _radius(text: str) -> float:
    """``--radius``: a number within the limits of a robot file's ``radius`` (:data:`rollplan.robot.ROBOT_KEYS`)."""
    try:
        return parse_number(text, "radius", _RADIUS.low, _RADIUS.high)
    except InputError as exc:
        raise argparse.ArgumentTypeError(f"{exc} {_RADIUS.unit}") from None


def _whole(text: str) -> int:
    try:
        return parse_whole(text, "value")
    except InputError as exc:
        raise argparse.ArgumentTypeError(str(exc).removeprefix("value = ")) from None


def _steps_per_leaf(text: str):
    """``--steps-per-leaf``: ``auto`` or a whole number."""
    if text.strip() == "auto":
        return "auto"
    try:
        return parse_whole(text, "value")
    except InputError:
        raise argparse.ArgumentTypeError(f"{text[:40]!r} is not allowed: it must be auto or a whole number (a multiple "
                                         "of 10 in [20, 2000])") from None


class _Claims:
    """The outputs the running command holds (:func:`rollplan.outputs.claim`), released when it ends."""

    stack: ExitStack | None = None
    files: dict = {}   # real path of each output of the running command -> the name given


def _check_outputs(json=None, figure=None, inputs=()) -> None:
    """Refuse unwritable output paths, unknown figure formats, outputs that are inputs and two outputs that are
    one file before any computation, and hold the outputs (a second process writing one of them is refused)."""
    if json == "-":   # stdout: no file to check, compare or hold
        json = None
    if json is not None:
        check_writable(json, inputs=inputs)
    if figure is not None:
        check_figure_path(figure)
        check_writable(figure, "figure", inputs=inputs)
    for name in (json, figure):
        if name is None:
            continue
        real = os.path.realpath(name)
        if real in _Claims.files:
            raise InputError(f"output {show_path(name)} is the same file as output "
                             f"{show_path(_Claims.files[real])}: give each output its own name")
        _Claims.files[real] = name
    if _Claims.stack is not None:
        _Claims.stack.enter_context(claim(json, figure))


def _emit_json(args, obj, unit: str) -> None:
    """Write ``obj`` (with ``version`` and ``units``) to ``--json FILE``, or to stdout for ``--json -``."""
    doc = tagged(obj, unit)
    if args.json == "-":
        text = json.dumps(doc, indent=1, allow_nan=False) + "\n"
        args.stdout.flush()
        try:
            fd = args.stdout.fileno()
        except (AttributeError, OSError, ValueError):   # a stream without a file descriptor (captured)
            args.stdout.write(text)
            args.stdout.flush()
        else:   # not through the stream: Python's buffered writer drops the rest of a short write into a pipe
            write_all(fd, text.encode())
    else:
        write_json(args.json, doc)
        print(f"wrote {args.json}")


def _g(x) -> str:
    """A number in a summary: 6 significant digits."""
    return f"{x:.6g}"


def _k_or_robot(args):
    """(k, robot) from --k / --robot."""
    if args.robot is not None:
        return None, load_robot(args.robot)
    return args.k, None


def _fmt_plan(p, unit) -> str:
    f = p.final
    lines = [
        f"  figure eight  a = {_g(p.a)} {unit}   b = {_g(p.b)} {unit}   gamma = {_g(p.gamma)} rad"
        f"   (branch m = {p.branch})",
        f"  one step      h = {_g(p.h)} {unit}   eta = {_g(p.eta)} rad",
        f"  path length   {_g(p.path_length)} {unit}",
        f"  final         u_a = {_g(f.u_a)} {unit}  v_a = {_g(f.v_a)} {unit}  psi = {_fmt_psi(f.psi)}"
        f"  u_o = {f.u_o:.3g} rad  v_o = {f.v_o:.3g} rad",
        f"  residual      {p.residual:.2e} ({NORM}; {p.certificate.method}, independent of the planner"
        f"{f', integration error bound {p.certificate.error_bound:.1e}' if p.certificate.error_bound else ''})",
    ]
    return "\n".join(lines)


def _fmt_all(p, unit) -> str:
    """``--all``: one line per plan (the figure eights of one leg), shortest first, and the count."""
    plans = [p] + list(p.alternatives)
    lines = [f"all plans: {len(plans)} (shortest first; a, b [{unit}], gamma [rad], L = contact path [{unit}])",
             f"  {'m':>6} {'a':>12} {'b':>12} {'gamma':>12} {'L':>12} {'residual':>9}"]
    for q in plans:
        e = q.legs[0] if getattr(q, "legs", None) else q
        if not hasattr(e, "branch"):
            lines.append(f"  {'-':>6} {'-':>12} {'-':>12} {'-':>12} {q.path_length:>12.6f} {q.residual:>9.1e}")
            continue
        lines.append(f"  {e.branch:>6d} {e.a:>12.9f} {e.b:>12.9f} {e.gamma:>12.9f} {q.path_length:>12.6f} "
                     f"{q.residual:>9.1e}")
    return "\n".join(lines)


def _fmt_state(x, unit, wrapped=False) -> str:
    """A state (u_a, v_a, psi, u_o, v_o) with its units: lengths in ``unit``, angles in rad; with ``wrapped``
    psi wrapped (:func:`_fmt_psi`), as a final state is printed."""
    units = (unit, unit, "rad", "rad", "rad")
    parts = [f"{_g(float(v))} {u}" for v, u in zip(x, units)]
    if wrapped:
        parts[2] = _fmt_psi(x[2])
    return "(" + ", ".join(parts) + ")"


def _fmt_psi(psi) -> str:
    """A reached psi wrapped to [-pi, pi], with the whole turns taken off (if any)."""
    from .core.plane import wrap_exact

    w, turns = wrap_exact(float(psi))
    return f"{_g(w)} rad" + (f" (wrapped; unwrapped {_g(float(psi))} rad, {turns:+d} turn{'s' * (abs(turns) != 1)})"
                             if turns else "")


def _fmt_solver(stats) -> str:
    """How the plan was found, in words (the JSON keeps the solver's own status and iteration count)."""
    d, n = stats.details, stats.iterations
    if stats.method == "none":
        return "none needed: the rolls alone, in closed form"
    if stats.method == "brentq":
        return f"circles of the turn by a scalar root (brentq); {stats.time_s * 1e3:.1f} ms"
    parts = []
    if "branches" in d:
        parts.append(f"exact search of (32)-(33): {d['branches']} branch(es) searched, {d['roots']} root(s) "
                     "certified or rejected")
    elif "candidates" in d:
        parts.append(f"{d['candidates']} brackets, {d['solves']} solves")
    polished = "0 iterations (already at the root)" if n == 0 else f"{n} iteration(s)"
    ok = stats.status in ("Solve_Succeeded", "success", "ok")
    parts.append(f"root polished by {stats.method}: {polished}{'' if ok else f' ({stats.status})'}")
    return "; ".join(parts) + f"; {stats.time_s * 1e3:.1f} ms"


def _fmt_composed(p, unit) -> str:
    """The lines of a composed plan (rollplan.planners.geometric.composed.ComposedPlan)."""
    R = p.radius
    what = {"empty": "the start is the goal: no motion", "rolls": "the approach and departure rolls alone",
            "one": "one leg of figure eights", "turn": "turn in place by pairs of equal circles",
            "two": "two legs of figure eights through an intermediate pole state"}[p.mode]
    lines = [f"  mode          {p.mode}: {what}"]
    if p.approach is not None:
        lines.append(f"  approach      roll of {_g(p.approach.sigma * R)} {unit} to the pole along the great circle "
                     f"(direction beta = {_g(p.approach.beta)} rad)")
    if p.legs or p.turn is not None:
        t = p.target
        lines.append(f"  eights do     (u_a, v_a, psi) = ({_g(t[0] * R)} {unit}, {_g(t[1] * R)} {unit}, "
                     f"{_g(t[2])} rad) from rest at the pole")
    for i, leg in enumerate(p.legs, 1):
        s = R / leg.radius
        lines.append(f"  leg {i}         {leg.steps} x figure eight a = {_g(leg.a * s)} {unit}   b = {_g(leg.b * s)} "
                     f"{unit}   gamma = {_g(leg.gamma)} rad   (branch m = {leg.branch})")
    if p.turn is not None:
        tr = p.turn
        lines.append(f"  turn          {tr.steps} pair(s) of circles b = {_g(tr.b * R)} {unit} "
                     f"({'+y' if tr.side == 0 else '-y'} side), eta = {_g(tr.eta)} rad each")
    if p.departure is not None:
        lines.append(f"  departure     roll of {_g(p.departure.sigma * R)} {unit} from the pole along the great "
                     f"circle (direction beta = {_g(p.departure.beta)} rad)")
    lines += [f"  path length   {_g(p.path_length)} {unit} in {len(p.pieces)} pieces",
              f"  final         {_fmt_state(p.final, unit, wrapped=True)}",
              f"  residual      {p.residual:.2e} ({NORM}; {p.certificate.method}, the whole motion from the start "
              "state)"]
    return "\n".join(lines)


def _is_timed(args) -> bool:
    return args.duration is not None or args.timing is not None


def _check_timing_outputs(args, inputs=()) -> None:
    """--timing-plot of ``plan`` and ``route``: a figure path, and a timed motion to draw."""
    if args.timing_plot is not None:
        _check_outputs(figure=args.timing_plot, inputs=inputs)
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
        robot = default = default_robot()
    else:
        default = None
    from .execution.limits import Limits
    from .execution.timing import get_law

    get_law(args.timing or "min-jerk").check(Limits.of(robot), args.duration)
    if default is not None:
        print("rollplan: no --robot given: using the default robot (rollplan/data/default_robot.toml); "
              "lengths in m")
    return robot


def _most_pieces(legs: str, steps: int) -> int:
    """The most pieces of a plan of ``steps`` figure eights per leg: two legs of two leaves per figure eight
    (one leg with ``--legs one``), and the rolls to and from the pole."""
    return (2 if legs == "one" else 4) * steps + 2


def _check_samples(args, pieces: int) -> None:
    """``--samples`` before any work: within [2, MAX_SAMPLES] and, with --json or --plot (the path sampled at
    the end of each piece), more than the ``pieces`` the plan may have; by default 2000, or pieces + 1."""
    from .execution.actuation import DEFAULT_SAMPLES, MAX_SAMPLES

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


def _plan_inputs(args, inputs=(), samples=True):
    """The checks of ``plan`` and ``route`` before any work: outputs (never one of ``inputs`` or the robot
    file), steps, samples (those of a plan; ``route`` checks them once it knows its legs), the robot and the
    timing law's needs; returns ``(k, robot)``."""
    inputs = [*inputs, args.robot]
    _check_outputs(json=args.json, figure=args.plot, inputs=inputs)
    _check_timing_outputs(args, inputs)
    check_steps(args.steps)
    if samples:
        _check_samples(args, _most_pieces(args.legs, args.steps))
    k, robot = _k_or_robot(args)
    return k, _robot_for_duration(args, k, robot)


def _stage(args, command: str, name: str) -> None:
    """Report the stage ``name`` of ``plan`` or ``route`` as progress (so long work is never silent)."""
    stages = ["planning"] + ["timing"] * _is_timed(args) + ["sampling"] * bool(args.json or args.plot) + \
        ["writing JSON"] * bool(args.json) + ["drawing"] * bool(args.plot or args.timing_plot) + ["done"]
    report(command, stages.index(name), len(stages) - 1, stage=name)


def _radius_in_use(args, robot) -> float:
    """The sphere's radius in the length unit of the command: --radius, else the robot's, else 1 (R)."""
    return args.radius if args.radius is not None else (robot.radius if robot is not None else 1.0)


def _check_target(args, robot, start=(0.0,) * 5, contact=(0.0, 0.0)) -> None:
    """--to (within reach of the start), --from and --contact before any work, each named in its message."""
    check_contact(start[3], start[4], "argument --from: start")
    check_contact(contact[0], contact[1], "argument --contact: goal")
    radius = _radius_in_use(args, robot)
    check_reach(State(*start), State(*args.to), radius, "argument --to: goal",
                "the start (--from)" if any(start) else "the start")


def cmd_plan(args) -> int:
    k, robot = _plan_inputs(args)
    _check_target(args, robot, args.start, args.contact)
    goal = (args.to[0], args.to[1], args.psi, args.contact[0], args.contact[1])
    _stage(args, "plan", "planning")
    p = geometric.plan(goal, args.steps, k, robot, args.radius, args.all, args.method, branch=args.branch,
                       start=args.start, legs=args.legs)
    unit = p.problem.unit
    g = p.goal
    composed = hasattr(p, "pieces")
    radius = f"R = {_g(p.radius)} {'m' if unit == 'm' else '(lengths in units of R)'}"
    if composed or tuple(p.problem.start) != (0.0,) * 5:
        print(f"rollplan: k = {_g(p.k)}, {radius}, steps = {p.steps}, from (u_a, v_a, psi, u_o, v_o) = "
              f"{_fmt_state(p.problem.start, unit)} to {_fmt_state(g, unit)}")
    else:
        print(f"rollplan: k = {_g(p.k)}, {radius}, steps = {p.steps}, target (u_a, v_a, psi) = "
              f"({_g(g.u_a)} {unit}, {_g(g.v_a)} {unit}, {_g(g.psi)} rad)")
    print(_fmt_composed(p, unit) if composed else _fmt_plan(p, unit))
    print(f"  solver        {_fmt_solver(p.stats)}")
    if args.all:
        print(_fmt_all(p, unit))
    _write_results(args, p, robot, unit, composed_to_dict, "plan")
    return EXIT_OK


def _write_results(args, p, robot, unit, to_dict, command) -> None:
    """--duration/--timing, --json, --plot and --timing-plot of ``plan`` and ``route``: ``args.samples``
    trajectory samples in all; each stage reported as progress."""
    if _is_timed(args):
        _stage(args, command, "timing")
    motion, extra = _timed(args, p, robot) if _is_timed(args) else (None, {})
    if args.json or args.plot:
        _stage(args, command, "sampling")
    traj = as_composed(p).sample(args.samples) if (args.json or args.plot) else None
    if args.json:
        _stage(args, command, "writing JSON")
        _emit_json(args, {**to_dict(p, traj), **extra}, unit)
    if args.plot or args.timing_plot:
        _stage(args, command, "drawing")
    if args.plot and motion is not None:
        from .plots.motion import plot_motion

        save_figure(plot_motion(motion, p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot and not hasattr(p, "pieces"):
        from .plots.plan import plot_plan

        save_figure(plot_plan(p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    elif args.plot:
        from .plots.composed import plot_composed

        save_figure(plot_composed(p, traj, unit), args.plot)
        print(f"wrote {args.plot}")
    if args.timing_plot:
        from .execution.timing import velocity_limit
        from .plots.timing import plot_timing

        moving = motion.path is not None and motion.limits.any
        limit = velocity_limit(motion.path, motion.limits, motion.profile) if moving else None
        save_figure(plot_timing(motion, limit), args.timing_plot)
        print(f"wrote {args.timing_plot}")


def cmd_route(args) -> int:
    k, robot = _plan_inputs(args, inputs=[args.waypoints], samples=False)
    waypoints = read_waypoints(args.waypoints)
    _check_samples(args, sum(_most_pieces(args.legs, w.steps or args.steps) for w in waypoints[1:]))
    radius = _radius_in_use(args, robot)
    geometric.route.check_legs(waypoints, radius, f"waypoints file {show_path(args.waypoints)}: ")
    print(f"rollplan route: {len(waypoints)} waypoints from {args.waypoints}")
    r = geometric.plan_route(waypoints, args.steps, k, robot, args.radius, args.legs, args.method,
                             progress=lambda done, total: report("route", done, total, stage="legs"))
    unit = r.problem.unit
    print(f"rollplan route: k = {_g(r.k)}, R = {_g(r.radius)} {'m' if unit == 'm' else '(lengths in units of R)'}, "
          f"{len(r.plans)} legs, default steps = {r.steps}")
    for i, (p, w, res) in enumerate(zip(r.plans, r.waypoints[1:], r.waypoint_residuals), 1):
        label = f" {w.label!r}" if w.label else ""
        print(f"  leg {i} to waypoint {i + 1}{label} {_fmt_state(w.state, unit)}: {getattr(p, 'mode', 'one')}, "
              f"{_g(p.path_length)} {unit}, waypoint residual {res:.2e} (R, rad)")
    print(f"  path length   {_g(r.path_length)} {unit} in {len(r.pieces)} pieces")
    print(f"  final         {_fmt_state(r.final, unit, wrapped=True)}")
    print(f"  residual      {r.residual:.2e} ({NORM}; {r.certificate.method}, the whole route from the first "
          "waypoint)")
    print(f"  time          {r.stats.time_s:.2f} s")
    _write_results(args, r, robot, unit, route_to_dict, "route")
    return EXIT_OK


def _timed(args, p, robot):
    """``--duration`` / ``--timing``: rotor rates, angles and torques, checked by the rotor-only simulation
    from the plan's start state."""
    from .execution.actuation import actuate, certify_motion
    from .execution.timing import round_up
    from .io import motion_to_dict

    timing = args.timing or "min-jerk"
    motion = actuate(p, robot, args.duration, args.samples, timing)
    sim = certify_motion(motion)
    lim = motion.limits
    shortest = motion.minimum_duration
    at_shortest = shortest is not None and motion.duration == shortest
    print(f"  motion        T = {_g(motion.duration)} s{' (the shortest feasible)' if at_shortest else ''}, "
          f"{motion.time.size} samples, timing {timing}"
          f"{' (rest-to-rest per piece: leaf, roll)' if timing == 'min-jerk' else ''}")
    if motion.path is None:
        print("  limits        none needed: the plan is the empty motion (at rest)")
    elif lim.any:   # the shortest rounded up to 6 digits is the least printed value --duration accepts
        print(f"  limits        {lim.describe()}: the shortest feasible duration with timing {timing} is "
              f"{_g(shortest)} s (as --duration: {_g(round_up(shortest))} s or more)")
    else:
        print("  limits        none in the robot file (add max_rotor_rate [rad/s] and max_rotor_torque [N m] "
              "to keep the motors within them)")
    rate, torque = abs(motion.rotor_rates).max(), abs(motion.rotor_torques).max()
    use_rate = f" ({rate / lim.max_rotor_rate:.1%} of the limit)" if lim.max_rotor_rate is not None else ""
    use_torque = f" ({torque / lim.max_rotor_torque:.1%} of the limit)" if lim.max_rotor_torque is not None else ""
    print(f"  rotors        max |rate| = {_g(rate)} rad/s{use_rate}   max |torque| = {_g(torque)} N m{use_torque}")
    print(f"  rotor-only    arrival error {sim.arrival_error:.2e} ({NORM}), position error "
          f"{sim.position_error * robot.radius:.2e} m (spline through the rotor rates, (11) and (6)-(10) by CVODES)")
    extra = motion_to_dict(motion)
    extra["rotor_simulation"] = {"arrival_error": sim.arrival_error, "position_error": sim.position_error,
                                 "final": [float(v) for v in sim.final]}
    return motion, extra


def cmd_step(args) -> int:
    _check_outputs(json=args.json)
    r = geometric.step(args.a, args.b, k=args.k, gamma=args.gamma)
    u, v = r.shift
    # final psi of one step equals eta
    print(f"rollplan step: a = {_g(r.a)} R, b = {_g(r.b)} R, k = {_g(r.k)}, gamma = {_g(r.gamma)} rad")
    print(f"  h = {_g(r.h)} R   eta = {_g(r.eta)} rad   direction = {_g(r.direction)} rad")
    print(f"  final u_a = {_g(u)} R   v_a = {_g(v)} R   psi = {_g(r.eta)} rad")
    if args.json:
        _emit_json(args, {"a": r.a, "b": r.b, "k": r.k, "gamma": r.gamma, "h": r.h, "eta": r.eta,
                          "direction": r.direction, "final": {"u_a": float(u), "v_a": float(v), "psi": r.eta}}, "R")
    return EXIT_OK


def cmd_reproduce(args) -> int:
    import time

    from .studies.paper import reproduce

    t0 = time.perf_counter()
    make_folder(args.out, parents=True)   # a folder that cannot be made is refused before the first line
    print(f"rollplan reproduce: Section III.C of the paper into {args.out}", file=sys.stderr)
    with Progress() as progress:
        result = reproduce(args.out, progress=progress)
    width = max(len(r.quantity) for r in result.rows)
    for r in result.rows:
        print(f"  {r.quantity:<{width}}  paper {r.paper:<11.9g} computed {r.computed:<12.6g} {r.status}")
    n_ok = sum(r.status == "reproduced" for r in result.rows)
    print(f"{n_ok} of {len(result.rows)} reproduced, {len(result.rows) - n_ok} discrepancies "
          f"(evidence in {args.out}/REPRODUCTION.md); {time.perf_counter() - t0:.1f} s")
    return EXIT_OK


def _noise(args):
    from .execution.plants import disturbance

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

    from .execution.feedback import Samples

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
    from .execution.feedback import execute_samples

    plant = plant or args.plant
    dist = _noise(args)
    first, piece, steps = _file_samples(rp, args, plant)
    timing = rp.timing or "min-jerk"
    common = {"plant": plant, "disturbances": dist, "timing": timing, "rest_readings": args.average,
              "tolerance": args.tolerance, "corrections": args.corrections, "progress": report}
    runs = [execute_samples(first, rp.start, rp.goal, steps, rp.robot, robot, piece, closed_loop=closed, **common,
                           **engine)
            for closed in (False, True)[:1 + bool(args.closed_loop)]]
    opened, run = runs[0], runs[-1]
    f, g, e = run.final, rp.goal, run.error
    n_corr = sum(s["mode"] == "correction" for s in run.segments)
    print(f"rollplan simulate: {plant} plant, {'closed' if args.closed_loop else 'open'} loop, the file's motion "
          f"({first.time.size} samples over {_g(first.time[-1] - first.time[0])} s, timing {timing}), robot k = "
          f"{_g(robot.k)} (planned k = {_g(rp.robot.k)}){', measurement noise ' + _g(args.noise) if dist else ''}")
    print(f"  final         u_a = {_g(f[0])} m  v_a = {_g(f[1])} m  psi = {_g(f[2])} rad"
          f"  u_o = {_g(f[3])} rad  v_o = {_g(f[4])} rad")
    print(f"  target        u_a = {_g(g.u_a)} m  v_a = {_g(g.v_a)} m  psi = {_g(g.psi)} rad")
    print(f"  arrival error {run.arrival_error:.3e} ({NORM}): position {_position(run.position_error, robot)}, "
          f"psi {e[2]:.3e} rad" + (f"; open loop {opened.arrival_error:.3e}, position "
                                    f"{_position(opened.position_error, robot)}" if args.closed_loop else ""))
    if args.closed_loop:
        print(f"  corrections   {n_corr} after the plan (tolerance {_g(args.tolerance)}, at most {args.corrections}; "
              f"re-plans and corrections timed {timing}, {_g(piece)} s a piece or the shortest within the limits; "
              f"state at rest: mean of {args.average} reading{'s' if args.average > 1 else ''})")
        if run.stopped:
            print(f"  stopped       {run.stopped}")
        print("  estimated k   " + ", ".join(_g(d["k"]) for d in run.estimates if "k" in d))
    if args.json:
        d = run.to_dict()
        d.update({"open_loop_arrival_error": opened.arrival_error, "robot": robot.as_dict(),
                  "model_robot": rp.robot.as_dict(), "noise": args.noise, "seed": args.seed,
                  "corrections": n_corr, "tolerance": args.tolerance, "average": args.average})
        _emit_json(args, d, "m")
    if args.plot:
        title = (f"{plant} plant, {'closed' if args.closed_loop else 'open'} loop on {args.plan_file}: arrival "
                 f"error {run.arrival_error:.2e} ({NORM})" + (f", open loop {opened.arrival_error:.2e}"
                                                            if args.closed_loop else ""))
        _plot_simulation(args, rp, run.time, run.state, run.rotor_rates, robot, title)
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


def _plot_simulation(args, rp, time, state, rates, robot, title) -> None:
    from .plots.motion import plot_simulation

    save_figure(plot_simulation(time, state, rates, rp.goal, _planned_states(rp, time), robot, title), args.plot)
    print(f"wrote {args.plot}")


def cmd_simulate(args) -> int:
    from .execution.plants import simulate_rotors
    from .io import load_rotor_plan

    _check_outputs(json=args.json, figure=args.plot, inputs=[args.plan_file, args.robot])
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
    print(f"rollplan simulate: {keep.size} samples over {_g(rp.time[-1] - rp.time[0])} s, robot k = {_g(robot.k)}"
          f"{' (planned k = %s)' % _g(rp.robot.k) if args.robot else ''}, R = {_g(robot.radius)} m")
    print(f"  final         u_a = {_g(f[0])} m  v_a = {_g(f[1])} m  psi = {_g(f[2])} rad"
          f"  u_o = {f[3]:.3g} rad  v_o = {f[4]:.3g} rad")
    print(f"  target        u_a = {_g(g.u_a)} m  v_a = {_g(g.v_a)} m  psi = {_g(g.psi)} rad")
    print(f"  arrival error {sim.arrival_error:.3e} ({NORM}): position {_position(sim.position_error, robot)}, "
          f"psi {e[2]:.3e} rad, u_o {e[3]:.1e} rad, v_o {e[4]:.1e} rad")
    if args.json:
        _emit_json(args, {"final": dict(zip(STATE_NAMES, map(float, sim.final))),
                          "arrival_error": sim.arrival_error, "position_error": sim.position_error,
                          "position_error_m": sim.position_error * robot.radius,
                          "error": dict(zip(STATE_NAMES, map(float, e))),
                          "error_units": "u_a, v_a and position_error in R; psi (wrapped), u_o, v_o in rad",
                          "robot": robot.as_dict()}, "m")
    if args.plot:
        title = (f"rotor-driven simulation of {args.plan_file}: arrival error {sim.arrival_error:.2e} ({NORM}),\n"
                 f"position error {sim.position_error * robot.radius:.2e} m")
        _plot_simulation(args, rp, sim.time, sim.state, rp.rotor_rates[keep], robot, title)
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

    from .execution import mujoco_engine as engine
    from .inputs import read_text

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
    print(f"rollplan simulate: MuJoCo {mujoco.__version__}, {run.steps} RK4 steps of {_g(run.timestep)} s, "
          f"robot k = {_g(robot.k)}{' (planned k = %s)' % _g(rp.robot.k) if args.robot else ''}, "
          f"R = {_g(robot.radius)} m{', rate loop gain %s N m s/rad' % _g(gain) if gain else ''}"
          f"{', model ' + show_path(args.mjcf) if args.mjcf else ''}")
    print(f"  final         u_a = {_g(f[0])} m  v_a = {_g(f[1])} m  psi = {_g(f[2])} rad"
          f"  u_o = {f[3]:.3g} rad  v_o = {f[4]:.3g} rad")
    print(f"  target        u_a = {_g(g.u_a)} m  v_a = {_g(g.v_a)} m  psi = {_g(g.psi)} rad")
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
        _emit_json(args, d, "m")
    if args.plot:
        from .plots.motion import plot_simulation

        title = (f"MuJoCo replay of {args.plan_file}: arrival error {run.arrival_error:.2e} ({NORM}),\n"
                 f"slip {run.slip:.2e} m, max penetration {run.max_penetration:.2e} m")
        save_figure(plot_simulation(run.time, run.state, run.rotor_rates, g, _planned_states(rp), robot, title),
                    args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


def cmd_mjcf(args) -> int:
    from .execution import mujoco_engine as engine
    from .outputs import write_atomic

    _check_outputs(json=args.out, inputs=[args.robot])
    robot = load_robot(args.robot) if args.robot else default_robot()
    settings = d = engine.DEFAULT_SETTINGS
    step = d.timestep if args.timestep is None else args.timestep
    # one option at a time (the time step first, with the default contact time constant of at least two of its
    # steps), so that a refusal names the option
    for flag, fields in (("--timestep", {"timestep": step, "solref": (max(d.solref[0], 2.0 * step), d.solref[1])}),
                         ("--floor-solref", {"solref": d.solref if args.floor_solref is None else
                                             tuple(args.floor_solref)}),
                         ("--friction", {"friction": d.friction if args.friction is None else args.friction}),
                         ("--rolling-resistance", {"rolling": args.rolling_resistance}),
                         ("--com-offset", {"com_offset": tuple(args.com_offset)})):
        if flag == "--floor-solref" and args.floor_solref is None:
            continue
        try:
            settings = replace(settings, **fields)
        except InputError as exc:
            raise InputError(f"{flag}: {exc}") from None
    try:
        xml = engine.mjcf(robot, settings)
    except InputError as exc:   # the settings hold; the offset is bounded by the robot's radius
        raise InputError(f"--com-offset: {exc}") from None
    model = engine.compile_model(xml)
    mass, com, inertia = engine.composite_inertia(model)
    R = robot.radius
    j_zz = inertia[2, 2]
    print(f"rollplan mjcf: robot k = {_g(robot.k)} (14), Jzz = {_g(robot.j_zz)} kg m^2, M = {_g(robot.mass_total)} kg")
    print(f"  MuJoCo        composite about the centre: diag {_g(inertia[0, 0])} {_g(inertia[1, 1])} {_g(j_zz)} "
          f"kg m^2, M = {_g(mass)} kg, centre of mass {_g(com[0])} {_g(com[1])} {_g(com[2])} m, "
          f"k = {_g((j_zz + mass * R * R) / j_zz)}")
    print(f"  contact       solref {_g(settings.solref[0])} s {_g(settings.solref[1])}, friction "
          f"{_g(settings.friction)}, rolling resistance {_g(settings.rolling)} m; RK4 at {_g(settings.timestep)} s")
    write_atomic(args.out, xml.encode(), "MJCF model")
    print(f"wrote {args.out}")
    return EXIT_OK


def cmd_animate(args) -> int:
    from .execution.plants import simulate_rotors
    from .io import load_rotor_plan
    from .plots.animation import make_animation

    _check_outputs(json=args.out, inputs=[args.plan_file])
    if not args.out.lower().endswith(".gif"):
        raise InputError(f"--out {args.out!r} is not allowed: animate writes a GIF; give a name ending in .gif")
    if not 2 <= args.frames <= 2000:
        raise InputError(f"--frames {args.frames} is not allowed: it must lie in [2, 2000]")
    if not 1 <= args.fps <= 100:
        raise InputError(f"--fps {args.fps} is not allowed: it must lie in [1, 100]")
    rp = load_rotor_plan(args.plan_file)
    keep = rp.distinct
    sim = simulate_rotors(rp.robot, rp.time[keep], rp.rotor_rates[keep], rp.goal, x0=rp.start.array())
    with Progress(unit="frames") as progress:
        make_animation(rp.time[keep], sim.state, rp.rotor_rates[keep], rp.robot, rp.goal, args.out, args.frames,
                       args.fps, progress=progress)
    print(f"wrote {args.out}")
    return EXIT_OK


def _fmt_row(name, a, b, fmt):
    return f"  {name:<34s} {format(a, fmt):>20s} {format(b, fmt):>20s}"


def cmd_compare(args) -> int:
    from .studies import comparison

    _check_outputs(json=args.json, figure=args.plot, inputs=[args.robot])
    k, robot = _k_or_robot(args)
    _check_target(args, robot)
    c = comparison.compare((args.to[0], args.to[1], args.psi), args.steps, k, robot, args.radius, args.horizon,
                           args.cost, args.intervals, args.degree, args.scheme, args.contact_bound, args.branches)
    p, r, prob = c.plan, c.result, c.problem
    unit = prob.unit
    g, tr = prob.goal, r.transcription
    print(f"rollplan compare: k = {_g(prob.k)}, R = {_g(prob.radius)} {'m' if unit == 'm' else '(lengths in R)'}, "
          f"T = {_g(c.horizon)} s, target (u_a, v_a, psi) = ({_g(g.u_a)} {unit}, {_g(g.v_a)} {unit}, {_g(g.psi)} rad), "
          f"cost {c.cost}, contact bound {_g(c.contact_bound)} rad, rest to rest")
    print(f"  geometric phase: {prob.steps} figure eight(s), a = {_g(p.a)} {unit}, b = {_g(p.b)} {unit}, "
          f"gamma = {_g(p.gamma)} rad, "
          f"branch {p.branch}, optimal timing ({len(c.branches)} branch(es) timed)")
    wins = sum(s.status == "ok" for s in c.starts)
    print(f"  collocation: contact accelerations, {tr.scheme} d = {tr.degree}, N = {tr.intervals}, best of "
          f"{len(c.starts)} starts ({wins} converged): {r.guess}, psi turns m = {r.turns}")
    compared = {"path_length": "path length", "angular_velocity": "int|omega|^2 dt",
                "rotor_energy": "int|tau|^2 dt"}
    print(f"  compared cost: {compared.get(c.cost, c.cost)}")
    print(f"  {'':<32s} {'geometric phase':>20s} {'collocation':>20s}")
    gc, oc = c.gp.costs, c.collocation.costs
    torque = "N m" if robot is not None else "J_zz rad/s^2"   # without a robot: J_zz = 1 (printed below)
    print(_fmt_row(f"contact path length [{unit}]", gc["path_length"], oc["path_length"], ".6g"))
    print(_fmt_row("int|omega|^2 dt [rad^2/s]", gc["angular_velocity"], oc["angular_velocity"], ".6g"))
    print(_fmt_row(f"int|tau|^2 dt [({torque})^2 s]", gc["rotor_energy"], oc["rotor_energy"], ".6g"))
    print(_fmt_row("peak rotor rate [rad/s]", gc["peak_rotor_rate"], oc["peak_rotor_rate"], ".6g"))
    print(_fmt_row(f"peak rotor torque [{torque}]", gc["peak_rotor_torque"], oc["peak_rotor_torque"], ".6g"))
    print(_fmt_row("final residual (CVODES)", c.gp.residual, c.collocation.residual, ".2e"))
    print(f"  (residuals: {NORM})")
    print(_fmt_row("solve time [s]", c.gp.solve_time_s, c.collocation.solve_time_s, ".3f"))
    if robot is None:
        print("  (without --robot, torques are those of a robot with this k and J_zz = 1)")
    if args.json:
        _emit_json(args, comparison.comparison_to_dict(c), unit)
    if args.plot:
        from .plots.compare import plot_comparison

        save_figure(plot_comparison(c, unit), args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


_K_HELP = "inertia ratio k in [0, %g] (default %g, the paper's case)" % (K_MAX, DEFAULT_K)
_STEPS = "in [1, %d]" % MAX_STEPS
_JSON_HELP = "write {} as JSON to FILE (- for stdout; the summary then goes to stderr)"


def _add_target_options(parser, to_default, steps_help, k_help=_K_HELP) -> None:
    """--to, --psi, --steps, --k | --robot, --radius: the target and the robot, as in ``plan``."""
    if to_default is None:
        parser.add_argument("--to", nargs=2, type=_number, metavar=("U", "V"), required=True,
                            help="target contact point (u_a, v_a) on the plane")
    else:
        parser.add_argument("--to", nargs=2, type=_number, metavar=("U", "V"), default=to_default,
                            help="target contact point (u_a, v_a) on the plane (default %g %g)" % tuple(to_default))
    parser.add_argument("--psi", type=_number, default=0.0, help="target contact angle [rad] (default 0)")
    parser.add_argument("--steps", type=_whole, default=1, help=steps_help)
    _add_robot_options(parser, k_help)


def _add_robot_options(parser, k_help=_K_HELP) -> None:
    """--k | --robot, --radius: the robot, as in ``plan``."""
    g = parser.add_mutually_exclusive_group()
    g.add_argument("--k", type=_number, default=None, help=k_help)
    g.add_argument("--robot", metavar="FILE.toml", help="robot parameters (k from eq. 14; lengths in metres)")
    parser.add_argument("--radius", type=_radius, default=None,
                        help=f"sphere radius R [m] in [{show_limit(_RADIUS.low)}, {show_limit(_RADIUS.high)}] (as "
                             "in a robot file); lengths are then in metres (default: lengths in units of R, or the "
                             "robot's radius)")


def _add_compare_parser(sub) -> None:
    sub.add_parser("compare", help="geometric-phase plan versus collocation optimum on one problem, rest to rest",
                   builder=_compare_arguments)


def _compare_arguments(c) -> None:
    from .planners import collocation
    from .planners.collocation.rest import HORIZON_RANGE, MAX_INTERVALS, MEMORY_GB, MIN_INTERVALS
    from .studies.comparison import COMPARED_COSTS, CONTACT_BOUND

    k_help = ("inertia ratio k in (1, %g] (default %g; without --robot the torques are those of a robot with this k, "
              "and every robot has k > 1 by eq. 14)" % (K_MAX, DEFAULT_K))
    _add_target_options(c, to_default=None, steps_help=f"figure eights n {_STEPS} of the geometric plan (default 1)",
                        k_help=k_help)
    c.add_argument("--cost", choices=COMPARED_COSTS, default="angular_velocity",
                   help="the cost compared, minimised by both (default angular_velocity; rotor_energy needs --robot)")
    c.add_argument("--horizon", type=_number, default=1.0,
                   help="time horizon T [s] of both motions in [%g, %g] (default 1)" % HORIZON_RANGE)
    c.add_argument("--intervals", type=_whole, default=100,
                   help=f"intervals N of both motions in [{MIN_INTERVALS}, {MAX_INTERVALS}] (default 100; 2N "
                        f"controls for the 7 end conditions; N = {MAX_INTERVALS} stays within about {MEMORY_GB} GB of "
                        "memory and takes 10 minutes or more)")
    c.add_argument("--degree", type=_whole, default=3, help="collocation degree d in [1, 9] (default 3)")
    c.add_argument("--scheme", choices=collocation.SCHEMES, default="legendre", help="collocation points")
    c.add_argument("--branches", type=_whole, default=2,
                   help="geometric-phase branches timed and used as warm starts, in [1, 100] (default 2)")
    c.add_argument("--contact-bound", type=_number, default=CONTACT_BOUND, metavar="RAD",
                   help="both planners: largest polar angle of the contact point from the south pole, in (0, pi/2) "
                        "(default %.4g rad = 80 deg)" % CONTACT_BOUND)
    c.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("both results"))
    c.add_argument("--plot", metavar="FILE.png", help="both contact paths and their omega, rotor rates, torques")
    c.set_defaults(func=cmd_compare)


def cmd_codegen(args) -> int:
    from . import codegen

    g = codegen.generate(args.out, args.steps_per_leaf, args.prefix, args.k_max, args.real, args.overwrite)
    print(f"rollplan codegen: wrote {len(g.files)} files to {g.out} (prefix {g.prefix!r}, "
          f"{g.steps_per_leaf} steps per leaf, 0.5 <= k <= {args.k_max:g}, {args.real})")
    print(f"  C code      {g.code_bytes} bytes ({g.model_bytes} generated by CasADi)")
    print(f"  work memory {g.work_doubles} doubles (static)")
    print(f"  build       make -C {g.out}   then   {g.out}/plan_demo [--all] U V PSI STEPS K [BRANCH]")
    return EXIT_OK


def _quiet_dask(args) -> None:
    """Without --verbose, Dask's own log (tracebacks of lost connections, on stderr) is silenced: the command
    says in one line what failed."""
    if getattr(args, "scheduler", None) is not None and not args.verbose:
        import distributed  # noqa: F401  (sets its loggers' levels on import: set ours after it)

        logging.getLogger("distributed").setLevel(logging.CRITICAL)


def cmd_batch(args) -> int:
    from .studies.batch import run_batch
    from .studies.executor import ExecutorError, cpu_count

    if args.out == "-":
        raise InputError("batch --out - is not allowed: batch writes its lines to a file that --resume reads back; "
                         "give --out FILE.jsonl")
    _quiet_dask(args)
    try:
        jobs = args.jobs if args.jobs is not None else cpu_count()
        r = run_batch(args.targets, args.out, jobs, args.resume, args.overwrite, args.method,
                      progress=not args.quiet, scheduler=args.scheduler)
    except interrupts.Terminated:
        print(f"rollplan: terminated; finished lines are kept in {args.out}: rerun with --resume", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:
        print(f"\nrollplan: interrupted; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return EXIT_INTERRUPTED
    except ExecutorError as exc:
        print(f"rollplan: the cluster failed: {exc}; finished lines are kept in {args.out}: rerun with --resume",
              file=sys.stderr)
        return EXIT_SOLVER
    print(f"rollplan batch: {r.total} targets, {r.skipped} already done, {r.planned} planned "
          f"({r.failed} failed) in {r.time_s:.1f} s; wrote {args.out}")
    if r.total and r.failed_total == r.total:
        print(f"rollplan: every row failed ({r.failed_total} of {r.total}); see 'reason' in {args.out}",
              file=sys.stderr)
        return EXIT_NOPLAN
    if r.failed_total:
        print(f"rollplan: {r.failed_total} of {r.total} rows failed; see 'reason' in {args.out}", file=sys.stderr)
        return EXIT_SOME_FAILED
    return EXIT_OK


def _per_k(path, k):
    """The output path for ``k``: ``{k}`` in it replaced by the value (also for a single --k)."""
    return path if path is None or path == "-" else path.replace("{k}", f"{k:g}")


def cmd_atlas(args) -> int:
    from .plots.atlas import plot_atlas
    from .studies.atlas import atlas_to_dict, compute_atlases

    several = len(args.k) > 1
    repeated = sorted({f"{k:g}" for k in args.k if args.k.count(k) > 1})
    if repeated:
        raise InputError(f"--k {' '.join(repeated)} is given more than once: give each value of k once")
    for path in (args.out, args.json):
        if several and path not in (None, "-") and "{k}" not in path:
            raise InputError(f"output path {path!r} is not allowed with several --k values: put {{k}} in it "
                             "(e.g. atlas_k{k}.png)")
    if several and args.json == "-":
        raise InputError("--json - is not allowed with several --k values: give a file name with {k}")
    for k in args.k:
        _check_outputs(json=None if args.json is None else _per_k(args.json, k),
                       figure=_per_k(args.out, k))
    with Progress(unit="blocks", delay=1.0) as progress:
        _quiet_dask(args)
        atlases = compute_atlases(args.k, args.steps, args.resolution, scheduler=args.scheduler, progress=progress)
    for at in atlases:
        out = _per_k(args.out, at.k)
        save_figure(plot_atlas(at), out)
        print(f"rollplan atlas: k = {_g(at.k)}, steps = {at.steps}, {at.a.size} x {at.b.size} grid on "
              f"(0, {_g(at.a[-1])} R]^2")
        print(f"  shift per step h in [{_g(at.h.min())}, {_g(at.h.max())}] R, holonomy eta in "
              f"[{_g(at.eta.min())}, {_g(at.eta.max())}] rad, {at.fold_cells} grid cells on the fold det = 0")
        print(f"wrote {out}")
        if args.json:
            _emit_json(argparse.Namespace(json=_per_k(args.json, at.k), stdout=args.stdout),
                       atlas_to_dict(at), "R")
    return EXIT_OK


_BATCH_EPILOG = """\
TARGETS.csv: a header, then one target per line; columns u_a, v_a (required), psi (default 0),
steps (default 1), k (default 2.5); an empty cell takes the default; more columns are carried into
the output; blank lines and lines starting with # are skipped. Example:

  # u_a, v_a in units of R, psi in rad
  u_a,v_a,psi,steps,k
  0,1,0,1,2.5
  0.5,0.3,0.4,2,
  -0.2,0.6

exit status: 0 every row planned, 1 some rows failed, 3 every row failed (each failed row has
"status": "failed" and a "reason" in the output), 2 bad input, 4 the cluster failed, 130 interrupted
(Ctrl-C) or 143 terminated (SIGTERM) (finished lines are kept: rerun with --resume).
"""


def _add_timing_options(parser) -> None:
    """--duration, --timing, --samples and --timing-plot of ``plan`` and ``route``."""
    from .execution.actuation import MAX_SAMPLES
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
    parser.add_argument("--samples", type=_whole, default=None,
                        help=f"samples of the trajectory in --json and --plot, in all, in [2, {MAX_SAMPLES}], "
                             "more than the pieces the motion may have (4 n + 2 for n figure eights per leg, a "
                             "route the sum over its legs); default 2000, or that + 1 when more; with --duration "
                             "or --timing also the least number of time samples (at "
                             "least 400 per piece for min-jerk, 3000 for the other laws)")
    parser.add_argument("--timing-plot", metavar="FILE.png",
                        help="with --duration or --timing: rotor rates and torques in time with the robot's limits, "
                             "and the phase plane (s, s') with the maximum velocity curve")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="rollplan", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"rollplan {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log the planner's progress")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser, metavar="COMMAND")

    p = sub.add_parser("plan", help="plan a motion between two states by figure eights (and rolls, turns, legs)")
    _add_target_options(p, to_default=(0.0, 1.0), steps_help=f"number of figure eights n {_STEPS} per leg (default 1)")
    p.add_argument("--from", dest="start", nargs=5, type=_number, default=(0.0,) * 5,
                   metavar=("U_A", "V_A", "PSI", "U_O", "V_O"),
                   help="start state (default 0 0 0 0 0: at rest at the origin, contact at the south pole); "
                        "lengths in the unit in use, angles in rad; off the pole psi is the contact angle of (2), "
                        "not a yaw")
    p.add_argument("--contact", nargs=2, type=_number, default=(0.0, 0.0), metavar=("U_O", "V_O"),
                   help="goal contact point on the sphere [rad] (default 0 0, the south pole); "
                        "cos(u_o) cos(v_o) >= 0.05")
    p.add_argument("--legs", choices=geometric.LEGS, default="fallback",
                   help="figure eights: one leg, with a turn in place or two legs only where one leg has no plan "
                        "(fallback, default); also search two legs and keep the shorter (shortest); one; two")
    p.add_argument("--all", action="store_true", help="also list every other verified solution branch (one leg)")
    p.add_argument("--branch", type=_whole, default=None, metavar="M",
                   help="only branch M of n eta = psi + 2 pi M (one leg of figure eights)")
    p.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    p.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("the plan"))
    p.add_argument("--plot", metavar="FILE.png", help="draw the contact path on the sphere (from below) and the "
                   "plane, and psi along it (with --duration or --timing: omega, rotor rates and torques in time)")
    _add_timing_options(p)
    p.set_defaults(func=cmd_plan)

    w = sub.add_parser("route", help="plan a route through waypoints (a CSV file), leg by leg, certified as one")
    w.add_argument("waypoints", metavar="WAYPOINTS.csv",
                   help="header u_a,v_a,psi[,u_o,v_o][,steps][,label]; one waypoint a row, the first is the start")
    w.add_argument("--steps", type=_whole, default=1,
                   help=f"figure eights n {_STEPS} per leg where a row does not say (default 1)")
    _add_robot_options(w)
    w.add_argument("--legs", choices=geometric.LEGS, default="fallback", help="as for plan (default fallback)")
    w.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    w.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("the route"))
    w.add_argument("--plot", metavar="FILE.png", help="draw the route's contact path")
    _add_timing_options(w)
    w.set_defaults(func=cmd_route)

    s = sub.add_parser("step", help="what one figure eight does: shift h and holonomy eta")
    s.add_argument("--a", type=_number, required=True, help="first leaf radius [R], 0 < a <= %g" % A_MAX)
    s.add_argument("--b", type=_number, default=None, help="second leaf radius [R], 0 < b <= %g (default a)" % A_MAX)
    s.add_argument("--k", type=_number, default=DEFAULT_K, help=_K_HELP)
    s.add_argument("--gamma", type=_number, default=0.0, help="rotation about OZ [rad] (default 0)")
    s.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("the result"))
    s.set_defaults(func=cmd_step)

    r = sub.add_parser("reproduce", help="regenerate the paper's case study (Figs 6-12, table, report)")
    r.add_argument("--out", required=True, metavar="DIR",
                   help="folder for fig06.png..fig12.png, reproduction.json, REPRODUCTION.md (created if missing)")
    r.set_defaults(func=cmd_reproduce)

    m = sub.add_parser("simulate", help="drive the robot by the plan file's own motion (its rotor rates, or its "
                       "torques) and report the arrival error; optionally in closed loop")
    m.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    m.add_argument("--robot", metavar="FILE.toml", help="simulate this (real) robot instead of the planned one")
    m.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("the simulated final state and errors"))
    m.add_argument("--plot", metavar="FILE.png", help="the simulated motion against the plan: paths, psi, deviation "
                   "in time, and the rotor rates that drove it")
    m.add_argument("--closed-loop", action="store_true",
                   help="run the file's motion, measure after each figure eight where it rests, estimate the robot, "
                        "re-plan the rest (with the file's timing law), then correct from the measured state until "
                        "--tolerance or --corrections")
    m.add_argument("--plant", choices=("rates", "torques"), default="rates",
                   help="drive the robot by the file's rotor rates (default) or by its motor torques (linear "
                        "between samples, a step at a time given twice)")
    m.add_argument("--noise", type=_number, default=0.0, metavar="SIGMA",
                   help="measurement noise: standard deviation on u_a, v_a [R] and the angles [rad], "
                        "at most 0.1 (default 0)")
    m.add_argument("--seed", type=_whole, default=0, help="seed of the noise, in [0, 2^63 - 1] (default 0)")
    m.add_argument("--engine", choices=("model", "mujoco"), default="model",
                   help="model: the paper's equations (default); mujoco: the plan's motor torques replayed on "
                        "MuJoCo's rigid-body model of the robot (pip install 'rollplan[mujoco]')")
    m.add_argument("--mjcf", metavar="FILE.xml", help="with --engine mujoco: this model (written by rollplan mjcf, "
                   "maybe edited) instead of the robot's own with the default settings")
    m.add_argument("--servo", type=_number, default=None, metavar="GAIN",
                   help="with --engine mujoco: add a rotor-rate loop around the planned rates, gain in [0, 1000] "
                        "N m s/rad (default none: torques alone); --closed-loop and --noise also work with "
                        "--engine mujoco (the state measured from MuJoCo's pose)")
    m.add_argument("--average", type=_whole, default=None, metavar="N",
                   help="closed loop: the state at rest is the mean of N sensor readings, N in [1, 10^6] (default 1)")
    m.add_argument("--tolerance", type=_number, default=None, metavar="TOL",
                   help="closed loop: no correction once the measured arrival error is below TOL, in (0, 1] (R and "
                        "rad; default 1e-6)")
    m.add_argument("--corrections", type=_whole, default=None, metavar="N",
                   help="closed loop: at most N correcting motions after the plan, N in [0, 100] (default 3)")
    m.set_defaults(func=cmd_simulate)

    j = sub.add_parser("mjcf", help="write the robot's MuJoCo model (MJCF): shell, two rotors, torque motors, floor")
    j.add_argument("--robot", metavar="FILE.toml", help="robot file (default: the shipped default robot)")
    j.add_argument("--out", required=True, metavar="FILE.xml", help="output MJCF file")
    j.add_argument("--com-offset", type=_number, nargs=3, default=[0.0, 0.0, 0.0], metavar=("DX", "DY", "DZ"),
                   help="centre of mass off the centre, in the shell's frame [m], shorter than R/2 (default 0 0 0)")
    j.add_argument("--floor-solref", type=_number, nargs=2, default=None, metavar=("TIMECONST", "DAMPRATIO"),
                   help="the contact's spring-damper: time constant [s] in [2 timesteps, 10], and damping ratio in "
                        "[0.01, 100] (default 0.0002 1, stiff: two RK4 steps, or 2 DT with --timestep)")
    j.add_argument("--rolling-resistance", type=_number, default=0.0, metavar="MU",
                   help="rolling friction [m] in [0, 1] (default 0: none)")
    j.add_argument("--friction", type=_number, default=None, metavar="MU",
                   help="sliding friction coefficient in [0.001, 1000] (default 2)")
    j.add_argument("--timestep", type=_number, default=None, metavar="DT",
                   help="RK4 step [s] in [1e-6, 0.01] (default 1e-4)")
    j.set_defaults(func=cmd_mjcf)

    a = sub.add_parser("animate", help="animate the sphere rolling under the plan's rotor rates (GIF)")
    a.add_argument("plan_file", metavar="PLAN.json", help="made by: rollplan plan ... --duration T --json FILE")
    a.add_argument("--out", metavar="FILE.gif", required=True, help="output animation (GIF)")
    a.add_argument("--frames", type=_whole, default=100, help="number of frames in [2, 2000] (default 100)")
    a.add_argument("--fps", type=_whole, default=20, help="frames per second in [1, 100] (default 20)")
    a.set_defaults(func=cmd_animate)

    _add_compare_parser(sub)

    c = sub.add_parser("codegen", help="write a self-contained C99 planner (CasADi code generation)")
    c.add_argument("--out", required=True, metavar="DIR",
                   help="output folder (created if missing); an existing one may hold only files codegen wrote "
                        "there and what their Makefile builds")
    c.add_argument("--overwrite", action="store_true",
                   help="write into an existing DIR that holds other files too (or files codegen wrote that were "
                        "changed since): the files of codegen's names are replaced, the others kept")
    c.add_argument("--steps-per-leaf", type=_steps_per_leaf, default="auto",
                   help="node intervals per leaf of the step map, a multiple of 10 in [20, 2000], or auto (the "
                        "default): the smallest of 240, 320, 400, ... 2000 whose step map is accurate to 1e-10 up "
                        "to --k-max")
    c.add_argument("--prefix", default="rollplan", help="prefix of the C symbols and files, a C identifier "
                   "(default rollplan)")
    c.add_argument("--k-max", type=_number, default=5.0,
                   help="largest k the C planner accepts (the smallest is 0.5), at most %g; refused unless its step "
                        "map is accurate to 1e-10 up to it (default 5)" % K_MAX)
    c.add_argument("--real", choices=("double", "float"), default="double",
                   help="C number type: float for single-precision FPUs (plans certified to 1e-4 only)")
    c.set_defaults(func=cmd_codegen)

    sub.add_parser("batch", help="plan every target of a CSV file (u_a, v_a, psi, steps, k) in parallel",
                   epilog=_BATCH_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter,
                   builder=_batch_arguments)

    sub.add_parser("atlas", help="maps of h(a, b) and eta(a, b) with contours and the fold of the step map",
                   builder=_atlas_arguments)
    return parser


def _batch_arguments(b) -> None:
    from .studies.executor import MAX_JOBS

    b.add_argument("targets", metavar="TARGETS.csv", help="CSV with header u_a, v_a[, psi, steps, k] (see below)")
    b.add_argument("--out", required=True, metavar="PLANS.jsonl", help="output: one JSON line per target, in order")
    b.add_argument("--jobs", type=_whole, default=None,
                   help=f"worker processes in [1, {MAX_JOBS}] (default: number of cores)")
    b.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="plan on a Dask distributed cluster instead, e.g. tcp://host:8786 (needs: pip install "
                        "'rollplan[distributed]'; workers: dask worker ADDRESS --nthreads 1)")
    b.add_argument("--resume", action="store_true", help="keep the lines in --out and plan only the missing rows")
    b.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    b.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
    b.add_argument("--quiet", action="store_true", help="no progress on stderr")
    b.set_defaults(func=cmd_batch)


def _atlas_arguments(t) -> None:
    from .studies.atlas import DEFAULT_RESOLUTION, MAX_RESOLUTION

    t.add_argument("--k", type=_number, nargs="+", default=[DEFAULT_K], metavar="K",
                   help=_K_HELP + "; several values sweep over k (then put {k} in --out and --json)")
    t.add_argument("--steps", type=_whole, default=1, help=f"also map what n figure eights reach, n {_STEPS} "
                   "(default 1)")
    t.add_argument("--resolution", type=_whole, default=DEFAULT_RESOLUTION,
                   help=f"grid points per axis in [2, {MAX_RESOLUTION}] (default {DEFAULT_RESOLUTION})")
    t.add_argument("--out", required=True, metavar="FILE.png", help="figure")
    t.add_argument("--json", metavar="FILE", help=_JSON_HELP.format("the maps"))
    t.add_argument("--scheduler", metavar="ADDRESS", default=None,
                   help="evaluate the grid on a Dask distributed cluster (pip install 'rollplan[distributed]')")
    t.set_defaults(func=cmd_atlas)


#: ``name='value'`` or ``name=True`` in a message of the Python API: an option to name in command-line syntax.
_API_OPTION = re.compile(r"\b([a-z][a-z_]*)=(?:'([^']*)'|True\b)")


#: ``name = value`` at the start of a message of the API: the value of the option --name (``steps per leaf``
#: for --steps-per-leaf), when the command has that option and it was given: the message names the option.
_API_NAME = re.compile(r"^([a-z](?:[a-z_ ]*[a-z])?) = ")
_NOT_OPTIONS = ("command", "func", "stdout", "waypoints", "targets", "plan_file")


def _cli_syntax(message: str, args) -> str:
    """A message of the API with its option hints in command-line syntax (``guess='warm'`` -> ``--guess warm``),
    for the options the command has."""
    def sub(m):
        if m.group(1) not in vars(args):
            return m.group(0)
        flag = "--" + m.group(1).replace("_", "-")
        return flag if m.group(2) is None else f"{flag} {m.group(2)}"

    def option(m):   # "k = 200.0 is not allowed" -> "argument --k: k = 200.0 is not allowed" (as argparse says it)
        dest = m.group(1).replace(" ", "_")
        if dest in _NOT_OPTIONS or getattr(args, dest, None) is None:
            return m.group(0)
        return f"argument --{dest.replace('_', '-')}: {m.group(0)}"

    return _API_OPTION.sub(sub, _API_NAME.sub(option, message, count=1))


def _drop_stdout(stream=None) -> None:
    """Point stdout (or ``stream``) at /dev/null, so that the text left in its buffer is not written again (and
    fails again, with an 'Exception ignored' message) when Python exits."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, (stream or sys.stdout).fileno())
        os.close(devnull)
    except (OSError, ValueError):   # stdout without a file descriptor (captured): nothing is flushed at exit
        pass


def main(argv=None) -> int:
    """Run the command in ``argv`` (default ``sys.argv[1:]``) and return its exit status (module docstring)."""
    with interrupts.terminate_as_interrupt():   # SIGTERM stops the command as Ctrl-C does (exit 143)
        status = _main(argv)
    interrupts.settle()   # decided: a late Ctrl-C (Python's shutdown) no longer turns it into death by SIGINT
    if status in (EXIT_INTERRUPTED, EXIT_TERMINATED):
        interrupts.forget_unhandled()
        if interrupts.abandoned() and interrupts.cli_follows():   # a solver still being built in a thread
            for stream in (sys.stdout, sys.stderr):
                with contextlib.suppress(OSError, ValueError):
                    stream.flush()
            os._exit(status)
    return status


def _main(argv) -> int:
    try:
        interrupts.end_start_up()   # from here Ctrl-C is KeyboardInterrupt: exit 130 below
        parser = build_parser()
        argv = sys.argv[1:] if argv is None else list(argv)
        if not argv:   # a bare `rollplan`: say what it can do
            parser.print_help(sys.stderr)
            return EXIT_INPUT
        args = parser.parse_args(argv)
    except KeyboardInterrupt as exc:
        terminated = isinstance(exc, interrupts.Terminated)
        print(f"rollplan: {'terminated' if terminated else 'interrupted'}", file=sys.stderr)
        return EXIT_TERMINATED if terminated else EXIT_INTERRUPTED
    logging.basicConfig(level=logging.INFO if args.verbose else logging.ERROR, format="%(name)s: %(message)s")
    if (getattr(args, "command", None) in ("plan", "compare", "route") and args.k is None and args.robot is None
            and getattr(args, "duration", None) is None and getattr(args, "timing", None) is None):
        args.k = DEFAULT_K
    args.stdout = sys.stdout
    to_stdout = getattr(args, "json", None) == "-"
    try:
        with ExitStack() as stack:
            _Claims.stack, _Claims.files = stack, {}
            with contextlib.redirect_stdout(sys.stderr) if to_stdout else contextlib.nullcontext(), \
                    Progress(delay=5.0) as progress, reporting(progress):
                status = args.func(args)
            args.stdout.flush()   # a full disk or a closed pipe behind stdout shows here, inside the handlers
            return status
    except interrupts.Terminated:   # SIGTERM, also inside the solvers
        print("rollplan: terminated", file=sys.stderr)
        return EXIT_TERMINATED
    except KeyboardInterrupt:  # Ctrl-C, also inside the solvers (rollplan.interrupts)
        print("\nrollplan: interrupted" if sys.stderr.isatty() else "rollplan: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except MemoryError:
        print("rollplan: error: not enough memory for this input", file=sys.stderr)
        return EXIT_INPUT
    except InputError as exc:
        print(f"rollplan: error: {_cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_INPUT
    except NoPlanError as exc:
        print(f"rollplan: no plan: {_cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_NOPLAN
    except SolverError as exc:
        print(f"rollplan: solver failed ({exc.status}): {_cli_syntax(str(exc), args)}", file=sys.stderr)
        return EXIT_SOLVER
    except OSError as exc:   # stdout on a full disk (`> /dev/full`), into a closed pipe (`| head -c1`): one line
        if exc.errno not in WRITE_FAILURES:
            raise
        _drop_stdout()
        try:
            print(f"rollplan: error: the standard output cannot be written: {WRITE_FAILURES[exc.errno]}",
                  file=sys.stderr)
        except OSError:   # stderr is gone too (`2>&1 | head`): the exit status says it
            _drop_stdout(sys.stderr)
        return EXIT_INPUT
    finally:
        _Claims.stack = None


if __name__ == "__main__":
    sys.exit(main())
