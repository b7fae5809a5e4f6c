"""The KKT certificate every solver's answer passes through.

For ``min ½ uᵀAu - bᵀu`` subject to ``u_i ≥ 0`` for ``i ∈ B`` the KKT conditions read

    A u - b = λ (λ supported on B),   u_B ≥ 0,   λ_B ≥ 0,   u_i λ_i = 0.

Each residual is scaled to be invariant under ``(u, b, λ) → (s u, s b, s λ)``:
with ``σ = max(‖Au‖∞, ‖b‖∞)``,

- stationarity    ``‖A u - b - λ‖∞ / σ``
- primal          ``max(0, -min u_B) / ‖u‖∞``
- dual            ``max(0, -min λ_B) / σ``
- complementarity ``max |u_i λ_i| / (‖u‖∞ σ)``
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import scipy.sparse as sp

_TINY = np.finfo(float).tiny


class KKTError(RuntimeError):
    """A solution failed its KKT certificate; carries the residuals."""

    def __init__(self, message: str, certificate: Certificate):
        super().__init__(f"{message}: {certificate.describe()}")
        self.certificate = certificate


class NotConvergedError(RuntimeError):
    """A solver stopped before convergence (iteration limit, solver status)."""


class BadInputError(ValueError):
    """The QP data are malformed (NaN/Inf, wrong shapes, indices out of range)."""


@dataclass(frozen=True)
class Certificate:
    stationarity: float
    primal: float
    dual: float
    complementarity: float
    tol: float

    @property
    def worst(self) -> float:
        return max(self.stationarity, self.primal, self.dual, self.complementarity)

    @property
    def ok(self) -> bool:
        return bool(np.isfinite(self.worst) and self.worst <= self.tol)

    def as_dict(self) -> dict[str, float | bool]:
        return {**asdict(self), "worst": self.worst, "ok": self.ok}

    def describe(self) -> str:
        return (
            f"stationarity={self.stationarity:.2e}, primal={self.primal:.2e}, dual={self.dual:.2e}, "
            f"complementarity={self.complementarity:.2e} (tolerance {self.tol:.1e})"
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
    return Certificate(
        stationarity=float(np.abs(Au - b - lam_full).max(initial=0.0) / sigma),
        primal=float(max(0.0, -uB.min(initial=0.0)) / unorm),
        dual=float(max(0.0, -lam.min(initial=0.0)) / sigma),
        complementarity=float(np.abs(uB * lam).max(initial=0.0) / (unorm * sigma)),
        tol=float(tol),
    )


def check_qp_data(A: sp.spmatrix, b: np.ndarray, constrained: np.ndarray) -> None:
    """Reject data that no solver should see: NaN/Inf, bad shapes, out-of-range indices."""
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
