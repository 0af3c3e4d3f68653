"""How the commands print results: numbers, states, plans and how they were found."""

from __future__ import annotations

from .common import NORM

__all__ = ["num", "fmt_plan", "fmt_all", "fmt_state", "fmt_psi", "fmt_solver", "fmt_composed"]


def num(x) -> str:
    """A number in a summary: 6 significant digits."""
    return f"{x:.6g}"


def fmt_plan(p, unit) -> str:
    f = p.final
    lines = [
        f"  figure eight  a = {num(p.a)} {unit}   b = {num(p.b)} {unit}   gamma = {num(p.gamma)} rad"
        f"   (branch m = {p.branch}{'' if p.curve == 'circles' else f', curve {p.curve}'})",
        f"  one step      h = {num(p.h)} {unit}   eta = {num(p.eta)} rad",
        f"  path length   {num(p.path_length)} {unit}",
        f"  final         u_a = {num(f.u_a)} {unit}  v_a = {num(f.v_a)} {unit}  psi = {fmt_psi(f.psi)}"
        f"  u_o = {f.u_o:.3g} rad  v_o = {f.v_o:.3g} rad",
        f"  residual      {p.residual:.2e} ({NORM}; {p.certificate.method}, independent of the planner"
        f"{f', integration error bound {p.certificate.error_bound:.1e}' if p.certificate.error_bound else ''})",
    ]
    return "\n".join(lines)


def fmt_all(p, unit) -> str:
    """``--all``: one line per plan (the figure eights of one leg), shortest first, and the count."""
    plans = [p] + list(p.alternatives)
    lines = [f"all plans: {len(plans)} (shortest first; a, b [{unit}], gamma [rad], L = contact path [{unit}])",
             f"  {'m':>6} {'a':>12} {'b':>12} {'gamma':>12} {'L':>12} {'residual':>9}"]
    for q in plans:
        e = q.legs[0] if q.legs else q
        if not hasattr(e, "branch"):
            lines.append(f"  {'-':>6} {'-':>12} {'-':>12} {'-':>12} {q.path_length:>12.6f} {q.residual:>9.1e}")
            continue
        lines.append(f"  {e.branch:>6d} {e.a:>12.9f} {e.b:>12.9f} {e.gamma:>12.9f} {q.path_length:>12.6f} "
                     f"{q.residual:>9.1e}")
    return "\n".join(lines)


def fmt_state(x, unit, wrapped=False) -> str:
    """A state (u_a, v_a, psi, u_o, v_o) with its units: lengths in ``unit``, angles in rad; with ``wrapped``
    psi wrapped (:func:`fmt_psi`), as a final state is printed."""
    units = (unit, unit, "rad", "rad", "rad")
    parts = [f"{num(float(v))} {u}" for v, u in zip(x, units)]
    if wrapped:
        parts[2] = fmt_psi(x[2])
    return "(" + ", ".join(parts) + ")"


def fmt_psi(psi) -> str:
    """A reached psi wrapped to [-pi, pi], with the whole turns taken off (if any)."""
    from ..core.plane import wrap_exact

    w, turns = wrap_exact(float(psi))
    return f"{num(w)} rad" + (f" (wrapped; unwrapped {num(float(psi))} rad, {turns:+d} turn{'s' * (abs(turns) != 1)})"
                             if turns else "")


def fmt_solver(stats) -> str:
    """How the plan was found, in words (the JSON keeps the solver's own status and iteration count)."""
    d, n = stats.details, stats.iterations
    if stats.method == "none":
        return "none needed: the rolls alone, in closed form"
    if stats.method == "brentq":
        return f"circles of the turn by a scalar root (brentq); {stats.time_s * 1e3:.1f} ms"
    if d.get("mode") == "based":
        return (f"{d['screened']} base point(s) screened by the pole search, {len(d['bases'])} solved locally by "
                f"{stats.method} ({stats.status}; not a complete search); {stats.time_s * 1e3:.1f} ms")
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


def fmt_composed(p, unit) -> str:
    """The lines of a composed plan (rollplan.planners.geometric.composed.ComposedPlan)."""
    R = p.radius
    what = {"empty": "the start is the goal: no motion", "rolls": "the approach and departure rolls alone",
            "one": "one leg of figure eights", "turn": "turn in place by pairs of equal circles",
            "two": "two legs of figure eights through an intermediate pole state",
            "based": "one leg of figure eights at a base point off the pole, between great-circle rolls"}[p.mode]
    lines = [f"  mode          {p.mode}: {what}"]
    if p.approach is not None:
        lines.append(f"  approach      roll of {num(p.approach.sigma * R)} {unit} to the pole along the great circle "
                     f"(direction beta = {num(p.approach.beta)} rad)")
    if p.legs or p.turn is not None:
        t = p.target
        lines.append(f"  eights do     (u_a, v_a, psi) = ({num(t[0] * R)} {unit}, {num(t[1] * R)} {unit}, "
                     f"{num(t[2])} rad) from rest at the pole")
    for i, leg in enumerate(p.legs, 1):
        s = R / leg.radius
        lines.append(f"  leg {i}         {leg.steps} x figure eight a = {num(leg.a * s)} {unit}   b = {num(leg.b * s)} "
                     f"{unit}   gamma = {num(leg.gamma)} rad   (branch m = {leg.branch})")
    if getattr(p, "base", None) is not None:
        e = p.base
        lines.append(f"  base point    {num(e.sigma)} rad from the pole (direction beta = {num(e.beta)} rad); "
                     f"{e.steps} x figure eight a = {num(e.a * R)} {unit}   b = {num(e.b * R)} {unit}   "
                     f"orientation = {num(e.orientation)} rad ({e.guarantee})")
    if p.turn is not None:
        tr = p.turn
        lines.append(f"  turn          {tr.steps} pair(s) of circles b = {num(tr.b * R)} {unit} "
                     f"({'+y' if tr.side == 0 else '-y'} side), eta = {num(tr.eta)} rad each")
    if p.departure is not None:
        lines.append(f"  departure     roll of {num(p.departure.sigma * R)} {unit} from the pole along the great "
                     f"circle (direction beta = {num(p.departure.beta)} rad)")
    lines += [f"  path length   {num(p.path_length)} {unit} in {len(p.pieces)} pieces",
              f"  final         {fmt_state(p.final, unit, wrapped=True)}",
              f"  residual      {p.residual:.2e} ({NORM}; {p.certificate.method}, the whole motion from the start "
              "state)"]
    return "\n".join(lines)
