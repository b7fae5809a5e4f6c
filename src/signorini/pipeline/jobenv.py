"""The environment the project's processes compute in, set in one place (``job_environment``).

- **One BLAS/OpenMP/Rayon thread** unless the caller says otherwise (``THREAD_VARIABLES`` already
  set are kept): jobs run side by side (``snakemake -c2``), and threaded BLAS inside the active-set
  loop oversubscribes the cores, many times slower on a loaded machine
  (docs/evidence/design-measurements.md#one-thread-per-job); a timed run then measures the CPU
  time of one core, as the PETSc peers' runs do.
- **Freed memory kept for reuse** (``ALLOCATOR_VARIABLES``, glibc's ``mallopt(3)`` settings, unless
  set): glibc serves every allocation above 32 MiB by a fresh ``mmap`` and returns it on ``free``,
  so each temporary array of a fine mesh (128 MB at N = 4001) is faulted in page by page and zeroed
  by the kernel, again at every Newton step and every V-cycle; from the heap, with nothing trimmed,
  the next temporary reuses the freed pages.  The arithmetic is the same (the same bits); the system
  time is what goes (docs/evidence/design-measurements.md#reuse-freed-memory).  Other C libraries
  ignore these variables.

Both must be in the environment when a process starts (glibc reads its settings at the first
allocation, numpy loads its BLAS on import): the Snakefile applies them once for every job it
starts (they inherit the environment); an entry point outside the workflow (a benchmark, the
tests) applies them first thing, for the processes it starts.  This module imports nothing but
``os``.
"""

from __future__ import annotations

import os
from collections.abc import MutableMapping

# RAYON: the thread pool of Clarabel's sparse factorisation (faer); without it a Clarabel call
# ran wider than one core and slower in wall time.
# OMP_THREAD_LIMIT: CHOLMOD's supernodal factorisation (Debian's, under the PETSc peers) asks for
# 4 OpenMP threads whatever OMP_NUM_THREADS says; on 2 cores vinewtonrsls + CHOLMOD then took more
# CPU time than with one thread, much of it system time and thread hand-overs.
# (docs/evidence/design-measurements.md#one-thread-per-job)
THREAD_VARIABLES = (
    "OMP_NUM_THREADS",
    "OMP_THREAD_LIMIT",
    "OPENBLAS_NUM_THREADS",
    "MKL_NUM_THREADS",
    "RAYON_NUM_THREADS",
)


# M_MMAP_MAX = 0: no allocation by mmap; M_TRIM_THRESHOLD: the heap's free top is kept up to 1 TiB
ALLOCATOR_VARIABLES = {"MALLOC_MMAP_MAX_": "0", "MALLOC_TRIM_THRESHOLD_": str(1 << 40)}


def job_environment(environ: MutableMapping[str, str] | None = None) -> MutableMapping[str, str]:
    """The environment a job computes in: ``single_threaded`` and ``reuse_freed_memory`` applied
    to ``environ`` (default: this process's environment, for the processes it starts); returns
    ``environ`` (e.g. a copy for a subprocess)."""
    return reuse_freed_memory(single_threaded(environ))


def reuse_freed_memory(environ: MutableMapping[str, str] | None = None) -> MutableMapping[str, str]:
    """Set each of ``ALLOCATOR_VARIABLES`` in ``environ`` (default: this process's environment)
    unless it is set already; returns ``environ``."""
    environ = os.environ if environ is None else environ
    for name, value in ALLOCATOR_VARIABLES.items():
        environ.setdefault(name, value)
    return environ


def single_threaded(environ: MutableMapping[str, str] | None = None) -> MutableMapping[str, str]:
    """Set each of ``THREAD_VARIABLES`` to 1 in ``environ`` (default: this process's environment)
    unless it is set already; returns ``environ`` (e.g. a copy for a subprocess)."""
    environ = os.environ if environ is None else environ
    for name in THREAD_VARIABLES:
        environ.setdefault(name, "1")
    return environ
