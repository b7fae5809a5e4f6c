"""What each norm of the error ``e = u − u_h`` combines, stated once for the three evaluators.

A norm combines *parts*, functions of ``(e, ∇e)`` on Ω:

========  ==================================  ========
``e``     ``e``                               value
``e+``    ``e⁺ = max(e, 0)``                  value
``e-``    ``e⁻ = max(−e, 0)``                 value
``d1``    ``∂₁e``                             gradient
``d2``    ``∂₂e``                             gradient
``grad``  ``|∇e| = (∂₁e² + ∂₂e²)^{1/2}``      gradient
========  ==================================  ========

and combines them in one of three ways: the ``p``-sum ``(Σ_parts ∫_Ω |part|^p)^{1/p}``
(``P_SUM``); its limit ``p = ∞``, the largest ``|part|`` over Ω (``MAX``; under the paper's
conventions over the point set that a field of ``Conventions`` names); or the sum of squares
``(Σ_parts ∫_Ω part²)^{1/2}`` (``SQUARES``, the ``p``-sum with ``p = 2`` written apart: its root is
a square root).  A norm on ∂Ω (``BOUNDARY``) combines the ``L²(∂Ω)`` norms of the trace ``e`` and
of its tangential derivative ``dt = ∂_t e``: it is the geometric mean of its *factors*, each the
root of the sum of squares of the ``L²(∂Ω)`` norms of its parts.

==============  ==============================================================================
``Lp``          the ``p``-sum of ``e`` (``e+``, ``e-`` for the one-sided ``Lpplus``, ``Lpminus``)
``W1p``         the ``p``-sum of the parts of ``Conventions.w1p_form`` (``W1P_PARTS``):
                ``e, d1, d2`` (components), ``e, grad`` (gradient) or ``grad`` (seminorm)
``Linf``        the maximum of the same parts (points ``linf_points``); ``W1inf``: ``w1inf_points``
``H1``          the sum of squares of ``e, d1, d2``
``L2boundary``  ``‖e‖_{L²(∂Ω)}``: one factor, ``(e,)``
``H12``         ``(‖e‖_{L²(∂Ω)} ‖e‖_{H¹(∂Ω)})^{1/2}``, the interpolation estimate of ``H^{1/2}(∂Ω)``:
                the factors ``(e,)`` and ``(e, dt)`` (``geometric_full``: the full ``H¹(∂Ω)`` norm)
                or ``(e,)`` and ``(dt,)`` (``geometric_semi``: the seminorm), ``Conventions.h12_form``
==============  ==============================================================================

Each evaluator brings its own arithmetic for the parts: ``fem.norms.conventional`` reduces
``|part / s|^p`` (``s`` a power of two) at the points of the paper's rules, the integer powers by
squarings; ``fem.norms.true`` integrates the squared magnitudes raised to ``p/2`` to a stated
accuracy; ``fem.norms.p1`` integrates the polynomials of a P1 function exactly.  A norm family of
existing parts is one entry of ``FAMILIES``, its name one entry of ``fem.norms.names.NAMED_NORMS``
(and of the config schema's pattern).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.names import NormName, norm_name

VALUE_PARTS = ("e", "e+", "e-")  # functions of e
GRADIENT_PARTS = ("d1", "d2", "grad")  # functions of ∇e
PARTS = VALUE_PARTS + GRADIENT_PARTS
ONE_SIDED_PARTS = ("e+", "e-")
NONNEGATIVE_PARTS = ("e+", "e-", "grad")  # their own magnitude
BOUNDARY_PARTS = ("e", "dt")  # the trace of e on ∂Ω and its tangential derivative ∂_t e

P_SUM, MAX, SQUARES, BOUNDARY = "p_sum", "max", "squares", "boundary"  # how a norm combines its parts

LP_PARTS = {"": ("e",), "plus": ("e+",), "minus": ("e-",)}  # by NormName.part
W1P_PARTS = {"components": ("e", "d1", "d2"), "gradient": ("e", "grad"), "seminorm": ("grad",)}  # by w1p_form
H12_FACTORS = {"geometric_full": (("e",), ("e", "dt")), "geometric_semi": (("e",), ("dt",))}  # by h12_form


@dataclass(frozen=True)
class NormDefinition:
    """A norm as its evaluators compute it: the ``combination`` (``P_SUM``, ``MAX``, ``SQUARES`` or
    ``BOUNDARY``) of its ``parts`` on Ω, in order; for ``MAX`` the ``Conventions`` field that names
    the point set of the maximum under the paper's conventions; for ``BOUNDARY`` the ``factors``
    whose geometric mean it is."""

    name: NormName
    combination: str
    parts: tuple[str, ...] = ()
    points: str = ""
    factors: tuple[tuple[str, ...], ...] = ()

    @property
    def p(self) -> float | None:
        """The exponent of the sum (2 for ``SQUARES``; ``math.inf`` for ``MAX``; None on ∂Ω)."""
        return 2.0 if self.combination == SQUARES else self.name.p

    @property
    def needs_gradient(self) -> bool:
        """Whether a part is a function of ``∇e``."""
        return any(part in GRADIENT_PARTS for part in self.parts)

    @property
    def one_sided(self) -> bool:
        """Whether a part is ``e⁺`` or ``e⁻`` (not a polynomial where ``e`` is)."""
        return any(part in ONE_SIDED_PARTS for part in self.parts)

    @property
    def boundary_parts(self) -> tuple[str, ...]:
        """The parts on ∂Ω whose ``L²(∂Ω)`` norms the factors combine, each once, in order."""
        return tuple(dict.fromkeys(part for factor in self.factors for part in factor))


def _p_norm(spec: NormName, parts: tuple[str, ...], points: str) -> NormDefinition:
    """The ``p``-sum of ``parts``; for ``p = ∞`` their maximum, over the point set of ``points``."""
    return NormDefinition(spec, MAX if spec.is_max else P_SUM, parts, points if spec.is_max else "")


# the definition of each family (``NormName.family``) under the conventions
FAMILIES: dict[str, Callable[[NormName, Conventions], NormDefinition]] = {
    "L": lambda spec, conv: _p_norm(spec, LP_PARTS[spec.part], "linf_points"),
    "W1": lambda spec, conv: _p_norm(spec, W1P_PARTS[conv.w1p_form], "w1inf_points"),
    "H1": lambda spec, conv: NormDefinition(spec, SQUARES, ("e", "d1", "d2")),
    "H12": lambda spec, conv: NormDefinition(spec, BOUNDARY, factors=H12_FACTORS[conv.h12_form]),
    "L2boundary": lambda spec, conv: NormDefinition(spec, BOUNDARY, factors=(("e",),)),
}


def define(name: str | NormName, conventions: Conventions | None = None) -> NormDefinition:
    """The definition of the norm ``name`` (a ``_true`` name: the same norm) under ``conventions``
    (the ``W^{1,p}`` form and the ``H^{1/2}`` formula); raises ``UnknownNormError`` outside the grammar."""
    spec = norm_name(name)
    return FAMILIES[spec.family](spec, conventions or Conventions())


def part(name: str, e: np.ndarray | None, de: np.ndarray | None) -> np.ndarray:
    """The values of the part ``name`` (``PARTS``) from those of ``e`` and ``∇e`` (``de``: (2, ...))."""
    if name == "e":
        return e
    if name in ONE_SIDED_PARTS:
        return np.maximum(e if name == "e+" else -e, 0.0)
    if name == "grad":
        return np.hypot(de[0], de[1])
    return de[{"d1": 0, "d2": 1}[name]]


def magnitude(name: str, e: np.ndarray | None, de: np.ndarray | None) -> np.ndarray:
    """``|part|``: the function whose largest value is the part's share of a maximum norm."""
    value = part(name, e, de)
    return value if name in NONNEGATIVE_PARTS else np.abs(value)
