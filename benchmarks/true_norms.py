"""Time every true norm (``<norm>_true``, ``signorini.fem.norms.true``) of Tables 1–2 on the paper's meshes.

    python benchmarks/true_norms.py [--N 101 201 301 401 501] [--out results/benchmarks/true_norms.json]

Reads the certified solutions of the paper scene (``results/paper/N<N>/solution.npz``; build them
with ``snakemake -c2 all``), times the convention norm and the true norm of each name in this process
(best of ``--repeat``, one thread), and writes per mesh and norm: the time, the number of refinement
levels, the value and its estimated quadrature error, with the 1-minute load average at the start
and end (the machine is shared: a load above 2 slows every number).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.norms.true import true_norm
from signorini.pipeline.jobenv import THREAD_VARIABLES
from signorini.published import TABLE2_NORMS
from signorini.studies.scene.store import SceneMesh

ROOT = Path(__file__).resolve().parents[1]


def measure(Ns: list[int], repeat: int) -> list[dict]:
    rows = []
    for N in Ns:
        at = SceneMesh({"x0": 0.5, "R": 0.45, "A": 10.0, "c": 1.0}, N, "sw_ne")
        u_h, mesh, problem = at.load_solution(ROOT / f"results/paper/N{N}/solution.npz"), at.mesh(), at.problem
        for name in TABLE2_NORMS:
            times = {}
            for kind in ("convention", "true"):
                best = float("inf")
                for _ in range(repeat):
                    t0 = time.perf_counter()
                    result = true_norm(problem, mesh, u_h, name) if kind == "true" else evaluate_norms(
                        problem, mesh, u_h, [name]
                    )
                    best = min(best, time.perf_counter() - t0)
                times[kind] = best
            rows.append(
                {
                    "N": N,
                    "norm": name,
                    "convention_s": times["convention"],
                    "true_s": times["true"],
                    "levels": [lv["level"] for lv in result.levels],
                    "value": result.value,
                    "error_estimate": result.error_estimate,
                }
            )
            print(f"N={N} {name}: convention {times['convention']:.2f} s, true {times['true']:.2f} s", flush=True)
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--N", type=int, nargs="+", default=[101, 201, 301, 401, 501])
    parser.add_argument("--repeat", type=int, default=1)
    parser.add_argument("--out", default=str(ROOT / "results/benchmarks/true_norms.json"))
    args = parser.parse_args()
    load0 = os.getloadavg()[0]
    rows = measure(args.N, args.repeat)
    out = {
        "date": time.strftime("%Y-%m-%d"),
        "load_1min": [load0, os.getloadavg()[0]],
        "threads": {name: os.environ.get(name, "unset") for name in THREAD_VARIABLES},
        "rows": rows,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
