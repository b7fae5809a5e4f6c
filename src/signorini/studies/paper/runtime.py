"""Stage ``runtime``: ``paper_figures/runtime.csv``, the run times of the rendered scene's
``discretise``, ``solve`` and ``norm`` jobs."""

from __future__ import annotations

import csv
import io
import os
from collections.abc import Mapping, Sequence

from signorini.pipeline.artifacts import CorruptArtifactError, atomic_write_text, load_json

BENCHMARK_FIELDS = {"s": "benchmark_wall_s", "cpu_time": "benchmark_cpu_s", "max_rss": "benchmark_max_rss_mb"}
# the in-job timer of each rule: (keys of the first artifact's timings, keys of every artifact's
# timings, what they cover); a per-mesh norms job builds its mesh once for all its norms
TIMERS = {
    "discretise": ((), ("build_s",), "mesh + assembly"),
    "solve": ((), ("load_s", "solve_s"), "load system + solve"),
    "norm": ((), ("mesh_s", "norm_s"), "mesh + error evaluation + norm"),
    "norms": (("mesh_s",), ("norm_s",), "mesh + error evaluation + norms (those under the conventions together)"),
}
COLUMNS = ["rule", "scene", "N", "norm", *BENCHMARK_FIELDS.values(), "timer_s", "timer_scope"]


def _last_benchmark(path: str | os.PathLike) -> Mapping[str, str]:
    with open(path, encoding="utf-8") as fh:
        rows = list(csv.DictReader(fh, delimiter="\t"))
    if not rows:
        raise CorruptArtifactError(f"{path}: empty benchmark file")
    return rows[-1]


def _timer(rule: str, artifacts: Sequence[Mapping]) -> float:
    """The in-job timer of a job from its artifacts' ``timings``; norms evaluated together
    (``norm_shared_by``) record their common time in each artifact, counted once."""
    once, each, _ = TIMERS[rule]

    def total(artifact: Mapping, keys: Sequence[str]) -> float:
        timings = artifact.get("timings", {})
        return sum(float(timings.get(key, 0.0)) for key in keys)

    seen, time_s = set(), total(artifacts[0], once)
    for artifact in artifacts:
        group = tuple(artifact.get("timings", {}).get("norm_shared_by", ()))
        if group and group in seen:
            continue
        seen.add(group)
        time_s += total(artifact, each)
    return time_s


def runtime_stage(jobs: Sequence[Mapping], out_csv: str | os.PathLike) -> None:
    """``runtime.csv`` from the jobs' ``benchmark:`` files and their in-job timers.

    ``jobs``: one mapping per job with ``rule``, ``scene``, ``N``, ``norm`` (or "", or the norms
    of a per-mesh job), ``benchmark`` (the TSV path) and ``artifacts`` (the job's JSONs, holding
    its timers).
    ``benchmark_*`` columns time the whole job (interpreter start, imports, I/O);
    ``timer_s`` is the timer around the measured call inside the job (``timer_scope``).
    """
    out = io.StringIO()
    writer = csv.DictWriter(out, COLUMNS, lineterminator="\n")
    writer.writeheader()
    for job in jobs:
        bench = _last_benchmark(job["benchmark"])
        record = {"rule": job["rule"], "scene": job["scene"], "N": int(job["N"]), "norm": job.get("norm", "")}
        for key, column in BENCHMARK_FIELDS.items():
            value = bench.get(key, "")
            record[column] = f"{float(value):.3f}" if value not in ("", "NA", "-") else ""
        record["timer_s"] = f"{_timer(job['rule'], [load_json(path) for path in job['artifacts']]):.3f}"
        record["timer_scope"] = TIMERS[job["rule"]][2]
        writer.writerow(record)
    atomic_write_text(out_csv, out.getvalue())
