"""The problems (S): ``-Δu + c u = f`` in the unit square with the Signorini conditions on the
boundary and a known solution ``u``, what the assembly, the norms and the stages take (``ExactProblem``),
and the one factory of a problem from a scene's parameters (``make_problem``).

The paper's problem is the manufactured solution of Christof & Haubner, Section 7 (``Problem``):
``u(x) = A ψ(r) ũ(r, θ)`` with ``ũ = -r^{3/2} sin(3θ/2)`` in polar coordinates
centred at the free point ``(x0, 0)`` on the bottom edge, ``ψ`` the degree-9
cut-off with ``ψ(0) = 1``, ``ψ^{(k)}(0) = 0`` (k = 1..4) and ``ψ^{(k)}(R) = 0``
(k = 0..4), and ``f = -Δu + c u``.  Since ``Δũ = 0`` away from the free point,

    -Δu = -A (2 ψ'(r) ∂_r ũ + ũ (ψ''(r) + ψ'(r)/r)),

so ``f`` has a closed form that stays bounded (ψ' = O(r⁴) near r = 0).

A further problem is a frozen dataclass deriving from ``ProblemBase`` with its ``kind``, its
parameters as fields (checked in ``__post_init__``: ``ProblemParameterError``) and ``u``,
``grad_u``, ``f``, ``as_dict``; it overrides the optional capabilities it has; it is listed in
``PROBLEM_KINDS`` and in the config schema's problem kinds (``$defs/problem_kind``).
"""

from __future__ import annotations

import contextlib
import contextvars
from dataclasses import asdict, dataclass, fields, replace
from typing import TYPE_CHECKING, ClassVar, Protocol

import numpy as np

if TYPE_CHECKING:
    from collections.abc import Iterator, Mapping

    from signorini.fem.derivatives import DerivativeBounds


class ProblemParameterError(ValueError):
    """A problem parameter is out of its admissible range; ``parameter`` names it (None: the
    parameters together, or the kind)."""

    def __init__(self, message: str, parameter: str | None = None):
        super().__init__(message)
        self.parameter = parameter


# Meshes from this many triangles evaluate the manufactured u and ∇u by the compiled point
# kernels (``fem.point_kernels``: the same bits); below, numba's import and loading cost more than
# they save (docs/evidence/design-measurements.md#compiled-point-kernels).
COMPILED_MIN_ELEMENTS = 1 << 20
_COMPILED = contextvars.ContextVar("compiled_points", default=False)


@contextlib.contextmanager
def compiled_points(enabled: bool = True) -> Iterator[None]:
    """Within the block, ``Problem.u`` and ``Problem.u_and_grad_u`` evaluate by the compiled point
    kernels if ``enabled`` (bit for bit the numpy evaluation, in one pass over the points)."""
    token = _COMPILED.set(enabled)
    try:
        yield
    finally:
        _COMPILED.reset(token)


def compiled_points_enabled() -> bool:
    """Whether the compiled point kernels are enabled here (``compiled_points``)."""
    return _COMPILED.get()


def compiled_points_for(triangles: int) -> contextlib.AbstractContextManager[None]:
    """``compiled_points`` for work over a mesh of ``triangles`` triangles: enabled from
    ``COMPILED_MIN_ELEMENTS`` on (the one place that decides)."""
    return compiled_points(triangles >= COMPILED_MIN_ELEMENTS)


