"""The multigrid route: the primal–dual active set iteration (``signorini.solvers.pdas``) with
each Newton system solved by conjugate gradients preconditioned with one multigrid V-cycle.

Cost in O(n): a V-cycle and a matrix-vector product per CG iteration and one hierarchy set-up,
where the direct route factorises (fill-in; time growing like n^1.5).  What makes it pay:

- **Geometric transfers where the grid is known.**  A Friedrichs–Keller matrix says which grid it
  lives on (``fk_grid``: (N + 1)² unknowns coupled to the neighbouring grid lines only), and its
  hierarchy halves that grid (``coarse_lines``: every other line, the last one kept, so odd N
  nests too) with the P1 interpolation between the meshes (``fk_transfer``) down to the coarsest
  level: Galerkin operators of 7 to 9 entries per row and an operator complexity of 4/3, set up
  in a fraction of classical AMG's time, with a smaller complexity than classical AMG's and fewer
  CG iterations for the whole solve (docs/evidence/design-measurements.md#multigrid-geometric-hierarchy).
  Any other matrix takes classical (Ruge–Stüben) AMG.

- **One hierarchy for every active set.**  Only boundary nodes are ever clamped, so the
  hierarchy's transfer operators are built once, for ``A`` itself (every node free), and kept.
  For an active set the fine operator is the clamped ``Ã(F)`` and every coarse operator is
  kept Galerkin, ``A_{l+1} = P_lᵀ A_l P_l``: the change ``Ã(F) - Ã(F')`` from the previous set
  lives in the rows and columns of the few nodes that changed status, so each coarse level is
  updated by a small product ``P_Sᵀ Δ_SS P_S`` over the affected nodes S, and the coarsest
  (at most ``max_coarse`` unknowns) is refactorised densely.  Galerkin coarse operators with a
  convergent smoother give a convergent, symmetric positive definite V-cycle whatever the
  transfers, and the transfers of ``A`` serve every set about as well as a fresh hierarchy
  (a few CG iterations more, for the final, the empty, the full and the cold start's contact sets
  alike).  A hierarchy built for one clamped set instead, reused unchanged for another, costs CG
  iterations for every node that changed status (docs/evidence/design-measurements.md#multigrid-one-hierarchy).
- **Inexact solves while the set moves.**  CG stops at the energy-relative accuracy
  ``inner_rtol``, and at least ``STEP_REDUCTION`` below where the step started (a change of a
  few nodes moves the global energy by less than ``inner_rtol`` but the nodes next to it, whose
  status is decided next, a lot).  A set that repeats is solved again to ``tol`` and tested once
  more (``pdas.iterate``).  Looser inner solves do not pay: ``inner_rtol`` = 1e-6 misjudges nodes
  (many Newton steps without ``STEP_REDUCTION``, more CG iterations with it than 1e-8 takes).  A
  tenfold reduction per step suffices: against a thousandfold, the same Newton steps and contact
  sets on the paper's problem from coarse to fine meshes and on stiff, large-amplitude, off-centre
  and cold-started cases, with fewer CG iterations
  (docs/evidence/design-measurements.md#multigrid-inner-tolerance).
- **Releases settled on a patch.**  From the cascade's start the contact set is too large at the
  end of the contact zone where the solution is biactive (u and λ vanish to second order there),
  and each Newton step releases about half of the excess: log₂ of it in steps of a few V-cycles.
  A step that only releases nodes is instead settled by an exact obstacle solve on a patch around
  them, the rest of the iterate held as Dirichlet data (``solvers.local``), and the iteration goes
  on from there: the same final test, fewer steps and V-cycles
  (docs/evidence/design-measurements.md#multigrid-local-release).
- **Warm starts.**  Each solve starts from the previous Newton iterate, the first from the
  warm start (in the cascade of ``fem.solve`` the coarser mesh's interpolant): a step that
  changed a few nodes costs a few iterations.  Without a warm start the route makes its own
  (``nested_start``, nested iteration from ``A`` and ``b`` alone): the problem restricted to the
  hierarchy's first coarse grid, solved the same way, prolongated.  The plain cold start grows
  the contact set by a node per Newton step; the nested one takes a fraction of its steps, CG
  iterations and time (docs/evidence/design-measurements.md#multigrid-nested-start).

Stopping test.  With ``M ≈ Ã⁻¹`` the preconditioned residual ``√(rᵀMr)`` estimates the energy
norm of the error ``‖e‖_Ã``, and ``xᵀDb`` estimates ``‖u‖²_Ã``; CG stops when
``√(rᵀMr) ≤ rtol √(xᵀDb)``.  On the paper's problem (against a solution refined with long-double
residuals) this ratio follows the max-norm relative error closely down to about 1e-14, where
double precision ends: ``tol = 1e-14`` gives errors of about 1e-14 max |u|
(docs/evidence/design-measurements.md#multigrid-stopping-test).  (A max-norm residual test cannot
do this: the rounding noise ``ε |A||u|`` of evaluating the residual hides the smooth error
components, which dominate the error.)  After
an accurate solve the true residual is compared with that rounding floor, and CG is restarted
from its iterate (iterative refinement) if the recurrence has drifted from it.

The V-cycle is the hierarchy's transfers with forward Gauss–Seidel before and backward
Gauss–Seidel after the coarse correction (a symmetric cycle, one sweep each way), run without
pyamg's residual bookkeeping.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from signorini.solvers import certificate, pdas
from signorini.solvers.certificate import KKTError, NotConvergedError, abs_product
from signorini.solvers.local import settle_release
from signorini.solvers.pdas import StepCallback, certified_result, clamped_values, initial_active, iterate, prepare_qp
from signorini.solvers.result import SolveResult
from signorini.solvers.stencil import StencilOperator, as_csr, concatenated_ranges, residual

log = logging.getLogger(__name__)

AMG_KINDS = ("geometric", "classical", "smoothed_aggregation")
REFINEMENTS = 2  # CG restarts from the true residual after an accurate solve, at most
FLOOR_FACTOR = 8.0  # the true residual of a converged solve is ~2 ε |A||x| (max norm)
STEP_REDUCTION = 0.1  # an inexact solve reduces its starting energy residual at least this much
NESTED_MIN_CELLS = 24  # a cold start solves the coarse grid's problem first if it has this many cells
GALERKIN_BLOCK_ROWS = 1 << 18  # coarse rows of R A P formed at a time (``galerkin_product``)
SMOOTHERS = {
    "presmoother": ("gauss_seidel", {"sweep": "forward"}),
    "postsmoother": ("gauss_seidel", {"sweep": "backward"}),
}


def fk_grid(A: sp.csr_matrix | StencilOperator) -> tuple[int, str] | None:
    """The Friedrichs–Keller grid ``(N, diagonal)`` whose vertex numbering ``A`` follows (vertex
    (i, j) is unknown i (N + 1) + j, ``signorini.fem.mesh``), read off the matrix: (N + 1)²
    unknowns, and couplings only to the same and the neighbouring grid lines.  The diagonal is the
    one whose coupling is stored, (i + 1, j + 1) at offset N + 2 for ``sw_ne``, (i + 1, j - 1) at
    offset N for ``nw_se`` (the last, resp. next-to-last, entry of a row); with neither (a 5-point
    stencil: c = 0) either serves.  None when ``A`` is not of this form.  Work in O(rows): each
    row's first, last and next-to-last entry."""
    N = math.isqrt(A.shape[0]) - 1
    if N < 2 or (N + 1) ** 2 != A.shape[0]:
        return None
    A = A if A.has_sorted_indices else A.sorted_indices()
    if A.shape[0] >= certificate.COMPILED_MIN_UNKNOWNS:  # the same four facts in one pass
        from signorini.solvers.kernels import row_reach

        lowest, highest, sw_ne, nw_se = row_reach(A.indptr, A.indices, N)
    else:
        rows = np.flatnonzero(np.diff(A.indptr) >= 2)
        first, last = A.indptr[rows], A.indptr[rows + 1] - 1
        low, high, before_last = (A.indices[k] - rows for k in (first, last, last - 1))
        lowest, highest = low.min(initial=0), high.max(initial=0)
        sw_ne, nw_se = bool((high == N + 2).any()), bool(((before_last == N) | (high == N)).any())
    if min(lowest, -highest) < -(N + 2):
        return None
    if sw_ne and nw_se:
        return None
    return N, "nw_se" if nw_se else "sw_ne"


