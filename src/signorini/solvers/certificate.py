"""The KKT certificate every solver's answer passes through.

For ``min ½ uᵀAu - bᵀu`` subject to ``u_i ≥ 0`` for ``i ∈ B`` the KKT conditions read

    A u - b = λ (λ supported on B),   u_B ≥ 0,   λ_B ≥ 0,   u_i λ_i = 0.

Each residual is scaled to be invariant under ``(u, b, λ) → (s u, s b, s λ)``:
with ``σ = max(‖Au‖∞, ‖b‖∞)``,

- stationarity    ``‖A u - b - λ‖∞ / σ``
- primal          ``max(0, -min u_B) / ‖u‖∞``
- dual            ``max(0, -min λ_B) / σ``
- complementarity ``max |u_i λ_i| / (‖u‖∞ σ)``

Rounding floor.  ``A u - b`` cannot be evaluated more accurately than about
``ε (|A||u|)_i`` per row (ε the unit round-off); the rounded *exact* solution has a residual
of that size.  When ``A u`` cancels (smooth data: ``u ≡ 1`` gives ``K u = 0``, so
``σ = ‖b‖∞ = O(h²)`` while ``|A||u| = O(1)``), the load-relative stationarity of even the
best double-precision solution is ``≈ ε ‖|A||u|‖∞ / σ = O(ε/h²)`` (for ``f ≡ 1, c = 1``, with
what a plain Cholesky solve left: docs/evidence/design-measurements.md#certificate-rounding-floor),
above any 1e-10 tolerance on fine meshes.  The certificate therefore
accepts residuals up to ``max(tol, min(floor, 1e-6))`` with ``floor = 16 ε ‖|A||u|‖∞ / σ`` (16
covers the 7 products of a P1 row and the rounding of u itself; the cap keeps an exploded ``u``
of a singular system from certifying itself).  For the paper's data the floor is
far below 1e-10, growing like N² (``floor`` in ``docs/evidence/core_N501.json`` and
``core_N2001_memory.json``).  ``tol = 0`` demands exact zeros (no floor).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

_TINY = np.finfo(float).tiny
ROUNDOFF_FACTOR = 16.0  # the floor is ROUNDOFF_FACTOR · ε · ‖|A||u|‖∞ / σ (module docstring)
# ...but never above this: a huge ‖|A||u|‖∞ / σ means u exploded (e.g. a singular system of an
# unbounded QP, u ~ 1e13), not cancellation, and its O(1) residual must not be certified
FLOOR_CAP = 1e-6


class KKTError(RuntimeError):
    """A solution failed its KKT certificate; carries the residuals."""

    def __init__(self, message: str, certificate: Certificate):
        super().__init__(f"{message}: {certificate.describe()}")
        self.certificate = certificate


class NotConvergedError(RuntimeError):
    """A solver stopped before convergence (iteration limit, solver status); ``status``: the
    solver's own status where it reported one (cvxpy's, e.g. ``user_limit``), else None."""

    def __init__(self, message: str, status: str | None = None):
        super().__init__(message)
        self.status = status


class BadInputError(ValueError):
    """The QP data are malformed (NaN/Inf, wrong shapes, indices out of range)."""


@dataclass(frozen=True)
class Certificate:
    stationarity: float
    primal: float
    dual: float
    complementarity: float
    tol: float
    floor: float = 0.0  # rounding floor of the residual evaluation, relative like the residuals

    @property
    def threshold(self) -> float:
        """What the residuals are compared with: ``max(tol, min(floor, FLOOR_CAP))``; exactly 0 when ``tol = 0``."""
        return max(self.tol, min(self.floor, FLOOR_CAP)) if self.tol > 0.0 else 0.0

    @property
    def worst(self) -> float:
        # np.max propagates NaN; Python's max(0.0, nan) is 0.0, which would certify a NaN residual
        return float(np.max([self.stationarity, self.primal, self.dual, self.complementarity]))

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.worst) and self.worst <= self.threshold)

    def as_dict(self) -> dict[str, float | bool]:
        return {**asdict(self), "threshold": self.threshold, "worst": self.worst, "ok": self.ok}

    def describe(self) -> str:
        floor = f", rounding floor {self.floor:.1e}" if self.floor > self.tol > 0.0 else ""
        return (
            f"stationarity={self.stationarity:.2e}, primal={self.primal:.2e}, dual={self.dual:.2e}, "
            f"complementarity={self.complementarity:.2e} (tolerance {self.tol:.1e}{floor})"
        )


def kkt_certificate(
    A: sp.spmatrix, b: np.ndarray, constrained: np.ndarray, u: np.ndarray, lam: np.ndarray, tol: float
) -> Certificate:
    """Relative KKT residuals of ``(u, λ)``; ``lam`` has one entry per constrained index."""
    Au = A @ u
    lam_full = np.zeros_like(u)
    lam_full[constrained] = lam
    sigma = max(np.abs(Au).max(initial=0.0), np.abs(b).max(initial=0.0), _TINY)
    unorm = max(np.abs(u).max(initial=0.0), _TINY)
    uB = u[constrained]
    rounding = abs_product(A, np.abs(u)).max(initial=0.0)  # ‖|A||u|‖∞
    floor = ROUNDOFF_FACTOR * np.finfo(float).eps * float(rounding) / sigma
    return Certificate(
        stationarity=float(np.abs(Au - b - lam_full).max(initial=0.0) / sigma),
        primal=float(max(0.0, -uB.min(initial=0.0)) / unorm),
        dual=float(max(0.0, -lam.min(initial=0.0)) / sigma),
        # two divisions: for u = 0, b = 0 (f ≡ 0) the product unorm·sigma = tiny² underflows to 0 (0/0 = NaN)
        complementarity=float(np.abs(uB * lam).max(initial=0.0) / unorm / sigma),
        tol=float(tol),
        floor=floor if np.isfinite(floor) else 0.0,
    )


# Relative thresholds of the structural checks in ``check_qp_data`` (scale-free: they compare
# entries of A with max |A_ij| or with A_ii, never with an absolute number).
SYMMETRY_RTOL = 1e-12  # max |A - Aᵀ| ≤ SYMMETRY_RTOL · max |A|
PSD_SHIFT = 1e-8  # A + PSD_SHIFT · diag(A) must admit a Cholesky factorisation


# Rows from which the compiled kernels pay for their import (``signorini.solvers.kernels``;
# docs/evidence/design-measurements.md#compiled-kernels); below, numpy code with the same bits.
COMPILED_MIN_UNKNOWNS = 1 << 21
ABS_CHUNK_ROWS = 1 << 20  # rows of |A| formed at a time by numpy's ``abs_product``


def abs_product(A: sp.spmatrix, y: np.ndarray) -> np.ndarray:
    """``|A| y`` for a sparse matrix, each row summed in CSR order from 0.0 as ``abs(A) @ y`` sums it,
    without forming ``|A|`` (at N = 4001 a copy of ``A`` is 1.3 GB): compiled for large matrices,
    else a block of rows at a time.  An operator that stands in for a matrix
    (``solvers.stencil.StencilOperator``) computes it itself, in the same order."""
    if hasattr(A, "abs_product"):
        return A.abs_product(y)
    A = sp.csr_matrix(A)
    out = np.empty(A.shape[0])
    y = np.ascontiguousarray(y, dtype=float)
    if A.shape[0] >= COMPILED_MIN_UNKNOWNS:
        from signorini.solvers.kernels import abs_product_rows

        abs_product_rows(A.indptr, A.indices, A.data, y, out)
        return out
    for start in range(0, A.shape[0], ABS_CHUNK_ROWS):
        stop = min(start + ABS_CHUNK_ROWS, A.shape[0])
        lo, hi = A.indptr[start], A.indptr[stop]
        products = np.abs(A.data[lo:hi]) * y[A.indices[lo:hi]]
        rows = np.repeat(np.arange(stop - start), np.diff(A.indptr[start : stop + 1]))
        out[start:stop] = np.bincount(rows, weights=products, minlength=stop - start)
    return out


def symmetry_and_dominance(A: sp.csr_matrix) -> tuple[float, float, bool]:
    """``max |A_ij|``, ``max |A - Aᵀ|`` over the stored entries and whether every row has
    ``A_ii ≥ Σ_{j≠i} |A_ij|`` (to 1e-12 A_ii), for ``A`` in canonical CSR form: in one compiled pass
    for large matrices (no ``Aᵀ``, no ``|A|``), else with numpy."""
    if A.shape[0] >= COMPILED_MIN_UNKNOWNS:
        from signorini.solvers.kernels import symmetry_and_dominance as compiled

        top, asym, dominant = compiled(A.indptr, A.indices, A.data)
        return float(top), float(asym), bool(dominant)
    d = A.diagonal()
    off = abs_product(A, np.ones(A.shape[1])) - np.abs(d)
    top = float(np.abs(A.data).max(initial=0.0))
    return top, float(np.abs((A - A.T).data).max(initial=0.0)), bool(np.all(d >= off - 1e-12 * d))


def check_psd(A: sp.spmatrix) -> None:
    """Reject a matrix that is not symmetric positive semidefinite (the QP would be non-convex,
    and for an indefinite ``A`` unbounded along some directions: no minimiser exists).

    Symmetry: ``max |A - Aᵀ| ≤ 1e-12 max |A|``.  Semidefiniteness, cheaply first: a symmetric
    matrix with positive diagonal and ``A_ii ≥ Σ_{j≠i} |A_ij|`` is PSD (Gershgorin).  P1 on
    non-obtuse meshes (every Friedrichs–Keller mesh) passes for every ``c ≥ 0``: ``K`` has
    zero row sums and non-positive off-diagonal entries, and the P1 mass matrix has
    ``M_ii = Σ_{j≠i} M_ij``, so ``Σ_{j≠i} |K_ij + c M_ij| ≤ K_ii + c M_ii``.  Otherwise (e.g. a
    jittered mesh with obtuse triangles) a Cholesky factorisation of ``A + 1e-8 diag(A)``
    decides (``linalg.is_positive_definite``); the shift admits the singular ``A = K`` of
    ``c = 0`` (semicoercive, still convex) and rejects ``λ_min(A) < -1e-8 max A_ii`` roughly.
    """
    A = sp.csr_matrix(A)
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
        A.sort_indices()
    top, asym, dominant = symmetry_and_dominance(A)
    scale = max(top, _TINY)
    if asym > SYMMETRY_RTOL * scale:
        raise BadInputError(
            f"matrix is not symmetric: max |A - Aᵀ| = {asym:.2e} = {asym / scale:.1e} max |A| "
            f"(tolerance {SYMMETRY_RTOL:.0e})"
        )
    if dominant:  # weakly diagonally dominant, positive diagonal (check_qp_data): PSD
        return
    from signorini.solvers.linalg import is_positive_definite

    if not is_positive_definite(A + PSD_SHIFT * sp.diags(A.diagonal())):
        raise BadInputError(
            "matrix is not positive semidefinite (Cholesky factorisation of A + 1e-8 diag(A) fails): "
            "the QP is non-convex and has no minimiser in general"
        )


def check_qp_data(A: sp.spmatrix, b: np.ndarray, constrained: np.ndarray) -> None:
    """Reject data that no solver should see: NaN/Inf, bad shapes, out-of-range, duplicate or
    no constrained indices, a matrix that is not symmetric positive semidefinite."""
    n = b.shape[0]
    if A.shape != (n, n):
        raise BadInputError(f"matrix shape {A.shape} does not match right-hand side length {n}")
    if not np.all(np.isfinite(b)):
        raise BadInputError(f"right-hand side has {np.count_nonzero(~np.isfinite(b))} NaN/Inf entries")
    data = sp.csr_matrix(A).data
    if not np.all(np.isfinite(data)):
        raise BadInputError(f"matrix has {np.count_nonzero(~np.isfinite(data))} NaN/Inf entries")
    if constrained.size and (constrained.min() < 0 or constrained.max() >= n):
        raise BadInputError("constrained indices out of range")
    if np.any(A.diagonal() <= 0):
        raise BadInputError("matrix has non-positive diagonal entries: it is not symmetric positive definite")
    # An empty set would make the QP the linear system A u = b: not a Signorini problem, and
    # almost always a caller's mistake (a wrong boundary index set); say so instead of solving.
    if constrained.size == 0:
        raise BadInputError("empty constraint set: no index carries the bound u_i ≥ 0 (not a Signorini QP)")
    if np.unique(constrained).size != constrained.size:
        raise BadInputError("duplicate constrained indices")
    check_psd(A)
