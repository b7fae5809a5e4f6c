"""The resources of a job (``signorini.pipeline.resources``): Slurm's limits read from ``sinfo``
and held against the jobs' requests."""

from __future__ import annotations

import subprocess
import sys

import pytest
from helpers import ROOT
from helpers import smoke_config as _smoke_config

from signorini.pipeline.config import ConfigError, check_config
from signorini.pipeline.resources import NodeLimits, parse_sinfo, slurm_time_minutes


@pytest.mark.parametrize(
    ("text", "minutes"),
    [("infinite", None), ("30", 30), ("30:00", 30), ("2:00:00", 120), ("1-00:00:00", 1440), ("2-12", 3600)],
)
def test_slurm_time_limits_are_read_in_minutes(text, minutes):
    assert slurm_time_minutes(text) == minutes


def test_the_largest_node_of_the_default_partition_is_the_limit():
    text = "main*|2|24105|infinite\nmain*|8|64000|infinite\nbig|64|512000|2-00:00:00\n"
    assert parse_sinfo(text) == NodeLimits("main", 8, 64000, None)
    assert parse_sinfo(text, "big") == NodeLimits("big", 64, 512000, 2880)
    with pytest.raises(ValueError, match="no node of partition gpu"):
        parse_sinfo(text, "gpu")


def test_a_job_longer_than_the_partition_allows_is_refused():
    """A mesh's Slurm job runs its discretise, solve and 7 norms one after another: it requests
    the sum of their run times (at N = 2001: 25 + 45 + (5 + 7 * 8) min)."""
    node = NodeLimits("short", 2, 64000, 120)
    check_config(_smoke_config([11, 1001]), node=node)
    message = (
        r"N\[1\]: N = 2001 requests 131 min for its mesh job \(discretise, solve and 7 norms one after "
        r"another\), more than the time limit of 120 min of Slurm partition short"
    )
    with pytest.raises(ConfigError, match=message):
        check_config(_smoke_config([11, 2001]), node=node)
    with pytest.raises(ConfigError, match=r"N = 9001 needs about .* GB for its solve job .* more than the 62.5 GB "
                       r"of the largest node of Slurm partition short"):
        check_config(_smoke_config([9001]), node=node)


def test_a_solve_job_requests_the_memory_of_the_route_it_takes():
    """``auto`` solves N = 301 by the direct route and N = 501 and 2001 by the multigrid route, whose
    request is the multigrid model's (measured 1.3 GiB against 9.9 GiB at N = 2001:
    docs/evidence/scale.json)."""
    from signorini.pipeline.resources import largest_job, mem_mb, solve_rule

    assert [solve_rule(s, 301) for s in ("active_set", "auto", "multigrid")] == ["solve", "solve", "solve_multigrid"]
    assert solve_rule("auto", 501) == "solve_multigrid"
    assert solve_rule("auto", 2001) == "solve_multigrid" and solve_rule("cvxpy_osqp", 2001) == "solve"
    assert mem_mb("solve_multigrid", 2001) < mem_mb("solve", 2001) / 5
    assert mem_mb("solve_multigrid", 4001) < mem_mb("solve", 4001) / 5
    assert largest_job(4001, "active_set")[0] == "solve" and largest_job(4001, "auto")[0] != "solve"


# the stages of docs/evidence/scale.json and the rules whose memory requests they measure
SCALE_STAGES = {"discretise": "discretise", "solve_multigrid": "solve_multigrid", "solve_direct": "solve",
                "convention_norms": "norm", "theory_quantities": "theory_quantities"}


def test_the_memory_requests_cover_the_measured_peaks_without_waste():
    """Every request at N = 2001 and 4001 lies above the peak resident memory measured there (a job
    beyond its request is killed on a cluster) and, for the O(n) stages, within 2.5 times it (a larger
    request keeps jobs from running side by side); the growth from 2001 to 4001, carried on to 8001,
    stays within the request there."""
    import json

    from signorini.pipeline.resources import mem_mb

    stages = json.loads((ROOT / "docs/evidence/scale.json").read_text())["stages"]
    true_norms = [name for name in stages if name.endswith("_true")]
    assert len(true_norms) == 7
    checked = 0
    for stage, record in stages.items():
        rule = "norm" if stage in true_norms else SCALE_STAGES[stage]
        peaks = {int(N): r["peak_rss_gib"] * 1024 for N, r in record.items() if r.get("peak_rss_gib")}
        for N, peak in peaks.items():
            assert mem_mb(rule, N) > peak, (stage, N)
            if rule != "solve" and N >= 2001:
                assert mem_mb(rule, N) < 2.5 * peak, (stage, N)
                checked += 1
        if rule != "solve":
            growth = (peaks[4001] - peaks[2001]) / (4001**2 - 2001**2)
            assert mem_mb(rule, 8001) > peaks[4001] + growth * (8001**2 - 4001**2), stage
    assert checked == 2 * (len(stages) - 1)