def compact(A: sp.csr_matrix) -> sp.csr_matrix | StencilOperator:
    """A Friedrichs–Keller matrix (``fk_grid``) of at least ``COMPILED_MIN_UNKNOWNS`` rows with
    sorted indices as the stencil of its centre row and the rows that differ
    (``solvers.stencil``), which the multigrid route solves with to the same bits without ``A``'s
    values in memory (0.84 GiB at N = 4001; docs/evidence/design-measurements.md#solve-without-matrix-values);
    any other matrix as it is."""
    if A.shape[0] < certificate.COMPILED_MIN_UNKNOWNS or not A.has_sorted_indices or (grid := fk_grid(A)) is None:
        return A
    side = grid[0] + 1
    return StencilOperator.from_csr(A, side * (side // 2) + side // 2) or A


def galerkin_product(A: sp.csr_matrix | StencilOperator, P: sp.csr_matrix, R: sp.csr_matrix) -> sp.csr_matrix:
    """``R (A P)`` as scipy forms it, bit for bit, ``GALERKIN_BLOCK_ROWS`` rows of ``R`` at a time:
    each block reads a range of fine rows, and the rows of ``A P`` in it are formed alone (a row
    of a product depends only on the same row of its left factor, and scipy sums it in the same
    order), so ``A P`` (1 GB at N = 4001) is never held whole.  ``A``: CSR, or a stencil operator
    whose rows are formed a block at a time (``rows_csr``)."""
    if R.shape[0] <= GALERKIN_BLOCK_ROWS:
        return (R @ (as_csr(A) @ P)).tocsr()
    blocks = []
    for lo in range(0, R.shape[0], GALERKIN_BLOCK_ROWS):
        hi = min(lo + GALERKIN_BLOCK_ROWS, R.shape[0])
        first, last = R.indptr[lo], R.indptr[hi]
        cols = R.indices[first:last]
        j0, j1 = int(cols.min()), int(cols.max()) + 1
        rows = A.rows_csr(j0, j1) if isinstance(A, StencilOperator) else A[j0:j1]
        block = sp.csr_matrix((R.data[first:last], cols - j0, R.indptr[lo : hi + 1] - first), shape=(hi - lo, j1 - j0))
        blocks.append(block @ (rows @ P))
    return sp.vstack(blocks, format="csr")


def coarse_lines(lines: np.ndarray) -> np.ndarray:
    """Every other grid line of ``lines``, the last one always kept: where the number of cells is
    odd, the last coarse cell spans three fine cells instead of two (the coarse grids stay nested
    and about uniform at any N)."""
    coarse = lines[::2].copy()
    coarse[-1] = lines[-1]
    return coarse


def _interval(lines: np.ndarray, coarse: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """For each of ``lines``, the coarse cell holding it and its position there in [0, 1]."""
    cell = np.clip(np.searchsorted(coarse, lines, side="right") - 1, 0, coarse.size - 2)
    return cell, (lines - coarse[cell]) / (coarse[cell + 1] - coarse[cell])


def fk_transfer(lines: np.ndarray, coarse: np.ndarray, diagonal: str) -> sp.csr_matrix:
    """The prolongation between two tensor grids of the unit square, both cut into triangles by
    the ``diagonal`` of each cell as the Friedrichs–Keller mesh is: the same grid ``lines`` in x
    and y (positions on the finest grid), the coarse one's a subset, ``coarse``.  Each fine vertex
    (i, j), unknown i · len(lines) + j, takes the coarse P1 function's value there (the
    barycentric weights of the coarse triangle holding it: 1 and ½, thirds in an odd grid's last cell)."""
    n, nc = lines.size, coarse.size
    if n * n >= certificate.COMPILED_MIN_UNKNOWNS:  # the same arrays, row by row
        from signorini.solvers.kernels import fk_transfer_rows

        cell, frac = _interval(lines, coarse)
        indptr, indices, data = fk_transfer_rows(cell, frac, nc, diagonal == "sw_ne")
        return sp.csr_matrix((data, indices, indptr), shape=(n * n, nc * nc))
    (cell_x, fx), (cell_y, fy) = _interval(lines, coarse), _interval(lines, coarse)
    cell_i, cell_j = np.repeat(cell_x, n), np.tile(cell_y, n)
    fx, fy = np.repeat(fx, n), np.tile(fy, n)

    def vertex(di: int, dj: int) -> np.ndarray:
        return (cell_i + di) * nc + cell_j + dj

    if diagonal == "sw_ne":  # triangles (0,0) (1,0) (1,1) below the diagonal, (0,0) (1,1) (0,1) above
        below = fx >= fy
        ends = [
            (vertex(0, 0), np.where(below, 1.0 - fx, 1.0 - fy)),
            (np.where(below, vertex(1, 0), vertex(0, 1)), np.abs(fx - fy)),
            (vertex(1, 1), np.where(below, fy, fx)),
        ]
    else:  # (0,0) (1,0) (0,1) below the diagonal, (1,0) (1,1) (0,1) above
        below = fx + fy <= 1.0
        ends = [
            (np.where(below, vertex(0, 0), vertex(1, 1)), np.abs(1.0 - fx - fy)),
            (vertex(1, 0), np.where(below, fx, 1.0 - fy)),
            (vertex(0, 1), np.where(below, fy, 1.0 - fx)),
        ]
    cols = np.stack([c for c, _ in ends], axis=1).astype(np.int32)  # row by row: CSR directly
    weights = np.stack([w for _, w in ends], axis=1)
    keep = weights > 1e-12  # a fine vertex on a coarse edge or vertex: exact zeros
    indptr = np.concatenate([[0], np.cumsum(keep.sum(axis=1))]).astype(np.int32)
    return sp.csr_matrix((weights[keep], cols[keep], indptr), shape=(n * n, nc * nc))


Grid = tuple[np.ndarray, str]  # the grid lines (positions on the finest grid) and the diagonal


def _geometric_levels(A: sp.csr_matrix | StencilOperator, grid: Grid, max_coarse: int) -> tuple[list, sp.csr_matrix]:
    """The levels of grid halving (``coarse_lines``) from ``A`` on ``grid`` until at most
    ``max_coarse`` unknowns are left, and the coarsest (Galerkin) operator."""
    from pyamg.multilevel import MultilevelSolver

    (lines, diagonal), levels = grid, []
    while lines.size**2 > max_coarse and lines.size > 2:
        coarse = coarse_lines(lines)
        level = MultilevelSolver.Level()
        level.A, level.P = A, fk_transfer(lines, coarse, diagonal)
        level.R = level.P.T.tocsr()
        # scipy's product, a block of coarse rows at a time: a compiled one saved no time
        # (docs/evidence/design-measurements.md#galerkin-product-by-scipy)
        A, lines = galerkin_product(A, level.P, level.R), coarse
        levels.append(level)
    return levels, A


def hierarchy(
    A: sp.csr_matrix | StencilOperator, kind: str = "geometric", max_coarse: int = 500, grid: Grid | None = None
):
    """A pyamg multilevel hierarchy of the symmetric positive (semi)definite ``A`` down to at most
    ``max_coarse`` unknowns, with forward Gauss–Seidel as presmoother and backward Gauss–Seidel
    as postsmoother.  ``geometric``: where ``A`` is a Friedrichs–Keller matrix (``fk_grid``), or
    lives on the given ``grid`` (a coarse grid of one, ``nested_start``), the P1 transfers of grid
    halving (``coarse_lines``: N → ⌊N/2⌋ cells) with Galerkin coarse operators; elsewhere
    classical AMG.  ``.grid``: the grid the transfers follow, or None."""
    import pyamg
    from pyamg.multilevel import MultilevelSolver
    from pyamg.relaxation.smoothing import change_smoothers

    if kind not in AMG_KINDS:
        raise ValueError(f"unknown algebraic multigrid {kind!r}; choose one of {AMG_KINDS}")
    if kind != "geometric":
        grid = None
    elif grid is None and (read := fk_grid(A)) is not None:
        grid = (np.arange(read[0] + 1), read[1])
    if kind == "smoothed_aggregation" or grid is None:  # algebraic: from the CSR matrix
        build = pyamg.smoothed_aggregation_solver if kind == "smoothed_aggregation" else pyamg.ruge_stuben_solver
        solver = build(as_csr(A), max_coarse=max_coarse, keep=False, **SMOOTHERS)
    else:
        levels, coarsest = _geometric_levels(A, grid, max_coarse)
        solver = MultilevelSolver([*levels, MultilevelSolver.Level()])
        solver.levels[-1].A = coarsest
        change_smoothers(solver, SMOOTHERS["presmoother"], SMOOTHERS["postsmoother"])
    solver.grid = grid  # what the transfers follow: the grid, or None (algebraic)
    return solver


def _positions(M: sp.csr_matrix, rows: np.ndarray, cols: np.ndarray) -> np.ndarray | None:
    """The positions in ``M.data`` of the entries ``(rows, cols)`` (``M`` with sorted indices),
    or None when one of them is not stored."""
    lines = np.unique(rows)
    pos = concatenated_ranges(M.indptr[lines], M.indptr[lines + 1])
    keys = np.repeat(lines, np.diff(M.indptr)[lines]).astype(np.int64) * M.shape[1] + M.indices[pos]
    wanted = rows.astype(np.int64) * M.shape[1] + cols
    k = np.minimum(np.searchsorted(keys, wanted), keys.size - 1)
    return pos[k] if keys.size and np.array_equal(keys[k], wanted) else None


class GalerkinHierarchy:
    """The transfers of one hierarchy of ``A``; the operators Galerkin for the clamped matrix
    ``Ã(F)`` of the current free set F (``update``), and ``z = M r`` one V-cycle (``__call__``)."""

    def __init__(
        self,
        A: sp.csr_matrix | StencilOperator,
        kind: str = "geometric",
        max_coarse: int = 500,
        grid: Grid | None = None,
    ):
        self.A = A  # every node free; a stencil operator stands in for the CSR matrix (``compact``)
        solver = hierarchy(A, kind, max_coarse, grid)
        self.levels, self.grid = solver.levels, solver.grid
        for level in self.levels[:-1]:  # smoothed aggregation's transfers are BSR
            # the restriction is the prolongation's transpose read column-wise: no copy, and the
            # same sums in the same order as its own CSR (ascending fine index in every coarse row)
            level.P = sp.csr_matrix(level.P)
            level.R = level.P.T
        for level in self.levels[1:]:
            level.A = sp.csr_matrix(level.A)
            level.A.sum_duplicates()
            level.A.sort_indices()
        # the fine operator in A's own pattern (explicit zeros kept), updated in place; every
        # level but the coarsest of a large grid as its stencil and the rows that differ (the fine
        # one without a copy of A's values), applied by the stencil kernels
        self.levels[0].A = A
        self.stencil_levels = self._stencils()
        if not self.stencil_levels[0]:
            self.levels[0].A = (
                A.tocsr()
                if isinstance(A, StencilOperator)
                else sp.csr_matrix((A.data.copy(), A.indices, A.indptr), shape=A.shape)
            )
        self.free = np.ones(A.shape[0], dtype=bool)  # A itself: every node free
        self.cycles = 0  # V-cycles applied (``__call__``)
        self._factor_coarsest()

    def _stencils(self) -> list[bool]:
        """Replace every level's operator but the coarsest's by a ``StencilOperator`` where the
        hierarchy follows a grid and the level has at least ``COMPILED_MIN_UNKNOWNS`` unknowns;
        which levels were."""
        found = [False] * len(self.levels)
        if self.grid is None or len(self.levels) < 2:  # one level: the coarsest, factorised
            return found
        lines = self.grid[0]
        for k, level in enumerate(self.levels[:-1]):
            if isinstance(level.A, StencilOperator):  # the fine operator given as one: changed apart
                level.A, found[k] = level.A.copy(), True
            elif level.A.shape[0] >= certificate.COMPILED_MIN_UNKNOWNS:
                side = lines.size
                op = StencilOperator.from_csr(level.A, side * (side // 2) + side // 2)
                if op is not None:
                    level.A, found[k] = op, True
            lines = coarse_lines(lines)
        return found

    @property
    def matrix(self) -> sp.csr_matrix:
        """The fine operator ``Ã(F)``."""
        return self.levels[0].A

    def operator_complexity(self) -> float:
        return sum(level.A.nnz for level in self.levels) / self.levels[0].A.nnz

    def cycle_work(self) -> float:
        """The work of one V-cycle in fine-grid work units (one unit: a product with the fine
        operator, its stored entries): per level but the coarsest, a Gauss–Seidel sweep each way and
        the residual (three passes over ``A_l``), the restriction and the prolongation; on the
        coarsest, the two triangular solves of its dense factor (``n_c²`` entries)."""
        entries = sum(3 * level.A.nnz + level.P.nnz + level.R.nnz for level in self.levels[:-1])
        return (entries + self.levels[-1].A.shape[0] ** 2) / self.levels[0].A.nnz

    def _factor_coarsest(self) -> None:
        coarsest = self.levels[-1].A.toarray()
        try:
            factor = sla.cho_factor(coarsest)
            self._coarse = lambda b: sla.cho_solve(factor, b)
        except np.linalg.LinAlgError:  # singular (c = 0, nothing clamped): least squares
            pinv = np.linalg.pinv(coarsest)
            self._coarse = lambda b: pinv @ b

    def update(self, free: np.ndarray) -> None:
        """Make the fine operator ``Ã(free)`` and every coarse operator its Galerkin product:
        the change lives in the rows of the nodes that changed status and of their neighbours,
        and its Galerkin image ``P_Sᵀ Δ_SS P_S`` in as few coarse rows (work in O(changes))."""
        changed = np.flatnonzero(free != self.free)
        if changed.size == 0:
            return
        A, fine = self.A, self.levels[0].A
        neighbours = A.indices[concatenated_ranges(A.indptr[changed], A.indptr[changed + 1])]
        S = np.unique(np.concatenate([changed, neighbours]))
        starts, ends = A.indptr[S], A.indptr[S + 1]
        pos, rows = concatenated_ranges(starts, ends), np.repeat(S, ends - starts)  # the stored entries of rows S
        values = clamped_values(A, rows, free, pos)
        if self.stencil_levels[0]:
            diff = values - fine.values_at(pos, rows)
            fine.set_values(pos, rows, values)
        else:
            diff = values - fine.data[pos]
            fine.data[pos] = values
        self.free = free.copy()
        keep = diff != 0.0
        rows, cols, diff = rows[keep], A.indices[pos][keep], diff[keep]
        for k, (level, coarse) in enumerate(zip(self.levels[:-1], self.levels[1:], strict=True), start=1):
            S = np.unique(rows)  # Δ is symmetric: its rows are its support
            delta = sp.csr_matrix((diff, (np.searchsorted(S, rows), np.searchsorted(S, cols))), shape=(S.size,) * 2)
            PS = level.P[S]
            support = np.unique(PS.indices)
            PS = sp.csr_matrix((PS.data, np.searchsorted(support, PS.indices), PS.indptr), shape=(S.size, support.size))
            image = sp.coo_matrix(PS.T @ delta @ PS)
            rows, cols, diff = support[image.row], support[image.col], image.data
            where = _positions(coarse.A, rows, cols) if rows.size else np.zeros(0, dtype=np.int64)
            if where is None:  # an entry outside the stored pattern (exact cancellation in the setup)
                coarse.A = sp.csr_matrix(coarse.A.tocsr() + sp.csr_matrix((diff, (rows, cols)), shape=coarse.A.shape))
                coarse.A.sort_indices()
                self.stencil_levels[k] = False
            elif self.stencil_levels[k]:
                coarse.A.add_values(where, rows, diff)
            else:
                np.add.at(coarse.A.data, where, diff)
        self._factor_coarsest()

    def __call__(self, r: np.ndarray) -> np.ndarray:
        self.cycles += 1
        if len(self.levels) == 1:
            return self._coarse(r)
        return self._cycle(0, r)

    def _cycle(self, lvl: int, b: np.ndarray) -> np.ndarray:
        level = self.levels[lvl]
        x = np.zeros_like(b)
        stencil = self.stencil_levels[lvl]  # the same sweeps and sums, row by row
        if stencil:  # the residual restricted a row at a time: never held
            level.A.gauss_seidel(x, b, forward=True, from_zero=True)
            coarse_b = level.A.restricted_residual(x, b, level.P)
        else:
            level.presmoother(level.A, x, b)
            coarse_b = level.R @ (b - level.A @ x)
        coarse_x = self._coarse(coarse_b) if lvl == len(self.levels) - 2 else self._cycle(lvl + 1, coarse_b)
        if stencil:  # x += P coarse_x without P coarse_x in memory, the same sums
            from signorini.solvers.kernels import prolongate_add

            prolongate_add(level.P.indptr, level.P.indices, level.P.data, coarse_x, x)
            level.A.gauss_seidel(x, b, forward=False)
        else:
            x += level.P @ coarse_x
            level.postsmoother(level.A, x, b)
        return x


def pcg(
    A: sp.csr_matrix,
    rhs: np.ndarray,
    x: np.ndarray,
    precondition: Callable[[np.ndarray], np.ndarray],
    rtol: float,
    max_iter: int,
    reduction: float | None = None,
    floor: float = 0.0,
    overwrite_x: bool = False,
) -> tuple[np.ndarray, int, float]:
    """Preconditioned CG from ``x`` until ``√(rᵀMr) ≤ rtol √(xᵀ rhs)`` (energy-relative, module
    docstring): ``(x, iterations, √(rᵀMr)/√(xᵀ rhs))``.  With ``reduction``, ``rtol`` is lowered to
    ``reduction`` times the initial ratio, but not below ``floor``; with ``overwrite_x`` the
    iterate is ``x`` itself, updated in place (no copy).  Raises ``NotConvergedError``
    after ``max_iter`` iterations or on a breakdown (``pᵀAp ≤ 0``: A is not positive definite)."""
    x = x if overwrite_x else x.copy()
    r = residual(A, x, rhs)
    p = precondition(r)  # the first direction: the preconditioned residual itself
    rz = float(r @ p)
    for k in range(max_iter + 1):
        energy = float(x @ rhs)
        ratio = np.sqrt(max(rz, 0.0) / energy) if energy > 0.0 else np.inf
        if k == 0 and reduction is not None and np.isfinite(ratio):
            rtol = max(floor, min(rtol, reduction * ratio))
        if ratio <= rtol:
            return x, k, ratio
        if k == max_iter:
            break
        q = A @ p
        pq = float(p @ q)
        if not pq > 0.0:
            raise NotConvergedError(f"conjugate gradients broke down (pᵀAp = {pq:.1e}): the system is singular")
        alpha = rz / pq
        _add(x, alpha, p)
        _add(r, -alpha, q)
        del q  # one vector less during the V-cycle
        z = precondition(r)
        rz, rz_old = float(r @ z), rz
        p *= rz / rz_old
        p += z
        del z  # rz holds what it gave: one vector less in the next step's products
    raise NotConvergedError(f"conjugate gradients did not reach {rtol:.0e} within {max_iter} iterations")


def _add(y: np.ndarray, a: float, x: np.ndarray) -> None:
    """``y += a x`` rounded as numpy rounds it; in place, without ``a x`` in memory, where the
    compiled kernels pay (a negative ``a``: the subtraction of ``|a| x``, the same bits)."""
    if y.size < certificate.COMPILED_MIN_UNKNOWNS:
        y += a * x
        return
    from signorini.solvers.kernels import axpy

    axpy(y, abs(a), x, a < 0.0)


class MultigridSystems:
    """The Newton systems of the multigrid route (``pdas.NewtonSystems``): PCG from the previous
    iterate, preconditioned by one ``GalerkinHierarchy`` kept up to date with the active set."""

    exact = False

    def __init__(self, A: sp.csr_matrix | StencilOperator, b: np.ndarray, start: np.ndarray, options: dict):
        self.A, self.b, self.x = A, b, start
        self.tol, self.inner_rtol, self.max_cg_iter = options["tol"], options["inner_rtol"], options["max_cg_iter"]
        ones = np.ones(b.size)
        # A 1 = 0 to round-off (c = 0: A = K): singular unless some node is clamped
        self.singular = np.abs(A @ ones).max() <= 16 * np.finfo(float).eps * abs_product(A, ones).max()
        t0 = time.perf_counter()
        self.hierarchy = GalerkinHierarchy(A, options["amg"], options["max_coarse"], options.get("grid"))
        self.amg, self.setup_s, self.update_s = options["amg"], time.perf_counter() - t0, 0.0
        self.cg_total = 0
        self.B, self.kkt_tol = options.get("B"), options.get("kkt_tol")  # what ``settle`` needs
        self.settles, self.settled_s = 0, 0.0
        self.products = 0  # products with the fine operator (CG's and the residual checks')
        self.work = 0.0  # fine-grid work units of the Newton steps (``GalerkinHierarchy.cycle_work``)
        self.last: dict = {}

    def _refine(self, rhs: np.ndarray, x: np.ndarray, free: np.ndarray) -> tuple[np.ndarray, int]:
        """Restart CG from the true residual while it exceeds its rounding floor (max norm)."""
        At, iterations = self.hierarchy.matrix, 0
        for _ in range(REFINEMENTS):
            floor = FLOOR_FACTOR * np.finfo(float).eps * np.max(abs_product(self.A, np.abs(x)), where=free, initial=0.0)
            self.products += 2  # |A| |x| and the residual
            misfit = residual(At, x, rhs)
            if np.abs(misfit, out=misfit).max() <= floor:
                break
            x, k, _ = pcg(At, rhs, x, self.hierarchy, self.tol, self.max_cg_iter, overwrite_x=True)
            iterations += k
            self.products += k + 1
        return x, iterations

    def __call__(self, free: np.ndarray, accurate: bool) -> np.ndarray:
        if free.all() and self.singular:
            raise NotConvergedError(
                "active set of 0 nodes leaves a singular system (A 1 = 0); with c = 0 the minimiser is then not unique"
            )
        t0 = time.perf_counter()
        self.hierarchy.update(free)
        self.update_s += time.perf_counter() - t0
        cycles, products = self.hierarchy.cycles, self.products
        rhs = np.where(free, self.b, 0.0)
        x, iterations, ratio = np.zeros_like(rhs), 0, 0.0  # D b = 0: u = 0 (Ã is definite here)
        if rhs.any():
            # inexact: to inner_rtol, and at least STEP_REDUCTION below the step's start (a change
            # of a few nodes moves the energy by less than inner_rtol, but the nodes next to it a lot)
            rtol, reduction = (self.tol, None) if accurate else (self.inner_rtol, STEP_REDUCTION)
            At, start = self.hierarchy.matrix, np.where(free, self.x, 0.0)
            self.x = None  # the previous iterate, in ``start`` now: one vector less while CG runs
            x, iterations, ratio = pcg(
                At, rhs, start, self.hierarchy, rtol, self.max_cg_iter, reduction, self.tol, overwrite_x=True
            )
            self.products += iterations + 1
        if accurate:
            x, more = self._refine(rhs, x, free)
            iterations += more
        self.x = x
        self.cg_total += iterations
        cycles, products = self.hierarchy.cycles - cycles, self.products - products
        work = products + cycles * self.hierarchy.cycle_work()
        self.work += work
        self.last = {
            "cg_iterations": iterations,
            "energy_residual": ratio,
            "accurate": accurate,
            "v_cycles": cycles,
            "work_units": work,
        }
        return x

    def counters(self) -> dict:
        return dict(self.last)

    def settle(self, u: np.ndarray, before: np.ndarray, after: np.ndarray) -> tuple | None:
        """``pdas.Settle``: the release from ``before`` to ``after`` settled on a patch
        (``local.settle_release``); the next solve starts from the settled iterate."""
        settled = settle_release(self.A, self.b, self.B, u, before, after, self.kkt_tol)
        if settled is not None:
            self.x = settled[0]
            self.settled_s += settled[2]["local_s"]
            self.settles += 1
        return settled

    def info(self) -> dict:
        return {
            "amg": self.amg,
            # what the requested kind gave: geometric falls back to classical AMG off a grid
            "hierarchy": "classical" if self.amg == "geometric" and self.hierarchy.grid is None else self.amg,
            "grid": None if self.hierarchy.grid is None else [self.hierarchy.grid[0].size - 1, self.hierarchy.grid[1]],
            "levels": len(self.hierarchy.levels),
            "operator_complexity": self.hierarchy.operator_complexity(),
            "setup_s": self.setup_s,
            "galerkin_update_s": self.update_s,
            "local_settles": self.settles,
            "local_s": self.settled_s,
            "cg_iterations": self.cg_total,
            "v_cycles": self.hierarchy.cycles,
            "work_units": self.work,
            "work_unit_entries": int(self.hierarchy.levels[0].A.nnz),
            "tol": self.tol,
            "inner_rtol": self.inner_rtol,
        }


def nested_start(H: GalerkinHierarchy, b: np.ndarray, B: np.ndarray, options: dict) -> np.ndarray | None:
    """A cold start's warm start (nested iteration): the QP restricted to the first coarse grid of
    the new hierarchy ``H`` — operator ``R A P``, load ``R b``, constrained where the coarse vertex
    is a constrained fine one — solved by this route (from its own nested start), prolongated.
    On nested grids ``P v ≥ 0`` on the boundary iff ``v ≥ 0`` on its coarse vertices, so this is the
    fine problem over the coarse space.  None without a geometric coarse grid of at least
    ``NESTED_MIN_CELLS`` cells, or when the coarse solve fails (the plain cold start follows)."""
    if H.grid is None or len(H.levels) < 2 or not H.free.all():
        return None
    lines, diagonal = H.grid
    coarse = coarse_lines(lines)
    if coarse.size - 1 < NESTED_MIN_CELLS:
        return None
    at = np.searchsorted(lines, coarse)  # the coarse lines among the fine ones
    constrained = np.zeros(b.size, dtype=bool)
    constrained[B] = True
    fine_vertex = (at[:, None] * lines.size + at[None, :]).ravel()
    level, operator = H.levels[0], H.levels[1].A
    try:
        coarse_result = multigrid_solve(
            operator.tocsr() if H.stencil_levels[1] else operator.copy(),
            level.R @ b,
            np.flatnonzero(constrained[fine_vertex]),
            **options,
            grid=(coarse, diagonal),
        )
    except (NotConvergedError, KKTError) as err:
        log.warning("nested start on %d cells failed (%s); solving from the plain cold start", coarse.size - 1, err)
        return None
    return level.P @ coarse_result.u


def multigrid_solve(
    A: sp.spmatrix | StencilOperator,
    b: np.ndarray,
    constrained: np.ndarray,
    warm_start: np.ndarray | None = None,
    max_iter: int = 100,
    kkt_tol: float = 1e-10,
    frontier_growth: bool = True,
    warm_start_dilation: int = 0,
    amg: str = "geometric",
    tol: float = 1e-14,
    inner_rtol: float = 1e-8,
    max_cg_iter: int = 500,
    max_coarse: int = 500,
    local_release: bool = True,
    warm_start_reach: int = pdas.WARM_START_REACH,
    *,
    callback: StepCallback | None = None,
    grid: Grid | None = None,
) -> SolveResult:
    """Solve ``min ½ uᵀAu - bᵀu`` s.t. ``u_B ≥ 0`` by the active-set iteration with multigrid-
    preconditioned CG (module docstring) and certify it.  ``A``: a sparse matrix, or the stencil
    operator standing in for a Friedrichs–Keller one (``compact``), solved with the same bits
    without a copy of its values.

    ``warm_start``: the first iterate, its zeros the first contact set; without one, the solution
    of the problem on the hierarchy's coarse grid (``nested_start``) where there is one, else
    the nodes pushed outwards.  ``amg``: ``geometric`` (``hierarchy``: grid halving on a
    Friedrichs–Keller matrix, classical AMG on any other), ``classical`` (Ruge–Stüben) or
    ``smoothed_aggregation``; ``tol``: the energy-relative accuracy of the final solves;
    ``inner_rtol``: of the solves while the set moves; ``max_cg_iter``: per solve;
    ``max_coarse``: unknowns of the coarsest level (a dense Cholesky factorisation; a smaller
    system is solved by it alone); ``local_release``: settle a Newton step that only releases
    nodes on a patch around them (``solvers.local``); ``warm_start_reach``: the frontier's reach in
    the first Newton step from ``warm_start`` (``pdas.Frontier``; one node from the route's own
    start); ``grid``: the grid of a geometric hierarchy, where ``A``'s own is not uniform (the
    coarse problems of ``nested_start``).  ``callback(row)`` receives
    each Newton step's row of ``SolveResult.history`` (iteration, active nodes, changes, the
    step's CG iterations and final energy residual, whether it was an accurate solve, elapsed
    seconds).  Raises ``NotConvergedError`` (the set does not settle in ``max_iter`` steps, CG
    fails, a singular system) and ``KKTError`` (the certificate exceeds ``kkt_tol``).
    """
    t0 = time.perf_counter()
    if amg not in AMG_KINDS:
        raise ValueError(f"unknown algebraic multigrid {amg!r}; choose one of {AMG_KINDS}")
    if not 0.0 < tol <= inner_rtol:
        raise ValueError(f"need 0 < tol <= inner_rtol, got tol={tol}, inner_rtol={inner_rtol}")
    if warm_start_reach < 1:
        raise ValueError(f"need warm_start_reach >= 1 (nodes), got {warm_start_reach}")
    A, b, B = prepare_qp(A, b, constrained, keep_stencil=True)
    shared = dict(amg=amg, tol=tol, inner_rtol=inner_rtol, max_cg_iter=max_cg_iter, max_coarse=max_coarse)
    systems = MultigridSystems(A, b, np.zeros_like(b), shared | {"grid": grid, "B": B, "kkt_tol": kkt_tol})
    settle = systems.settle if local_release else None
    nested, reach = None, warm_start_reach if warm_start is not None else 1
    if warm_start is None:
        iteration = dict(max_iter=max_iter, kkt_tol=kkt_tol, frontier_growth=frontier_growth)
        iteration |= {"local_release": local_release}
        warm_start = nested = nested_start(systems.hierarchy, b, B, shared | iteration)
    active = initial_active(A, b, B, warm_start, warm_start_dilation)
    if warm_start is not None:
        systems.x = np.asarray(warm_start, dtype=float)
    try:
        u, active, history = iterate(systems, A, b, B, active, max_iter, frontier_growth, callback, log, settle, reach)
    except NotConvergedError as err:
        if nested is None:
            raise
        log.warning("the nested start did not settle (%s); solving from the plain cold start", err)
        systems.x = np.zeros_like(b)
        active = initial_active(A, b, B, None)
        u, active, history = iterate(systems, A, b, B, active, max_iter, frontier_growth, callback, log, settle)
    info = systems.info() | {"nested_start": nested is not None}
    result = certified_result(A, b, B, u, active, kkt_tol, t0, "multigrid", info, history)
    result.hierarchy = systems.hierarchy  # Galerkin for the final set: the estimate reuses it
    return result
