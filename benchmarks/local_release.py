"""The multigrid route from the cascade start with and without settling releases on a patch
(``signorini.solvers.local``), on the paper's problem, one process, one thread:

    python benchmarks/local_release.py [--N 501 1001 2001 4001] [--repeats 2] [--out FILE]

Per mesh the system is assembled once; then the two settings are solved alternately
(``--repeats`` times each: without, with, without, with, ...), so a drift of the machine's speed
hits both alike.  The JSON holds, per mesh and setting, what the solve counted (Newton steps,
V-cycles, fine-grid work units with and without the cascade's, settled releases, the largest
patch), its CPU seconds (every run, the median), the seconds of the local solves, and whether the
two settings gave the same contact set and u to 1e-12 · max |u|; ``ratio_cpu_interval`` the ratio
of the median CPU times (with / without) with its bootstrap interval and verdict
(``signorini.intervals``: a tie when the interval contains 1), and the 1-minute load average
before every run.  It runs in a job's environment (``signorini.pipeline.jobenv``: one thread).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from signorini import intervals
from signorini.fem.discrete import build
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.jobenv import job_environment

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = {"plain": False, "settled": True}  # local_release off, on


def counts(result) -> dict:
    """What one solve counted (deterministic: the same in every repeat)."""
    info, rows = result.info, result.history
    return {
        "newton_steps": result.iterations,
        "v_cycles": info["v_cycles"],
        "work_units": round(info["work_units"], 2),
        "work_units_total": round(info.get("work_units_total", info["work_units"]), 2),
        "local_settles": info["local_settles"],
        "largest_patch": max((row["local_unknowns"] for row in rows if "local_unknowns" in row), default=0),
        # per Newton step: contact nodes / changes / V-cycles, A for an accurate solve
        "steps": [f"{r['active']}/{r['changes']}/{r['v_cycles']}{'A' if r['accurate'] else ''}" for r in rows],
    }


def measure(N: int, repeats: int) -> dict:
    disc = build(Problem(), N)
    runs: dict[str, dict] = {name: {"cpu_s": [], "local_s": [], "load1_before": []} for name in SETTINGS}
    results = {}
    for _ in range(repeats):
        for name, local in SETTINGS.items():
            load = os.getloadavg()[0]
            t0 = time.process_time()
            result = solve_discrete(disc, "multigrid", local_release=local)
            runs[name]["cpu_s"].append(round(time.process_time() - t0, 3))
            runs[name]["local_s"].append(round(result.info["local_s"], 3))
            runs[name]["load1_before"].append(load)
            results[name] = result
    out = {name: counts(results[name]) | runs[name] for name in SETTINGS}
    for name in SETTINGS:
        out[name]["cpu_s_median"] = float(np.median(out[name]["cpu_s"]))
    plain, settled = results["plain"], results["settled"]
    out["same_contact_set"] = bool(np.array_equal(np.sort(plain.active), np.sort(settled.active)))
    out["max_difference_over_max_u"] = float(np.abs(plain.u - settled.u).max() / np.abs(plain.u).max())
    ratio = intervals.ratio(*(intervals.median(np.array(out[k]["cpu_s"]), (k,)) for k in ("settled", "plain")))
    out["ratio_cpu_interval"] = ratio.summary() | {"verdict": intervals.verdict(ratio)}
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, nargs="+", default=[501, 1001, 2001, 4001])
    parser.add_argument("--repeats", type=int, default=2)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/local_release.json")
    args = parser.parse_args()
    environment = job_environment(dict(os.environ))
    if environment != dict(os.environ):  # a job's threads and allocator, set before numpy starts
        os.execve(sys.executable, [sys.executable, *sys.argv], environment)
    result = {
        "machine": {"cpus": os.cpu_count(), "processor": platform.processor() or platform.machine()},
        "problem": "the paper's (Section 7), from the cascade start",
        "meshes": {},
    }
    for N in args.N:
        result["meshes"][str(N)] = measure(N, args.repeats)
        print(
            N,
            json.dumps(
                {
                    k: (v if not isinstance(v, dict) else {kk: vv for kk, vv in v.items() if kk != "steps"})
                    for k, v in result["meshes"][str(N)].items()
                }
            ),
            flush=True,
        )
    args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
