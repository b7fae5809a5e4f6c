"""The operator of a structured grid stored as one stencil and the rows that differ from it.

On a Friedrichs–Keller grid every interior row of the P1 matrix is the same 7-point stencil,
bit for bit; only the rows of the boundary ring differ, and, once nodes are clamped, the rows
next to them.  ``StencilOperator`` keeps the stencil (its column offsets and values) once and the
other rows as a small CSR matrix, and applies the operator row by row in compiled kernels: the
product, the residual and the Gauss–Seidel sweeps of the multigrid route.  Each row is summed in
the order of the CSR matrix it came from (ascending column), from 0.0, as scipy's product and
pyamg's Gauss–Seidel sum it, so every result is bit-identical to theirs while the values of the
fine operator (a copy of ``A``'s, 0.9 GB at N = 4001) are not stored.

The kernels are ``signorini.solvers.kernels``: the multigrid route builds this operator only for
matrices that large (``certificate.COMPILED_MIN_UNKNOWNS``).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from signorini.solvers import kernels

STENCIL_SHARE = 0.5  # a matrix is stored as a stencil only if at least this share of its rows follow it


class StencilOperator:
    """A square CSR matrix ``A`` (sorted indices) as the stencil of its row ``centre`` and the rows
    that differ from it; ``positions`` of ``A.data`` address its entries (``values_at``,
    ``set_values``), so the operator can be changed in ``A``'s pattern as a CSR copy would be.

    ``from_csr`` returns None where fewer than ``STENCIL_SHARE`` of the rows follow the stencil."""

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
        starts, ends = self._indptr[rows], self._indptr[rows + 1]
        lengths = ends - starts
        indptr = np.concatenate([[0], np.cumsum(lengths)]).astype(np.int64)
        pos = np.arange(int(lengths.sum())) + np.repeat(starts - indptr[:-1], lengths)
        values = data[pos] if data is not None else self.values_at(pos, np.repeat(rows, lengths))
        self.ex_indptr, self.ex_indices, self.ex_data = indptr, self._indices[pos].copy(), values
        self.kind[self.rows] = -1
        self.rows = rows
        self.kind[rows] = np.arange(rows.size, dtype=np.int32)

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

    def tocsr(self) -> sp.csr_matrix:
        """The matrix as CSR in ``A``'s pattern (a full copy of its values)."""
        data = np.empty(self.nnz)
        stencil = np.flatnonzero(self.kind < 0)
        data[(self._indptr[stencil][:, None] + np.arange(self.values.size)).ravel()] = np.tile(
            self.values, stencil.size
        )
        lengths = np.diff(self.ex_indptr)
        data[np.arange(self.ex_data.size) + np.repeat(self._indptr[self.rows] - self.ex_indptr[:-1], lengths)] = (
            self.ex_data
        )
        return sp.csr_matrix((data, self._indices, self._indptr), shape=self.shape)

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
        x = np.ascontiguousarray(x, dtype=float)
        y = np.empty(self.shape[0])
        kernels.apply(x, x, y, False, self.kind, *self._stencil(), self.ex_indptr, self.ex_indices, self.ex_data)
        return y

    def residual(self, x: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``b - A x``, bit-identical to the two steps."""
        r = np.empty(self.shape[0])
        kernels.apply(x, b, r, True, self.kind, *self._stencil(), self.ex_indptr, self.ex_indices, self.ex_data)
        return r

    def gauss_seidel(self, x: np.ndarray, b: np.ndarray, forward: bool, from_zero: bool = False) -> None:
        """One Gauss–Seidel sweep on ``x`` in place, forward or backward.  ``from_zero``: ``x`` is
        zero and the sweep forward, so a stencil row's entries right of the diagonal multiply zeros
        and are left out (adding ±0 to a sum that starts at +0 changes none of its bits; the chain
        each row waits on is shorter)."""
        n = self.shape[0]
        start, stop, step = (0, n, 1) if forward else (n - 1, -1, -1)
        diagonal = float(self.values[self.diagonal_at]) if self.diagonal_at >= 0 else 0.0
        others = (self.ex_indptr, self.ex_indices, self.ex_data)
        stencil = self._stencil(True, lower_only=from_zero and forward)
        kernels.gauss_seidel(x, b, start, stop, step, self.kind, *stencil, diagonal, *others)
