"""The compiled kernels of the solvers (numba): row-by-row passes over a sparse matrix that numpy
would make in several passes with temporaries of the matrix's size.

Importing numba and loading the cached kernels costs about 1.3 s per process
(docs/evidence/design-measurements.md#compiled-kernels), more than they save below a few million
unknowns: callers import this module only for matrices of at least ``COMPILED_MIN_UNKNOWNS`` rows
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
def asymmetry_rows(indptr, indices, data):  # pragma: no cover - compiled
    """``max |A - Aᵀ|`` over the stored entries of a CSR matrix with sorted indices, without
    forming ``Aᵀ``: each ``A_ij`` against ``A_ji`` found by bisection in row j (0 if not stored)."""
    top = 0.0
    for i in range(indptr.size - 1):
        for jj in range(indptr[i], indptr[i + 1]):
            j = indices[jj]
            lo, hi = indptr[j], indptr[j + 1]
            while lo < hi:
                mid = (lo + hi) // 2
                if indices[mid] < i:
                    lo = mid + 1
                else:
                    hi = mid
            mirror = data[lo] if lo < indptr[j + 1] and indices[lo] == i else 0.0
            top = max(top, abs(data[jj] - mirror))
    return top


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
def gauss_seidel(
    x, b, start, stop, step, kind, offsets, values, diagonal, ex_indptr, ex_indices, ex_data
):  # pragma: no cover
    """pyamg's ``gauss_seidel`` (``amg_core/relaxation.h``): rows ``start:stop:step`` in turn, the
    off-diagonal sum in CSR order from 0.0, a row with a zero diagonal left as it is.  ``offsets``
    and ``values``: the stencil without its diagonal entry ``diagonal``."""
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
