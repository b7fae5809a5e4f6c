"""A target of the workflow built from a cold cache: its wall time and the table of its jobs.

    python benchmarks/cold_target.py theory fine --out docs/evidence/cold_targets.json

Each target is built by ``snakemake -c2 <target>`` in a fresh clone of the committed tree (no
results, no Snakemake metadata; the clone's ``src`` first on the path), one target after the other.
Recorded per target: the wall time of the Snakemake call, its exit code, the 1-minute load before
and after, and from the jobs' ``benchmark:`` files (Snakemake's, one per job) the jobs per rule
group with the sums of their wall and CPU seconds and their largest resident memory.  The clone is
removed afterwards unless ``--keep`` (then its path is recorded, ``clone``: its outputs can be copied).

Keys: ``targets[<target>] = {wall_s, exit_code, load1: [before, after], jobs, groups: {<group>:
{jobs, wall_s, cpu_s, max_rss_gib}}, sum_wall_s, sum_cpu_s, longest: [[job, wall_s], ...]}``; the
machine's cores and the date.  A timing under a load above the cores is flagged (``loaded``).
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
# the rule groups of the job table, by the name of the benchmark file (results/<scene>/benchmarks/N<N>/<name>.tsv)
GROUPS = (
    ("true norms", lambda name: name.startswith("norm_") and name.endswith("_true")),
    ("convention norms (one job per norm)", lambda name: name.startswith("norm_")),
    ("convention norms (per mesh)", lambda name: name == "norms"),
    ("theory quantities", lambda name: name == "theory"),
    ("mesh generation", lambda name: name == "mesh"),
    ("discretise", lambda name: name == "discretise"),
    ("solve", lambda name: name == "solve"),
)


def group_of(name: str) -> str:
    """The job table's group of a benchmark file's name (``other`` where none matches)."""
    return next((group for group, matches in GROUPS if matches(name)), "other")


def job_table(results: Path) -> dict:
    """The jobs of the benchmark files under ``results``: per group the count, the sums of wall and
    CPU seconds and the largest resident memory; the sums over all jobs and the five longest."""
    groups: dict[str, dict] = {}
    jobs = []
    for path in sorted(results.glob("*/benchmarks/**/*.tsv")):
        with path.open(encoding="utf-8") as f:
            row = next(csv.DictReader(f, delimiter="\t"))
        wall, cpu = float(row["s"]), float(row.get("cpu_time") or 0.0)
        rss = float(row["max_rss"]) / 1024 if row.get("max_rss") not in (None, "", "NA", "-") else 0.0
        name = path.relative_to(results).as_posix().removesuffix(".tsv")
        jobs.append((name, wall))
        g = groups.setdefault(group_of(path.stem), {"jobs": 0, "wall_s": 0.0, "cpu_s": 0.0, "max_rss_gib": 0.0})
        g["jobs"] += 1
        g["wall_s"] += wall
        g["cpu_s"] += cpu
        g["max_rss_gib"] = max(g["max_rss_gib"], rss)
    return {
        "jobs": len(jobs),
        "groups": groups,
        "sum_wall_s": sum(g["wall_s"] for g in groups.values()),
        "sum_cpu_s": sum(g["cpu_s"] for g in groups.values()),
        "longest": [list(job) for job in sorted(jobs, key=lambda job: -job[1])[:5]],
    }


def build_cold(target: str, keep: bool = False) -> dict:
    """``snakemake -c2 <target>`` in a fresh clone of HEAD: the record of the module docstring."""
    clone = Path(tempfile.mkdtemp(prefix=f"cold-{target}-"))
    try:
        subprocess.run(["git", "clone", "--quiet", "--local", str(ROOT), str(clone)], check=True)
        env = {**os.environ, "PYTHONPATH": str(clone / "src")}
        snakemake = Path(sys.executable).with_name("snakemake")
        load0, t0 = os.getloadavg()[0], time.perf_counter()
        proc = subprocess.run(
            [str(snakemake), "-c2", target], cwd=clone, env=env, capture_output=True, text=True, encoding="utf-8"
        )
        wall = time.perf_counter() - t0
        record = {"wall_s": wall, "exit_code": proc.returncode, "load1": [load0, os.getloadavg()[0]]}
        if proc.returncode:
            record["stderr_tail"] = proc.stderr.strip().splitlines()[-5:]
        if keep:
            record["clone"] = str(clone)
        return record | job_table(clone / "results")
    finally:
        if not keep:
            shutil.rmtree(clone, ignore_errors=True)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("targets", nargs="+")
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--keep", action="store_true", help="keep the clones")
    args = parser.parse_args(argv)
    cores = os.cpu_count() or 1
    out = {"date": time.strftime("%Y-%m-%d %H:%M"), "cores": cores, "targets": {}}
    for target in args.targets:
        record = build_cold(target, args.keep)
        record["loaded"] = max(record["load1"]) > cores
        out["targets"][target] = record
        print(f"{target}: {record['wall_s']:.0f} s, exit {record['exit_code']}, {record['jobs']} jobs", flush=True)
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
