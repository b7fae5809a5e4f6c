"""The manufactured Signorini solution of Christof & Haubner, Section 7.

``u(x) = A ψ(r) ũ(r, θ)`` with ``ũ = -r^{3/2} sin(3θ/2)`` in polar coordinates
centred at the free point ``(x0, 0)`` on the bottom edge, ``ψ`` the degree-9
cut-off with ``ψ(0) = 1``, ``ψ^{(k)}(0) = 0`` (k = 1..4) and ``ψ^{(k)}(R) = 0``
(k = 0..4), and ``f = -Δu + c u``.  Since ``Δũ = 0`` away from the free point,

    -Δu = -A (2 ψ'(r) ∂_r ũ + ũ (ψ''(r) + ψ'(r)/r)),

so ``f`` has a closed form that stays bounded (ψ' = O(r⁴) near r = 0).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np


class ProblemParameterError(ValueError):
    """A manufactured-problem parameter is out of its admissible range."""


@dataclass(frozen=True)
class Problem:
    """Parameters of the manufactured solution (defaults: the paper's)."""

    x0: float = 0.5  # free point (x0, 0) on the bottom edge
    R: float = 0.45  # support radius of the cut-off ψ
    A: float = 10.0  # amplitude
    c: float = 1.0  # reaction coefficient in -Δu + c u = f

    def __post_init__(self) -> None:
        for name in ("x0", "R", "A", "c"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not np.isfinite(value):
                raise ProblemParameterError(f"problem parameter {name}={value!r} must be a finite number")
        if not 0.0 < self.x0 < 1.0:
            raise ProblemParameterError(f"x0={self.x0} must lie strictly inside the bottom edge (0, 1)")
        if not self.R > 0.0:
            raise ProblemParameterError(f"R={self.R} must be positive")
        if self.x0 - self.R <= 0.0 or self.x0 + self.R >= 1.0 or self.R >= 1.0:
            raise ProblemParameterError(
                f"support of u (disc of radius R={self.R} around ({self.x0}, 0)) must stay inside the "
                "unit square: need R < x0 and x0 + R < 1"
            )
        if self.A < 0.0:
            raise ProblemParameterError(f"amplitude A={self.A} must be non-negative (A < 0 violates u ≥ 0)")
        if self.c < 0.0:
            raise ProblemParameterError(f"reaction coefficient c={self.c} must be non-negative")

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_params(cls, params: dict) -> Problem:
        """The problem of a scene's ``problem`` block (numbers as floats)."""
        return cls(**{k: float(v) for k, v in params.items()})

    def singular_points(self) -> np.ndarray:
        """(2, 1): the free point (x0, 0), where u ~ r^{3/2} is not smooth (quadrature is graded there)."""
        return np.array([[self.x0], [0.0]])

    def boundary_breaks(self) -> np.ndarray:
        """(2, 2): (x0 ± R, 0), where the cut-off joins 0 (C⁴ only): boundary rules split there."""
        return np.array([[self.x0 - self.R, self.x0 + self.R], [0.0, 0.0]])

    # --- the cut-off ψ(r) = 1 - S(r/R), S(s) = s⁵(126 - 420 s + 540 s² - 315 s³ + 70 s⁴) ---
    def psi(self, r: np.ndarray) -> np.ndarray:
        """ψ(r); the C⁴ degree-9 polynomial cut-off, zero for r ≥ R."""
        # ψ = 1 - S(s) = S(1 - s) by the symmetry of S; the second form is exactly 0 at s = 1
        t = 1.0 - np.clip(np.asarray(r, dtype=float) / self.R, 0.0, 1.0)
        return t**5 * (126.0 + t * (-420.0 + t * (540.0 + t * (-315.0 + 70.0 * t))))

    def dpsi(self, r: np.ndarray) -> np.ndarray:
        """ψ'(r) = -630 s⁴ (1 - s)⁴ / R."""
        s = np.clip(np.asarray(r, dtype=float) / self.R, 0.0, 1.0)
        return -630.0 * s**4 * (1.0 - s) ** 4 / self.R

    def dpsi_over_r(self, r: np.ndarray) -> np.ndarray:
        """ψ'(r)/r = -630 s³ (1 - s)⁴ / R², without the division by r."""
        s = np.clip(np.asarray(r, dtype=float) / self.R, 0.0, 1.0)
        return -630.0 * s**3 * (1.0 - s) ** 4 / self.R**2

    def d2psi(self, r: np.ndarray) -> np.ndarray:
        """ψ''(r) = -2520 s³ (1 - s)³ (1 - 2 s) / R²."""
        s = np.clip(np.asarray(r, dtype=float) / self.R, 0.0, 1.0)
        return -2520.0 * s**3 * (1.0 - s) ** 3 * (1.0 - 2.0 * s) / self.R**2

    # --- the singular harmonic factor, via complex square roots (no trigonometry) ---
    # With z = (x₁ - x0) + i x₂ (x₂ ≥ 0), ũ = -Im z^{3/2} and ∇ũ = -(3/2)(Im √z, Re √z),
    # where Re √z = √((r + dx)/2) and Im √z = √((r - dx)/2).  On the contact part
    # (x₂ = 0, dx > 0) this gives ũ = 0 exactly, not to round-off.
    def polar(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r, θ) with θ = arccos((x₁ - x0)/r) ∈ [0, π] (the paper's definition for x₂ ≥ 0)."""
        dx, dy = np.asarray(x[0], dtype=float) - self.x0, np.asarray(x[1], dtype=float)
        return np.hypot(dx, dy), np.arctan2(np.abs(dy), dx)

    def _local(self, x: np.ndarray):
        """Points inside the support r < R: mask, dx, dy, r, Re √z, Im √z, ũ."""
        x = np.asarray(x, dtype=float)
        dx, dy = x[0] - self.x0, np.abs(x[1])
        r = np.hypot(dx, dy)
        inside = r < self.R
        dx, dy, r = dx[inside], dy[inside], r[inside]
        re = np.sqrt(np.maximum(r + dx, 0.0) / 2.0)
        im = np.sqrt(np.maximum(r - dx, 0.0) / 2.0)
        ut = -im * (3.0 * re * re - im * im)
        return inside, dx, dy, r, re, im, ut

    def u(self, x: np.ndarray) -> np.ndarray:
        """u = A ψ(r) ũ(r, θ), ũ = -r^{3/2} sin(3θ/2)."""
        inside, _, _, r, _, _, ut = self._local(x)
        out = np.zeros(np.shape(x)[1:])
        out[inside] = self.A * self.psi(r) * ut
        return out

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        """∇u = A ((ψ'/r) ũ (dx, dy) + ψ ∇ũ), stacked as shape (2, ...)."""
        inside, dx, dy, r, re, im, ut = self._local(x)
        out = np.zeros(np.shape(x))
        psi, dpr = self.psi(r), self.dpsi_over_r(r)
        out[0][inside] = self.A * (dpr * ut * dx - 1.5 * psi * im)
        out[1][inside] = self.A * (dpr * ut * dy - 1.5 * psi * re)
        return out

    def minus_laplace_u(self, x: np.ndarray) -> np.ndarray:
        """-Δu = -A (2 ψ' ∂_r ũ + ũ (ψ'' + ψ'/r)), using Δũ = 0 and r ∂_r ũ = (3/2) ũ."""
        inside, _, _, r, _, _, ut = self._local(x)
        out = np.zeros(np.shape(x)[1:])
        dpr = self.dpsi_over_r(r)
        out[inside] = -self.A * ut * (3.0 * dpr + self.d2psi(r) + dpr)
        return out

    def f(self, x: np.ndarray) -> np.ndarray:
        """Right-hand side f = -Δu + c u."""
        inside, _, _, r, _, _, ut = self._local(x)
        out = np.zeros(np.shape(x)[1:])
        dpr = self.dpsi_over_r(r)
        out[inside] = self.A * ut * (-4.0 * dpr - self.d2psi(r) + self.c * self.psi(r))
        return out


# --- problems with simple data and a closed-form solution (stability atlas, degenerate contact) ---
#
# Same interface as ``Problem`` (``u``, ``grad_u``, ``f``, ``c``, ``as_dict``), so ``assembly``,
# ``discrete`` and ``norms`` take them unchanged.  With f ≡ const the load vector is
# ``b = f M 1`` (the quadrature is exact), and ``K 1 = 0`` (no Dirichlet part), so the
# constant solutions below are also the *discrete* solutions, up to round-off.


def _check_parameters(obj, names: tuple[str, ...]) -> None:
    """Every named parameter a finite number, the reaction coefficient ``c`` non-negative."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise ProblemParameterError(f"problem parameter {name}={value!r} must be a finite number")
    if obj.c < 0.0:
        raise ProblemParameterError(f"reaction coefficient c={obj.c} must be non-negative")


@dataclass(frozen=True)
class ConstantProblem:
    """``-Δu + c u = f ≡ value`` with the Signorini conditions on all of ∂Ω.

    - ``value > 0``, ``c > 0``: ``u ≡ value / c``; ``u > 0`` and ``∂_ν u = 0`` on ∂Ω, so the
      contact set is empty (**no contact**).
    - ``value = 0``: ``u ≡ 0``, and ``u = ∂_ν u = 0`` on all of ∂Ω: every boundary point is
      **biactive** (weakly active, non-strict complementarity), the worst case for an
      active-set method.
    - ``value < 0`` is excluded: the solution is then the Dirichlet solution (full contact,
      ``u ≤ 0``, ``∂_ν u ≥ 0`` by the maximum principle and Hopf's lemma), with no closed
      form; ``FullContactProblem`` is a full-contact case that has one.  Note that
      ``u ≡ 0`` is *not* the solution for ``f ≡ -1``: the constraint acts on ∂Ω only and
      ``-Δ0 + c 0 = 0 ≠ -1`` in Ω.
    """

    value: float = 1.0
    c: float = 1.0

    def __post_init__(self) -> None:
        _check_parameters(self, ("value", "c"))
        if self.value < 0.0:
            raise ProblemParameterError(
                f"value={self.value} < 0: the solution is the Dirichlet solution, not known in closed form "
                "(use FullContactProblem for full contact)"
            )
        if self.value > 0.0 and self.c == 0.0:
            raise ProblemParameterError("value > 0 needs c > 0 (for c = 0 the problem has no solution: ∫f > 0)")

    @property
    def exact(self) -> float:
        """The constant solution ``value / c`` (0 for ``value = 0``)."""
        return self.value / self.c if self.value > 0.0 else 0.0

    def as_dict(self) -> dict[str, float | str]:
        return {"kind": "constant", "value": float(self.value), "c": float(self.c)}

    def u(self, x: np.ndarray) -> np.ndarray:
        return np.full(np.shape(x)[1:], self.exact)

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(x))

    def f(self, x: np.ndarray) -> np.ndarray:
        return np.full(np.shape(x)[1:], float(self.value))


@dataclass(frozen=True)
class FullContactProblem:
    """``u = -A sin(π x₁) sin(π x₂)``, ``f = -Δu + c u = -A (2π² + c) sin(π x₁) sin(π x₂) ≤ 0``.

    ``u = 0`` on ∂Ω and ``∂_ν u = A π sin(π s) ≥ 0`` (``s`` the arclength on an edge), so
    ``u`` satisfies the Signorini conditions with **full contact**; the contact is strict
    except at the four corners, where ``∂_ν u = 0`` (biactive).
    """

    A: float = 1.0
    c: float = 1.0

    def __post_init__(self) -> None:
        _check_parameters(self, ("A", "c"))
        if self.A < 0.0:
            raise ProblemParameterError(f"amplitude A={self.A} must be non-negative (A < 0 violates ∂_ν u ≥ 0)")

    def as_dict(self) -> dict[str, float | str]:
        return {"kind": "full_contact", "A": float(self.A), "c": float(self.c)}

    def u(self, x: np.ndarray) -> np.ndarray:
        return -self.A * np.sin(np.pi * x[0]) * np.sin(np.pi * x[1])

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        s1, s2 = np.sin(np.pi * x[0]), np.sin(np.pi * x[1])
        c1, c2 = np.cos(np.pi * x[0]), np.cos(np.pi * x[1])
        return -self.A * np.pi * np.stack([c1 * s2, s1 * c2])

    def f(self, x: np.ndarray) -> np.ndarray:
        return (2.0 * np.pi**2 + self.c) * self.u(x)


PROBLEM_KINDS = {"manufactured": Problem, "constant": ConstantProblem, "full_contact": FullContactProblem}


def make_problem(params: dict):
    """A problem from a parameter mapping; ``kind`` (default ``manufactured``) selects the class
    of ``PROBLEM_KINDS``, the other keys are its parameters."""
    params = dict(params)
    kind = params.pop("kind", "manufactured")
    if kind not in PROBLEM_KINDS:
        raise ProblemParameterError(f"unknown problem kind {kind!r}; choose one of {sorted(PROBLEM_KINDS)}")
    try:
        return PROBLEM_KINDS[kind](**params)
    except TypeError as err:
        raise ProblemParameterError(f"{kind} problem: {err}") from None
