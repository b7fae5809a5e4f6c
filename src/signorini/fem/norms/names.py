"""The grammar of norm names, defined once.

=============  =====================================================================
``Lp``         ``L^p(Ω)`` for any p ≥ 1 (``L2``, ``L4``, ``L16``, ``L2.5``); ``Linf``
``Lp<part>``   ``‖(u − u_h)^±‖_{L^p}`` with ``<part>`` = ``plus`` or ``minus``
``W1p``        ``W^{1,p}(Ω)`` (``W14``, ``W116``); ``W1inf``
``H1``         ``H¹(Ω)``
``H12``        ``H^{1/2}(∂Ω)``
``L2boundary`` ``L²(∂Ω)``
``<name>_true`` the same norm evaluated to a stated accuracy (``fem.norms.true``), for every
               name above: ``L4_true``, ``Linfplus_true``, ``W1inf_true``, ``H12_true``
=============  =====================================================================

A name without the suffix is evaluated with the paper's conventions (``fem.norms.conventions.Conventions``:
fixed rules and point sets); with it, to a relative accuracy of about 1e-4 with an error estimate.

``parse_norm_name`` is the only parser: the norms (``fem.norms.conventional``, ``fem.norms.true``), the
exact norms of a P1 function (``fem.norms.p1``), the expected rates and the labels
(``signorini.published``) all use it.  The evaluators take a name parsed or not (``norm_name``), so
that ``fem.norms.evaluate`` parses each name once.  ``NORM_PATTERN`` is the grammar as one regular
expression, the config schema's pattern of a norm name (tests/fem/norms/test_names.py holds them
equal); what each family combines is ``fem.norms.families``.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

NAMED_NORMS = {"H1": 2.0, "H12": None, "L2boundary": None}  # the norms named by a word, and their exponent
BOUNDARY_NORMS = ("H12", "L2boundary")  # norms of the trace on ∂Ω
TRUE_SUFFIX = "_true"  # the converged evaluation of the same norm
_NUMBER = r"[0-9]+(\.[0-9]+)?"  # an exponent p (refused below 1 by the parser)
_PATTERN = re.compile(rf"^(?P<family>L|W1)(?P<p>inf|{_NUMBER})(?P<part>plus|minus)?$")
# the grammar as one regular expression: the config schema's pattern of a norm name, character for character
NORM_PATTERN = (
    rf"^(L({_NUMBER}|inf)(plus|minus)?|W1({_NUMBER}|inf)|{'|'.join(map(re.escape, NAMED_NORMS))})"
    rf"({TRUE_SUFFIX})?$"
)
# the grammar in words (what error messages say)
GRAMMAR = (
    "a norm is L or W1 followed by an exponent p ≥ 1 (a number such as 4 or 2.5, or inf: L4, Linf, W14, "
    f"W1inf), Lp or Linf followed by plus or minus (one-sided), {', '.join(list(NAMED_NORMS)[:-1])} or "
    f"{list(NAMED_NORMS)[-1]}; each may end in {TRUE_SUFFIX} (converged evaluation)"
)


class UnknownNormError(ValueError):
    """A norm name outside the grammar."""


@dataclass(frozen=True)
class NormName:
    """A parsed norm name: ``family`` is ``L``, ``W1``, ``H1``, ``H12`` or ``L2boundary``;
    ``p`` the exponent of ``L``/``W1`` (``math.inf`` for ``inf``; 2 for ``H1``; None for the
    boundary norms); ``part`` is ``""``, ``"plus"`` or ``"minus"``; ``true`` marks the converged
    evaluation (suffix ``_true``) of the norm named ``base``."""

    name: str
    family: str
    p: float | None
    part: str = ""
    true: bool = False

    @property
    def base(self) -> str:
        """The name without the ``_true`` suffix: the same norm under the paper's conventions."""
        return self.name.removesuffix(TRUE_SUFFIX) if self.true else self.name

    @property
    def on_boundary(self) -> bool:
        return self.family in BOUNDARY_NORMS

    @property
    def is_max(self) -> bool:
        """A maximum norm (``Linf``, ``W1inf``): evaluated on a point set, not integrated."""
        return self.p is not None and math.isinf(self.p)

    @property
    def is_lp_family(self) -> bool:
        """``L^p`` or ``W^{1,p}`` of the whole error (no one-sided part): the rate-against-p norms."""
        return self.family in ("L", "W1") and not self.part and not self.true


def parse_norm_name(name: str) -> NormName:
    """Parse ``name``; raises ``UnknownNormError`` outside the grammar (or for p < 1)."""
    name = str(name)
    true = name.endswith(TRUE_SUFFIX)
    base = name.removesuffix(TRUE_SUFFIX)
    if base in NAMED_NORMS:
        return NormName(name, base, NAMED_NORMS[base], true=true)
    m = _PATTERN.match(base)
    if m is None or (m["family"] == "W1" and m["part"]):
        raise UnknownNormError(f"unknown norm {name!r}; {GRAMMAR}")
    p = math.inf if m["p"] == "inf" else float(m["p"])
    if p < 1.0:
        raise UnknownNormError(f"norm {name!r}: need p ≥ 1")
    return NormName(name, m["family"], p, m["part"] or "", true=true)


def norm_name(name: str | NormName) -> NormName:
    """``name`` parsed (``parse_norm_name``), or as it is when already parsed: the evaluators take
    either, so that a name is parsed once however many layers it passes."""
    return name if isinstance(name, NormName) else parse_norm_name(name)


def canonical_norm_name(name: str) -> str:
    """The one spelling of the norm ``name`` names (``L1.0``, ``L01`` → ``L1``; ``W12.50`` →
    ``W12.5``); raises ``UnknownNormError`` outside the grammar."""
    spec = parse_norm_name(name)
    suffix = TRUE_SUFFIX if spec.true else ""
    if spec.family in ("L", "W1"):
        lp, w1p = lp_names(spec.p)
        return (lp + spec.part if spec.family == "L" else w1p) + suffix
    return spec.family + suffix


def true_name(name: str) -> str:
    """The converged variant of a norm name (``L4`` → ``L4_true``; a true name is returned as is)."""
    spec = parse_norm_name(name)
    return spec.name if spec.true else spec.name + TRUE_SUFFIX


def lp_names(p: float) -> tuple[str, str]:
    """The names of the ``L^p`` and ``W^{1,p}`` norms (``L6``/``W16``, ``L2.5``/``W12.5``, ``Linf``/``W1inf``)."""
    if math.isinf(p):
        s = "inf"
    elif float(p).is_integer():
        s = str(int(p))
    else:
        s = repr(float(p))
    return f"L{s}", f"W1{s}"
