"""Time per-mesh jobs of this tree against those of a git revision, in turn, so that each ratio is
measured in one run.

    python benchmarks/stage_jobs.py --baseline 9c38473 --N 1001 --stages theory_quantities L4 Linf W14 L4_true
    python benchmarks/stage_jobs.py --baseline HEAD~3 --N 201 --repeats 2 --out /tmp/s.json   # a quick check

A job is a stage function as the pipeline's job runs it: ``benchmarks/scale.py``'s child, a fresh
process with one BLAS thread (``theory_quantities``, ``convention_norms``, one norm by name — any of
the theory scene's norms, ``_true`` ones included —, ``discretise``, ``solve_direct``,
``solve_multigrid``).  All jobs read the same assembled system and multigrid solution, made once by
this tree in ``--workdir``; the baseline's jobs import ``signorini`` from a git worktree of
``--baseline`` (in a temporary directory, removed at the end).  The two trees run alternately,
``--repeats`` times each (baseline, tree, baseline, tree, ...), so a drift of the machine's speed
hits both alike; ``--warm-up`` unrecorded runs of each tree come first (a fresh worktree compiles
its kernels in its first run).  Per stage the JSON holds each tree's CPU seconds (every run, the median) and peak
resident memory, ``ratio_cpu``: the median of the pairwise ratios tree / baseline,
``ratio_cpu_interval``: the ratio of the two trees' median CPU times with its bootstrap interval and
verdict (``signorini.intervals``: a tie when the interval contains 1), and the 1-minute load average
before and after every run (``loaded_runs``: the runs under a load above the cores).
"""

from __future__ import annotations

import argparse
import functools
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCALE = ROOT / "benchmarks/scale.py"


@functools.cache
def _scale():
    """``benchmarks/scale.py`` as a module: its child runs one stage as the pipeline's job does."""
    spec = importlib.util.spec_from_file_location("scale_benchmark", SCALE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def run_job(stage: str, N: int, workdir: Path, src: Path, timeout_s: float) -> dict:
    """One job of ``stage`` on mesh N with ``signorini`` imported from ``src``: its CPU and wall
    seconds, peak RSS and the load average before and after (or why it failed)."""
    return _scale().run_child(stage, N, workdir, timeout_s, src=src)


def summarise(runs: dict[str, list[dict]]) -> dict:
    """Per tree: every run's CPU seconds, their median and the peak RSS; the median of the pairwise
    CPU ratios tree / baseline, and the ratio of the medians with its interval and verdict."""
    from signorini import intervals

    out: dict = {}
    for tree, records in runs.items():
        cpu = [r["cpu_s"] for r in records if "cpu_s" in r]
        out[tree] = {
            "cpu_s": cpu,
            "median_cpu_s": statistics.median(cpu) if cpu else None,
            "peak_rss_gib": max((r["peak_rss_gib"] for r in records if "peak_rss_gib" in r), default=None),
            "failed": [r.get("failed") or r.get("skipped") for r in records if "cpu_s" not in r],
        }
    pairs = [
        t["cpu_s"] / b["cpu_s"]
        for b, t in zip(runs["baseline"], runs["tree"], strict=False)
        if "cpu_s" in b and "cpu_s" in t and b["cpu_s"] > 0
    ]
    out["ratio_cpu"] = statistics.median(pairs) if pairs else None
    if out["tree"]["cpu_s"] and out["baseline"]["cpu_s"]:
        tree, base = (intervals.median(out[k]["cpu_s"], (k,)) for k in ("tree", "baseline"))
        ratio = intervals.ratio(tree, base)
        out["ratio_cpu_interval"] = ratio.summary() | {"verdict": intervals.verdict(ratio)}
    return out


def measure(args: argparse.Namespace, baseline_src: Path) -> dict:
    trees = {"baseline": baseline_src, "tree": ROOT / "src"}
    for stage in ("discretise", "solve_multigrid"):  # the inputs of every job, made once by this tree
        name = "system.npz" if stage == "discretise" else "solution_multigrid.npz"
        if not (args.workdir / f"N{args.N}" / name).exists():
            made = run_job(stage, args.N, args.workdir, trees["tree"], args.timeout)
            if "cpu_s" not in made:
                raise SystemExit(f"{stage} at N = {args.N} failed: {made}")
    stages, loads, loaded = {}, [], []
    cores = os.cpu_count() or 1
    for stage in args.stages:
        for _ in range(args.warm_up):  # not recorded: compiles each tree's kernels into its cache
            for src in trees.values():
                run_job(stage, args.N, args.workdir, src, args.timeout)
        runs: dict[str, list[dict]] = {"baseline": [], "tree": []}
        for k in range(args.repeats):
            for tree, src in trees.items():
                record = run_job(stage, args.N, args.workdir, src, args.timeout)
                runs[tree].append(record)
                loads += record["load1"]
                if max(record["load1"]) > cores:
                    loaded.append(f"{stage}/{tree}/{k}")
                print(f"{stage} {tree}: {record}", file=sys.stderr, flush=True)
        stages[stage] = summarise(runs) | {"runs": runs}
    return {
        "stages": stages,
        "load1": {"min": min(loads), "median": statistics.median(loads), "max": max(loads), "cores": cores},
        "loaded_runs": loaded,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--baseline", required=True, help="a git revision of this repository")
    parser.add_argument("--N", type=int, default=1001)
    parser.add_argument("--stages", nargs="+", default=["theory_quantities", "L4", "Linf", "W14", "L4_true"])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--warm-up", type=int, default=0, help="unrecorded runs of each tree per stage first (its compiled kernels)"
    )
    parser.add_argument("--workdir", type=Path, default=ROOT / "results/benchmarks/scale")
    parser.add_argument("--timeout", type=float, default=1800.0, help="per job, seconds")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/stage_jobs.json")
    args = parser.parse_args(argv)
    from signorini.pipeline.jobenv import job_environment

    # the jobs' environment (threads, allocator) before they start: glibc reads it at start-up
    job_environment()
    t0 = time.time()
    git = ["git", "-C", str(ROOT)]

    def ask(*words: str) -> str:
        return subprocess.run([*git, *words], capture_output=True, text=True, encoding="utf-8", check=True).stdout

    revision, head = ask("rev-parse", args.baseline), ask("rev-parse", "HEAD")
    dirty = ask("status", "--porcelain", "src")
    with tempfile.TemporaryDirectory() as tmp:
        worktree = Path(tmp) / "baseline"
        subprocess.run([*git, "worktree", "add", "--detach", str(worktree), args.baseline], check=True)
        try:
            result = measure(args, worktree / "src")
        finally:
            subprocess.run([*git, "worktree", "remove", "--force", str(worktree)], check=False)
    out = {
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "N": args.N,
        "unknowns": (args.N + 1) ** 2,
        "baseline": revision.strip(),
        "tree": head.strip() + (" (with uncommitted changes in src/)" if dirty.strip() else ""),
        "repeats": args.repeats,
        "warm_up": args.warm_up,
        **result,
        "wall_s": time.time() - t0,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    for stage, rec in out["stages"].items():
        print(f"{stage}: tree / baseline CPU = {rec['ratio_cpu']}", flush=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
