"""The operator of a structured grid as one stencil and the rows that differ: every product,
residual and Gauss–Seidel sweep bit-identical to scipy's and pyamg's on the CSR matrix, and the
multigrid route's solutions unchanged in every bit."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from pyamg import amg_core

from signorini.fem.assembly import system_matrix
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.problem import Problem
from signorini.solvers import certificate, multigrid_solve
from signorini.solvers.multigrid import GalerkinHierarchy
from signorini.solvers.pdas import clamped_values
from signorini.solvers.stencil import StencilOperator


def _centre(A: sp.csr_matrix) -> int:
    side = int(round(np.sqrt(A.shape[0])))
    return side * (side // 2) + side // 2


def _same(a: np.ndarray, b: np.ndarray) -> bool:
    return a.tobytes() == b.tobytes()


def _assert_applies_as_csr(op: StencilOperator, M: sp.csr_matrix, rng) -> None:
    """Product, residual and both sweeps of ``op`` against scipy and pyamg on ``M``, bit for bit."""
    n = M.shape[0]
    x, b = rng.standard_normal(n), rng.standard_normal(n)
    assert _same(op @ x, M @ x)
    assert _same(op.residual(x, b), b - M @ x)
    for start, forward, from_zero in ((x, True, False), (x, False, False), (np.zeros(n), True, True)):
        got, expected = start.copy(), start.copy()
        op.gauss_seidel(got, b, forward, from_zero)
        amg_core.gauss_seidel(M.indptr, M.indices, M.data, expected, b, *((0, n, 1) if forward else (n - 1, -1, -1)))
        assert _same(got, expected)
    assert _same(op.tocsr().toarray(), M.toarray())


@pytest.mark.parametrize(("N", "diagonal", "c"), [(21, "sw_ne", 1.0), (40, "nw_se", 1.0), (33, "sw_ne", 0.0)])
def test_the_stencil_operator_applies_the_matrix_bit_for_bit(rng, N, diagonal, c):
    """On the assembled Friedrichs–Keller matrices (N odd and even, both diagonals, c = 0 and 1):
    every interior row is the stencil, the boundary ring is stored apart, and every operation
    equals the CSR one."""
    A = sp.csr_matrix(build(Problem(c=c), N, diagonal).A)
    op = StencilOperator.from_csr(A, _centre(A))
    # K + c M couples the diagonal's neighbours through M only: 5 entries for c = 0
    assert op is not None and op.offsets.size == (7 if c else 5) and op.nnz == A.nnz
    assert op.rows.size == 4 * N  # the boundary ring
    _assert_applies_as_csr(op, A, rng)


def test_a_matrix_without_a_common_stencil_stays_csr():
    """A jittered mesh's rows all differ: no stencil operator (the multigrid route copies the CSR)."""
    A = sp.csr_matrix(system_matrix(friedrichs_keller(21, jitter=0.3, seed=1), 1.0))
    A.sort_indices()
    assert StencilOperator.from_csr(A, _centre(A)) is None


def test_changed_entries_are_stored_apart_and_read_back(rng):
    """Clamping nodes changes entries of stencil rows: those rows move apart with their other values
    kept, and the operator equals the clamped CSR matrix in every bit, over several clamped sets."""
    disc = build(Problem(), 31)
    A = sp.csr_matrix(disc.A)
    op = StencilOperator.from_csr(A, _centre(A))
    rows_of = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    free = np.ones(A.shape[0], dtype=bool)
    for flips in (1, 5, disc.boundary.size // 2):
        nodes = rng.choice(disc.boundary, size=flips, replace=False)
        free[nodes] = ~free[nodes]
        touched = np.flatnonzero(np.isin(rows_of, nodes) | np.isin(A.indices, nodes))
        values = clamped_values(A, rows_of[touched], free, touched)
        op.set_values(touched, rows_of[touched], values)
        assert _same(op.values_at(touched, rows_of[touched]), values)
        clamped = sp.csr_matrix((clamped_values(A, rows_of, free), A.indices, A.indptr), shape=A.shape)
        _assert_applies_as_csr(op, clamped, rng)


def test_v_cycles_and_solves_are_those_of_the_csr_fine_operator(rng, monkeypatch):
    """The hierarchy's fine operator as a stencil gives the V-cycle of its CSR copy bit for bit,
    after Galerkin updates too, and a cold multigrid solve (nested start, several levels, unseen
    parameters) the same solution, multipliers and work in every bit."""
    disc = build(Problem(x0=0.43, R=0.37, A=7.0, c=2.5), 63, "nw_se")
    A = sp.csr_matrix(disc.A)
    free = np.ones(A.shape[0], dtype=bool)
    free[rng.choice(disc.boundary, size=40, replace=False)] = False
    r = rng.standard_normal(A.shape[0])
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)  # the kernels on a small mesh
    with_stencil = GalerkinHierarchy(A, max_coarse=20)
    with_stencil.update(free)
    solved = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=20)
    # the fine and the first coarse levels as stencils (Galerkin updates of a coarse one included),
    # a small level where too few rows follow the stencil and the coarsest as CSR
    assert isinstance(with_stencil.matrix, StencilOperator) and with_stencil.stencil_levels[:2] == [True, True]
    assert not with_stencil.stencil_levels[-1] and not all(with_stencil.stencil_levels)
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", A.shape[0] + 1)  # numpy and pyamg
    plain = GalerkinHierarchy(A, max_coarse=20)
    plain.update(free)
    assert sp.isspmatrix_csr(plain.matrix)
    assert _same(with_stencil(r), plain(r))
    reference = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=20)
    assert _same(solved.u, reference.u) and _same(solved.lam, reference.lam)
    assert solved.info["v_cycles"] == reference.info["v_cycles"] and solved.info["nested_start"]
