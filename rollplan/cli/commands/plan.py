"""``rollplan plan``: a motion between two states by figure eights (and rolls, turns, legs)."""

from __future__ import annotations

import math

from ...errors import InputError
from ...io import composed_to_dict, refined_to_dict
from ...planners import geometric, solve
from ...planners.refined import RefinedPlan
from ...problem import Problem
from ..arguments import JSON_HELP, STEPS_HELP, add_target_options, number, whole
from ..common import EXIT_OK, NORM, check_target, emit_json
from ..format import fmt_all, fmt_composed, fmt_plan, fmt_solver, fmt_state, num
from ..planning import add_timing_options, plan_inputs, stage, write_results


def _pieces_flags(args) -> list:
    """The flags given that need the plan's closed-form pieces."""
    return [flag for flag, given in (("--all", args.all), ("--duration", args.duration is not None),
                                     ("--timing", args.timing is not None), ("--plot", args.plot is not None),
                                     ("--timing-plot", args.timing_plot is not None)) if given]


def _check_refine(args) -> str:
    """--refine and --polish fast return one motion in time: they do not combine with --all, timing or plots
    (--polish fast not with --branch either). Returns the polish to plan with: ``"fast"`` by default, ``"off"``
    when those flags are given."""
    other = _pieces_flags(args)
    if args.refine and other:
        raise InputError(f"--refine does not combine with {other[0]}: the polished motion is one certified motion "
                         "in time, not closed-form pieces (plan without --refine for it)")
    if args.branch is not None:   # one branch of the figure eights: a plan of closed-form pieces too
        other.append("--branch")
    if args.polish == "fast" and other:
        raise InputError(f"--polish fast does not combine with {other[0]}: the polished motion is one certified "
                         "motion in time, not closed-form pieces (use --polish off for it)")
    if args.polish is None:
        return "off" if other else "fast"
    return args.polish


def _print_refined(p, unit) -> None:
    """The polish's lines: the polished motion, or why the plan was kept."""
    if not isinstance(p, RefinedPlan):
        print(f"  refined       none, the plan is kept ({p.stats.details.get('refine', '')})")
        return
    det = p.stats.details
    starts = "from the straight line (fast polish)" if det.get("polish") == "fast" else \
        "warm-started by the plan and straight lines"
    print(f"  refined       path length {num(p.path_length)} {unit} (unrefined {num(p.unrefined_length)} {unit}; "
          f"{p.path_length / p.unrefined_length:.3f} x): minimum-path-length collocation {starts}, "
          f"{det['intervals']} intervals of constant contact accelerations, polar angle <= "
          f"{num(round(math.degrees(det['contact_bound']), 6))} deg")
    print(f"  final         {fmt_state(p.final, unit, wrapped=True)}")
    print(f"  residual      {p.residual:.2e} ({NORM}, and the final contact rates; {p.certificate.method}, the whole "
          "polished motion from the start state)")
    print(f"  refine time   {num(round(det['refine_time_s'], 3))} s "
          f"(the plan: {num(round(det['unrefined_time_s'], 3))} s)")


def _write_refined(args, p, unit) -> None:
    """--json of --refine (the polished motion has no plot or timing here)."""
    if not args.json:
        return
    stage(args, "plan", "sampling")
    traj = p.sample(args.samples)
    stage(args, "plan", "writing JSON")
    emit_json(args, refined_to_dict(p, traj), unit)


def cmd_plan(args) -> int:
    polish = _check_refine(args)
    k, robot = plan_inputs(args)
    check_target(args, robot, args.start, args.contact)
    goal = (args.to[0], args.to[1], args.psi, args.contact[0], args.contact[1])
    stage(args, "plan", "planning")
    problem = Problem(goal, start=args.start, k=k, robot=robot, radius=args.radius)
    p = solve(problem, "geometric", root_solver=args.method, legs=args.legs, steps=args.steps, all_solutions=args.all,
              branch=args.branch, base=args.base, refine=args.refine,
              curve=args.curve, polish=polish)
    refined = p
    if isinstance(p, RefinedPlan):
        p = p.unrefined
    unit = p.problem.unit
    g = p.goal
    composed = not isinstance(p, geometric.Plan)   # the paper's one-leg plan has a summary of its own
    radius = f"R = {num(p.radius)} {'m' if unit == 'm' else '(lengths in units of R)'}"
    if composed or tuple(p.problem.start) != (0.0,) * 5:
        print(f"rollplan: k = {num(p.k)}, {radius}, steps = {p.steps}, from (u_a, v_a, psi, u_o, v_o) = "
              f"{fmt_state(p.problem.start, unit)} to {fmt_state(g, unit)}")
    else:
        print(f"rollplan: k = {num(p.k)}, {radius}, steps = {p.steps}, target (u_a, v_a, psi) = "
              f"({num(g.u_a)} {unit}, {num(g.v_a)} {unit}, {num(g.psi)} rad)")
    print(fmt_composed(p, unit) if composed else fmt_plan(p, unit))
    print(f"  solver        {fmt_solver(p.stats)}")
    if args.all:
        print(fmt_all(p, unit))
    if args.refine or isinstance(refined, RefinedPlan) or "refine" in refined.stats.details:
        _print_refined(refined, unit)
        _write_refined(args, refined, unit)
    else:
        write_results(args, p, robot, unit, composed_to_dict, "plan")
    return EXIT_OK


