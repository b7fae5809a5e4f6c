"""Memory and run-time requests of the per-mesh jobs, defined once: the rules' ``resources`` and
the config check's bound use them.  Memory grows with the number of unknowns, (N + 1)² ≈ N²; the
constants follow the peak memory of each stage at N = 2001 and 4001 (``docs/evidence/scale.json``,
per stage and mesh; the theory quantities with their Ritz projection by multigrid CG) with a fifth
or more of headroom, so that a request at N = 8001 extrapolates the measured growth; a solve job's
request follows the route its scene's solver takes on that mesh.
The run-time requests are generous multiples of the run times on a loaded machine, since a job
that outlives its request is killed (docs/evidence/design-measurements.md#job-requests)."""

from __future__ import annotations

import functools
import math
import os
import resource
import subprocess
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, NamedTuple

from signorini.fem.norms.names import parse_norm_name

# rule: (base, N² per unit) of the memory request in MB and of the run-time request in minutes
MEM_MB = {
    "discretise": (500, 5000),  # the stencil assembly streams: O(n) memory
    "solve": (500, 400),  # the direct route: a sparse Cholesky factor with its fill-in
    "solve_multigrid": (500, 3000),  # the multigrid route: the matrix, its hierarchy, a few vectors
    # the multigrid route on a mesh family's matrix: classical AMG's hierarchy is larger
    # (its peak memory: docs/evidence/cold_meshes.json)
    "solve_amg": (500, 700),
    "norm": (500, 6000),
    "theory_quantities": (500, 3000),  # O(n): the matrix, its AMG hierarchy, chunks of quadrature
    "work_precision_measure": (1500, 250),
}
RUNTIME_MIN = {
    "discretise": (5, 200000),
    # the active-set steps grow faster than N² (docs/evidence/design-measurements.md#job-requests)
    "solve": (5, 100000),
    "norm": (5, 500000),
    # a true norm: twice a convention norm's request (branch and bound, pruning; the same page)
    "true_norm": (5, 250000),
    "theory_quantities": (5, 100000),
}
SCENE_RULES = ("discretise", "solve", "norm")  # the jobs every scene runs on each mesh


def solve_rule(solver: str, N: int, paper_mesh: bool = True) -> str:
    """The key of ``MEM_MB`` for a solve by ``solver`` on mesh ``N``: the route ``auto`` takes
    there (``solvers.exact_route``) decides between the direct and the multigrid model, and the
    multigrid route off the paper's mesh takes classical AMG (``solve_amg``)."""
    from signorini.solvers import exact_route

    if exact_route(solver, (int(N) + 1) ** 2) != "multigrid":
        return "solve"
    return "solve_multigrid" if paper_mesh else "solve_amg"


# the mesh parameter at which a family's number of vertices per (N + 1)² is counted: small enough
# to build in a moment, large enough to stand for the finest meshes
# (docs/evidence/design-measurements.md#vertex-factor)
VERTEX_FACTOR_N = 32


def vertex_factor(mesh_spec: Mapping[str, Any]) -> float:
    """About how many times ``(N + 1)²`` vertices the mesh of a scene's ``mesh`` block has: 1 for
    the paper's mesh, else its count on the mesh of ``VERTEX_FACTOR_N`` (a graded mesh has several
    times the Friedrichs–Keller mesh's vertices at the same ``N``)."""
    from signorini.fem.mesh_families import check_mesh_spec, paper_mesh

    if paper_mesh(mesh_spec):
        return 1.0
    family, params = check_mesh_spec(mesh_spec)
    return _vertex_factor(family, tuple(sorted(params.items())))


@functools.cache
def _vertex_factor(family: str, params: tuple) -> float:
    from signorini.fem.mesh_families import build_mesh

    return build_mesh(family, VERTEX_FACTOR_N, **dict(params)).p.shape[1] / (VERTEX_FACTOR_N + 1) ** 2


def sized_N(N: int, mesh_spec: Mapping[str, Any]) -> int:
    """The ``N`` of a Friedrichs–Keller mesh with about as many vertices as the mesh ``N`` of a
    scene's ``mesh`` block: what its jobs' requests are computed from (``N`` itself on the paper's
    mesh)."""
    return max(int(round((int(N) + 1) * math.sqrt(vertex_factor(mesh_spec)))) - 1, int(N))


def mem_mb(rule: str, N: int) -> int:
    """The memory request of a job of ``rule`` on the mesh with ``N`` cells per side, in MB."""
    base, per = MEM_MB[rule]
    return base + int(N) ** 2 // per


