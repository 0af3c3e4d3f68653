"""``rollplan step``: what one figure eight does (shift h and holonomy eta)."""

from __future__ import annotations

import math

from ...core import families
from ...core.curves import A_MAX
from ...planners import geometric
from ...problem import DEFAULT_K, check_k
from ..arguments import JSON_HELP, K_HELP, number
from ..common import EXIT_OK, check_outputs, emit_json
from ..format import num


def cmd_step(args) -> int:
    check_outputs(json=args.json)
    if args.curve == "circles":
        r = geometric.step(args.a, args.b, k=args.k, gamma=args.gamma)
        a, b, k, gamma, (u, v), eta = r.a, r.b, r.k, r.gamma, r.shift, r.eta
    else:
        k = check_k(args.k)
        b = args.a if args.b is None else args.b
        u, v, eta = families.step(args.curve, args.a, b, k=k, gamma=args.gamma)
        a, b, gamma = float(args.a), float(b), float(args.gamma)
    h, direction = math.hypot(u, v), math.atan2(v, u)
    # final psi of one step equals eta
    family = "" if args.curve == "circles" else f"curve = {args.curve}, "
    print(f"rollplan step: {family}a = {num(a)} R, b = {num(b)} R, k = {num(k)}, gamma = {num(gamma)} rad")
    print(f"  h = {num(h)} R   eta = {num(eta)} rad   direction = {num(direction)} rad")
    print(f"  final u_a = {num(u)} R   v_a = {num(v)} R   psi = {num(eta)} rad")
    if args.json:
        emit_json(args, {"curve": args.curve, "a": a, "b": b, "k": k, "gamma": gamma, "h": h, "eta": float(eta),
                         "direction": direction, "final": {"u_a": float(u), "v_a": float(v), "psi": float(eta)}},
                  "R")
    return EXIT_OK


def register(sub) -> None:
    """The ``step`` command's options."""
    s = sub.add_parser("step", help="what one figure eight does: shift h and holonomy eta")
    s.add_argument("--curve", choices=families.FAMILIES, default="circles",
                   help="leaf family of the figure eight (default circles; docs/design/curve-families.md)")
    s.add_argument("--a", type=number, required=True,
                   help="first leaf size [R] (a circle's radius; half the chord to the leaf's farthest point), "
                        "0 < a <= %g" % A_MAX)
    s.add_argument("--b", type=number, default=None, help="second leaf size [R], 0 < b <= %g (default a)" % A_MAX)
    s.add_argument("--k", type=number, default=DEFAULT_K, help=K_HELP)
    s.add_argument("--gamma", type=number, default=0.0, help="rotation about OZ [rad] (default 0)")
    s.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the result"))
    s.set_defaults(func=cmd_step)
