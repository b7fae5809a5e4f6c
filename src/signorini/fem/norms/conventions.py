"""The conventions of the paper's norms: the choices its text leaves open, and their allowed values.

A norm name (``fem.norms.names``) says which norm; a ``Conventions`` says how the paper evaluates
it (``fem.norms.conventional``): the triangle rule of the integrals, the point sets of the maxima, the form of
the ``W^{1,p}`` norm and the formula of the ``H^{1/2}(∂Ω)`` estimate.  The ``W^{1,p}`` form and the
``H^{1/2}`` formula also define the ``<name>_true`` norms (``fem.norms.true``) and the exact norms
of a P1 function (``fem.norms.p1``): what each combines is written once, in ``fem.norms.families``.
Kept apart from the norms so that each of those modules (and the workflow's config check) can
import it without importing the others.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

from signorini.fem.quadrature import TRIANGLE_RULES

QUADRATURES = TRIANGLE_RULES
W1P_FORMS = ("components", "gradient", "seminorm")
MAX_POINTS = ("vertices", "midpoints", "quadrature", "all")
H12_FORMS = ("geometric_full", "geometric_semi")


@dataclass(frozen=True)
class Conventions:
    """The choices the paper leaves open (see the README for the evidence behind the defaults)."""

    quadrature: str = "stroud4_acute1"
    w1p_form: str = "components"
    linf_points: str = "all"
    w1inf_points: str = "quadrature"
    h12_form: str = "geometric_full"

    def __post_init__(self) -> None:
        for name, allowed in (
            ("quadrature", QUADRATURES),
            ("w1p_form", W1P_FORMS),
            ("linf_points", MAX_POINTS),
            ("w1inf_points", MAX_POINTS),
            ("h12_form", H12_FORMS),
        ):
            if getattr(self, name) not in allowed:
                raise ValueError(f"unknown convention {name}={getattr(self, name)!r}; choose one of {allowed}")

    def as_dict(self) -> dict[str, str]:
        return asdict(self)
