"""What the timing protocol's stopping rule costs: replay the samples a work-precision run recorded
under other values of ``budget_s``, ``min_repeats`` and ``spread``.

    python benchmarks/timing_budget.py results/work_precision   # -> docs/evidence/timing_budget.json

Every timed run of the study records its accepted samples' CPU seconds in order (``times``), the
calls per sample and the reference kernel's time (``ref_s``).  Replaying a sequence under another
rule stops it at the first sample where that rule stops (``timing.Timer``'s order: the budget, then
``max_repeats``, then ``min_repeats`` samples within ``spread``); a rule that would want more samples
than were taken keeps them all, so the fractions are upper bounds.  The budget counts each sample's
calls and the kernel run after it; the spread is taken of the CPU seconds, which on a quiet machine
follow the reference units the study uses.  For each rule: the seconds of sampling it keeps, as a
fraction of what the run took, and how far each run's median moves (largest relative change).
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RULES = [  # (budget_s, min_repeats, spread): the shipped rule first
    (20.0, 3, 0.05),
    (10.0, 3, 0.05),
    (20.0, 2, 0.05),
    (10.0, 2, 0.05),
    (6.0, 3, 0.05),
]
MAX_REPEATS = 7


def spread(values: list[float]) -> float:
    mid = statistics.median(values)
    return (max(values) - min(values)) / mid if len(values) > 1 and mid > 0 else 0.0


def samples_kept(times: list[float], calls: int, kernel_s: float, rule: tuple[float, int, float]) -> int:
    """How many of the recorded samples the rule takes before it stops."""
    budget, min_repeats, tolerance = rule
    wall = kernel_s  # the kernel before the first sample
    for k in range(1, len(times) + 1):
        wall += times[k - 1] * calls + kernel_s
        if wall >= budget or k >= MAX_REPEATS or (k >= min_repeats and spread(times[k - min_repeats : k]) <= tolerance):
            return k
    return len(times)


def replay(runs: list[tuple[list[float], int, float]]) -> dict:
    def cost(n: int, times: list[float], calls: int, kernel_s: float) -> float:
        return sum(t * calls + kernel_s for t in times[:n]) + kernel_s

    recorded = sum(cost(len(t), t, c, k) for t, c, k in runs)
    out = {}
    for rule in RULES:
        kept = [samples_kept(t, c, k, rule) for t, c, k in runs]
        seconds = sum(cost(n, t, c, k) for n, (t, c, k) in zip(kept, runs, strict=True))
        moves = [
            abs(statistics.median(t[:n]) / statistics.median(t) - 1.0) for n, (t, _, _) in zip(kept, runs, strict=True)
        ]
        out[f"budget_s={rule[0]:g} min_repeats={rule[1]} spread={rule[2]:g}"] = {
            "sampling_s": seconds,
            "fraction": seconds / recorded,
            "samples": sum(kept),
            "largest_median_change": max(moves),
            "median_median_change": statistics.median(moves),
        }
    return {"recorded_sampling_s": recorded, "rules": out}


def read_runs(directory: Path) -> list[tuple[list[float], int, float]]:
    runs = []
    for path in sorted(directory.glob("N*/work_precision/*.json")):
        for record in json.loads(path.read_text(encoding="utf-8"))["records"]:
            if record.get("time_runs") and record.get("times"):
                times = [float(x) for x in str(record["times"]).split()]
                runs.append((times, int(record.get("calls") or 1), float(record.get("ref_s") or 0.0)))
    return runs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("results", type=Path, help="a study's results directory (results/work_precision)")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/timing_budget.json")
    parser.add_argument("--note", default="", help="what the replayed run was (machine, load, jobs)")
    args = parser.parse_args(argv)
    runs = read_runs(args.results)
    if not runs:
        raise SystemExit(f"no timed runs under {args.results}")
    out = {"date": time.strftime("%Y-%m-%d %H:%M"), "note": args.note, "runs": len(runs), **replay(runs)}
    args.out.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    for name, rec in out["rules"].items():
        moved = rec["largest_median_change"]
        print(f"{name}: {rec['fraction']:.2f} of the sampling, medians moved by at most {moved:.3f}")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
