"""What the true norms (``fem.norms.true``) know of the derivatives of an exact solution: bounds of
its second derivatives and the Hölder constant of its gradient, by which the true maxima exclude
triangles (``DerivativeBounds``), and ``u`` with ``∇u`` in one evaluation.

A problem states its bounds by ``derivative_bounds()`` (``fem.problem.ExactProblem``; none by
default); for the manufactured ``Problem`` they are ``ManufacturedBounds``, derived below from its closed form
``u = A ψ(r) ũ(r, θ)``, ``ũ = −Im z^{3/2}``, ``z = (x₁ − x0) + i x₂``.  The cut-off ψ(r) = S(1 − r/R)
and its derivatives on [0, R] (s = r/R):

- ``|ψ| ≤ 1``;
- ``|ψ'| R = 630 s⁴ (1 − s)⁴ ≤ 630/256`` (``PSI1``);
- ``|ψ''| R² = 2520 s³ (1 − s)³ |1 − 2s| ≤ 2520 (6/7)³ / (64 √7)`` (``PSI2``: with t = 1 − 2s the
  factor is (1 − t²)³ |t| / 64, largest at t² = 1/7), and
  ``|ψ'/r| R² = 630 s³ (1 − s)⁴ ≤ 630 (3/7)³ (4/7)⁴``, smaller.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

if TYPE_CHECKING:
    from signorini.fem.problem import ExactProblem, Problem

PSI1 = 630.0 / 256.0  # max |ψ'| R
PSI2 = 2520.0 * (6.0 / 7.0) ** 3 / (64.0 * np.sqrt(7.0))  # max(|ψ''|, |ψ'/r|) R²


class DerivativeBounds(Protocol):
    """Bounds of the derivatives of ``u``, ``r`` the distance to the problem's singular point (to the
    origin where it has none): ``hessian_bound(r_lo, r_hi)`` ≥ ‖D²u(x)‖₂ for ``r_lo ≤ r ≤ r_hi``,
    and ``gradient_holder_bound(r_hi)`` = H with ``|∇u(x) − ∇u(y)| ≤ H |x − y|^{1/2}`` within ``r_hi``."""

    def hessian_bound(self, r_lo: np.ndarray, r_hi: np.ndarray) -> np.ndarray: ...

    def gradient_holder_bound(self, r_hi: np.ndarray) -> np.ndarray: ...


@dataclass(frozen=True)
class ManufacturedBounds:
    """The bounds of the derivatives of the manufactured solution ``problem``."""

    problem: Problem

    def hessian_bound(self, r_lo: np.ndarray, r_hi: np.ndarray) -> np.ndarray:
        """An upper bound of the spectral norm ‖D²u(x)‖₂ over the points x of Ω̄ with
        ``r_lo ≤ |x − (x0, 0)| ≤ r_hi`` (inf where ``r_lo = 0``: D²u ~ r^{-1/2}).

        ``D²u = A (ψ D²ũ + ∇ψ ∇ũᵀ + ∇ũ ∇ψᵀ + ũ D²ψ)``.  ũ = Im f, f = −z^{3/2}, is harmonic on Ω̄
        minus the free point (the upper half-plane branch, continued across the bottom edge), so
        its Hessian ``[[Im f'', Re f''], [Re f'', −Im f'']]`` has the eigenvalues
        ``±|f''| = ±(3/4) r^{-1/2}``; ``|∇ũ| = |f'| = (3/2) r^{1/2}`` and ``|ũ| ≤ r^{3/2}``;
        ``∇ψ = ψ' r̂`` and D²ψ has the eigenvalues ψ'' and ψ'/r.  Hence, with ρ = min(r_hi, R),
        ``‖D²u‖₂ ≤ A ((3/4) r_lo^{-1/2} + 3 (PSI1/R) ρ^{1/2} + (PSI2/R²) ρ^{3/2})``, and 0 where
        ``r_lo ≥ R`` (u ≡ 0 there)."""
        p = self.problem
        r_lo, r_hi = np.asarray(r_lo, dtype=float), np.asarray(r_hi, dtype=float)
        rho = np.minimum(r_hi, p.R)
        with np.errstate(divide="ignore"):
            singular = 0.75 / np.sqrt(r_lo)
        bound = p.A * (singular + 3.0 * PSI1 / p.R * np.sqrt(rho) + PSI2 / p.R**2 * rho**1.5)
        return np.where(r_lo >= p.R, 0.0, bound)

    def gradient_holder_bound(self, r_hi: np.ndarray) -> np.ndarray:
        """An H with ``|∇u(x) − ∇u(y)| ≤ H |x − y|^{1/2}`` for all x, y of Ω̄ within ``r_hi`` of (x0, 0).

        ``∇u = A (ψ ∇ũ + ũ ∇ψ)`` and ``∇ũ = −(3/2)(Im √z, Re √z)``.  √z and √w lie in the closed
        first quadrant, so ``Re(√z conj √w) ≥ 0``, ``|√z − √w| ≤ |√z + √w|`` and
        ``|√z − √w|² ≤ |√z − √w| |√z + √w| = |z − w|``: ``|ψ(x)(∇ũ(x) − ∇ũ(y))| ≤ (3/2) |x − y|^{1/2}``.
        Further ``|(ψ(x) − ψ(y)) ∇ũ(y)| ≤ (PSI1/R) |x − y| (3/2) r_hi^{1/2}``, and ũ∇ψ (zero beyond
        R) has the derivative ``∇ũ ∇ψᵀ + ũ D²ψ``, at most ``(3/2)(PSI1/R) ρ^{1/2} + (PSI2/R²) ρ^{3/2}``
        (ρ = min(r_hi, R)) on the convex set of those points.  Both points lie within r_hi of the
        free point: ``|x − y| ≤ (2 r_hi)^{1/2} |x − y|^{1/2}``."""
        p = self.problem
        r_hi = np.asarray(r_hi, dtype=float)
        rho = np.minimum(r_hi, p.R)
        lipschitz = 1.5 * PSI1 / p.R * (np.sqrt(r_hi) + np.sqrt(rho)) + PSI2 / p.R**2 * rho**1.5
        return p.A * (1.5 + np.sqrt(2.0 * r_hi) * lipschitz)


def derivative_bounds(problem: ExactProblem) -> DerivativeBounds | None:
    """The bounds of the derivatives of the problem's solution (``problem.derivative_bounds()``:
    ``ManufacturedBounds`` for the manufactured ``Problem``), or None."""
    return problem.derivative_bounds()


def u_and_grad_u(problem: ExactProblem, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(u(x), ∇u(x))`` (``problem.u_and_grad_u``: for the manufactured ``Problem`` with one
    evaluation of its polar quantities, bit for bit ``problem.u(x)`` and ``problem.grad_u(x)``)."""
    return problem.u_and_grad_u(x)
