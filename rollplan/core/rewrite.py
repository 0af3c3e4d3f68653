"""Symbolic rewriting of CasADi functions into cheaper, equivalent forms.

:func:`algebraic` removes the trigonometric functions of inverse trigonometric results that the model's
contact coordinates (24)-(25) produce, so compiled right sides of (28)-(30) (the C planner's certificate and
time law, the Python planner's RK8 certificate) evaluate fewer transcendental functions; the result is
checked against the original graph.
"""

from __future__ import annotations

import casadi as ca
import numpy as np

__all__ = ["algebraic"]


def algebraic(f: ca.Function, check: int = 6, angles: tuple = ()) -> ca.Function:
    """``f`` (an SX Function) with the trigonometric functions of angles that are themselves inverse
    trigonometric results written algebraically, and common subexpressions shared.

    The contact coordinates of a point on the sphere are ``u_o = atan2(-x, -z)``, ``v_o = asin(y)`` (24)-(25),
    and the model takes cos, sin and tan of them; the rewrite uses the identities
    ``cos(atan2(p, q)) = q / sqrt(p^2 + q^2)``, ``sin(atan2(p, q)) = p / sqrt(p^2 + q^2)``,
    ``tan(atan2(p, q)) = p / q``,
    ``cos(asin(p)) = sqrt(1 - p^2)``, ``sin(asin(p)) = p``, ``tan(asin(p)) = p / sqrt(1 - p^2)`` on the expression
    graph (no equation of the model is retyped: the graph is replayed instruction by instruction), then
    :func:`casadi.cse`. The result is checked against ``f`` at ``check`` random points (relative 1e-12).

    With ``angles`` (indices of scalar inputs), the result takes ``cos t`` and ``sin t`` (inputs ``cos_<name>``,
    ``sin_<name>``) in place of each such input t: ``cos t``, ``sin t`` and ``tan t`` of the graph become them; a
    ValueError if the graph uses t otherwise.
    """
    ins = f.sx_in()
    flat_in = [ca.vertsplit(ca.vec(x)) if x.numel() else [] for x in ins]
    unit = {j: [ca.SX.sym(f"{how}_{f.name_in(j)}") for how in ("cos", "sin")] for j in angles}
    orig, ins = ins, [x for j, x in enumerate(ins) for x in unit.get(j, [x])]
    names = [n for j, n in enumerate(f.name_in()) for n in ([u.name() for u in unit[j]] if j in unit else [n])]
    w, src = [None] * f.sz_w(), [None] * f.sz_w()
    outs = [[ca.SX(0)] * f.nnz_out(i) for i in range(f.n_out())]
    trig = (ca.OP_COS, ca.OP_SIN, ca.OP_TAN)
    for n in range(f.n_instructions()):
        op, o, i = f.instruction_id(n), f.instruction_output(n), f.instruction_input(n)
        if op == ca.OP_INPUT:
            w[o[0]], src[o[0]] = flat_in[i[0]][i[1]], ("angle", i[0], None) if i[0] in unit else None
        elif op == ca.OP_OUTPUT:
            outs[o[0]][o[1]] = w[i[0]]
        elif op == ca.OP_CONST:
            w[o[0]], src[o[0]] = ca.SX(f.instruction_constant(n)), None
        else:
            a, origin, val = w[i[0]], src[i[0]], None
            if op in trig and origin is not None:
                p, q = origin[1], origin[2]
                if origin[0] == "angle":
                    c, s = unit[p]
                    val = (c, s, s / c)[trig.index(op)]
                elif origin[0] == ca.OP_ATAN2:
                    r = ca.sqrt(p * p + q * q)
                    val = (q / r, p / r, p / q)[trig.index(op)]
                else:
                    c = ca.sqrt(1 - p * p)
                    val = (c, p, p / c)[trig.index(op)]
            if val is None:
                val = ca.SX.unary(op, a) if len(i) < 2 or i[1] < 0 else ca.SX.binary(op, a, w[i[1]])
            w[o[0]] = val
            src[o[0]] = (op, a, w[i[1]]) if op == ca.OP_ATAN2 else ((op, a, None) if op == ca.OP_ASIN else None)
    res = [ca.SX(f.sparsity_out(j), ca.vertcat(*outs[j])) if outs[j] else ca.SX(f.sparsity_out(j))
           for j in range(f.n_out())]
    for j in angles:
        if any(ca.depends_on(r, orig[j]) for r in res):
            raise ValueError(f"{f.name()} depends on {f.name_in(j)} otherwise than by its cos and sin")
    g = ca.Function(f.name(), ins, ca.cse(res), names, f.name_out())
    rng = np.random.default_rng(1)
    for _ in range(check):
        args = [rng.uniform(0.05, 0.65, x.numel()) for x in orig]
        g_args = [v for j, x in enumerate(args) for v in ([np.cos(x), np.sin(x)] if j in unit else [x])]
        want, got = (np.concatenate([np.array(v).ravel() for v in h.call(a)]) for h, a in ((f, args), (g, g_args)))
        if not np.allclose(got, want, rtol=1e-12, atol=1e-12 * (1.0 + np.abs(want).max())):
            raise ValueError(f"the algebraic form of {f.name()} differs from the original")
    return g
