"""``rollplan route``: a route through waypoints, leg by leg, certified as one."""

from __future__ import annotations

from ...inputs import show_path
from ...io import route_to_dict
from ...planners import geometric
from ...progress import report
from ...waypoints import read_waypoints
from ..arguments import JSON_HELP, STEPS_HELP, add_robot_options, whole
from ..common import EXIT_OK, NORM, radius_in_use
from ..format import fmt_state, num
from ..planning import add_timing_options, check_samples, most_pieces, plan_inputs, write_results


def cmd_route(args) -> int:
    k, robot = plan_inputs(args, inputs=[args.waypoints], samples=False)
    waypoints = read_waypoints(args.waypoints)
    check_samples(args, sum(most_pieces(args.legs, w.steps or args.steps) for w in waypoints[1:]))
    radius = radius_in_use(args, robot)
    geometric.route.check_legs(waypoints, radius, f"waypoints file {show_path(args.waypoints)}: ")
    print(f"rollplan route: {len(waypoints)} waypoints from {args.waypoints}")
    r = geometric.plan_route(waypoints, args.steps, k, robot, args.radius, args.legs, root_solver=args.method,
                             progress=lambda done, total: report("route", done, total, stage="legs"))
    unit = r.problem.unit
    print(f"rollplan route: k = {num(r.k)}, R = {num(r.radius)} {'m' if unit == 'm' else '(lengths in units of R)'}, "
          f"{len(r.plans)} legs, default steps = {r.steps}")
    for i, (p, w, res) in enumerate(zip(r.plans, r.waypoints[1:], r.waypoint_residuals), 1):
        label = f" {w.label!r}" if w.label else ""
        print(f"  leg {i} to waypoint {i + 1}{label} {fmt_state(w.state, unit)}: {p.mode}, "
              f"{num(p.path_length)} {unit}, waypoint residual {res:.2e} (R, rad)")
    print(f"  path length   {num(r.path_length)} {unit} in {len(r.pieces)} pieces")
    print(f"  final         {fmt_state(r.final, unit, wrapped=True)}")
    print(f"  residual      {r.residual:.2e} ({NORM}; {r.certificate.method}, the whole route from the first "
          "waypoint)")
    print(f"  time          {r.stats.time_s:.2f} s")
    write_results(args, r, robot, unit, route_to_dict, "route")
    return EXIT_OK


def register(sub) -> None:
    """The ``route`` command's options."""
    w = sub.add_parser("route", help="plan a route through waypoints (a CSV file), leg by leg, certified as one")
    w.add_argument("waypoints", metavar="WAYPOINTS.csv",
                   help="header u_a,v_a,psi[,u_o,v_o][,steps][,label]; one waypoint a row, the first is the start")
    w.add_argument("--steps", type=whole, default=1,
                   help=f"figure eights n {STEPS_HELP} per leg where a row does not say (default 1)")
    add_robot_options(w)
    w.add_argument("--legs", choices=geometric.LEGS, default="fallback", help="as for plan (default fallback)")
    w.add_argument("--method", choices=sorted(geometric.SOLVERS), default=geometric.DEFAULT_ROOT_SOLVER,
                   help="root solver")
    w.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the route"))
    w.add_argument("--plot", metavar="FILE.png", help="draw the route's contact path")
    add_timing_options(w)
    w.set_defaults(func=cmd_route)
