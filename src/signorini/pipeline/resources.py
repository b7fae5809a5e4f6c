"""Memory and run-time requests of the per-mesh jobs, defined once: the rules' ``resources`` and
the config check's bound use them.  Memory grows with the number of unknowns, (N + 1)² ≈ N²; the
constants follow the peaks measured at N = 2001 (README: discretise 3.7 GB, solve 7.5 GB, norm
≤ 1.8 GB, theory_quantities 3.0 GB) with some headroom."""

from __future__ import annotations

import os

# rule: (base, N² per unit) of the memory request in MB and of the run-time request in minutes
MEM_MB = {
    "discretise": (500, 1000),
    "solve": (500, 500),
    "norm": (500, 2000),
    "theory_quantities": (1000, 500),
    "work_precision_measure": (1500, 250),
}
RUNTIME_MIN = {"discretise": (5, 20000), "solve": (5, 20000), "norm": (5, 50000), "theory_quantities": (5, 50000)}
SCENE_RULES = ("discretise", "solve", "norm")  # the jobs every scene runs on each mesh


def mem_mb(rule: str, N: int) -> int:
    """The memory request of a job of ``rule`` on the mesh with ``N`` cells per side, in MB."""
    base, per = MEM_MB[rule]
    return base + int(N) ** 2 // per


def runtime_min(rule: str, N: int) -> int:
    """The run-time request of a job of ``rule`` on the mesh with ``N`` cells per side, in minutes."""
    base, per = RUNTIME_MIN[rule]
    return base + int(N) ** 2 // per


def machine_mem_mb() -> int:
    """The physical memory of this machine in MB."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2**20


def largest_job(N: int) -> tuple[str, int]:
    """The scene job with the largest memory request on mesh ``N``: (rule, MB)."""
    return max(((rule, mem_mb(rule, N)) for rule in SCENE_RULES), key=lambda item: item[1])
