"""``rollplan step``: what one figure eight does (shift h and holonomy eta)."""

from __future__ import annotations

from ...core.curves import A_MAX
from ...planners import geometric
from ...problem import DEFAULT_K
from ..arguments import JSON_HELP, K_HELP, number
from ..common import EXIT_OK, check_outputs, emit_json
from ..format import num


def cmd_step(args) -> int:
    check_outputs(json=args.json)
    r = geometric.step(args.a, args.b, k=args.k, gamma=args.gamma)
    u, v = r.shift
    # final psi of one step equals eta
    print(f"rollplan step: a = {num(r.a)} R, b = {num(r.b)} R, k = {num(r.k)}, gamma = {num(r.gamma)} rad")
    print(f"  h = {num(r.h)} R   eta = {num(r.eta)} rad   direction = {num(r.direction)} rad")
    print(f"  final u_a = {num(u)} R   v_a = {num(v)} R   psi = {num(r.eta)} rad")
    if args.json:
        emit_json(args, {"a": r.a, "b": r.b, "k": r.k, "gamma": r.gamma, "h": r.h, "eta": r.eta,
                          "direction": r.direction, "final": {"u_a": float(u), "v_a": float(v), "psi": r.eta}}, "R")
    return EXIT_OK


def register(sub) -> None:
    """The ``step`` command's options."""
    s = sub.add_parser("step", help="what one figure eight does: shift h and holonomy eta")
    s.add_argument("--a", type=number, required=True, help="first leaf radius [R], 0 < a <= %g" % A_MAX)
    s.add_argument("--b", type=number, default=None, help="second leaf radius [R], 0 < b <= %g (default a)" % A_MAX)
    s.add_argument("--k", type=number, default=DEFAULT_K, help=K_HELP)
    s.add_argument("--gamma", type=number, default=0.0, help="rotation about OZ [rad] (default 0)")
    s.add_argument("--json", metavar="FILE", help=JSON_HELP.format("the result"))
    s.set_defaults(func=cmd_step)
