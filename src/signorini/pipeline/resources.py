"""Memory and run-time requests of the per-mesh jobs, defined once: the rules' ``resources`` and
the config check's bound use them.  Memory grows with the number of unknowns, (N + 1)² ≈ N²; the
constants follow the peaks measured at N = 2001 (``docs/evidence/scale.json``: discretise
0.9 GiB, solve 7.3 GiB by the direct route and 1.8 GiB by the multigrid route (6.9 GiB at
N = 4001), a mesh's 20 convention norms in one job 1.9 GiB, theory_quantities 2.3 GiB, its Ritz
projection by multigrid CG) with some headroom; a solve
job's request follows the route its scene's solver takes on that mesh.  Run times at N = 2001
on a loaded 2-CPU machine (load about 4): discretise 130 s, solve 216 s, a norm 20–80 s,
theory_quantities 228 s; the requests are about ten times these, since a job that outlives its
request is killed."""

from __future__ import annotations

import os
import subprocess
from collections.abc import Sequence
from dataclasses import dataclass

from signorini.fem.norms.names import parse_norm_name

# rule: (base, N² per unit) of the memory request in MB and of the run-time request in minutes
MEM_MB = {
    "discretise": (500, 4000),  # the stencil assembly streams: O(n) memory
    "solve": (500, 500),  # the direct route: a sparse Cholesky factor with its fill-in
    "solve_multigrid": (500, 2000),  # the multigrid route: the matrix, its hierarchy, a few vectors
    "norm": (500, 2000),
    "theory_quantities": (500, 1500),  # O(n): the matrix, its AMG hierarchy, chunks of quadrature
    "work_precision_measure": (1500, 250),
}
RUNTIME_MIN = {
    "discretise": (5, 200000),
    "solve": (5, 100000),  # the active-set steps grow with N: N = 1001 -> 2001 took 8x
    "norm": (5, 500000),
    "true_norm": (5, 250000),  # a true norm: at most about twice a convention norm (branch and bound, pruning)
    "theory_quantities": (5, 100000),
}
SCENE_RULES = ("discretise", "solve", "norm")  # the jobs every scene runs on each mesh


def solve_rule(solver: str, N: int) -> str:
    """The key of ``MEM_MB`` for a solve by ``solver`` on mesh ``N``: the route ``auto`` takes
    there (``solvers.exact_route``) decides between the direct and the multigrid model."""
    from signorini.solvers import exact_route

    return "solve_multigrid" if exact_route(solver, (int(N) + 1) ** 2) == "multigrid" else "solve"


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


def machine_mem_mb() -> int:
    """The physical memory of this machine in MB."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2**20


def largest_job(N: int, solver: str = "active_set") -> tuple[str, int]:
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
