"""Sparse symmetric positive definite factorisations.

Backends, in the order ``prefer="auto"`` tries them:

- ``cholmod``: supernodal CHOLMOD as bundled (with OpenBLAS) in ``cvxopt``'s wheels;
  a ``Factorizer`` runs the symbolic analysis (AMD ordering) once per sparsity pattern and
  refactorises numerically only.  (``cholespy`` runs CHOLMOD simplicial and its fork
  ``sksparse-minimal`` runs it supernodal on reference BLAS: both factorise slower);
- ``pardiso``: MKL PARDISO through ``pypardiso`` (large wheels with MKL; optional,
  not in environment.lock), real SPD mode; a ``Factorizer`` analyses the sparsity
  pattern once and refactorises numerically only.  Its factorisation is faster but its
  solves are slower, and the whole active-set solve took longer than with (simplicial)
  CHOLMOD, with a large fixed cost per call on small meshes;
- ``superlu``: SciPy's SuperLU in symmetric mode, always available; a logged
  notice says when the faster backends are missing.

The figures behind this order: docs/evidence/design-measurements.md#factorisation-backends;
``benchmarks/core.py`` measures them anew (``results/benchmarks/``).
"""

from __future__ import annotations

import importlib.util
import logging
from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

log = logging.getLogger(__name__)

BACKENDS = ("cholmod", "pardiso", "superlu")
_MODULES = {"pardiso": "pypardiso", "cholmod": "cvxopt"}
_notice_given = False

Solve = Callable[[np.ndarray], np.ndarray]


def available_backends() -> list[str]:
    """The installed factorisation backends, fastest first."""
    return [b for b in BACKENDS if b == "superlu" or importlib.util.find_spec(_MODULES[b]) is not None]


def backend_name(prefer: str = "auto") -> str:
    """The factorisation backend that ``factorize`` uses for ``prefer``."""
    global _notice_given
    if prefer not in ("auto", *BACKENDS):
        raise ValueError(f"unknown factorisation backend {prefer!r}; choose auto or one of {BACKENDS}")
    installed = available_backends()
    if prefer == "auto":
        if installed[0] == "superlu" and not _notice_given:
            log.warning("neither cvxopt (CHOLMOD) nor pypardiso is installed: using SciPy's SuperLU")
            _notice_given = True
        return installed[0]
    if prefer not in installed:
        raise RuntimeError(f"factorisation backend {prefer!r} requested but {_MODULES[prefer]} is not installed")
    return prefer