@pytest.mark.parametrize(("solver", "fits"), [("active_set", False), ("auto", True), ("multigrid", True)])
def test_a_mesh_fits_or_not_by_the_route_of_its_scene(solver, fits):
    """N = 4001 on 24 GB: the direct route's factor does not fit, the multigrid route's jobs do."""
    config = _smoke_config([11, 4001])
    config["scenes"]["smoke"]["solver"] = solver
    if fits:
        check_config(config, 24 * 1024)
    else:
        from signorini.pipeline.resources import mem_mb

        need = f"{mem_mb('solve', 4001) / 1024:.1f}".replace(".", r"\.")
        with pytest.raises(ConfigError, match=rf"N = 4001 needs about {need} GB for its solve job"):
            check_config(config, 24 * 1024)


# --- the memory a job can use: the machine, its cgroup, the ulimits ------------------------------

GB = 2**30


def fake_cgroups(tmp_path, v2: dict[str, str] | None = None, v1: dict[str, str] | None = None):
    """A /proc/self and a root with cgroup hierarchies: ``v2``/``v1`` map a cgroup directory (the
    process's first) to its limit file's text."""
    proc, root = tmp_path / "proc", tmp_path / "root"
    proc.mkdir(parents=True)
    groups, mounts = [], []
    for version, limits, mount, name in ((2, v2, "sys/fs/cgroup", "memory.max"),
                                         (1, v1, "sys/fs/cgroup/memory", "memory.limit_in_bytes")):
        if limits is None:
            continue
        groups.append("0::" + next(iter(limits)) if version == 2 else "4:memory:" + next(iter(limits)))
        kind = "cgroup2 cgroup2 rw" if version == 2 else "cgroup cgroup rw,memory"
        mounts.append(f"3{version} 23 0:2{version} / /{mount} rw,relatime - {kind}")
        for directory, text in limits.items():
            (root / mount / directory.strip("/")).mkdir(parents=True, exist_ok=True)
            (root / mount / directory.strip("/") / name).write_text(text + "\n", encoding="utf-8")
    (proc / "cgroup").write_text("\n".join(groups) + "\n", encoding="utf-8")
    (proc / "mountinfo").write_text("\n".join(mounts) + "\n", encoding="utf-8")
    return proc, root


def test_the_cgroup_limit_is_read_from_v2_and_v1_and_their_parents(tmp_path):
    from signorini.pipeline.resources import cgroup_mem_mb

    proc, root = fake_cgroups(tmp_path / "a", v2={"/user.slice/job": str(4 * GB), "/user.slice": "max"})
    assert cgroup_mem_mb(proc, root) == 4096
    proc, root = fake_cgroups(tmp_path / "b", v2={"/user.slice/job": "max", "/user.slice": str(3 * GB)})
    assert cgroup_mem_mb(proc, root) == 3072  # a parent's limit bounds the child
    proc, root = fake_cgroups(tmp_path / "c", v1={"/docker/abc": str(2 * GB), "/": "9223372036854771712"})
    assert cgroup_mem_mb(proc, root) == 2048
    proc, root = fake_cgroups(tmp_path / "d", v2={"/": "max"})
    assert cgroup_mem_mb(proc, root) is None
    assert cgroup_mem_mb(tmp_path / "none", tmp_path) is None  # no /proc: no limit known


