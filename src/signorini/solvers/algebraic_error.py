"""The first-order algebraic error of a computed solution: how far ``u_h`` may be from the exact
minimiser ``u_h*`` of the discrete QP, from its KKT residual (the digits of a reported error that
round-off cannot change; ``signorini.formatting.certified_digits``).

The correction solves one clamped system with the contact set of ``u_h``: a sparse factorisation
on the meshes of the direct route, conjugate gradients with the multigrid route's preconditioner
on the large ones (O(n) time and memory; the estimate needs only a few correct digits).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from signorini.solvers.certificate import _TINY
from signorini.solvers.linalg import factorize
from signorini.solvers.multigrid import GalerkinHierarchy, pcg
from signorini.solvers.stencil import StencilOperator, as_csr

# the correction is an estimate (used with a safety factor): CG to this energy-relative accuracy
ESTIMATE_RTOL = 1e-3
ESTIMATE_MAX_CG = 500


@dataclass(frozen=True)
class AlgebraicError:
    """The first-order algebraic error ``δ ≈ u_h − u_h*`` of a computed solution (``u_h*`` the exact
    minimiser of the QP), from its KKT residual ``r = A u_h − b − λ``.

    On the contact set ``𝒜`` of ``u_h`` the residual vanishes (λ absorbs it) and ``δ = 0``; on the
    free nodes ``F`` the exact solution with the same contact set satisfies ``A_FF u*_F = b_F``, so
    ``δ_F = A_FF⁻¹ r_F``: exact to first order whenever the contact set is the exact one (a
    residual near round-off leaves it unchanged wherever complementarity is strict).  With zero
    primal, dual and complementarity residuals the variational inequality also gives the rigorous
    energy bound ``‖u_h − u_h*‖_A ≤ ‖r‖_{A⁻¹}`` (``energy``, here with ``A_FF``: the contact set's
    nodes are fixed).  ``delta``: the vector; ``energy = (r_Fᵀ δ_F)^{1/2}``."""

    delta: np.ndarray
    energy: float

    def summary(self, u: np.ndarray) -> dict[str, float]:
        """JSON-ready: the energy, ``max |δ|`` and ``max |δ| / max |u_h|``."""
        top = float(np.abs(self.delta).max(initial=0.0))
        return {
            "energy": self.energy,
            "max": top,
            "relative_max": top / max(float(np.abs(u).max(initial=0.0)), _TINY),
        }


def linearised_error(
    A: sp.spmatrix | StencilOperator,
    b: np.ndarray,
    constrained: np.ndarray,
    u: np.ndarray,
    lam: np.ndarray,
    active: np.ndarray,
    route: str = "direct",
    hierarchy: GalerkinHierarchy | None = None,
) -> AlgebraicError:
    """``AlgebraicError`` of ``(u, λ)`` with contact set ``active`` (constrained indices with ``u = 0``):
    ``A`` with the contact rows and columns replaced by the identity, solved by one sparse
    factorisation (the direct route, ``route="direct"``) or by multigrid-preconditioned CG (``"multigrid"``),
    with the solver's own ``hierarchy`` when given (``SolveResult.hierarchy``: no second set-up)."""
    A = A if isinstance(A, StencilOperator) else sp.csr_matrix(A)  # a stencil operator: ``multigrid.compact``
    free = np.ones(u.size, dtype=bool)
    free[np.asarray(active, dtype=np.int64)] = False
    lam_full = np.zeros_like(u)
    lam_full[constrained] = lam
    r = np.where(free, A @ u - b - lam_full, 0.0)
    if route == "multigrid":
        delta = _multigrid_correction(A, free, r, hierarchy)
    else:
        keep = sp.diags(free.astype(float))
        clamped = (keep @ as_csr(A) @ keep + sp.diags((~free).astype(float))).tocsr()
        delta = np.asarray(factorize(clamped)(r), dtype=float)
    delta[~free] = 0.0
    return AlgebraicError(delta=delta, energy=float(np.sqrt(max(float(r @ delta), 0.0))))


def _multigrid_correction(
    A: sp.csr_matrix | StencilOperator, free: np.ndarray, r: np.ndarray, hierarchy: GalerkinHierarchy | None
) -> np.ndarray:
    """``Ã⁻¹ r`` by CG with the multigrid route's Galerkin hierarchy for the clamped matrix ``Ã``."""
    if not r.any():
        return np.zeros_like(r)
    hierarchy = GalerkinHierarchy(A) if hierarchy is None else hierarchy
    hierarchy.update(free)
    delta, _, _ = pcg(
        hierarchy.matrix, r, np.zeros_like(r), hierarchy, ESTIMATE_RTOL, ESTIMATE_MAX_CG, overwrite_x=True
    )
    return delta