class Factorizer:
    """Repeated factorisations of SPD matrices with the sparsity pattern of ``pattern``.

    ``factorizer(data)`` factorises the matrix whose CSR values (in ``pattern``'s
    order) are ``data`` and returns ``x = solve(y)`` for vectors or (n, k) blocks.
    CHOLMOD and PARDISO refactorise in place: only the last factorisation stays valid, and
    calling an older ``solve`` raises ``RuntimeError``.
    """

    def __init__(self, pattern: sp.spmatrix, prefer: str = "auto"):
        self.backend = backend_name(prefer)
        self.pattern = sp.csr_matrix(pattern, copy=True)
        self.pattern.sum_duplicates()
        self.pattern.sort_indices()
        self.n = self.pattern.shape[0]
        self._generation = 0
        if self.backend == "cholmod":
            from cvxopt import cholmod, matrix, spmatrix

            # lower triangle in CSC order (CHOLMOD's input), as positions into the CSR values
            position = sp.csr_matrix((np.arange(1.0, self.pattern.nnz + 1), self.pattern.indices, self.pattern.indptr))
            lower = sp.tril(position, format="csc")
            lower.sort_indices()
            self._lower = lower.data.astype(np.int64) - 1
            cols = np.repeat(np.arange(self.n, dtype=np.int64), np.diff(lower.indptr))
            rows = lower.indices.astype(np.int64)
            self._matrix = spmatrix(
                matrix(self.pattern.data[self._lower]), matrix(rows), matrix(cols), (self.n, self.n)
            )
            self._symbolic = cholmod.symbolic(self._matrix)  # ordering + symbolic analysis, once
        if self.backend == "pardiso":
            import pypardiso

            rows = np.repeat(np.arange(self.n), np.diff(self.pattern.indptr))
            self._upper = self.pattern.indices >= rows  # PARDISO's SPD mode reads the upper triangle
            upper = sp.csr_matrix(
                (self.pattern.data[self._upper], self.pattern.indices[self._upper], _indptr(rows[self._upper], self.n)),
                shape=self.pattern.shape,
            )
            self._matrix = upper
            self._solver = pypardiso.PyPardisoSolver(mtype=2)
            self._analysed = False

    def __call__(self, data: np.ndarray) -> Solve:
        data = np.asarray(data, dtype=float)
        if self.backend == "pardiso":
            return self._pardiso(data)
        if self.backend == "cholmod":
            return self._cholmod(data)
        A = sp.csr_matrix((data, self.pattern.indices, self.pattern.indptr), shape=self.pattern.shape).tocsc()
        lu = spla.splu(A, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
        return lambda y: lu.solve(np.asarray(y, dtype=float))

    def _current(self) -> Callable[[], None]:
        """A new generation of the in-place factor, and a check that it is still the current one."""
        self._generation += 1
        generation = self._generation

        def check() -> None:
            if generation != self._generation:
                raise RuntimeError("stale factorisation: the Factorizer has refactorised since")

        return check

    def _cholmod(self, data: np.ndarray) -> Solve:
        from cvxopt import cholmod, matrix

        self._matrix.V = matrix(data[self._lower])
        try:
            cholmod.numeric(self._matrix, self._symbolic)
        except ArithmeticError as err:  # cvxopt: the column of the first non-positive pivot
            raise np.linalg.LinAlgError(f"matrix is not positive definite (CHOLMOD: pivot {err})") from err
        check, factor, n = self._current(), self._symbolic, self.n

        def solve(y: np.ndarray) -> np.ndarray:
            check()
            y = np.asarray(y, dtype=float)
            x = matrix(y.reshape(n, -1))  # a column-major copy
            cholmod.solve(factor, x)  # sys = 0: x = A⁻¹ y
            return np.array(x).reshape(y.shape)

        return solve

    def _pardiso(self, data: np.ndarray) -> Solve:
        solver, A = self._solver, self._matrix
        A.data = np.ascontiguousarray(data[self._upper])
        dummy = np.zeros((self.n, 1), order="F")
        if not self._analysed:  # symbolic analysis (ordering) once per pattern
            solver.set_phase(11)
            solver._call_pardiso(A, dummy)
            self._analysed = True
        solver.set_phase(22)  # numerical factorisation only
        solver._call_pardiso(A, dummy)
        check = self._current()

        def solve(y: np.ndarray) -> np.ndarray:
            check()
            y = np.asarray(y, dtype=float)
            solver.set_phase(33)
            return solver._call_pardiso(A, np.asfortranarray(y)).reshape(y.shape)

        return solve


def is_positive_definite(A: sp.spmatrix, prefer: str = "auto") -> bool:
    """Whether the symmetric matrix ``A`` is numerically positive definite: its sparse
    Cholesky factorisation ``A = L Lᵀ`` exists (supernodal CHOLMOD stops at the first
    non-positive pivot).  SciPy's SuperLU, run without off-diagonal pivoting in symmetric mode, computes
    ``A = L D Lᵀ``-like factors with ``D = diag(U)``; ``A`` is positive definite iff no row
    was swapped and every pivot ``U_ii > 0`` (Sylvester: the pivots are ratios of leading
    principal minors)."""
    A = sp.csr_matrix(A)
    A.sum_duplicates()
    A.sort_indices()
    backend = backend_name(prefer)
    if backend != "superlu":  # supernodal CHOLMOD (LLᵀ) and PARDISO's SPD mode stop at a bad pivot
        try:
            Factorizer(A, backend)(A.data)
        except (np.linalg.LinAlgError, ValueError, RuntimeError):
            return False
        return True
    try:
        lu = spla.splu(A.tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0, options={"SymmetricMode": True})
    except RuntimeError:  # exactly singular
        return False
    return bool(np.array_equal(lu.perm_r, lu.perm_c) and np.all(lu.U.diagonal() > 0.0))


def _indptr(rows: np.ndarray, n: int) -> np.ndarray:
    return np.concatenate([[0], np.cumsum(np.bincount(rows, minlength=n))]).astype(np.int32)


def factorize(A: sp.spmatrix, prefer: str = "auto") -> Solve:
    """Factorise the SPD matrix ``A`` once; return ``x = solve(y)`` for vectors or (n, k) blocks."""
    A = sp.csr_matrix(A)
    A.sum_duplicates()
    A.sort_indices()
    return Factorizer(A, prefer)(A.data)
