"""The frontier's reach in the first Newton step from the cascade's warm start (the exact routes'
option ``warm_start_reach``, ``signorini.solvers.pdas.WARM_START_REACH``): one node against two,
on the paper's problem from N = 101 to 2001 and on cases of the stability atlas, for both exact
routes (the direct one up to N = 1001):

    python benchmarks/frontier_first_reach.py [--N 101 201 ...] [--out FILE]

What a solve counts does not depend on the machine's speed: per case, route and reach the
JSON holds the Newton steps, the V-cycles on the final mesh (the multigrid route), the contact
set's size, and whether the two reaches gave the same contact set and u to 1e-12 · max |u|.  The
totals sum each count over the cases; ``worse`` lists the runs that took more steps or V-cycles
with two nodes than with one.
"""

from __future__ import annotations

import argparse
import json
import platform
import time
from pathlib import Path

import numpy as np

from signorini.fem.discrete import build
from signorini.fem.problem import make_problem
from signorini.fem.solve import solve_discrete

ROOT = Path(__file__).resolve().parents[1]
REACHES = (1, 2)
ROUTES = ("multigrid", "active_set")
DIRECT_MAX_N = 1001  # the direct route above it: minutes per solve (docs/evidence/scale.json)
# cases of the stability atlas (workflow/config.yaml) that both exact routes solve, at their N
ATLAS_CASES = {
    "c_0": ({"c": 0.0}, 101),
    "c_1e+04": ({"c": 1.0e4}, 101),
    "A_1e+06": ({"A": 1.0e6}, 101),
    "biactive_R0.1": ({"R": 0.1}, 101),
    "x0_0.6_R0.3": ({"x0": 0.6, "R": 0.3}, 201),
    "R_0.3": ({"R": 0.3}, 201),
}


def counts(result) -> dict:
    return {
        "newton_steps": result.iterations,
        "v_cycles": result.info.get("v_cycles"),
        "contact_nodes": int(result.active.size),
    }


def run(problem_params: dict, N: int) -> dict:
    disc = build(make_problem(problem_params), N)
    out: dict = {}
    for route in ROUTES if N <= DIRECT_MAX_N else ROUTES[:1]:
        results = {reach: solve_discrete(disc, route, warm_start_reach=reach) for reach in REACHES}
        one, two = results[1], results[2]
        out[route] = {
            **{f"reach{r}": counts(results[r]) for r in REACHES},
            "same_contact_set": bool(np.array_equal(np.sort(one.active), np.sort(two.active))),
            "max_difference_over_max_u": float(np.abs(one.u - two.u).max() / max(np.abs(one.u).max(), 1e-300)),
        }
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, nargs="+", default=[101, 201, 301, 401, 501, 601, 751, 1001, 1501, 2001])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/frontier_first_reach.json")
    args = parser.parse_args()
    cases = {f"paper_N{N}": ({}, N) for N in args.N} | ATLAS_CASES
    runs = {}
    for name, (params, N) in cases.items():
        runs[name] = {"N": N, "problem": params, **run(params, N)}
        print(name, json.dumps({k: v for k, v in runs[name].items() if k in ROUTES}), flush=True)
    totals, worse = {}, []
    for name, case in runs.items():
        for key, value in case.items():
            if key not in ROUTES:
                continue
            for reach in REACHES:
                for count in ("newton_steps", "v_cycles"):
                    if value[f"reach{reach}"][count] is not None:
                        totals.setdefault(key, {}).setdefault(f"reach{reach}", {}).setdefault(count, 0)
                        totals[key][f"reach{reach}"][count] += value[f"reach{reach}"][count]
            one, two = value["reach1"], value["reach2"]
            if two["newton_steps"] > one["newton_steps"] or (two["v_cycles"] or 0) > (one["v_cycles"] or 0):
                worse.append(f"{name} {key}")
    report = {
        "date": time.strftime("%Y-%m-%d"),
        "python": platform.python_version(),
        "reaches": list(REACHES),
        "runs": runs,
        "totals": totals,
        "worse": worse,
        "all_same_contact_sets": all(v["same_contact_set"] for c in runs.values() for k, v in c.items() if k in ROUTES),
    }
    args.out.write_text(json.dumps(report, indent=1) + "\n", encoding="utf-8")
    print(json.dumps({"totals": totals, "worse": worse}, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
