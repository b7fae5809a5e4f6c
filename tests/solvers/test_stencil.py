"""The operator of a structured grid as one stencil and the rows that differ: every product,
residual and Gauss–Seidel sweep bit-identical to scipy's and pyamg's on the CSR matrix, and the
multigrid route's solutions unchanged in every bit."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import scipy.sparse as sp
from pyamg import amg_core

from signorini.fem.assembly import system_matrix
from signorini.fem.discrete import build
from signorini.fem.mesh import fk_boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.solvers import certificate, multigrid, multigrid_solve
from signorini.solvers.multigrid import GalerkinHierarchy, coarse_lines, compact, fk_transfer, galerkin_product
from signorini.solvers.pdas import clamped_values
from signorini.solvers.stencil import StencilOperator, entries


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


def _same_csr(P: sp.csr_matrix, Q: sp.csr_matrix) -> bool:
    """The same arrays, dtypes and bits (the stored order within a row included)."""
    return P.shape == Q.shape and all(
        getattr(P, a).dtype == getattr(Q, a).dtype and _same(getattr(P, a), getattr(Q, a))
        for a in ("indptr", "indices", "data")
    )


@pytest.mark.parametrize(("N", "diagonal", "c"), [(22, "nw_se", 1.0), (31, "sw_ne", 2.5)])
def test_the_operator_stands_in_for_the_matrix(rng, N, diagonal, c):
    """What the solve reads of ``A`` it reads of the operator with the same bits: rows as CSR
    (a range, a set, all), entries at positions, ``|A| y``; a copy changes apart from it."""
    A = sp.csr_matrix(build(Problem(c=c), N, diagonal).A)
    op = StencilOperator.from_csr(A, _centre(A))
    assert _same_csr(op.tocsr(), A) and _same_csr(op.rows_csr(N + 3, 5 * N), A[N + 3 : 5 * N])
    B = fk_boundary_nodes(N)
    assert _same_csr(op.row_block(B), A[B])
    rows_of = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    at = rng.choice(A.nnz, size=200, replace=False)
    assert _same(entries(op, at, rows_of[at]), A.data[at])
    y = rng.standard_normal(A.shape[0])
    assert _same(op.abs_product(y), certificate.abs_product(A, y))
    changed = op.copy()
    changed.set_values(at[:3], rows_of[at[:3]], np.zeros(3))
    assert _same_csr(op.tocsr(), A) and not _same(changed.tocsr().data, A.data)


@pytest.mark.parametrize(("N", "diagonal"), [(40, "sw_ne"), (45, "nw_se")])
def test_the_galerkin_product_by_blocks_is_scipys(monkeypatch, N, diagonal):
    """``R (A P)`` formed a few coarse rows at a time, from the CSR matrix or from the operator:
    scipy's whole product array for array (stored order and index dtype included), on two levels."""
    A = sp.csr_matrix(build(Problem(x0=0.52, R=0.38, c=1.5), N, diagonal).A)
    lines = np.arange(N + 1)
    for _ in range(2):
        P = fk_transfer(lines, coarse_lines(lines), diagonal)
        R = P.T.tocsr()
        whole = (R @ (A @ P)).tocsr()
        monkeypatch.setattr(multigrid, "GALERKIN_BLOCK_ROWS", 7)
        assert _same_csr(galerkin_product(A, P, R), whole)
        op = StencilOperator.from_csr(A, _centre(A))
        assert op is None or _same_csr(galerkin_product(op, P, R), whole)
        monkeypatch.undo()
        A, lines = whole, coarse_lines(lines)
        A.sum_duplicates()
        A.sort_indices()


def test_a_compact_matrix_solves_to_the_same_bits_without_its_values(monkeypatch):
    """The multigrid route given the operator in place of ``A`` (``compact``): cold on unseen
    parameters (nested start) and from the cascade on the paper's problem (releases settled on a
    patch), the same solution, multipliers, contact set, work and algebraic error in every bit as
    from the CSR matrix; and no CSR copy of the operator is alive in any Newton step."""
    import gc
    import weakref

    from signorini.fem.solve import solve_discrete
    from signorini.solvers.algebraic_error import linearised_error

    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)
    monkeypatch.setattr(multigrid, "GALERKIN_BLOCK_ROWS", 100)
    assert compact(sp.csr_matrix(np.eye(9))).shape == (9, 9)  # no grid: the matrix as it is
    copies = []
    rows_csr = StencilOperator.rows_csr

    def recorded(self, lo, hi):
        out = rows_csr(self, lo, hi)
        copies.append(weakref.ref(out.data))
        return out

    def no_copy_alive(row):
        gc.collect()
        assert all(ref() is None for ref in copies)

    monkeypatch.setattr(StencilOperator, "rows_csr", recorded)
    cases = [(Problem(x0=0.46, R=0.41, A=6.0, c=1.5), 127, "nw_se", False), (Problem(), 201, "sw_ne", True)]
    for problem, N, diagonal, cascade in cases:
        disc = build(problem, N, diagonal)
        A = sp.csr_matrix(disc.A)
        op = compact(A)
        assert isinstance(op, StencilOperator)
        copies.clear()
        if cascade:
            got = solve_discrete(dataclasses.replace(disc, A=op), "multigrid", max_coarse=30, callback=no_copy_alive)
            expected = solve_discrete(disc, "multigrid", max_coarse=30)
            assert got.info["cascade"]["N"] == N // 4 and got.info["local_settles"] > 0
        else:
            got = multigrid_solve(op, disc.b, disc.boundary, max_coarse=30, callback=no_copy_alive)
            expected = multigrid_solve(A, disc.b, disc.boundary, max_coarse=30)
            assert got.info["nested_start"]
        assert copies  # the data check and the Galerkin products read it as CSR, and let it go
        assert _same(got.u, expected.u) and _same(got.lam, expected.lam) and _same(got.active, expected.active)
        counted = ("v_cycles", "cg_iterations", "work_units", "local_settles")
        assert [got.info[k] for k in counted] == [expected.info[k] for k in counted]
        assert got.iterations == expected.iterations
        errors = [
            linearised_error(M, disc.b, disc.boundary, r.u, r.lam, r.active, "multigrid", r.hierarchy)
            for M, r in ((op, got), (A, expected))
        ]
        assert _same(errors[0].delta, errors[1].delta) and errors[0].energy == errors[1].energy
