"""``rollplan plan``: a motion between two states by figure eights (and rolls, turns, legs)."""

from __future__ import annotations

from ...io import composed_to_dict
from ...planners import geometric, solve
from ...problem import Problem
from ..arguments import JSON_HELP, STEPS_HELP, add_target_options, number, whole
from ..common import EXIT_OK, check_target
from ..format import fmt_all, fmt_composed, fmt_plan, fmt_solver, fmt_state, num
from ..planning import add_timing_options, plan_inputs, stage, write_results


def cmd_plan(args) -> int:
    k, robot = plan_inputs(args)
    check_target(args, robot, args.start, args.contact)
    goal = (args.to[0], args.to[1], args.psi, args.contact[0], args.contact[1])
    stage(args, "plan", "planning")
    problem = Problem(goal, start=args.start, k=k, robot=robot, radius=args.radius)
    p = solve(problem, "geometric", root_solver=args.method, legs=args.legs, steps=args.steps, all_solutions=args.all,
              branch=args.branch, base=args.base, curve=args.curve)
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
    p.add_argument("--method", choices=sorted(geometric.SOLVERS), default="ipopt", help="root solver")
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
