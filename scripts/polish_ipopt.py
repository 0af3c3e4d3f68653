"""Which plans IPOPT's polish changes: the default plan (C search, C Newton polish, C RK8 certificate in one call)
against the same root polished again by IPOPT (``root_solver="ipopt"``) and certified by the Python RK8 certifier.

    python scripts/polish_ipopt.py [--per-k 24] [--out-dir results]

Writes ``polish_ipopt.md`` and ``polish_ipopt.json``. For random pole-to-pole targets (|u_a|, |v_a| <= 1.5 R,
|psi| <= 3 rad, n = 1..3) at several k, both paths are run; per plan: the change of (a, b) by IPOPT, its iterations,
the residual of (32)-(33) on the leaf map (``refine.leaf_residual``) at the C root and at IPOPT's, and the certified
residual + bound of both paths.
"""

from __future__ import annotations

import argparse
import datetime
import math
import sys
from pathlib import Path


def parse_args(argv=None):
    """The command line, read before the slow imports below (a bad option is refused at once)."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-k", type=int, default=24, help="targets per k (default 24)")
    ap.add_argument("--out-dir", default="results", help="where to write polish_ipopt.md and .json")
    return ap.parse_args(argv)


if __name__ == "__main__":
    parse_args()

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))

import rollplan  # noqa: E402
from rollplan.core.plane import target_shift, wrap_exact  # noqa: E402
from rollplan.io import write_atomic, write_json  # noqa: E402
from rollplan.planners.geometric.leafmap import panels_for  # noqa: E402
from rollplan.planners.geometric.refine import leaf_residual  # noqa: E402

from benchmark import git_commit  # noqa: E402

KS = (0.0, 0.3, 1.0, 2.5, 5.0, 10.0, 30.0)


def leaf_miss(a, b, k, target, steps, branch):
    """|F(a, b)| of (32)-(33) on the leaf map on the plan's branch (units of R and rad)."""
    psi_w, turns = wrap_exact(target[2])
    eta = (psi_w + 2 * math.pi * (branch + turns)) / steps
    h = float(target_shift(math.hypot(target[0], target[1]), eta, steps))
    f = leaf_residual(panels_for(k))([a, b], [k, eta, h])
    return float(np.linalg.norm(np.array(f).ravel()))


def measure(per_k: int, seed: int = 0) -> dict:
    rng = np.random.default_rng(seed)
    rows = []
    for k in KS:
        for _ in range(per_k):
            target = (float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-1.5, 1.5)), float(rng.uniform(-3, 3)))
            steps = int(rng.integers(1, 4))
            try:
                c = rollplan.plan(target, steps, k=k, legs="one")
            except rollplan.NoPlanError:
                try:
                    rollplan.plan(target, steps, k=k, legs="one", root_solver="ipopt")
                    rows.append({"k": k, "n": steps, "target": target, "outcome": "IPOPT only"})
                except rollplan.NoPlanError:
                    rows.append({"k": k, "n": steps, "target": target, "outcome": "no plan (both)"})
                continue
            q = rollplan.plan(target, steps, k=k, legs="one", root_solver="ipopt")
            rows.append({"k": k, "n": steps, "target": target, "outcome": "plan (both)",
                         "same branch": q.branch == c.branch,
                         "da": q.a - c.a, "db": q.b - c.b, "ipopt iterations": q.stats.iterations,
                         "ipopt status": q.stats.status,
                         "leaf residual C": leaf_miss(c.a, c.b, k, target, steps, c.branch),
                         "leaf residual IPOPT": leaf_miss(q.a, q.b, k, target, steps, q.branch),
                         "certified C": c.certificate.residual + c.certificate.error_bound,
                         "certified IPOPT": q.certificate.residual + q.certificate.error_bound})
    return {"rows": rows}


def summary(rows) -> dict:
    both = [r for r in rows if r["outcome"] == "plan (both)"]
    moved = [r for r in both if r["da"] != 0.0 or r["db"] != 0.0]
    better = [r for r in both if r["leaf residual IPOPT"] < r["leaf residual C"]]
    return {"targets": len(rows), "plans": len(both), "no plan (both)": sum(r["outcome"] == "no plan (both)"
                                                                             for r in rows),
            "plan by IPOPT only": sum(r["outcome"] == "IPOPT only" for r in rows),
            "other branch": sum(not r["same branch"] for r in both),
            "(a, b) changed by IPOPT": len(moved),
            "largest change of a or b [R]": max((max(abs(r["da"]), abs(r["db"])) for r in both), default=0.0),
            "IPOPT iterations (max)": max((r["ipopt iterations"] for r in both), default=0),
            "leaf residual lower after IPOPT": len(better),
            "largest leaf residual C": max((r["leaf residual C"] for r in both), default=0.0),
            "largest leaf residual IPOPT": max((r["leaf residual IPOPT"] for r in both), default=0.0),
            "largest certified residual + bound, C": max((r["certified C"] for r in both), default=0.0),
            "largest certified residual + bound, IPOPT path": max((r["certified IPOPT"] for r in both), default=0.0)}


def to_markdown(report) -> str:
    s = report["summary"]
    lines = ["# Which plans IPOPT's polish changes", "",
             f"{report['date']}, commit {report['commit']}; written by scripts/polish_ipopt.py.", "",
             "Random pole-to-pole targets (|u_a|, |v_a| <= 1.5 R, |psi| <= 3 rad, n = 1..3), "
             f"{report['per_k']} per k for k in {', '.join(f'{k:g}' for k in KS)}: the default plan (C search, C "
             "Newton polish, C RK8 certificate) against `root_solver=\"ipopt\"` (the C search's root polished again "
             "by IPOPT, then the Python RK8 certificate).", "",
             "| quantity | value |", "|---|---:|"]
    lines += [f"| {key} | {value:.3g} |" if isinstance(value, float) else f"| {key} | {value} |"
              for key, value in s.items()]
    lines += ["", "Leaf residual: |F(a, b)| of (32)-(33) on the leaf map (units of R and rad) at the plan's (a, b); "
              "certified: the certificate's residual plus its error bound (accepted when <= 1e-9).", "",
              "| k | n | target | da | db | IPOPT it. | leaf res. C | leaf res. IPOPT | cert. C | cert. IPOPT |",
              "|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in report["rows"]:
        t = "(" + ", ".join(f"{x:.3f}" for x in r["target"]) + ")"
        if r["outcome"] != "plan (both)":
            lines.append(f"| {r['k']:g} | {r['n']} | {t} | {r['outcome']} | | | | | | |")
            continue
        lines.append(f"| {r['k']:g} | {r['n']} | {t} | {r['da']:.1e} | {r['db']:.1e} | {r['ipopt iterations']} | "
                     f"{r['leaf residual C']:.1e} | {r['leaf residual IPOPT']:.1e} | {r['certified C']:.1e} | "
                     f"{r['certified IPOPT']:.1e} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> int:
    args = parse_args(argv)
    m = measure(args.per_k)
    report = {"date": datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC"),
              "commit": git_commit(), "per_k": args.per_k, "summary": summary(m["rows"]), "rows": m["rows"]}
    out = Path(args.out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "polish_ipopt.json", report)
    write_atomic(out / "polish_ipopt.md", to_markdown(report).encode(), "polish_ipopt.md")
    print(to_markdown(report).split("\n\n| k |")[0])
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
