"""The compiled kernels of the solvers (numba): row-by-row passes over a sparse matrix that numpy
would make in several passes with temporaries of the matrix's size.

Importing numba and loading the cached kernels costs each process more than they save below a few
million unknowns (docs/evidence/design-measurements.md#compiled-kernels): callers import this
module only for matrices of at least ``COMPILED_MIN_UNKNOWNS`` rows
(``signorini.solvers.certificate``) and otherwise take numpy code that gives the same bits.  Each
kernel sums a row in the order of its CSR entries from 0.0, as scipy's products and pyamg's
Gauss–Seidel do.  Compiled once per machine and cached beside this module.
"""

from __future__ import annotations

import numba
import numpy as np


@numba.njit(cache=True)
def abs_product_rows(indptr, indices, data, y, out):  # pragma: no cover - compiled
    """``out = |A| y`` of a CSR matrix."""
    for i in range(out.size):
        total = 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            total += abs(data[jj]) * y[indices[jj]]
        out[i] = total


@numba.njit(cache=True)
def symmetry_and_dominance(indptr, indices, data):  # pragma: no cover - compiled
    """One pass over a CSR matrix with sorted indices: ``max |A_ij|``; ``max |A - Aᵀ|`` over the
    stored entries without forming ``Aᵀ`` (each ``A_ij`` against ``A_ji`` found by bisection in
    row j, 0 if not stored); and whether every row has ``A_ii ≥ Σ_{j≠i} |A_ij| - 1e-12 A_ii``
    (the off-diagonal sum as ``|A| 1 - |A_ii|``, ``|A| 1`` summed in CSR order)."""
    top, asym, dominant = 0.0, 0.0, True
    for i in range(indptr.size - 1):
        total, diag = 0.0, 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            j, value = indices[jj], data[jj]
            top = max(top, abs(value))
            total += abs(value) * 1.0
            if j == i:
                diag = value
            lo, hi = indptr[j], indptr[j + 1]
            while lo < hi:
                mid = (lo + hi) // 2
                if indices[mid] < i:
                    lo = mid + 1
                else:
                    hi = mid
            mirror = data[lo] if lo < indptr[j + 1] and indices[lo] == i else 0.0
            asym = max(asym, abs(value - mirror))
        if not diag >= (total - abs(diag)) - 1e-12 * diag:
            dominant = False
    return top, asym, dominant


@numba.njit(cache=True)
def stencil_rows(indptr, indices, data, offsets, values):  # pragma: no cover - compiled
    """1 for every row equal to the stencil (same columns at the same offsets, same bits)."""
    n, m = indptr.size - 1, offsets.size
    out = np.zeros(n, np.uint8)
    for i in range(n):
        s = indptr[i]
        if indptr[i + 1] - s != m:
            continue
        same = True
        for k in range(m):
            if indices[s + k] != i + offsets[k] or data[s + k] != values[k]:
                same = False
                break
        if same:
            out[i] = 1
    return out


# The stencil reaches the kernels as tuples: their length is known when a kernel is compiled, so
# the loop over the stencil is unrolled (docs/evidence/design-measurements.md#stencil-operator).


@numba.njit(cache=True)
def apply(x, b, out, residual, kind, offsets, values, ex_indptr, ex_indices, ex_data):  # pragma: no cover - compiled
    """``out = A x`` of a stencil operator, or with ``residual`` ``out = b - A x``, each row summed
    in CSR order from 0.0 (scipy's ``csr_matvec``)."""
    for i in range(kind.size):
        row, total = kind[i], 0.0
        if row < 0:
            for k in range(len(offsets)):
                total += values[k] * x[i + offsets[k]]
        else:
            for jj in range(ex_indptr[row], ex_indptr[row + 1]):
                total += ex_data[jj] * x[ex_indices[jj]]
        out[i] = b[i] - total if residual else total


@numba.njit(cache=True)
def restricted_residual(
    x, b, kind, offsets, values, ex_indptr, ex_indices, ex_data, p_indptr, p_indices, p_data, coarse
):  # pragma: no cover - compiled
    """``coarse += Pᵀ (b - A x)`` of a stencil operator and a CSR prolongation ``P``, the residual
    formed a row at a time as ``apply`` forms it and scattered as scipy's product with the
    transpose (``csc_matvec``: row by row of ``P``, in its stored order), so ``b - A x`` is never
    held."""
    # apply's row sum written out again: called from a helper kernel, the loop over the stencil's
    # tuple is no longer unrolled (docs/evidence/design-measurements.md#stencil-operator)
    for i in range(kind.size):
        row, total = kind[i], 0.0
        if row < 0:
            for k in range(len(offsets)):
                total += values[k] * x[i + offsets[k]]
        else:
            for jj in range(ex_indptr[row], ex_indptr[row + 1]):
                total += ex_data[jj] * x[ex_indices[jj]]
        residual = b[i] - total
        for kk in range(p_indptr[i], p_indptr[i + 1]):
            coarse[p_indices[kk]] += p_data[kk] * residual


@numba.njit(cache=True)
def axpy(y, a, x, subtract):  # pragma: no cover - compiled
    """``y += a x`` (or ``y -= a x``) in place, rounded as numpy's ``y += a * x`` rounds: the
    product, then the sum."""
    for i in range(y.size):
        if subtract:
            y[i] -= a * x[i]
        else:
            y[i] += a * x[i]


