"""How the Table 1 columns move when the QP is solved inexactly.

    python benchmarks/qp_tolerance.py [--N 201] [--out docs/evidence/qp_tolerance.csv]

Solves (S_h) exactly (active set) and with cvxpy/OSQP at a sweep of tolerances
(no polishing, as a generic QP code would return it), and reports each norm of
``u - u_h`` relative to its value for the exact discrete solution, next to the
published cell.  This is the measurement behind the README's remark that the
paper's L⁴ (and H^{1/2}) cells at h = 1/201 cannot be matched by any convention.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import pandas as pd

from signorini.fem.discrete import build
from signorini.fem.norms.conventional import Conventions, compute_norms, error_field
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import cvxpy_solve

ROOT = Path(__file__).resolve().parents[1]
COLUMNS = ["L4", "Linf", "W14", "W1inf", "H12"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--N", type=int, default=201)
    ap.add_argument("--out", type=Path, default=ROOT / "docs/evidence/qp_tolerance.csv")
    args = ap.parse_args()
    problem = Problem()
    disc = build(problem, args.N)
    conv = Conventions()
    exact = solve_discrete(disc)
    ref = compute_norms(error_field(problem, disc.mesh, exact.u, conv), COLUMNS)
    paper = pd.read_csv(ROOT / "workflow/reference/paper_table1.csv", comment="#", encoding="utf-8")
    paper = paper.set_index(paper["h"].str.split("/").str[1].astype(int))
    rows = [{"solver": "active_set", "tol": 0.0, **{c: ref[c] for c in COLUMNS}}]
    for tol in (1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-8):
        res = cvxpy_solve(disc.A, disc.b, disc.boundary, "OSQP", tol=tol, check=False, polish=False, max_iter=200000)
        val = compute_norms(error_field(problem, disc.mesh, res.u, conv), COLUMNS)
        rows.append({"solver": "cvxpy_osqp", "tol": tol, **val, "kkt_worst": res.certificate.worst})
    df = pd.DataFrame(rows)
    for c in COLUMNS:
        df[f"moved_{c}"] = df[c] / ref[c] - 1.0
        df[f"paper_dev_{c}"] = df[c] / paper.loc[args.N, c] - 1.0
    args.out.parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(args.out, index=False, float_format="%.6e", encoding="utf-8")
    print(df[["solver", "tol", *[f"moved_{c}" for c in COLUMNS], *[f"paper_dev_{c}" for c in COLUMNS]]].to_string())


if __name__ == "__main__":
    main()
