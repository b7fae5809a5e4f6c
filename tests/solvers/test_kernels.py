"""The compiled kernels on hand-made matrices: which rows follow a stencil, a Gauss–Seidel row
with a zero diagonal left as pyamg leaves it, and the rows stored apart summed in their order.
(Their agreement with scipy and pyamg on assembled matrices: ``test_stencil.py``,
``test_certificate.py``.)"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from pyamg import amg_core

from signorini.solvers import kernels


def _tridiagonal(n: int) -> sp.csr_matrix:
    return sp.csr_matrix(sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n)))


def test_a_row_follows_the_stencil_only_with_its_offsets_and_its_bits():
    A = _tridiagonal(6)
    A.data[A.indptr[3] + 2] = -1.0 + 2.0**-52  # A_34 one bit off
    A.data[A.indptr[4]] = 0.0  # A_43 an explicit zero: the same columns, another value
    offsets, values = np.array([-1, 0, 1]), np.array([-1.0, 2.0, -1.0])
    follows = kernels.stencil_rows(A.indptr, A.indices, A.data, offsets, values)
    # rows 0 and 5 have two entries; rows 3 and 4 differ in a value
    assert follows.tolist() == [0, 1, 1, 0, 0, 0]


def test_a_zero_diagonal_leaves_its_unknown_as_pyamg_does():
    """Every row stored apart (kind ≥ 0), one with a zero diagonal: the sweep equals pyamg's."""
    A = _tridiagonal(5).tolil()
    A[2, 2] = 0.0
    A = sp.csr_matrix(A)
    kind = np.arange(5, dtype=np.int32)
    x, b = np.linspace(1.0, 2.0, 5), np.array([1.0, -2.0, 3.0, 0.5, 4.0])
    got, expected = x.copy(), x.copy()
    indptr = A.indptr.astype(np.int64)
    kernels.gauss_seidel(got, b, 0, 5, 1, kind, (-1, 1), (-1.0, -1.0), 2.0, indptr, A.indices, A.data)
    amg_core.gauss_seidel(A.indptr, A.indices, A.data, expected, b, 0, 5, 1)
    assert got.tobytes() == expected.tobytes() and got[2] == x[2]


def test_rows_of_either_kind_give_the_product_and_the_residual():
    """Interior rows by the stencil, the two end rows stored apart: ``A x`` and ``b - A x``."""
    A = _tridiagonal(6)
    ends = np.array([0, 5])
    kind = np.full(6, -1, dtype=np.int32)
    kind[ends] = [0, 1]
    ex = A[ends]
    x, b = np.arange(6.0) ** 2, np.ones(6)
    stencil = ((-1, 0, 1), (-1.0, 2.0, -1.0))
    y, r = np.empty(6), np.empty(6)
    others = (ex.indptr.astype(np.int64), ex.indices, ex.data)
    kernels.apply(x, x, y, False, kind, *stencil, *others)
    kernels.apply(x, b, r, True, kind, *stencil, *others)
    assert y.tobytes() == (A @ x).tobytes() and r.tobytes() == (b - A @ x).tobytes()