def runtime_min(rule: str, N: int) -> int:
    """The run-time request of a job of ``rule`` on the mesh with ``N`` cells per side, in minutes."""
    base, per = RUNTIME_MIN[rule]
    return base + int(N) ** 2 // per


def norms_runtime_min(N: int, norms: Sequence[str]) -> int:
    """The run-time request of a job computing ``norms`` on mesh ``N`` one after another (one norm,
    or a scene's norms with ``norm_jobs: per_mesh``): one start, and each norm's share, in minutes."""
    shares = (runtime_min("true_norm" if parse_norm_name(n).true else "norm", N) for n in norms)
    return RUNTIME_MIN["norm"][0] + sum(share - RUNTIME_MIN["norm"][0] for share in shares)


def mesh_group_runtime_min(N: int, norms: Sequence[str]) -> int:
    """The run-time request of a mesh's Slurm job in the slurm profile, whose group runs the mesh's
    discretise, solve and its ``norms`` one after another: the sum of theirs, in minutes."""
    return runtime_min("discretise", N) + runtime_min("solve", N) + norms_runtime_min(N, norms)


class MemoryLimit(NamedTuple):
    """A memory limit in MB and what sets it, as the messages say it: ``of this machine``,
    ``of the cgroup limit``, ``of ulimit -v`` or ``of ulimit -d``."""

    mb: int
    source: str


