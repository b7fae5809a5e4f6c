"""Sparse symmetric positive definite factorisations.

CHOLMOD through ``cholespy`` (wheels on PyPI, no system libraries) when it is
installed; otherwise SciPy's SuperLU, with a logged notice, since SuperLU is
about 2–3× slower on these 2D Laplace-type matrices.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

log = logging.getLogger(__name__)

try:  # pragma: no cover - exercised implicitly by whichever branch is installed
    from cholespy import CholeskySolverD, MatrixType

    HAVE_CHOLESPY = True
except ImportError:  # pragma: no cover
    HAVE_CHOLESPY = False

_notice_given = False

Solve = Callable[[np.ndarray], np.ndarray]


def backend_name(prefer: str = "auto") -> str:
    """The factorisation backend that ``factorize`` uses for ``prefer``."""
    if prefer not in ("auto", "cholmod", "superlu"):
        raise ValueError(f"unknown factorisation backend {prefer!r}; choose auto, cholmod or superlu")
    if prefer == "superlu" or not HAVE_CHOLESPY:
        if prefer == "cholmod":
            raise RuntimeError("backend 'cholmod' requested but cholespy is not installed")
        return "superlu"
    return "cholmod"


def factorize(A: sp.spmatrix, prefer: str = "auto") -> Solve:
    """Factorise the SPD matrix ``A`` once; return ``x = solve(y)`` for vectors or (n, k) blocks."""
    global _notice_given
    backend = backend_name(prefer)
    A = sp.csc_matrix(A)
    n = A.shape[0]
    if backend == "cholmod":
        factor = CholeskySolverD(
            n,
            A.indptr.astype(np.int32),
            A.indices.astype(np.int32),
            np.ascontiguousarray(A.data, dtype=float),
            MatrixType.CSC,
        )

        def solve(y: np.ndarray) -> np.ndarray:
            y = np.ascontiguousarray(y, dtype=float)
            x = np.empty_like(y)
            factor.solve(y, x)
            return x

        return solve
    if prefer == "auto" and not _notice_given:
        log.warning("cholespy is not installed: falling back to SciPy's SuperLU (slower); pip install cholespy")
        _notice_given = True
    lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    return lambda y: lu.solve(np.asarray(y, dtype=float))
