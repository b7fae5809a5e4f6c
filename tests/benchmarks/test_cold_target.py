"""benchmarks/cold_target.py: the job table of a cold build from the jobs' benchmark files."""

from __future__ import annotations

from pathlib import Path

import pytest
from helpers import benchmark

cold_target = benchmark("cold_target")

HEADER = "s\th:m:s\tmax_rss\tmax_vms\tmax_uss\tmax_pss\tio_in\tio_out\tmean_load\tcpu_time\n"


def _job(path: Path, wall: float, cpu: float, rss_mb: float) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(HEADER + f"{wall}\t0:00:01\t{rss_mb}\t1\t1\t1\t0\t0\t50\t{cpu}\n", encoding="utf-8")


@pytest.mark.parametrize(
    ("name", "group"),
    [
        ("norm_L4_true", "true norms"),
        ("norm_L4", "convention norms (one job per norm)"),
        ("norms", "convention norms (per mesh)"),
        ("theory", "theory quantities"),
        ("mesh", "mesh generation"),
        ("discretise", "discretise"),
        ("solve", "solve"),
        ("atlas_case", "other"),
    ],
)
def test_each_benchmark_file_falls_in_one_group(name, group):
    assert cold_target.group_of(name) == group


def test_the_job_table_sums_per_group_and_lists_the_longest_jobs(tmp_path):
    results = tmp_path / "results"
    _job(results / "theory/benchmarks/N101/norm_L4_true.tsv", 2.0, 1.5, 100.0)
    _job(results / "theory/benchmarks/N201/norm_L4_true.tsv", 5.0, 4.0, 300.0)
    _job(results / "theory/benchmarks/N201/solve.tsv", 1.0, 0.5, 1024.0)
    table = cold_target.job_table(results)
    assert table["jobs"] == 3
    true = table["groups"]["true norms"]
    assert true == {"jobs": 2, "wall_s": 7.0, "cpu_s": 5.5, "max_rss_gib": 300.0 / 1024}
    assert table["groups"]["solve"]["max_rss_gib"] == 1.0
    assert table["sum_wall_s"] == 8.0 and table["sum_cpu_s"] == 6.0
    assert table["longest"][0] == ["theory/benchmarks/N201/norm_L4_true", 5.0]
