"""The paper's facts, defined once: the norms of its Tables 1–2 and Figure 3, their labels
(Markdown, LaTeX, matplotlib) and the expected orders of convergence as a function of the norm.

Norm names follow the grammar of ``signorini.fem.norms.names``.
"""

from __future__ import annotations

import math

from signorini.fem.norms.names import NormName, parse_norm_name

TABLE1_NORMS = ("L4", "Linf", "W14", "W1inf", "H12")
TABLE2_NORMS = ("L4", "L16", "Linf", "W14", "W116", "W1inf", "H12")
PAPER_NORMS = TABLE2_NORMS  # every norm the paper reports
FIGURE3_NORMS = ("L4", "W14")
CRITICAL_P = 4.0  # the rates change at p = 4 (Remark 6.2)


def expected_order(family: str, p: float) -> float:
    """The order of the a priori estimate (minus ε) of ``‖u − u_h‖`` in ``L^p`` (``family="L"``)
    or ``W^{1,p}`` (``"W1"``), Theorem 6.1: ``2`` and ``1`` for ``p ≤ 4``, ``3/2 + 2/p`` and
    ``1/2 + 2/p`` beyond (``p = ∞``: ``3/2`` and ``1/2``)."""
    if not p >= 1.0:
        raise ValueError(f"p={p} must be ≥ 1")
    base = {"L": 2.0, "W1": 1.0}[family]
    return base if p <= CRITICAL_P else base - 0.5 + 2.0 / p


def expected_rate(norm: str) -> float | None:
    """The expected order (minus ε) of the error in the named norm: ``expected_order`` for
    ``L^p``/``W^{1,p}`` and their one-sided parts (Theorems 5.4, 5.7), 1 for ``H¹``, 3/2 for
    ``H^{1/2}(∂Ω)`` (Table 2's ``theo.`` row); None where the paper states none."""
    spec = parse_norm_name(norm)
    if spec.family in ("L", "W1"):
        return expected_order(spec.family, spec.p)
    return {"H1": 1.0, "H12": 1.5}.get(spec.family)


THEORETICAL_ORDERS = {n: expected_rate(n) for n in TABLE2_NORMS}  # Table 2, row "theo."

_SUPERSCRIPT = str.maketrans("0123456789", "⁰¹²³⁴⁵⁶⁷⁸⁹")


def _exponent(p: float) -> str:
    return "inf" if math.isinf(p) else (str(int(p)) if float(p).is_integer() else repr(float(p)))


def _domain(spec: NormName, tex: bool) -> str:
    if spec.on_boundary:
        return r"(\partial\Omega)" if tex else "(∂Ω)"
    return r"(\Omega)" if tex else "(Ω)"


def _space_md(spec: NormName) -> str:
    if spec.family == "H12":
        return "H^{1/2}"
    if spec.family in ("H1", "L2boundary"):
        return "H¹" if spec.family == "H1" else "L²"
    e = _exponent(spec.p)
    if spec.family == "W1":
        return f"W^{{1,{'∞' if e == 'inf' else e}}}"
    if e == "inf":
        return "L^∞"
    return f"L{e.translate(_SUPERSCRIPT)}" if e.isdigit() else f"L^{{{e}}}"


def _space_tex(spec: NormName) -> str:
    if spec.family in ("H12", "H1", "L2boundary"):
        return {"H12": "H^{1/2}", "H1": "H^1", "L2boundary": "L^2"}[spec.family]
    e = _exponent(spec.p)
    e = r"\infty" if e == "inf" else e
    if spec.family == "W1":
        return f"W^{{1,{e}}}"
    return f"L^{e}" if len(e) == 1 or e == r"\infty" else f"L^{{{e}}}"


_PART_MD = {"": "", "plus": " (positive part)", "minus": " (negative part)"}
_PART_TEX = {"": "", "plus": r"\ (+)", "minus": r"\ (-)"}


def label_md(norm: str) -> str:
    """Markdown/Unicode label of a norm's space: ``L⁴(Ω)``, ``W^{1,∞}(Ω)``, ``H^{1/2}(∂Ω)``;
    ``W^{1,∞}(Ω) (true)`` for the converged evaluation."""
    spec = parse_norm_name(norm)
    return _space_md(spec) + _domain(spec, tex=False) + _PART_MD[spec.part] + (" (true)" if spec.true else "")


def label_tex(norm: str, domain: bool = True) -> str:
    """LaTeX (and matplotlib mathtext) label: ``$L^4(\\Omega)$``; ``domain=False`` drops ``(\\Omega)``
    but keeps ``(\\partial\\Omega)`` of the boundary norms (``$L^4$``, ``$H^{1/2}(\\partial\\Omega)$``)."""
    spec = parse_norm_name(norm)
    where = _domain(spec, tex=True) if domain or spec.on_boundary else ""
    true = r"\ (\mathrm{true})" if spec.true else ""
    return f"${_space_tex(spec)}{where}{_PART_TEX[spec.part]}{true}$"


def error_label_tex(norm: str) -> str:
    """``$\\|u-u_h\\|_{L^4(\\Omega)}$``: the error in the named norm (matplotlib mathtext)."""
    return r"$\|u-u_h\|_{" + label_tex(norm).strip("$") + "}$"