@numba.njit(cache=True)
def stencil_csr_data(indptr, kind, values, ex_indptr, ex_data, lo, hi, out):  # pragma: no cover - compiled
    """The stored values of rows ``lo:hi`` of a stencil operator in its CSR pattern, into ``out``
    (the positions ``indptr[lo]:indptr[hi]``)."""
    first = indptr[lo]
    for i in range(lo, hi):
        row, at = kind[i], indptr[i] - first
        if row < 0:
            for k in range(values.size):
                out[at + k] = values[k]
        else:
            for jj in range(ex_indptr[row], ex_indptr[row + 1]):
                out[at + jj - ex_indptr[row]] = ex_data[jj]


@numba.njit(cache=True)
def prolongate_add(indptr, indices, data, y, x):  # pragma: no cover - compiled
    """``x += P y`` of a CSR matrix ``P`` without ``P y`` in memory: each row of ``P y`` summed in
    CSR order from 0.0 (scipy's ``csr_matvec``), then added, as ``x += P @ y`` rounds."""
    for i in range(x.size):
        total = 0.0
        for jj in range(indptr[i], indptr[i + 1]):
            total += data[jj] * y[indices[jj]]
        x[i] += total


@numba.njit(cache=True)
def gauss_seidel(
    x, b, start, stop, step, kind, offsets, values, diagonal, ex_indptr, ex_indices, ex_data
):  # pragma: no cover
    """pyamg's ``gauss_seidel`` (``amg_core/relaxation.h``): rows ``start:stop:step`` in turn, the
    off-diagonal sum in CSR order from 0.0, a row with a zero diagonal left as it is.  ``offsets``
    and ``values``: the stencil without its diagonal entry ``diagonal``.  Its arithmetic keeps
    pyamg's bits, at about twice the time of a reordered sweep
    (docs/evidence/design-measurements.md#gauss-seidel-chain)."""
    for i in range(start, stop, step):
        rsum, diag, row = 0.0, diagonal, kind[i]
        if row < 0:
            for k in range(len(offsets)):
                rsum += values[k] * x[i + offsets[k]]
        else:
            diag = 0.0
            for jj in range(ex_indptr[row], ex_indptr[row + 1]):
                j = ex_indices[jj]
                if j == i:
                    diag = ex_data[jj]
                else:
                    rsum += ex_data[jj] * x[j]
        if diag != 0.0:
            x[i] = (b[i] - rsum) / diag


@numba.njit(cache=True)
def _fk_weights(ci, cj, fx, fy, nc, sw_ne):  # pragma: no cover - compiled
    """The three (column, weight) of a fine vertex in ``multigrid.fk_transfer``'s order and
    arithmetic."""
    if sw_ne:
        below = fx >= fy
        c0, w0 = ci * nc + cj, (1.0 - fx) if below else (1.0 - fy)
        c1, w1 = ((ci + 1) * nc + cj) if below else (ci * nc + cj + 1), abs(fx - fy)
        c2, w2 = (ci + 1) * nc + cj + 1, fy if below else fx
    else:
        below = fx + fy <= 1.0
        c0, w0 = (ci * nc + cj) if below else ((ci + 1) * nc + cj + 1), abs(1.0 - fx - fy)
        c1, w1 = (ci + 1) * nc + cj, fx if below else (1.0 - fy)
        c2, w2 = ci * nc + cj + 1, fy if below else (1.0 - fx)
    return c0, w0, c1, w1, c2, w2


@numba.njit(cache=True)
def fk_transfer_rows(cell, frac, nc, sw_ne):  # pragma: no cover - compiled
    """The CSR arrays of ``multigrid.fk_transfer`` for grid lines with coarse ``cell`` and position
    ``frac`` in it (the same in x and y): two passes, counting and then filling, so no array is
    larger than the result."""
    n = cell.size
    indptr = np.zeros(n * n + 1, np.int32)
    for r in range(n * n):
        c0, w0, c1, w1, c2, w2 = _fk_weights(cell[r // n], cell[r % n], frac[r // n], frac[r % n], nc, sw_ne)
        indptr[r + 1] = indptr[r] + (w0 > 1e-12) + (w1 > 1e-12) + (w2 > 1e-12)
    indices, data = np.empty(indptr[-1], np.int32), np.empty(indptr[-1])
    for r in range(n * n):
        c0, w0, c1, w1, c2, w2 = _fk_weights(cell[r // n], cell[r % n], frac[r // n], frac[r % n], nc, sw_ne)
        k = indptr[r]
        for c, w in ((c0, w0), (c1, w1), (c2, w2)):
            if w > 1e-12:
                indices[k], data[k] = c, w
                k += 1
    return indptr, indices, data


@numba.njit(cache=True)
def row_reach(indptr, indices, N):  # pragma: no cover - compiled
    """For ``multigrid.fk_grid``, over the rows with at least two entries (sorted indices): the
    smallest offset of a first entry and the largest of a last entry (0 if none), whether a last
    entry lies at offset N + 2, and whether a last or next-to-last entry lies at offset N."""
    lowest, highest, sw_ne, nw_se = 0, 0, False, False
    for i in range(indptr.size - 1):
        first, last = indptr[i], indptr[i + 1] - 1
        if last - first < 1:
            continue
        high = indices[last] - i
        lowest, highest = min(lowest, indices[first] - i), max(highest, high)
        sw_ne = sw_ne or high == N + 2
        nw_se = nw_se or high == N or indices[last - 1] - i == N
    return lowest, highest, sw_ne, nw_se