def register(sub) -> None:
    """The ``plan`` command's options."""
    p = sub.add_parser("plan", help="plan a motion between two states by figure eights (and rolls, turns, legs)")
    add_target_options(p, to_default=(0.0, 1.0),
                       steps_help=f"number of figure eights n {STEPS_HELP} per leg (default 1)")
    p.add_argument("--from", dest="start", nargs=5, type=number, default=(0.0,) * 5,
                   metavar=("U_A", "V_A", "PSI", "U_O", "V_O"),
                   help="start state (default 0 0 0 0 0: at rest at the origin, contact at the south pole); "
                        "lengths in the unit in use, angles in rad; off the pole psi is the contact angle of (2), "
                        "not a yaw")
    p.add_argument("--contact", nargs=2, type=number, default=(0.0, 0.0), metavar=("U_O", "V_O"),
                   help="goal contact point on the sphere [rad] (default 0 0, the south pole); "
                        "cos(u_o) cos(v_o) >= 0.05")
    p.add_argument("--legs", choices=geometric.LEGS, default="fallback",
                   help="figure eights: one leg, with a turn in place or two legs only where one leg has no plan "
                        "(fallback, default); also search two legs and keep the shorter (shortest); one; two")
    p.add_argument("--base", choices=geometric.BASES, default="pole",
                   help="where the figure eights are traced: at the south pole (pole, default); or also at base "
                        "points between the start and goal contact points, keeping the shorter plan (any; slower: "
                        "seconds)")
    p.add_argument("--all", action="store_true", help="also list every other verified solution branch (one leg)")
    p.add_argument("--branch", type=whole, default=None, metavar="M",
                   help="only branch M of n eta = psi + 2 pi M (one leg of figure eights)")
    p.add_argument("--method", choices=sorted(geometric.SOLVERS), default=geometric.DEFAULT_ROOT_SOLVER,
                   help="root solver")
    p.add_argument("--refine", action="store_true",
                   help="polish the plan into a shorter certified motion: a minimum-path-length optimal-control solve "
                        "(rest to rest, 60 intervals of constant contact accelerations, polar angle <= 80 deg) "
                        "warm-started by the plan and straight lines; the plan is kept, with a note, when that is not "
                        "shorter or not certified (seconds; not with --all, --duration, --timing, --plot, "
                        "--timing-plot)")
    p.add_argument("--polish", choices=geometric.POLISHES, default=None,
                   help="between full states (start or goal contact point off the south pole): fast (the default "
                        "unless --all, --duration, --timing, --plot or --timing-plot is given) replaces the plan by a "
                        "minimum-path-length optimal-control solve on 8 intervals from the straight line, certified "
                        "the same way, when that is shorter (about 0.1 s warm); off: the figure-eight plan itself")
    p.add_argument("--curve", choices=geometric.CURVE_CHOICES, default="circles",
                   help="leaf family of the figure eight: circles (default), viviani, triangle, square (these for "
                        "k >= 0.5), or best: the shortest certified plan over the families "
                        "(docs/design/curve-families.md); other than circles, one leg from rest at the origin to a "
                        "goal at the pole")
    p.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the plan"))
    p.add_argument("--plot", metavar="FILE.png", help="draw the contact path on the sphere (from below) and the "
                   "plane, and psi along it (with --duration or --timing: omega, rotor rates and torques in time)")
    add_timing_options(p)
    p.set_defaults(func=cmd_plan)
