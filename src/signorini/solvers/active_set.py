"""Primal–dual active set (semismooth Newton) on the boundary constraints.

For an active set 𝒜 ⊂ B the Newton step solves ``u_𝒜 = 0``, ``(A u)_F = b_F``
(F the complement), i.e. ``Ã u = D b`` with ``Ã = D A D + (I - D)`` and ``D`` the
indicator of F; then ``λ = (A u - b)_𝒜`` and the next set is
``{i ∈ 𝒜 : λ_i > -ε_λ} ∪ {i ∈ B \\ 𝒜 : u_i < -ε_u}`` with relative thresholds ε (scale-free).
The iteration stops when the set repeats.

Linear algebra: the first system is factorised (CHOLMOD or PARDISO, see linalg.py).  A later
set differs from the factorised one ``Ã₀`` (free set W) in a few nodes: P = nodes now clamped
but free in ``Ã₀``, Q = nodes now free but clamped in ``Ã₀``.  Its system is ``Ã₀`` bordered
by one column per changed node (``BorderedSolver``), solved exactly by block elimination with
the columns ``Ã₀⁻¹ e_p`` and ``Ã₀⁻¹ A_{W,q}``.  The columns are kept across Newton steps, so a
node that changes status costs one extra triangular solve over the whole iteration (batched
per step), not one per step as a Krylov correction would.  Only a large change (more than
``refactor_above`` columns) triggers a new factorisation.  A warm start (e.g. a coarser
solution interpolated) gives the first active set, so a fine solve typically costs one
factorisation plus a handful of triangular solves.  All clamped matrices keep ``A``'s
sparsity pattern, so PARDISO analyses the pattern once and later factorisations are
numerical only.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from signorini.solvers.certificate import KKTError, NotConvergedError, check_qp_data, kkt_certificate
from signorini.solvers.linalg import Factorizer, Solve
from signorini.solvers.result import SolveResult

log = logging.getLogger(__name__)


def _clamped_values(A: sp.csr_matrix, rows: np.ndarray, free: np.ndarray) -> np.ndarray:
    """CSR values of Ã = D A D + (I - D) in ``A``'s own sparsity pattern (explicit zeros kept,
    so every active set shares one symbolic factorisation)."""
    cols = A.indices
    data = np.where(free[rows] & free[cols], A.data, 0.0)
    data[(rows == cols) & ~free[rows]] = 1.0
    return data


class BorderedSolver:
    """Solve ``Ã(F) u = D r`` (rows F: ``(A u)_F = r_F``; rows outside F: ``u = 0``, whatever
    ``r`` holds there) for free sets F close to the factorised one, W, with ``factor = Ã(W)⁻¹``.

    With P = W \\ F (newly clamped) and Q = F \\ W (newly free), the system is

        [A_WW   A_WQ  -E_P] [u_W]   [r_W]
        [A_QW   A_QQ   0  ] [u_Q] = [r_Q]        (μ = (A u - r)_P, the multipliers
        [-E_Pᵀ  0      0  ] [ μ ]   [ 0 ]         of the extra clamps u_P = 0)

    Eliminating ``u_W = z - G u_Q + H μ`` with ``z = A_WW⁻¹ r_W``, ``G = A_WW⁻¹ A_WQ`` and
    ``H = A_WW⁻¹ E_P`` leaves the small symmetric (indefinite) system

        [A_QQ - A_QW G   A_QW H] [u_Q]   [r_Q - A_QW z]
        [G_P             -H_P  ] [ μ ] = [z_P         ]

    ``A_WW⁻¹ y`` is ``Ã(W)⁻¹ y`` for ``y`` supported on W.  Columns of G and H are computed
    once per node (in one block solve per call) and cached.
    """

    def __init__(self, A: sp.csr_matrix, factor: Solve, free: np.ndarray):
        self.A, self.factor, self.free = A, factor, free.copy()
        self.columns: dict[int, np.ndarray] = {}
        self.solves = 0  # right-hand sides passed to the factor
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # (r_W, A_WW⁻¹ r_W): b repeats

    def n_columns(self, free: np.ndarray) -> int:
        """Border size (|P| + |Q|) for the free set ``free``."""
        return int(np.count_nonzero(free != self.free))

    def _column(self, nodes: np.ndarray) -> None:
        new = [int(i) for i in nodes if int(i) not in self.columns]
        if not new:
            return
        rhs = np.zeros((self.A.shape[0], len(new)))
        for k, i in enumerate(new):
            if self.free[i]:  # newly clamped node p: H column, A_WW⁻¹ e_p
                rhs[i, k] = 1.0
            else:  # newly free node q: G column, A_WW⁻¹ A_{W,q} (A symmetric: row q)
                lo, hi = self.A.indptr[i], self.A.indptr[i + 1]
                cols = self.A.indices[lo:hi]
                keep = self.free[cols]
                rhs[cols[keep], k] = self.A.data[lo:hi][keep]
        out = self.factor(rhs)
        self.solves += len(new)
        for k, i in enumerate(new):
            self.columns[i] = np.ascontiguousarray(out[:, k])

    def __call__(self, free: np.ndarray, r: np.ndarray) -> np.ndarray:
        W = self.free
        P = np.flatnonzero(W & ~free)
        Q = np.flatnonzero(~W & free)
        rW = np.where(W, r, 0.0)
        if self._last is not None and np.array_equal(self._last[0], rW):
            z = self._last[1]
        else:
            z = self.factor(rW)
            self.solves += 1
            self._last = (rW, z)
        if P.size + Q.size == 0:
            return z.copy()  # z stays cached
        self._column(np.concatenate([P, Q]))
        G = np.column_stack([self.columns[q] for q in Q]) if Q.size else np.zeros((r.size, 0))
        H = np.column_stack([self.columns[p] for p in P]) if P.size else np.zeros((r.size, 0))
        AQ = self.A[Q]
        S = np.block([[AQ[:, Q].toarray() - AQ @ G, AQ @ H], [G[P], -H[P]]])
        rhs = np.concatenate([r[Q] - AQ @ z, z[P]])
        y = sla.solve(S, rhs, assume_a="sym")
        uQ, mu = y[: Q.size], y[Q.size :]
        u = z - G @ uQ + H @ mu  # a new array: z stays cached
        u[Q] = uQ
        u[P] = 0.0  # = 0 up to round-off by the last block row
        return u


def active_set_solve(
    A: sp.spmatrix,
    b: np.ndarray,
    constrained: np.ndarray,
    warm_start: np.ndarray | None = None,
    max_iter: int = 100,
    kkt_tol: float = 1e-10,
    refactor_above: int = 40,
    frontier_growth: bool = True,
    warm_start_dilation: int = 0,
    backend: str = "auto",
) -> SolveResult:
    """Solve ``min ½ uᵀAu - bᵀu`` s.t. ``u_B ≥ 0`` exactly (to round-off) and certify it.

    Raises ``NotConvergedError`` when the set has not repeated after ``max_iter``
    Newton steps or cycles, and ``KKTError`` when the final certificate exceeds ``kkt_tol``.
    """
    t0 = time.perf_counter()
    A = sp.csr_matrix(A, copy=True)
    A.sum_duplicates()
    A.sort_indices()
    b = np.asarray(b, dtype=float)
    B = np.asarray(constrained, dtype=np.int64)
    check_qp_data(A, b, B)
    n = b.size

    if warm_start is not None:
        w = np.asarray(warm_start, dtype=float)
        if w.shape != (n,) or not np.all(np.isfinite(w)):
            raise ValueError(f"warm start must be a finite vector of length {n}")
        # predicted contact: where the warm start vanishes (its residual A w - b is no
        # multiplier estimate when w is interpolated from a coarser mesh)
        active = w[B] <= 0.0
        # Grow the predicted contact set by a few boundary neighbours: for an
        # M-matrix (P1 on Friedrichs–Keller meshes, c h² small) starting from a
        # superset of the true contact set keeps the iterates feasible and the
        # active set shrinks monotonically in small steps; an undersized start
        # instead swings the whole far boundary (where u_h is O(h²)) into contact.
        if warm_start_dilation > 0:
            pattern = (abs(A[B][:, B]) > 0).astype(np.int8)
            for _ in range(warm_start_dilation):
                active = (pattern @ active.astype(np.int8)) > 0
    else:
        active = b[B] <= 0.0  # nodes pushed outwards start in contact

    rows = np.repeat(np.arange(n), np.diff(A.indptr))
    factorizer = Factorizer(A, backend)
    bordered: BorderedSolver | None = None
    n_factor = n_solves = n_columns = 0
    seen: set[bytes] = set()
    # boundary-graph adjacency: a node may enter the contact set next to one already in it
    adjacency = (abs(A[B][:, B]) > 0).astype(np.int8)
    for it in range(1, max_iter + 1):
        free = np.ones(n, dtype=bool)
        free[B[active]] = False
        # refactorise on a large change, or when the column cache (memory: n per column) is full
        if bordered is None or max(bordered.n_columns(free), len(bordered.columns) // 2) > refactor_above:
            if bordered is not None:
                n_solves += bordered.solves
                n_columns += len(bordered.columns)
            try:
                factor = factorizer(_clamped_values(A, rows, free))
            except np.linalg.LinAlgError as err:  # c = 0 and too few contact nodes: A_FF singular
                raise NotConvergedError(
                    f"active set of {int(active.sum())} nodes leaves a singular system ({err}); "
                    "with c = 0 the minimiser is then not unique"
                ) from err
            bordered = BorderedSolver(A, factor, free)
            n_factor += 1
        u = bordered(free, b)  # rows outside F are ignored, so b's solve is reused across steps
        lam = np.where(active, (A @ u - b)[B], 0.0)
        # hysteresis below round-off keeps degenerate (u = λ = 0) nodes from flip-flopping;
        # ≥ keeps them when everything vanishes (f ≡ 0: eps_lam = 0), where releasing the
        # whole boundary would leave the singular K of c = 0 to factorise
        eps_lam = 1e-13 * max(np.abs(lam).max(initial=0.0), np.abs(b).max(initial=0.0))
        eps_u = 1e-13 * np.abs(u).max(initial=0.0)
        keep = active & (lam >= -eps_lam)
        grow = ~active & (u[B] < -eps_u)
        if frontier_growth:
            # Grow the contact set only at its ends while that is possible.  An
            # undersized contact set near the free point pushes the whole far boundary
            # (where u_h is O(h²)-small and biactive in the limit) below zero; the
            # plain PDAS step would clamp all of it and release it again, two large
            # changes that each cost a factorisation.  The full step is taken when no
            # violated node touches the contact set, so termination is PDAS's own.
            frontier = grow & ((adjacency @ active.astype(np.int8)) > 0)
            if frontier.any():
                grow = frontier
        new_active = keep | grow
        log.info(  # progress of long solves: one line per Newton step
            "iteration %d: %d active, %d changes, factorized=%s columns=%d, %.2f s",
            it,
            active.sum(),
            np.count_nonzero(new_active != active),
            n_factor,
            n_columns + len(bordered.columns),
            time.perf_counter() - t0,
        )
        if np.array_equal(new_active, active):
            break
        key = np.packbits(new_active).tobytes()
        if key in seen:
            raise NotConvergedError(f"active set cycles after {it} iterations")
        seen.add(np.packbits(active).tobytes())
        active = new_active
    else:
        raise NotConvergedError(f"active set did not repeat within max_iter={max_iter} iterations")

    # Iterative refinement: the direct solve leaves a residual that grows with N (Cholesky's
    # |L||Lᵀ| term; 32 ε |A||u| at N = 1001 for u ≡ 1), one step brings it down to the
    # ε |A||u| of evaluating it, the certificate's rounding floor.  Skipped when the residual
    # is already within 4 ε |A||u| (a quarter of that floor).  Clamped rows have zero
    # residual: u_𝒜 stays 0.
    residual = np.where(free, b - A @ u, 0.0)
    if np.abs(residual).max() > 4 * np.finfo(float).eps * (abs(A) @ np.abs(u)).max(initial=0.0):
        u = u + bordered(free, residual)
    n_solves += bordered.solves
    n_columns += len(bordered.columns)
    lam = np.where(active, (A @ u - b)[B], 0.0)
    u[B[active]] = 0.0
    wall = time.perf_counter() - t0
    cert = kkt_certificate(A, b, B, u, lam, kkt_tol)
    result = SolveResult(
        u=u,
        lam=lam,
        active=B[active],
        iterations=it,
        wall_time_s=wall,
        certificate=cert,
        solver="active_set",
        info={
            "factorizations": n_factor,
            "triangular_solves": n_solves,
            "correction_columns": n_columns,
            "backend": factorizer.backend,
        },
    )
    if not cert.ok:
        raise KKTError("active_set solution fails its KKT certificate", cert)
    return result
