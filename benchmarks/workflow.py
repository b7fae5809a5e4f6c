"""Wall time of the workflow itself, in a temporary copy of the repository (Snakefile, workflow/, src/):

    python benchmarks/workflow.py            # -> results/benchmarks/bench.json

- ``cold_s``: one ``snakemake -c2 all`` from an empty cache;
- ``noop_s``: ``snakemake -c2 all`` on the built cache ("Nothing to be done"), median of ``--repeats`` (5);
- ``dry_run_s``: ``snakemake -n all`` on the built cache, median of ``--repeats``;

with every single run, the 1-minute load average before each and the machine.  The JSON is written
atomically.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))


def timed(repo: Path, *args: str) -> tuple[float, str]:
    """Wall time of one Snakemake call in ``repo`` and its output; a failed call raises."""
    t0 = time.perf_counter()
    proc = subprocess.run([SNAKEMAKE, *args], cwd=repo, capture_output=True, encoding="utf-8")
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"snakemake {' '.join(args)} failed:\n{proc.stderr[-3000:]}")
    return seconds, proc.stdout + proc.stderr


def repeated(repo: Path, repeats: int, *args: str) -> dict:
    runs, loads = [], []
    for _ in range(repeats):
        loads.append(os.getloadavg()[0])
        seconds, out = timed(repo, *args)
        if "Nothing to be done" not in out:
            raise RuntimeError(f"snakemake {' '.join(args)} was not a no-op:\n{out[-2000:]}")
        runs.append(seconds)
    return {"median_s": statistics.median(runs), "runs_s": runs, "load1_before": loads}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, default=ROOT / "results/benchmarks/bench.json")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT / "src"))
    from signorini.pipeline.artifacts import save_json

    with tempfile.TemporaryDirectory(prefix="signorini-bench-") as tmp:
        repo = Path(tmp)
        shutil.copy2(ROOT / "Snakefile", repo / "Snakefile")
        for name in ("workflow", "src"):
            shutil.copytree(ROOT / name, repo / name, ignore=shutil.ignore_patterns("__pycache__"))
        load_cold = os.getloadavg()[0]
        cold_s, _ = timed(repo, "-c2", "all", "-q")
        result = {
            "cold_s": cold_s,
            "cold_load1_before": load_cold,
            "noop_s": repeated(repo, args.repeats, "-c2", "all", "-q"),
            "dry_run_s": repeated(repo, args.repeats, "-n", "all"),
        }
    result["machine"] = {"cpus": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version()}
    result["date"] = time.strftime("%Y-%m-%d %H:%M:%S")
    result["note"] = "wall times of whole Snakemake calls (interpreter start included) in a copy of the repository"
    save_json(args.out, result)
    print(
        f"cold snakemake -c2 all: {cold_s:.1f} s; no-op: {result['noop_s']['median_s']:.2f} s; "
        f"dry run: {result['dry_run_s']['median_s']:.2f} s (medians of {args.repeats}) -> {args.out}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