class ExactProblem(Protocol):
    """What the assembly, the norms and the stages use of a problem: the reaction coefficient ``c``,
    ``u``, ``∇u`` and ``f`` at points ``x`` of shape (2, ...), and its parameters (``as_dict``); and
    the optional capabilities, which ``ProblemBase`` gives as their defaults: the points where ``u``
    is not smooth (``singular_points``: boundary rules split and grade there) and further break points
    on ∂Ω (``boundary_breaks``: split there), bounds of the derivatives of ``u`` (``derivative_bounds``,
    by which the true maxima exclude triangles), ``u`` with ``∇u`` in one evaluation, the problem
    with ``u ≡ 0`` on the same pieces (``vanishing``: the norms of a P1 function, e.g. an algebraic
    error, are its errors there), and a disc outside which ``u`` and ``f`` are exactly zero
    (``support``: the load vector leaves out the triangles that cannot meet it), and the parameters of
    compiled point kernels for ``u`` (``point_kernel``: the true norms run whole rules inside them)."""

    c: float

    def u(self, x: np.ndarray) -> np.ndarray: ...

    def grad_u(self, x: np.ndarray) -> np.ndarray: ...

    def f(self, x: np.ndarray) -> np.ndarray: ...

    def as_dict(self) -> dict: ...

    def singular_points(self) -> np.ndarray: ...

    def boundary_breaks(self) -> np.ndarray: ...

    def derivative_bounds(self) -> DerivativeBounds | None: ...

    def u_and_grad_u(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...

    def vanishing(self) -> ExactProblem: ...

    def support(self) -> tuple[np.ndarray, float] | None: ...

    def point_kernel(self) -> tuple[float, ...] | None: ...


class ProblemBase:
    """The defaults of the optional capabilities of ``ExactProblem``: no singular point, no break
    point, no bounds of the derivatives, ``u`` and ``∇u`` evaluated apart, ``u ≡ 0`` as a
    ``Vanishing`` problem; and the construction from a scene's parameters."""

    kind: ClassVar[str]

    def singular_points(self) -> np.ndarray:
        """(2, k) points where ``u`` is not smooth: none."""
        return np.zeros((2, 0))

    def boundary_breaks(self) -> np.ndarray:
        """(2, k) further points on ∂Ω where ``u`` is less smooth: none."""
        return np.zeros((2, 0))

    def derivative_bounds(self) -> DerivativeBounds | None:
        """Bounds of the derivatives of ``u``: none known."""
        return None

    def u_and_grad_u(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(u(x), ∇u(x))``."""
        return self.u(x), self.grad_u(x)

    def vanishing(self) -> ExactProblem:
        """``u ≡ 0`` with this problem's points (``Vanishing``)."""
        return Vanishing(self)

    def support(self) -> tuple[np.ndarray, float] | None:
        """(centre (2,), radius) of a disc outside which ``u`` and ``f`` are exactly ``+0.0``; None:
        they may be non-zero anywhere."""
        return None

    def point_kernel(self) -> tuple[float, ...] | None:
        """The parameters of this problem's compiled point kernels (``fem.point_kernels``), which
        whole rules over triangles may run inside, where they are enabled (``compiled_points``); None:
        evaluate with numpy."""
        return None

    @classmethod
    def parameters(cls) -> tuple[str, ...]:
        """The names of the problem's parameters (its fields)."""
        return tuple(f.name for f in fields(cls))

    @classmethod
    def from_params(cls, params: Mapping) -> ProblemBase:
        """The problem of a parameter block (integers as floats)."""
        return cls(**{k: float(v) if type(v) is int else v for k, v in params.items()})


class _ZeroBounds:
    """The derivatives of ``u ≡ 0``: all zero."""

    def hessian_bound(self, r_lo: np.ndarray, r_hi: np.ndarray) -> np.ndarray:
        return np.zeros(np.broadcast(r_lo, r_hi).shape)

    def gradient_holder_bound(self, r_hi: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(r_hi))


@dataclass(frozen=True)
class Vanishing(ProblemBase):
    """``u ≡ 0`` (and ``f ≡ 0``) with the reaction, singular and break points of ``problem``: the
    boundary rules split where the problem's do."""

    problem: ExactProblem

    @property
    def c(self) -> float:
        return self.problem.c

    def u(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(x)[1:])

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(x))

    def f(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(x)[1:])

    def as_dict(self) -> dict:
        return {**self.problem.as_dict(), "vanishing": True}

    def singular_points(self) -> np.ndarray:
        return self.problem.singular_points()

    def boundary_breaks(self) -> np.ndarray:
        return self.problem.boundary_breaks()

    def derivative_bounds(self) -> DerivativeBounds:
        return _ZeroBounds()

    def support(self) -> tuple[np.ndarray, float]:
        """The empty disc (radius 0): ``u`` and ``f`` vanish everywhere."""
        return np.zeros(2), 0.0


@dataclass(frozen=True)
class Problem(ProblemBase):
    """The paper's manufactured solution (module docstring) by its parameters (defaults: the paper's)."""

    kind: ClassVar[str] = "manufactured"
    x0: float = 0.5  # free point (x0, 0) on the bottom edge
    R: float = 0.45  # support radius of the cut-off ψ
    A: float = 10.0  # amplitude
    c: float = 1.0  # reaction coefficient in -Δu + c u = f

    def __post_init__(self) -> None:
        for name in ("x0", "R", "A", "c"):
            value = getattr(self, name)
            if not isinstance(value, (int, float)) or not np.isfinite(value):
                raise ProblemParameterError(f"problem parameter {name}={value!r} must be a finite number", name)
        if not 0.0 < self.x0 < 1.0:
            raise ProblemParameterError(f"x0={self.x0} must lie strictly inside the bottom edge (0, 1)", "x0")
        if not self.R > 0.0:
            raise ProblemParameterError(f"R={self.R} must be positive", "R")
        if self.x0 - self.R <= 0.0 or self.x0 + self.R >= 1.0 or self.R >= 1.0:
            raise ProblemParameterError(
                f"support of u (disc of radius R={self.R} around ({self.x0}, 0)) must stay inside the "
                "unit square: need R < x0 and x0 + R < 1",
                "R",
            )
        if self.A < 0.0:
            raise ProblemParameterError(f"amplitude A={self.A} must be non-negative (A < 0 violates u ≥ 0)", "A")
        if self.c < 0.0:
            raise ProblemParameterError(f"reaction coefficient c={self.c} must be non-negative", "c")

    def as_dict(self) -> dict[str, float]:
        return {k: float(v) for k, v in asdict(self).items()}

    @classmethod
    def from_params(cls, params: Mapping) -> Problem:
        """The problem of a scene's ``problem`` block (numbers as floats)."""
        return cls(**{k: float(v) for k, v in params.items()})

    def singular_points(self) -> np.ndarray:
        """(2, 1): the free point (x0, 0), where u ~ r^{3/2} is not smooth (quadrature is graded there)."""
        return np.array([[self.x0], [0.0]])

    def boundary_breaks(self) -> np.ndarray:
        """(2, 2): (x0 ± R, 0), where the cut-off joins 0 (C⁴ only): boundary rules split there."""
        return np.array([[self.x0 - self.R, self.x0 + self.R], [0.0, 0.0]])

    def support(self) -> tuple[np.ndarray, float]:
        """The disc r < R around the free point: outside it ``_local`` leaves ``u``, ``∇u`` and ``f``
        at the zeros they start from; for ``A = 0`` the empty disc of radius 0."""
        return np.array([self.x0, 0.0]), self.R if self.A != 0.0 else 0.0

    def vanishing(self) -> Problem:
        """The same problem with amplitude 0: u ≡ 0 with the same free point and cut-off."""
        return replace(self, A=0.0)

    def derivative_bounds(self) -> DerivativeBounds:
        """The bounds derived from the closed form (``fem.derivatives.ManufacturedBounds``)."""
        from signorini.fem.derivatives import ManufacturedBounds

        return ManufacturedBounds(self)

    def u_and_grad_u(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(u(x), ∇u(x))`` with one evaluation of the polar quantities, bit for bit ``u(x)`` and
        ``grad_u(x)`` (the same operations; for ``A = 0`` zeros without evaluating them, where those
        give zeros of either sign)."""
        if self.A == 0.0:  # u ≡ 0 (the norms of a P1 function, e.g. an algebraic error): nothing to evaluate
            return np.zeros(np.shape(x)[1:]), np.zeros(np.shape(x))
        if _COMPILED.get():
            return self._compiled(x, gradient=True)
        where, dx, dy, r, re, im, ut = self._local(x)
        shape = np.shape(x)[1:]
        psi, dpr, _ = self._cutoff(r)
        radial = dpr * ut
        value, grad = self._placed(where, self.A * psi * ut, shape), np.empty((2, *shape))
        self._placed(where, self.A * (radial * dx - 1.5 * psi * im), shape, grad[0, ...])
        self._placed(where, self.A * (radial * dy - 1.5 * psi * re), shape, grad[1, ...])
        return value, grad

    # --- the cut-off ψ(r) = 1 - S(r/R), S(s) = s⁵(126 - 420 s + 540 s² - 315 s³ + 70 s⁴) ---
    # Powers as products (numpy's ``**`` with an exponent above 2 calls ``pow`` per element), from
    # one ``s = r/R`` and ``t = 1 - s`` per point: ``_cutoff`` gives ψ, ψ'/r and ψ'' at once, each
    # bit for bit the value of its method below.
    def _s(self, r: np.ndarray) -> np.ndarray:
        return np.clip(np.asarray(r, dtype=float) / self.R, 0.0, 1.0)

    @staticmethod
    def _psi_of(t: np.ndarray) -> np.ndarray:
        t2 = t * t
        return t2 * t2 * t * (126.0 + t * (-420.0 + t * (540.0 + t * (-315.0 + 70.0 * t))))

    def _dpsi_over_r_of(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        t2 = t * t
        return -630.0 * (s * s * s) * (t2 * t2) / (self.R * self.R)

    def _d2psi_of(self, s: np.ndarray, t: np.ndarray) -> np.ndarray:
        return -2520.0 * (s * s * s) * (t * t * t) * (1.0 - 2.0 * s) / (self.R * self.R)

    def _cutoff(self, r: np.ndarray, second: bool = False) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
        """(ψ, ψ'/r, ψ'' if ``second`` else None) at ``r``."""
        s = self._s(r)
        t = 1.0 - s
        return self._psi_of(t), self._dpsi_over_r_of(s, t), self._d2psi_of(s, t) if second else None

    def psi(self, r: np.ndarray) -> np.ndarray:
        """ψ(r); the C⁴ degree-9 polynomial cut-off, zero for r ≥ R."""
        # ψ = 1 - S(s) = S(1 - s) by the symmetry of S; the second form is exactly 0 at s = 1
        return self._psi_of(1.0 - self._s(r))

    def dpsi(self, r: np.ndarray) -> np.ndarray:
        """ψ'(r) = -630 s⁴ (1 - s)⁴ / R."""
        s = self._s(r)
        t2 = (1.0 - s) * (1.0 - s)
        return -630.0 * (s * s) * (s * s) * (t2 * t2) / self.R

    def dpsi_over_r(self, r: np.ndarray) -> np.ndarray:
        """ψ'(r)/r = -630 s³ (1 - s)⁴ / R², without the division by r."""
        s = self._s(r)
        return self._dpsi_over_r_of(s, 1.0 - s)

    def d2psi(self, r: np.ndarray) -> np.ndarray:
        """ψ''(r) = -2520 s³ (1 - s)³ (1 - 2 s) / R²."""
        s = self._s(r)
        return self._d2psi_of(s, 1.0 - s)

    # --- the singular harmonic factor, via complex square roots (no trigonometry) ---
    # With z = (x₁ - x0) + i x₂ (x₂ ≥ 0), ũ = -Im z^{3/2} and ∇ũ = -(3/2)(Im √z, Re √z),
    # where Re √z = √((r + dx)/2) and Im √z = √((r - dx)/2).  On the contact part
    # (x₂ = 0, dx > 0) this gives ũ = 0 exactly, not to round-off.
    def polar(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(r, θ) with θ = arccos((x₁ - x0)/r) ∈ [0, π] (the paper's definition for x₂ ≥ 0)."""
        dx, dy = np.asarray(x[0], dtype=float) - self.x0, np.asarray(x[1], dtype=float)
        return np.hypot(dx, dy), np.arctan2(np.abs(dy), dx)

    def _local(self, x: np.ndarray):
        """``where`` the points inside the support r < R are (the mask, None if all of them, and
        whether the values are over every point), and dx, dy, r, Re √z, Im √z, ũ flat over the
        points inside, or over every point where most are inside (a compress costs more than
        evaluating the few outside, which ``_placed`` sets to +0.0).
        ``r = √(dx² + dy²)``, not ``hypot`` (docs/evidence/design-measurements.md#distance-by-square-root):
        ``√(fl(dx²)) = |dx|`` exactly, so ``ũ`` stays 0 on the contact part."""
        x = np.asarray(x, dtype=float)
        dx, dy = x[0] - self.x0, np.abs(x[1])
        r = np.sqrt(dx * dx + dy * dy)
        inside = r < self.R
        count = np.count_nonzero(inside)
        dense = 2 * count > inside.size
        if dense:
            dx, dy, r = dx.ravel(), dy.ravel(), r.ravel()
        else:
            dx, dy, r = dx[inside], dy[inside], r[inside]
        where = (None if count == inside.size else inside, dense)
        re = np.sqrt(np.maximum(r + dx, 0.0) * 0.5)
        im = np.sqrt(np.maximum(r - dx, 0.0) * 0.5)
        ut = -im * (3.0 * re * re - im * im)
        return where, dx, dy, r, re, im, ut

    @staticmethod
    def _placed(
        where: tuple[np.ndarray | None, bool], values: np.ndarray, shape: tuple[int, ...], out: np.ndarray | None = None
    ) -> np.ndarray:
        """``values`` at the points inside the support (``_local``'s ``where``), ``+0.0`` at the
        others, as an array of ``shape`` (into ``out`` if given)."""
        inside, dense = where
        if inside is None or dense:
            full = values.reshape(shape) if inside is None else np.where(inside, values.reshape(shape), 0.0)
            if out is None:
                return full
            out[...] = full
            return out
        if out is None:
            out = np.zeros(shape)
        else:
            out.fill(0.0)
        out[inside] = values
        return out

    def u(self, x: np.ndarray) -> np.ndarray:
        """u = A ψ(r) ũ(r, θ), ũ = -r^{3/2} sin(3θ/2) (+0.0 everywhere for A = 0)."""
        if self.A == 0.0:
            return np.zeros(np.shape(x)[1:])
        if _COMPILED.get():
            return self._compiled(x, gradient=False)
        where, _, _, r, _, _, ut = self._local(x)
        return self._placed(where, self.A * self.psi(r) * ut, np.shape(x)[1:])

    def _point_parameters(self) -> tuple[float, float, float]:
        """(x0, R, A) as floats: one compiled specialisation of the kernels."""
        return float(self.x0), float(self.R), float(self.A)

    def point_kernel(self) -> tuple[float, float, float] | None:
        """(x0, R, A) of the manufactured kernels where ``compiled_points`` enables them and u ≢ 0."""
        return self._point_parameters() if _COMPILED.get() and self.A != 0.0 else None

    def _compiled(self, x: np.ndarray, gradient: bool):
        """``u(x)``, or ``(u(x), ∇u(x))`` if ``gradient``, by the compiled point kernels."""
        from signorini.fem import point_kernels  # numba: only where the kernels pay (``compiled_points``)

        x = np.asarray(x, dtype=float)
        shape = x.shape[1:]
        px, py = np.ascontiguousarray(x[0]).ravel(), np.ascontiguousarray(x[1]).ravel()
        u = np.empty(px.size)
        if not gradient:
            point_kernels.manufactured_u(px, py, *self._point_parameters(), u)
            return u.reshape(shape)
        grad = np.empty((2, px.size))
        point_kernels.manufactured_u_and_grad(px, py, *self._point_parameters(), u, grad[0], grad[1])
        return u.reshape(shape), grad.reshape((2, *shape))

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        """∇u = A ((ψ'/r) ũ (dx, dy) + ψ ∇ũ), stacked as shape (2, ...)."""
        return self.u_and_grad_u(x)[1]

    def minus_laplace_u(self, x: np.ndarray) -> np.ndarray:
        """-Δu = -A (2 ψ' ∂_r ũ + ũ (ψ'' + ψ'/r)), using Δũ = 0 and r ∂_r ũ = (3/2) ũ."""
        where, _, _, r, _, _, ut = self._local(x)
        _, dpr, d2 = self._cutoff(r, second=True)
        return self._placed(where, -self.A * ut * (3.0 * dpr + d2 + dpr), np.shape(x)[1:])

    def f(self, x: np.ndarray) -> np.ndarray:
        """Right-hand side f = -Δu + c u (+0.0 everywhere for A = 0)."""
        if self.A == 0.0:
            return np.zeros(np.shape(x)[1:])
        where, _, _, r, _, _, ut = self._local(x)
        psi, dpr, d2 = self._cutoff(r, second=True)
        return self._placed(where, self.A * ut * (-4.0 * dpr - d2 + self.c * psi), np.shape(x)[1:])


# --- problems with simple data and a closed-form solution (stability atlas, degenerate contact) ---
#
# With f ≡ const the load vector is
# ``b = f M 1`` (the quadrature is exact), and ``K 1 = 0`` (no Dirichlet part), so the
# constant solutions below are also the *discrete* solutions, up to round-off.


def _check_parameters(obj, names: tuple[str, ...]) -> None:
    """Every named parameter a finite number, the reaction coefficient ``c`` non-negative."""
    for name in names:
        value = getattr(obj, name)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not np.isfinite(value):
            raise ProblemParameterError(f"problem parameter {name}={value!r} must be a finite number", name)
    if obj.c < 0.0:
        raise ProblemParameterError(f"reaction coefficient c={obj.c} must be non-negative", "c")


@dataclass(frozen=True)
class ConstantProblem(ProblemBase):
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

    kind: ClassVar[str] = "constant"
    value: float = 1.0
    c: float = 1.0

    def __post_init__(self) -> None:
        _check_parameters(self, ("value", "c"))
        if self.value < 0.0:
            raise ProblemParameterError(
                f"value={self.value} < 0: the solution is the Dirichlet solution, not known in closed form "
                "(use FullContactProblem for full contact)",
                "value",
            )
        if self.value > 0.0 and self.c == 0.0:
            raise ProblemParameterError("value > 0 needs c > 0 (for c = 0 the problem has no solution: ∫f > 0)", "c")

    @property
    def exact(self) -> float:
        """The constant solution ``value / c`` (0 for ``value = 0``)."""
        return self.value / self.c if self.value > 0.0 else 0.0

    def as_dict(self) -> dict[str, float | str]:
        return {"kind": self.kind, "value": float(self.value), "c": float(self.c)}

    def u(self, x: np.ndarray) -> np.ndarray:
        return np.full(np.shape(x)[1:], self.exact)

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        return np.zeros(np.shape(x))

    def f(self, x: np.ndarray) -> np.ndarray:
        return np.full(np.shape(x)[1:], float(self.value))


@dataclass(frozen=True)
class FullContactProblem(ProblemBase):
    """``u = -A sin(π x₁) sin(π x₂)``, ``f = -Δu + c u = -A (2π² + c) sin(π x₁) sin(π x₂) ≤ 0``.

    ``u = 0`` on ∂Ω and ``∂_ν u = A π sin(π s) ≥ 0`` (``s`` the arclength on an edge), so
    ``u`` satisfies the Signorini conditions with **full contact**; the contact is strict
    except at the four corners, where ``∂_ν u = 0`` (biactive).
    """

    kind: ClassVar[str] = "full_contact"
    A: float = 1.0
    c: float = 1.0

    def __post_init__(self) -> None:
        _check_parameters(self, ("A", "c"))
        if self.A < 0.0:
            raise ProblemParameterError(f"amplitude A={self.A} must be non-negative (A < 0 violates ∂_ν u ≥ 0)", "A")

    def as_dict(self) -> dict[str, float | str]:
        return {"kind": self.kind, "A": float(self.A), "c": float(self.c)}

    def u(self, x: np.ndarray) -> np.ndarray:
        return -self.A * np.sin(np.pi * x[0]) * np.sin(np.pi * x[1])

    def grad_u(self, x: np.ndarray) -> np.ndarray:
        s1, s2 = np.sin(np.pi * x[0]), np.sin(np.pi * x[1])
        c1, c2 = np.cos(np.pi * x[0]), np.cos(np.pi * x[1])
        return -self.A * np.pi * np.stack([c1 * s2, s1 * c2])

    def f(self, x: np.ndarray) -> np.ndarray:
        return (2.0 * np.pi**2 + self.c) * self.u(x)


# the problems by kind: the config schema lists the same kinds ($defs/problem_kind)
PROBLEM_KINDS: dict[str, type[ProblemBase]] = {cls.kind: cls for cls in (Problem, ConstantProblem, FullContactProblem)}
DEFAULT_KIND = Problem.kind  # a parameter block without ``kind``: the paper's problem


def problem_class(params: Mapping) -> type[ProblemBase]:
    """The class of the problem ``params`` describe (its ``kind``, default ``DEFAULT_KIND``)."""
    kind = params.get("kind", DEFAULT_KIND)
    if kind not in PROBLEM_KINDS:
        raise ProblemParameterError(f"unknown problem kind {kind!r}; choose one of {sorted(PROBLEM_KINDS)}", "kind")
    return PROBLEM_KINDS[kind]


def make_problem(params: Mapping) -> ExactProblem:
    """The problem of a parameter block (a scene's ``problem``, an atlas case's, a recorded one):
    ``kind`` (default ``DEFAULT_KIND``, the paper's manufactured problem) selects the class of
    ``PROBLEM_KINDS``, the other keys are its parameters (``from_params``); a kind, a parameter
    name or value the class does not admit raises ``ProblemParameterError``."""
    cls = problem_class(params)
    own = {k: v for k, v in params.items() if k != "kind"}
    unknown = sorted(set(own) - set(cls.parameters()))
    if unknown:
        raise ProblemParameterError(
            f"{cls.kind} problem: unknown parameter {', '.join(map(repr, unknown))}; its parameters: "
            f"{', '.join(cls.parameters())}",
            unknown[0],
        )
    try:
        return cls.from_params(own)
    except ProblemParameterError:
        raise
    except (TypeError, ValueError) as err:
        raise ProblemParameterError(f"{cls.kind} problem: {err}") from None
