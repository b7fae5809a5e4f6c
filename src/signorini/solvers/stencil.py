"""The operator of a structured grid stored as one stencil and the rows that differ from it.

On a Friedrichs–Keller grid every interior row of the P1 matrix is the same 7-point stencil,
bit for bit; only the rows of the boundary ring differ, and, once nodes are clamped, the rows
next to them.  ``StencilOperator`` keeps the stencil (its column offsets and values) once and the
other rows as a small CSR matrix, and applies the operator row by row in compiled kernels: the
product, the residual and the Gauss–Seidel sweeps of the multigrid route.  Each row is summed in
the order of the CSR matrix it came from (ascending column), from 0.0, as scipy's product and
pyamg's Gauss–Seidel sum it, so every result is bit-identical to theirs while the values of the
fine operator (a copy of ``A``'s, 0.9 GB at N = 4001) are not stored.

The operator also stands in for ``A`` itself (``multigrid.compact``): the multigrid route and the
algebraic-error estimate read a matrix's entries through ``entries``, its ``|A| y`` through
``abs_product``, its rows through ``rows_csr`` and ``row_block``, so a job that holds only the
operator solves with the same bits without ``A``'s values in memory.

The kernels are ``signorini.solvers.kernels``, imported where an operator is applied (importing
them costs a process more than they save below ``certificate.COMPILED_MIN_UNKNOWNS`` rows, and the
multigrid route builds this operator only for matrices that large).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

STENCIL_SHARE = 0.5  # a matrix is stored as a stencil only if at least this share of its rows follow it


class StencilOperator:
    """A square CSR matrix ``A`` (sorted indices) as the stencil of its row ``centre`` and the rows
    that differ from it; ``positions`` of ``A.data`` address its entries (``values_at``,
    ``set_values``), so the operator can be changed in ``A``'s pattern as a CSR copy would be.

    ``from_csr`` returns None where fewer than ``STENCIL_SHARE`` of the rows follow the stencil."""

    has_sorted_indices = True  # the pattern's columns ascend in every row (``multigrid.fk_grid`` reads it)

    def __init__(self, A: sp.csr_matrix, centre: int, stencil: np.ndarray | None = None):
        lo, hi = A.indptr[centre], A.indptr[centre + 1]
        self.shape, self.nnz, self.dtype = A.shape, A.nnz, A.data.dtype
        self.offsets = A.indices[lo:hi].astype(np.int64) - centre
        self.values = A.data[lo:hi].copy()
        self.diagonal_at = int(np.flatnonzero(self.offsets == 0)[0]) if np.any(self.offsets == 0) else -1
        self._indptr, self._indices = A.indptr, A.indices  # A's pattern (shared, not copied)
        if stencil is None:
            stencil = self.follows(A, centre)
        self.kind = np.full(A.shape[0], -1, dtype=np.int32)  # -1: the stencil; k: row k of the others
        self.rows = np.zeros(0, dtype=np.int64)
        self._others(np.flatnonzero(~stencil), A.data)

    @staticmethod
    def follows(A: sp.csr_matrix, centre: int) -> np.ndarray:
        """Which rows of ``A`` equal row ``centre`` shifted (same offsets, same bits)."""
        from signorini.solvers import kernels

        lo, hi = A.indptr[centre], A.indptr[centre + 1]
        offsets, values = A.indices[lo:hi].astype(np.int64) - centre, A.data[lo:hi].copy()
        return kernels.stencil_rows(A.indptr, A.indices, A.data, offsets, values).view(bool)

    @classmethod
    def from_csr(cls, A: sp.csr_matrix, centre: int) -> StencilOperator | None:
        """The operator, or None where fewer than ``STENCIL_SHARE`` of the rows follow row ``centre``."""
        stencil = cls.follows(A, centre)
        return cls(A, centre, stencil) if np.count_nonzero(stencil) >= STENCIL_SHARE * A.shape[0] else None

    def _others(self, rows: np.ndarray, data: np.ndarray | None = None) -> None:
        """Store ``rows`` (ascending) apart: their entries from ``data`` (``A``'s pattern), or,
        without it, from the rows stored apart so far and the stencil for the others."""
        indptr, pos, row_of = self._row_entries(rows)
        values = data[pos] if data is not None else self.values_at(pos, row_of)
        self.ex_indptr, self.ex_indices, self.ex_data = indptr, self._indices[pos].copy(), values
        self.kind[self.rows] = -1
        self.rows = rows
        self.kind[rows] = np.arange(rows.size, dtype=np.int32)

    def _row_entries(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """For ``rows`` in their order: the row pointers of their entries stacked, the entries'
        positions in ``A``'s pattern and the row of each."""
        starts, ends = self._indptr[rows], self._indptr[rows + 1]
        indptr = np.concatenate([[0], np.cumsum(ends - starts)]).astype(np.int64)
        return indptr, concatenated_ranges(starts, ends), np.repeat(rows, ends - starts)

    def _promote(self, rows: np.ndarray) -> None:
        """Store ``rows`` apart too (their values are still the stencil's)."""
        new = np.setdiff1d(np.unique(rows), self.rows)
        if new.size:
            self._others(np.union1d(self.rows, new))

    @property
    def indptr(self) -> np.ndarray:
        """The row pointers of the CSR pattern the operator came from (positions address it)."""
        return self._indptr

    @property
    def indices(self) -> np.ndarray:
        """The column indices of that pattern."""
        return self._indices

    def _where(self, positions: np.ndarray, rows: np.ndarray) -> np.ndarray:
        return self.ex_indptr[self.kind[rows]] + (positions - self._indptr[rows])

    def values_at(self, positions: np.ndarray, rows: np.ndarray) -> np.ndarray:
        """The entries at ``positions`` of ``A.data`` (``rows``: the row of each)."""
        stencil = self.kind[rows] < 0
        out = np.empty(positions.size)
        out[stencil] = self.values[positions[stencil] - self._indptr[rows[stencil]]]
        out[~stencil] = self.ex_data[self._where(positions[~stencil], rows[~stencil])]
        return out

    def set_values(self, positions: np.ndarray, rows: np.ndarray, values: np.ndarray) -> None:
        """Set the entries at ``positions`` of ``A.data`` (their rows are stored apart first)."""
        self._promote(rows[self.kind[rows] < 0])
        self.ex_data[self._where(positions, rows)] = values

    def add_values(self, positions: np.ndarray, rows: np.ndarray, increments: np.ndarray) -> None:
        """Add ``increments`` to the entries at distinct ``positions`` (``np.add.at`` on a CSR copy)."""
        self.set_values(positions, rows, self.values_at(positions, rows) + increments)

    def copy(self) -> StencilOperator:
        """An operator of the same entries that changes apart (the pattern and stencil shared)."""
        other = object.__new__(StencilOperator)
        other.__dict__.update(self.__dict__)
        other.kind, other.rows = self.kind.copy(), self.rows.copy()
        other.ex_indptr, other.ex_indices, other.ex_data = (
            a.copy() for a in (self.ex_indptr, self.ex_indices, self.ex_data)
        )
        return other

    def rows_csr(self, lo: int, hi: int) -> sp.csr_matrix:
        """Rows ``lo:hi`` as CSR in ``A``'s pattern (``A[lo:hi]``: the same arrays)."""
        from signorini.solvers import kernels

        first, last = int(self._indptr[lo]), int(self._indptr[hi])
        data = np.empty(last - first)
        kernels.stencil_csr_data(self._indptr, self.kind, self.values, self.ex_indptr, self.ex_data, lo, hi, data)
        indptr = self._indptr[lo : hi + 1] - self._indptr[lo]
        return sp.csr_matrix((data, self._indices[first:last], indptr), shape=(hi - lo, self.shape[1]))

    def tocsr(self) -> sp.csr_matrix:
        """The matrix as CSR in ``A``'s pattern (a full copy of its values)."""
        return self.rows_csr(0, self.shape[0])

    def row_block(self, rows: np.ndarray) -> sp.csr_matrix:
        """The rows ``rows`` (in their order) as CSR: ``A[rows]``."""
        rows = np.asarray(rows, dtype=np.int64)
        indptr, pos, row_of = self._row_entries(rows)
        values = self.values_at(pos, row_of)
        return sp.csr_matrix((values, self._indices[pos], indptr), shape=(rows.size, self.shape[1]))

    def _stencil(self, without_diagonal: bool = False, lower_only: bool = False) -> tuple[tuple, tuple]:
        """The stencil's offsets and values as tuples (the kernels unroll loops over them): all,
        without the diagonal entry, or only the entries left of the diagonal."""
        keep = [
            k
            for k in range(self.offsets.size)
            if not (without_diagonal and k == self.diagonal_at) and not (lower_only and self.offsets[k] >= 0)
        ]
        return tuple(int(self.offsets[k]) for k in keep), tuple(float(self.values[k]) for k in keep)

    def __matmul__(self, x: np.ndarray) -> np.ndarray:
        from signorini.solvers import kernels

        x = np.ascontiguousarray(x, dtype=float)
        y = np.empty(self.shape[0])
        kernels.apply(x, x, y, False, self.kind, *self._stencil(), self.ex_indptr, self.ex_indices, self.ex_data)
        return y

    def residual(self, x: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``b - A x``, bit-identical to the two steps."""
        from signorini.solvers import kernels

        r = np.empty(self.shape[0])
        kernels.apply(x, b, r, True, self.kind, *self._stencil(), self.ex_indptr, self.ex_indices, self.ex_data)
        return r

    def restricted_residual(self, x: np.ndarray, b: np.ndarray, P: sp.csr_matrix) -> np.ndarray:
        """``Pᵀ (b - A x)`` for a CSR ``P``, bit-identical to ``P.T @ (b - A @ x)`` without the
        residual in memory."""
        from signorini.solvers import kernels

        coarse = np.zeros(P.shape[1])
        kernels.restricted_residual(
            x,
            b,
            self.kind,
            *self._stencil(),
            self.ex_indptr,
            self.ex_indices,
            self.ex_data,
            P.indptr,
            P.indices,
            P.data,
            coarse,
        )
        return coarse

    def gauss_seidel(self, x: np.ndarray, b: np.ndarray, forward: bool, from_zero: bool = False) -> None:
        """One Gauss–Seidel sweep on ``x`` in place, forward or backward.  ``from_zero``: ``x`` is
        zero and the sweep forward, so a stencil row's entries right of the diagonal multiply zeros
        and are left out (adding ±0 to a sum that starts at +0 changes none of its bits; the chain
        each row waits on is shorter)."""
        from signorini.solvers import kernels

        n = self.shape[0]
        start, stop, step = (0, n, 1) if forward else (n - 1, -1, -1)
        diagonal = float(self.values[self.diagonal_at]) if self.diagonal_at >= 0 else 0.0
        others = (self.ex_indptr, self.ex_indices, self.ex_data)
        stencil = self._stencil(True, lower_only=from_zero and forward)
        kernels.gauss_seidel(x, b, start, stop, step, self.kind, *stencil, diagonal, *others)

    def abs_product(self, y: np.ndarray) -> np.ndarray:
        """``|A| y``, each row summed in CSR order from 0.0 as ``certificate.abs_product`` sums it."""
        from signorini.solvers import kernels

        y = np.ascontiguousarray(y, dtype=float)
        out = np.empty(self.shape[0])
        offsets, values = self._stencil()
        stencil = (offsets, tuple(abs(v) for v in values))
        kernels.apply(y, y, out, False, self.kind, *stencil, self.ex_indptr, self.ex_indices, np.abs(self.ex_data))
        return out


def concatenated_ranges(starts: np.ndarray, ends: np.ndarray) -> np.ndarray:
    """The concatenated ranges ``starts[k]:ends[k]`` (with a CSR matrix's ``indptr``: the positions
    of the stored entries of rows)."""
    lengths = ends - starts
    offsets = np.repeat(starts - np.concatenate([[0], np.cumsum(lengths)[:-1]]), lengths)
    return np.arange(int(lengths.sum())) + offsets


def as_csr(A: sp.csr_matrix | StencilOperator) -> sp.csr_matrix:
    """A CSR matrix as it is; the CSR copy of an operator standing in for one."""
    return A.tocsr() if isinstance(A, StencilOperator) else A


def residual(A: sp.csr_matrix | StencilOperator, x: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``b - A x`` of a matrix (two vectors formed) or of an operator standing in for one (one)."""
    return A.residual(x, b) if isinstance(A, StencilOperator) else b - A @ x


def entries(A: sp.csr_matrix | StencilOperator, positions: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The entries at ``positions`` of the stored values of a CSR matrix or of the operator standing
    in for it (``rows``: the row of each)."""
    return A.values_at(positions, rows) if isinstance(A, StencilOperator) else A.data[positions]