def physical_mem_mb() -> int:
    """The physical memory of this machine in MB."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2**20


def _cgroup_dirs(proc: Path, root: Path) -> list[tuple[Path, Path, str]]:
    """(the process's cgroup directory, the mount point, the limit file) of each memory cgroup
    hierarchy mounted here: cgroup v2 (``memory.max``) and v1's memory controller
    (``memory.limit_in_bytes``), found through ``mountinfo`` (a container may mount either, or both)."""
    try:
        groups = (proc / "cgroup").read_text(encoding="utf-8").splitlines()
        mounts = (proc / "mountinfo").read_text(encoding="utf-8").splitlines()
    except OSError:
        return []
    paths = {}  # "v2" or "v1": the process's cgroup path
    for line in groups:
        hid, controllers, path = (line.split(":", 2) + ["", ""])[:3]
        if hid == "0" and not controllers:
            paths["v2"] = path
        elif "memory" in controllers.split(","):
            paths["v1"] = path
    found = []
    for line in mounts:
        fields, _, tail = line.partition(" - ")
        parts, kind = fields.split(), tail.split()
        if len(parts) < 5 or len(kind) < 3:
            continue
        v1 = kind[0] == "cgroup" and "memory" in kind[2].split(",")
        version = "v2" if kind[0] == "cgroup2" else "v1" if v1 else ""
        if version not in paths:
            continue
        mount_root, mount_point = parts[3], root / parts[4].lstrip("/")
        # the cgroup's path below the mount's root (a cgroup namespace shows the mount's root itself)
        rel = os.path.relpath(paths[version], mount_root) if paths[version].startswith(mount_root) else "."
        limit = "memory.max" if version == "v2" else "memory.limit_in_bytes"
        found.append((mount_point / rel, mount_point, limit))
    return found


def cgroup_mem_mb(proc: str | os.PathLike = "/proc/self", root: str | os.PathLike = "/") -> int | None:
    """The smallest memory limit in MB of this process's cgroup and its parents (cgroup v2
    ``memory.max``, v1 ``memory.limit_in_bytes``); None without one.  ``proc`` and ``root`` (where
    the mount points of ``mountinfo`` lie) are parameters so that a test can give its own tree."""
    limits = []
    for directory, mount_point, name in _cgroup_dirs(Path(proc), Path(root)):
        while True:  # a parent's limit bounds its children too
            try:
                text = (directory / name).read_text(encoding="utf-8").strip()
            except OSError:
                text = "max"
            if text.isdigit():
                limits.append(int(text) // 2**20)  # v1 writes "no limit" as a huge number: min() drops it
            if directory == mount_point or mount_point not in directory.parents:
                break
            directory = directory.parent
    return min(limits, default=None)


# ulimit's options for the address-space limits of a process, by the resource module's names
RLIMITS = {"RLIMIT_AS": "ulimit -v", "RLIMIT_DATA": "ulimit -d"}


def rlimit_mem_mb(getrlimit: Callable[[int], tuple[int, int]] = resource.getrlimit) -> list[MemoryLimit]:
    """The soft address-space limits of this process (``ulimit -v``, ``ulimit -d``) that are set,
    in MB; each job inherits them, a process each."""
    out = []
    for name, option in RLIMITS.items():
        soft = getrlimit(getattr(resource, name))[0]
        if soft != resource.RLIM_INFINITY and soft >= 0:
            out.append(MemoryLimit(soft // 2**20, f"of {option}"))
    return out


def usable_memory(per_process: bool = True, proc: str | os.PathLike = "/proc/self", root: str | os.PathLike = "/",
                  getrlimit: Callable[[int], tuple[int, int]] = resource.getrlimit) -> MemoryLimit:
    """The memory a job can use: the smallest of the physical memory, the cgroup limit and (with
    ``per_process``, for one job) the address-space limits, with what sets it.  Without
    ``per_process`` it is what all jobs running at once may use together: a ulimit holds for each
    process on its own, the cgroup and the machine for all of them."""
    limits = [MemoryLimit(physical_mem_mb(), "of this machine")]
    if (cgroup := cgroup_mem_mb(proc, root)) is not None:
        limits.append(MemoryLimit(cgroup, "of the cgroup limit"))
    if per_process:
        limits += rlimit_mem_mb(getrlimit)
    return min(limits, key=lambda limit: limit.mb)


def machine_mem_mb() -> int:
    """The memory one job can use in MB (``usable_memory``): the physical memory unless a cgroup
    or a ulimit sets less."""
    return usable_memory().mb


def given_mem_mb(workflow) -> int | None:
    """The global ``mem_mb`` resource the user gave (``--resources mem_mb=…``, ``mem=…`` or a
    profile's ``resources``; Snakemake stores each as ``mem_mb``), or None."""
    given = getattr(workflow, "global_resources", {}).get("mem_mb")
    value = getattr(given, "value", given)
    return value if isinstance(value, int) else None


def largest_job(N: int, solver: str = "direct") -> tuple[str, int]:
    """The scene job with the largest memory request on mesh ``N`` when its solves use ``solver``:
    (rule, MB)."""
    rules = (solve_rule(solver, N) if rule == "solve" else rule for rule in SCENE_RULES)
    return max(((rule, mem_mb(rule, N)) for rule in rules), key=lambda item: item[1])


@dataclass(frozen=True)
class NodeLimits:
    """What one job can get on the largest node of a Slurm partition: CPUs, memory in MB and the
    partition's time limit in minutes (None: unlimited)."""

    partition: str
    cpus: int
    mem_mb: int
    time_limit_min: int | None


def slurm_time_minutes(text: str) -> int | None:
    """A Slurm time limit (``infinite``, ``MM``, ``MM:SS``, ``HH:MM:SS``, ``D-HH[:MM[:SS]]``) in
    whole minutes, rounded down; None when unlimited."""
    text = text.strip()
    if text.lower() in ("infinite", "unlimited", "n/a"):
        return None
    days, _, clock = text.rpartition("-")
    parts = [int(p) for p in clock.split(":")]
    if days:  # D-HH, D-HH:MM, D-HH:MM:SS
        hours, minutes = parts[0], (parts[1] if len(parts) > 1 else 0)
    elif len(parts) == 3:
        hours, minutes = parts[0], parts[1]
    else:  # MM or MM:SS
        hours, minutes = 0, parts[0]
    return (int(days or 0) * 24 + hours) * 60 + minutes


def parse_sinfo(text: str, partition: str | None = None) -> NodeLimits:
    """The largest node of ``partition`` (default: the cluster's default partition, marked ``*``)
    from the lines ``partition|CPUs|memory MB|time limit`` of ``sinfo -N -h -o '%P|%c|%m|%l'``."""
    rows = [line.split("|") for line in text.splitlines() if line.strip()]
    if partition is None:
        default = [row for row in rows if row[0].endswith("*")]
        rows = default or rows
    else:
        rows = [row for row in rows if row[0].rstrip("*") == partition]
    if not rows:
        raise ValueError(f"sinfo lists no node of partition {partition or '(default)'}")
    limits = [slurm_time_minutes(row[3]) for row in rows]
    return NodeLimits(
        partition=rows[0][0].rstrip("*"),
        cpus=max(int(row[1].rstrip("+")) for row in rows),
        mem_mb=max(int(row[2].rstrip("+")) for row in rows),
        time_limit_min=None if None in limits else max(limits),
    )


def slurm_node_limits(partition: str | None = None) -> NodeLimits:
    """The largest node of a Slurm partition as ``sinfo`` reports it (the cluster's default
    partition unless one is named)."""
    cmd = ["sinfo", "--Node", "--noheader", "--format=%P|%c|%m|%l"]
    if partition:
        cmd.append(f"--partition={partition}")
    out = subprocess.run(cmd, capture_output=True, encoding="utf-8", check=True, timeout=60).stdout
    return parse_sinfo(out, partition)
