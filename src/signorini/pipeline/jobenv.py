"""The environment the project's processes compute in, set in one place.

One BLAS/OpenMP/Rayon thread unless the caller says otherwise (``THREAD_VARIABLES`` already set are
kept): jobs run side by side (``snakemake -c2``), and threaded BLAS inside the active-set loop
oversubscribes the cores, many times slower on a loaded machine
(docs/evidence/design-measurements.md#one-thread-per-job); a timed run then measures the CPU time
of one core, as the PETSc peers' runs do.  It must be applied before numpy loads its BLAS:
the Snakefile applies it once for the workflow process and every job it starts (they inherit the
environment); an entry point outside the workflow (a benchmark, the tests) applies it first thing.
This module imports nothing but ``os``.
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


def single_threaded(environ: MutableMapping[str, str] | None = None) -> MutableMapping[str, str]:
    """Set each of ``THREAD_VARIABLES`` to 1 in ``environ`` (default: this process's environment)
    unless it is set already; returns ``environ`` (e.g. a copy for a subprocess)."""
    environ = os.environ if environ is None else environ
    for name in THREAD_VARIABLES:
        environ.setdefault(name, "1")
    return environ
