"""Number and table formatting of the rendered outputs (Markdown, LaTeX, CSV).

Digits of a computed value.  A value ``v`` known up to an uncertainty ``δ`` (how far round-off in
the discrete solution can move it: ``studies.scene.norm.algebraic_uncertainty``) is written with
``certified_digits(v, δ)`` significant digits, the count whose last unit is not below ``δ``,
at most the paper's five; an order of convergence with ``certified_decimals(δ)`` decimals, at
most the paper's four.  Every format (CSV, Markdown, LaTeX, the figures) writes the same rounded
value (``round_sig``), so the outputs do not depend on the processor's round-off.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence

_SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")


SIG_DIGITS = 5  # the paper's precision of an error: 5.8699·10⁻⁴
EOC_DECIMALS = 4  # ... and of an order of convergence: 1.9968


def certified_digits(value: float, uncertainty: float, cap: int = SIG_DIGITS) -> int:
    """Significant digits of ``value`` whose unit is at least ``uncertainty``,
    ``⌊log10(|value| / uncertainty)⌋``, clipped to ``[1, cap]`` (``cap`` when nothing is uncertain)."""
    if not (math.isfinite(value) and value != 0.0):
        return cap
    if not uncertainty > 0.0:
        return cap if uncertainty == 0.0 else 1  # NaN: nothing is certified
    return max(1, min(cap, math.floor(math.log10(abs(value) / uncertainty))))


def certified_decimals(uncertainty: float, cap: int = EOC_DECIMALS) -> int:
    """Decimals of a quantity of order one known to ``± uncertainty``: ``⌊−log10 uncertainty⌋``
    clipped to ``[0, cap]``."""
    if not uncertainty > 0.0:
        return cap if uncertainty == 0.0 else 0
    return max(0, min(cap, math.floor(-math.log10(uncertainty))))


def ceil_sig(x: float) -> float:
    """``x > 0`` rounded up to one significant digit, as ``f"{x:.0e}"`` prints it (a bound stays a
    bound); ``x`` itself where that is not defined (zero, negative, NaN, infinite)."""
    if not (math.isfinite(x) and x > 0.0):
        return x
    rounded = f"{x:.0e}"
    if float(rounded) >= x:
        return float(rounded)
    mantissa, exponent = rounded.split("e")
    return float(f"{int(mantissa) + 1}e{exponent}")


def round_sig(x: float, digits: int) -> float:
    """``x`` rounded to ``digits`` significant digits (correctly rounded decimal, as printed)."""
    return float(f"{x:.{digits - 1}e}") if math.isfinite(x) else x


def sig_csv(x: float, digits: int) -> str:
    """``x`` with ``digits`` significant digits for a CSV cell: ``5.8746e-04``."""
    return f"{x:.{digits - 1}e}"


def certified_errors(errors, uncertainties, norms: Sequence[str]) -> tuple[list[list[float]], list[list[int]]]:
    """Per row of the frame ``errors`` and norm: the value rounded to its certified digits, and those
    digits (``uncertainties``: the same frame with the uncertainties; ``None``: the paper's 5 digits).
    What Table 1 prints and Figure 3 draws."""
    values, digits = [], []
    for i in range(len(errors)):
        row = [float(errors[n].iloc[i]) for n in norms]
        unc = [0.0] * len(norms) if uncertainties is None else [float(uncertainties[n].iloc[i]) for n in norms]
        d = [certified_digits(v, u) for v, u in zip(row, unc, strict=True)]
        digits.append(d)
        values.append([round_sig(v, k) for v, k in zip(row, d, strict=True)])
    return values, digits


def markdown_text(text: str) -> str:
    """``text`` with each ``_{`` outside code spans written ``\\_{``: a subscript in TeX's spelling
    (``‖e‖_{L²(∂Ω)}``) that Markdown would otherwise take for the start or end of an emphasis,
    setting the text between two of them in italics."""
    spans = text.split("`")
    return "`".join(span.replace("_{", "\\_{") if i % 2 == 0 else span for i, span in enumerate(spans))


def h_label(N: int | str) -> str:
    """The paper's row label ``1/N``."""
    return f"1/{int(N)}"


def _mantissa_exponent(x: float, digits: int) -> tuple[str, int]:
    if x == 0 or not math.isfinite(x):
        return f"{x:.{digits}f}", 0
    exponent = math.floor(math.log10(abs(x)))
    mantissa = x / 10.0**exponent
    if round(abs(mantissa), digits) >= 10.0:  # 9.99996 rounds up to 10.0000
        mantissa, exponent = mantissa / 10.0, exponent + 1
    return f"{mantissa:.{digits}f}", exponent


def sci_md(x: float, digits: int = 4) -> str:
    """``5.8699·10⁻⁴`` (the paper's notation, 5 significant digits)."""
    m, e = _mantissa_exponent(x, digits)
    return f"{m}·10{str(e).translate(_SUPERSCRIPT)}"


def sci_tex(x: float, digits: int = 4) -> str:
    """``$5.8699 \\cdot 10^{-4}$``."""
    m, e = _mantissa_exponent(x, digits)
    return f"${m} \\cdot 10^{{{e}}}$"


def fmt_time(t: float) -> str:
    """``0.123 s`` below a second, ``12.3 s`` above, ``—`` when unknown."""
    if not math.isfinite(t):
        return "—"
    return f"{t:.3f} s" if t < 1.0 else f"{t:.1f} s"


def fmt_rel(x: float) -> str:
    """A relative quantity with two significant digits (``1.2e-05``), ``0`` or ``—``."""
    return "—" if not math.isfinite(x) else ("0" if x == 0 else f"{x:.1e}")


def fmt_timed(t: Mapping) -> str:
    """A time with its interval (``intervals.Estimate.summary``, with its ``samples``):
    ``1.6 s (1.3–1.8)``, ``12.4 s (1 sample)``, ``—``."""
    if not math.isfinite(t["value"]):
        return "—"
    if t["interval"]:
        lo, hi = (fmt_time(t[k]).removesuffix(" s") for k in ("lo", "hi"))
        return f"{fmt_time(t['value'])} ({lo}–{hi})"
    return f"{fmt_time(t['value'])} (1 sample)" if t.get("samples") == 1 else fmt_time(t["value"])


def fmt_factor(x: float) -> str:
    """A factor as the ratios print it: ``0.82``, ``1.3``, ``12``."""
    return f"{x:.2f}" if x < 1.0 else (f"{x:.1f}" if x < 10.0 else f"{x:.0f}")


def fmt_ratio(r: Mapping) -> str:
    """A ratio with its interval and ``verdict`` (``intervals``): ``×2.0 (1.6–2.4)``, a tie
    (``tie (×0.82–1.3)``) or without one."""
    if not math.isfinite(r["value"]):
        return "—"
    if r["verdict"] == "tie":
        return f"tie (×{fmt_factor(r['lo'])}–{fmt_factor(r['hi'])})"
    if r["interval"]:
        return f"×{fmt_factor(r['value'])} ({fmt_factor(r['lo'])}–{fmt_factor(r['hi'])})"
    return f"×{fmt_factor(r['value'])} (undetermined: one sample each)"


def _signed(x: float) -> str:
    return f"{x:.2f}".replace("-", "−")


def fmt_fit(p: Mapping) -> str:
    """An exponent or slope with its interval: ``1.05 (1.01–1.11)``, ``−0.95 (−0.97 to −0.93)``."""
    if not math.isfinite(p["value"]):
        return "—"
    if not p["interval"]:
        return _signed(p["value"])
    dash = " to " if min(p["lo"], p["hi"]) < 0 else "–"
    return f"{_signed(p['value'])} ({_signed(p['lo'])}{dash}{_signed(p['hi'])})"


def md_table(header: Sequence[str], rows: Sequence[Sequence[str]], align: str = "r") -> str:
    """A Markdown table; the first column left-aligned, the others right (``align="r"``) or left."""
    sep = ["---"] + [("---:" if align == "r" else "---")] * (len(header) - 1)
    lines = ["| " + " | ".join(header) + " |", "| " + " | ".join(sep) + " |"]
    lines += ["| " + " | ".join(row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def tex_table(header: Sequence[str], rows: Sequence[Sequence[str]], caption: str, label: str) -> str:
    """A booktabs LaTeX table environment."""
    cols = "l" + "r" * (len(header) - 1)
    body = [" & ".join(header) + r" \\", r"\midrule"]
    body += [" & ".join(row) + r" \\" for row in rows]
    return "\n".join(
        [
            "% generated by the signorini workflow (signorini.tables); needs \\usepackage{booktabs}",
            r"\begin{table}[ht]",
            r"\centering",
            f"\\caption{{{caption}}}",
            f"\\label{{{label}}}",
            f"\\begin{{tabular}}{{{cols}}}",
            r"\toprule",
            *body,
            r"\bottomrule",
            r"\end{tabular}",
            r"\end{table}",
            "",
        ]
    )


def tex_h(label: str) -> str:
    """A row label in LaTeX: ``1/101`` -> ``$1/101$``; other labels unchanged."""
    if label.startswith("1/"):
        return f"$1/{label[2:]}$"
    return label


def csv_text(header: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """CSV text; floats round-trip (``repr``), None is an empty cell."""
    out = [",".join(header)]
    for row in rows:
        out.append(",".join("" if v is None else (repr(float(v)) if isinstance(v, float) else str(v)) for v in row))
    return "\n".join(out) + "\n"