def test_the_memory_a_job_can_use_is_the_smallest_limit_and_says_which(tmp_path):
    import resource

    from signorini.pipeline.resources import MemoryLimit, physical_mem_mb, usable_memory

    machine = physical_mem_mb()
    proc, root = fake_cgroups(tmp_path, v2={"/job": str(machine // 2 * 2**20)})
    unlimited = lambda which: (resource.RLIM_INFINITY, resource.RLIM_INFINITY)  # noqa: E731
    ulimit_v = lambda which: (machine // 4 * 2**20 if which == resource.RLIMIT_AS else -1, -1)  # noqa: E731
    assert usable_memory(proc=tmp_path / "none", root=tmp_path, getrlimit=unlimited) == (machine, "of this machine")
    assert usable_memory(proc=proc, root=root, getrlimit=unlimited) == MemoryLimit(machine // 2, "of the cgroup limit")
    assert usable_memory(proc=proc, root=root, getrlimit=ulimit_v) == MemoryLimit(machine // 4, "of ulimit -v")
    # all jobs together: a ulimit bounds each process, not their sum
    assert usable_memory(False, proc=proc, root=root, getrlimit=ulimit_v).source == "of the cgroup limit"


def test_a_mesh_beyond_a_cgroup_limit_is_refused_naming_it(tmp_path, monkeypatch):
    """A limit below the physical memory used to be unseen: the job died with a bare MemoryError."""
    from functools import partial

    from signorini.pipeline import resources

    proc, root = fake_cgroups(tmp_path, v2={"/job": str(2 * GB)})
    monkeypatch.setattr(resources, "usable_memory", partial(resources.usable_memory, proc=proc, root=root))
    check_config(_smoke_config([11, 401]))
    need = f"{resources.mem_mb('solve', 1001) / 1024:.1f}".replace(".", r"\.")
    with pytest.raises(ConfigError, match=rf"N\[1\]: N = 1001 needs about {need} GB .* more than the 2\.0 GB of the "
                       r"cgroup limit$"):
        check_config(_smoke_config([11, 1001]))


def test_a_mesh_beyond_ulimit_v_is_refused_naming_it():
    """For real: the shipped config under ``ulimit -v 4000000`` (3.8 GB); its fine scene's N = 4001
    needs 5.7 GB."""
    from signorini.pipeline.resources import usable_memory

    if usable_memory(False).mb < 8 * 1024:
        pytest.skip("this machine (or its cgroup) has less than 8 GB: the limit would be its own")
    command = ["bash", "-c", 'ulimit -v 4000000 && exec "$0" -m signorini.pipeline.config', sys.executable]
    proc = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert proc.returncode == 1, proc.stderr
    message = ("N = 4001 needs about 5.7 GB for its solve_multigrid job (estimate from the peaks measured at N = 2001 "
               "and 4001), more than the 3.8 GB of ulimit -v")
    assert proc.stderr.strip().endswith(message), proc.stderr


def test_a_family_meshs_requests_follow_its_vertices_and_its_solver_route():
    from signorini.pipeline.resources import mem_mb, sized_N, solve_rule, vertex_factor

    assert vertex_factor({}) == 1.0 and sized_N(501, {}) == 501 and sized_N(501, {"family": "union_jack"}) == 501
    graded = {"family": "graded", "grading": 2.0}
    assert 5.0 < vertex_factor(graded) < 6.0  # refined toward the free point: several times the vertices
    assert 1.1 < vertex_factor({"family": "delaunay", "seed": 1}) < 1.2  # a triangular lattice inside
    assert sized_N(448, graded) > 2 * 448 and mem_mb("norm", sized_N(448, graded)) > mem_mb("norm", 448)
    assert solve_rule("auto", 1001, paper_mesh=False) == "solve_amg" and solve_rule("direct", 1001, False) == "solve"
    assert mem_mb("solve_amg", 1001) > mem_mb("solve_multigrid", 1001)


# the rule whose memory model requests each stage of benchmarks/scale.py (the others: a norm job)
SCALE_STAGE_RULES = {
    "discretise": "discretise",
    "solve_direct": "solve",
    "solve_multigrid": "solve_multigrid",
    "theory_quantities": "theory_quantities",
}


def test_every_stage_of_the_committed_scale_run_fits_in_its_request():
    """The memory models hold the peaks measured by ``benchmarks/scale.py``
    (``docs/evidence/scale.json``) at every mesh, with headroom."""
    import json

    from signorini.pipeline.resources import mem_mb

    stages = json.loads((ROOT / "docs/evidence/scale.json").read_text(encoding="utf-8"))["stages"]
    measured = [
        (stage, int(N), rec["peak_rss_gib"] * 1024)
        for stage, by_N in stages.items()
        for N, rec in by_N.items()
        if "peak_rss_gib" in rec
    ]
    assert {stage for stage, _, _ in measured} >= set(SCALE_STAGE_RULES)
    short = [(s, N, round(peak), mem_mb(SCALE_STAGE_RULES.get(s, "norm"), N)) for s, N, peak in measured
             if 1.05 * peak > mem_mb(SCALE_STAGE_RULES.get(s, "norm"), N)]
    assert not short, f"peak MB above the request / 1.05: {short}"
