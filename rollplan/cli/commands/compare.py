"""``rollplan compare``: the geometric-phase plan against the collocation optimum, rest to rest."""

from __future__ import annotations

from ...io import save_figure
from ...problem import DEFAULT_K, K_MAX
from ..arguments import JSON_HELP, STEPS_HELP, add_target_options, number, whole
from ..common import EXIT_OK, NORM, check_outputs, check_target, emit_json, k_or_robot
from ..format import num


def _fmt_row(name, a, b, fmt):
    return f"  {name:<34s} {format(a, fmt):>20s} {format(b, fmt):>20s}"


def cmd_compare(args) -> int:
    from ...studies import comparison

    check_outputs(json=args.json, figure=args.plot, inputs=[args.robot])
    k, robot = k_or_robot(args)
    check_target(args, robot)
    c = comparison.compare((args.to[0], args.to[1], args.psi), args.steps, k, robot, args.radius, args.horizon,
                           args.cost, args.intervals, args.degree, args.scheme, args.contact_bound, args.branches,
                           curve=args.curve)
    p, r, prob = c.plan, c.result, c.problem
    unit = prob.unit
    g, tr = prob.goal, r.transcription
    print(f"rollplan compare: k = {num(prob.k)}, R = {num(prob.radius)} {'m' if unit == 'm' else '(lengths in R)'}, "
          f"T = {num(c.horizon)} s, target (u_a, v_a, psi) = ({num(g.u_a)} {unit}, {num(g.v_a)} {unit}, "
          f"{num(g.psi)} rad), "
          f"cost {c.cost}, contact bound {num(c.contact_bound)} rad, rest to rest")
    print(f"  geometric phase: {prob.steps} figure eight(s), a = {num(p.a)} {unit}, b = {num(p.b)} {unit}, "
          f"gamma = {num(p.gamma)} rad, {'' if p.curve == 'circles' else f'curve {p.curve}, '}"
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
        emit_json(args, comparison.comparison_to_dict(c), unit)
    if args.plot:
        from ...plots.compare import plot_comparison

        save_figure(plot_comparison(c, unit), args.plot)
        print(f"wrote {args.plot}")
    return EXIT_OK


def _compare_arguments(c) -> None:
    from ...planners import collocation
    from ...planners.collocation.rest import HORIZON_RANGE, MAX_INTERVALS, MEMORY_GB, MIN_INTERVALS
    from ...planners.geometric import CURVE_CHOICES
    from ...studies.comparison import COMPARED_COSTS, CONTACT_BOUND

    k_help = ("inertia ratio k in (1, %g] (default %g; without --robot the torques are those of a robot with this k, "
              "and every robot has k > 1 by eq. 14)" % (K_MAX, DEFAULT_K))
    add_target_options(c, to_default=None, steps_help=f"figure eights n {STEPS_HELP} of the geometric plan (default 1)",
                        k_help=k_help)
    c.add_argument("--curve", choices=CURVE_CHOICES, default="circles",
                   help="leaf family of the geometric plan (default circles; best: the family of the shortest plan; "
                        "its timing rests at the path's corners)")
    c.add_argument("--cost", choices=COMPARED_COSTS, default="angular_velocity",
                   help="the cost compared, minimised by both (default angular_velocity; rotor_energy needs --robot)")
    c.add_argument("--horizon", type=number, default=1.0,
                   help="time horizon T [s] of both motions in [%g, %g] (default 1)" % HORIZON_RANGE)
    c.add_argument("--intervals", type=whole, default=100,
                   help=f"intervals N of both motions in [{MIN_INTERVALS}, {MAX_INTERVALS}] (default 100; 2N "
                        f"controls for the 7 end conditions; N = {MAX_INTERVALS} stays within about {MEMORY_GB} GB of "
                        "memory and takes 10 minutes or more)")
    c.add_argument("--degree", type=whole, default=3, help="collocation degree d in [1, 9] (default 3)")
    c.add_argument("--scheme", choices=collocation.SCHEMES, default="legendre", help="collocation points")
    c.add_argument("--branches", type=whole, default=2,
                   help="geometric-phase branches timed and used as warm starts, in [1, 100] (default 2)")
    c.add_argument("--contact-bound", type=number, default=CONTACT_BOUND, metavar="RAD",
                   help="both planners: largest polar angle of the contact point from the south pole, in (0, pi/2) "
                        "(default %.4g rad = 80 deg)" % CONTACT_BOUND)
    c.add_argument("--json", metavar="FILE", help=JSON_HELP.format("both results"))
    c.add_argument("--plot", metavar="FILE.png", help="both contact paths and their omega, rotor rates, torques")
    c.set_defaults(func=cmd_compare)


def register(sub) -> None:
    """The ``compare`` command (its options are added when it is used: they need the collocation planner)."""
    sub.add_parser("compare", help="geometric-phase plan versus collocation optimum on one problem, rest to rest",
                   builder=_compare_arguments)
