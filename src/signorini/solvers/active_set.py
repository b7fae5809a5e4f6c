"""Primal–dual active set (semismooth Newton) on the boundary constraints.

For an active set 𝒜 ⊂ B the Newton step solves ``u_𝒜 = 0``, ``(A u)_F = b_F``
(F the complement), i.e. ``Ã u = D b`` with ``Ã = D A D + (I - D)`` and ``D`` the
indicator of F; then ``λ = (A u - b)_𝒜`` and the next set is
``{i ∈ 𝒜 : λ_i > -ε_λ} ∪ {i ∈ B \\ 𝒜 : u_i < -ε_u}`` with relative thresholds ε (scale-free).
The iteration stops when the set repeats.

Linear algebra: the first system is factorised (PARDISO or CHOLMOD, see linalg.py); a later set that
differs from the factorised one in ``k`` nodes changes ``Ã`` by a rank ≤ 2k
term, so preconditioned CG with the old factor converges in ≤ 2k + 1 steps.
Only a large change (more than ``refactor_above`` nodes) triggers a new
factorisation.  A warm start (e.g. a coarser solution interpolated) gives the
first active set, so a fine solve typically costs one factorisation plus a few
dozen triangular solves.  All clamped matrices keep ``A``'s sparsity pattern, so PARDISO
analyses the pattern once and later factorisations are numerical only.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.sparse as sp

from signorini.solvers.certificate import KKTError, NotConvergedError, check_qp_data, kkt_certificate
from signorini.solvers.linalg import Factorizer
from signorini.solvers.result import SolveResult

log = logging.getLogger(__name__)


def _clamped_values(A: sp.csr_matrix, rows: np.ndarray, free: np.ndarray) -> np.ndarray:
    """CSR values of Ã = D A D + (I - D) in ``A``'s own sparsity pattern (explicit zeros kept,
    so every active set shares one symbolic factorisation)."""
    cols = A.indices
    data = np.where(free[rows] & free[cols], A.data, 0.0)
    data[(rows == cols) & ~free[rows]] = 1.0
    return data


def _pcg(matvec, rhs: np.ndarray, precond, x0: np.ndarray, rtol: float, maxiter: int) -> tuple[np.ndarray, int, float]:
    """Preconditioned CG for an SPD operator; returns (x, iterations, relative residual)."""
    x = x0.copy()
    r = rhs - matvec(x)
    norm_rhs = max(np.linalg.norm(rhs), np.finfo(float).tiny)
    rel = np.linalg.norm(r) / norm_rhs
    if rel <= rtol:
        return x, 0, rel
    z = precond(r)
    p = z.copy()
    rz = r @ z
    for k in range(1, maxiter + 1):
        Ap = matvec(p)
        alpha = rz / (p @ Ap)
        x += alpha * p
        r -= alpha * Ap
        rel = np.linalg.norm(r) / norm_rhs
        if rel <= rtol:
            return x, k, rel
        z = precond(r)
        rz_new = r @ z
        p = z + (rz_new / rz) * p
        rz = rz_new
    return x, maxiter, rel


def active_set_solve(
    A: sp.spmatrix,
    b: np.ndarray,
    constrained: np.ndarray,
    warm_start: np.ndarray | None = None,
    max_iter: int = 100,
    kkt_tol: float = 1e-10,
    cg_rtol: float = 1e-14,
    refactor_above: int = 64,
    max_cg: int = 300,
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
    factor_free = None  # free-indicator of the factorised matrix
    factor = None
    n_factor = n_solves = n_cg = 0
    seen: set[bytes] = set()
    u = np.zeros(n)
    # boundary-graph adjacency: a node may enter the contact set next to one already in it
    adjacency = (abs(A[B][:, B]) > 0).astype(np.int8)
    for it in range(1, max_iter + 1):
        free = np.ones(n, dtype=bool)
        free[B[active]] = False
        rhs = np.where(free, b, 0.0)
        values = _clamped_values(A, rows, free)
        Ac = sp.csr_matrix((values, A.indices, A.indptr), shape=A.shape)
        changed = n if factor_free is None else int(np.count_nonzero(free != factor_free))
        if factor is None or changed > refactor_above:
            factor, factor_free = factorizer(values), free
            u = factor(rhs)
            n_factor += 1
            n_solves += 1
        elif changed > 0:
            u, k, rel = _pcg(Ac.__matmul__, rhs, factor, factor(rhs), cg_rtol, min(2 * changed + 20, max_cg))
            n_solves += k + 1
            n_cg += k
            if rel > cg_rtol:  # stagnation: fall back to a fresh factorisation
                log.info("PCG stagnated at relative residual %.1e; refactorising", rel)
                factor, factor_free = factorizer(values), free
                u = factor(rhs)
                n_factor += 1
                n_solves += 1
        # else: same set as the factorised one; u is already its solution
        lam = np.where(active, (A @ u - b)[B], 0.0)
        # hysteresis below round-off keeps degenerate (u = λ = 0) nodes from flip-flopping
        eps_lam = 1e-13 * max(np.abs(lam).max(initial=0.0), np.abs(b).max(initial=0.0))
        eps_u = 1e-13 * np.abs(u).max(initial=0.0)
        keep = active & (lam > -eps_lam)
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
        log.debug(
            "iteration %d: %d active, %d changes, factorized=%s cg=%d",
            it,
            active.sum(),
            np.count_nonzero(new_active != active),
            n_factor,
            n_cg,
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

    if factor_free is not None and np.array_equal(factor_free, free):
        # One step of iterative refinement with the factor of this very matrix: the direct
        # solve leaves a residual that grows with N (Cholesky's |L||Lᵀ| term; 32 ε |A||u| at
        # N = 1001 for u ≡ 1), one step brings it down to the ε |A||u| of evaluating it, the
        # certificate's rounding floor.  Clamped rows have zero residual: u_𝒜 stays 0.
        u = u + factor(rhs - Ac @ u)
        n_solves += 1
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
            "cg_iterations": n_cg,
            "backend": factorizer.backend,
        },
    )
    if not cert.ok:
        raise KKTError("active_set solution fails its KKT certificate", cert)
    return result
