"""Verdicts on the deviations of our Table 1 from the published one, each chosen by a condition on
the numbers: how many digits a column reproduces, whether the agreement was fitted (the convention
that matches was chosen among several that do not) or predicted (every candidate convention gives
it), a row that stands out, a steady offset, and what the load vector's quadrature rule changes.

Each verdict carries its strength: *by construction* (true because of how it was set up),
*measured* (a computed condition on these data), *explained* (a measured cause accounts for it) or
*open* (measured, cause unknown). ``reproduction.md`` and ``summary.md`` both print them.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import replace

import numpy as np
import pandas as pd

from signorini.fem.norms.conventions import Conventions
from signorini.published import label_md
from signorini.studies.paper.reference import relative_deviation
from signorini.studies.verdict import Verdict

# the options of docs/evidence/conventions.csv that each published column depends on
OPTIONS = {
    "L4": ("quadrature",),
    "Linf": ("quadrature", "points"),
    "W14": ("quadrature", "w1p_form"),
    "W1inf": ("quadrature", "points", "w1p_form"),
    "H12": ("h12_form",),
}
# two candidate rules agree on a column when their worst deviations differ by less than this
# (relative): then the column does not depend on the rule, and its agreement is a prediction
RULE_INDEPENDENT = 1e-3
OUTLIER_FACTOR = 3.0  # a row stands out when its deviation exceeds this × the other rows' median
STEADY_ROWS = 3  # the finest rows that a steady offset spans
STEADY_SPREAD = 0.5  # ... with the same sign and a spread below this fraction of their mean
# a relative change below half a unit of the fifth significant digit leaves a printed cell alone
PRINTED_DIGITS = 5
PRINTED = 0.5 * 10.0 ** (1 - PRINTED_DIGITS)


def deviations(ours: Mapping, paper: Mapping, norm: str) -> dict[str, float]:
    """``{row: (ours − paper)/|paper|}`` of one column over the published mesh rows."""
    return {
        row: relative_deviation(ours[row][norm], vals[norm])
        for row, vals in paper.items()
        if row.startswith("1/") and norm in vals and norm in ours.get(row, {})
    }


def digits_phrase(dev: float) -> str:
    """``"4 significant digits"`` for a relative deviation of 0.01 %."""
    n = digits_agreeing(dev)
    return f"{n} significant digit{'' if n == 1 else 's'}"


def digits_agreeing(dev: float) -> int:
    """The significant digits two values share when they differ by ``dev`` (relative): 4 for 0.01 %."""
    return int(np.floor(-np.log10(max(abs(dev), 1e-16)))) if abs(dev) < 1 else 0


def outlier_rows(devs: Mapping[str, float]) -> list[str]:
    """Rows whose |deviation| exceeds ``OUTLIER_FACTOR`` × the median |deviation| of the other rows."""
    out = []
    for row, dev in devs.items():
        others = [abs(d) for r, d in devs.items() if r != row]
        if others and abs(dev) > OUTLIER_FACTOR * max(float(np.median(others)), 1e-4):
            out.append(row)
    return out


def steady_offset(devs: Mapping[str, float]) -> tuple[float, float] | None:
    """``(min, max)`` deviation of the ``STEADY_ROWS`` finest rows if they share a sign, exceed the
    printed precision and spread less than ``STEADY_SPREAD`` × their mean; else None."""
    rows = sorted(devs, key=lambda r: int(r.split("/")[1]))[-STEADY_ROWS:]
    values = np.array([devs[r] for r in rows])
    if len(values) < STEADY_ROWS or np.min(np.abs(values)) < 10 * PRINTED:
        return None
    if not (np.all(values > 0) or np.all(values < 0)):
        return None
    if np.ptp(values) >= STEADY_SPREAD * abs(np.mean(values)):
        return None
    return float(values.min()), float(values.max())


def rule_dependence(conventions_csv: str | os.PathLike, norm: str, conv: Conventions) -> dict[str, float]:
    """Per candidate quadrature rule (the other options at ``conv``'s choice): the worst |relative
    deviation| from the published column over the meshes (``docs/evidence/conventions.csv``)."""
    frame = pd.read_csv(conventions_csv, encoding="utf-8")
    frame = frame[frame["diagonal"] == "sw_ne"]
    chosen = {
        "quadrature": conv.quadrature,
        "points": conv.w1inf_points if norm == "W1inf" else conv.linf_points,
        "w1p_form": conv.w1p_form,
        "h12_form": conv.h12_form,
    }
    varied = "h12_form" if norm == "H12" else "quadrature"
    for option in OPTIONS[norm]:
        if option != varied:
            frame = frame[frame[option] == chosen[option]]
    worst = frame.groupby(varied)[f"dev_{norm}"].apply(lambda s: float(np.max(np.abs(s))))
    return {str(k): float(v) for k, v in worst.items()}


def agreement_verdict(devs: Mapping[str, float], by_rule: Mapping[str, float], chosen: str) -> Verdict:
    """How a column agrees with the paper: the digits of its worst cell, and whether the agreement
    was fitted (the chosen rule is the closest candidate, the others clearly worse) or holds for
    every candidate rule alike (``rule_dependence``)."""
    worst = max(abs(d) for d in devs.values())
    close = f"every cell within {100 * worst:.2f} % ({digits_phrase(worst)})"
    values = sorted(by_rule.values())
    if not values or np.ptp(values) < RULE_INDEPENDENT:
        return Verdict(f"{close}, the same for each of the {len(values)} candidate rules: not fitted", "measured")
    others = [v for k, v in by_rule.items() if k != chosen]
    mine = by_rule.get(chosen, worst)
    if mine > min(values) + RULE_INDEPENDENT:
        return Verdict(f"{close}; the candidate rules differ and the chosen one is not the closest", "measured")
    ties = sum(abs(v - mine) < RULE_INDEPENDENT for v in others)
    if ties:
        return Verdict(
            f"{close}; {ties + 1} of the {len(values)} candidate rules give it alike: not fitted", "measured"
        )
    return Verdict(
        f"{close}; the rule was chosen among {len(values)} candidates because it matches this column "
        f"(the next best: {100 * min(others):.2f} %)",
        "by construction",
    )


def load_rule_verdict(load_rule_csv: str | os.PathLike) -> Verdict:
    """What integrating ``b`` by the norms' rule changes in Table 1 (``studies.paper.load_rule``)."""
    frame = pd.read_csv(load_rule_csv, encoding="utf-8")
    worst = frame.loc[frame["relative_change"].abs().idxmax()]
    size = float(abs(worst["relative_change"]))
    where = f"largest: {label_md(worst['norm'])} at h = 1/{int(worst['N'])}"
    if size < PRINTED:
        return Verdict(
            f"integrating the load vector by the norms' 16-point rule instead moves Table 1's cells by at most "
            f"{size:.1e} relative ({where}), below the {PRINTED_DIGITS} printed digits: the load rule explains "
            "none of the deviations",
            "measured",
        )
    return Verdict(
        f"integrating the load vector by the norms' 16-point rule moves Table 1's cells by up to "
        f"{100 * size:.2f} % ({where})",
        "measured",
    )


def _rest(devs: Mapping[str, float], row: str) -> float:
    """The largest |deviation| in percent of the rows other than ``row``."""
    return 100 * max(abs(d) for r, d in devs.items() if r != row)


def rows_label(rows: Sequence[str]) -> str:
    return ", ".join(f"h = {r}" for r in rows)


def boundary_split_verdict(h12_csv: str | os.PathLike, offset: tuple[float, float] | None) -> Verdict:
    """What splitting the boundary rule at the kink moves in ``H^{1/2}``, against its steady offset."""
    frame = pd.read_csv(h12_csv, encoding="utf-8")
    moved = (frame["split"] / frame["whole_edges"] - 1.0).abs()
    text = f"splitting the boundary rule at the kink moves H^{{1/2}} by at most {100 * moved.max():.2f} %"
    if offset is None:
        return Verdict(text, "measured")
    share = float(moved.max() / min(abs(offset[0]), abs(offset[1])))
    return Verdict(f"{text}, {100 * share:.0f} % of its steady offset: it explains at most that part", "measured")


def table1_verdicts(
    ours: Mapping,
    paper: Mapping,
    conventions_csv: str | os.PathLike,
    load_rule_csv: str | os.PathLike | None = None,
    h12_csv: str | os.PathLike | None = None,
    conv: Conventions | None = None,
    tables: tuple[str, ...] = (),
) -> list[tuple[str, Verdict]]:
    """Every verdict on Table 1's deviations, as ``(norm or topic, verdict)`` in reading order;
    ``tables`` (the files of ``ours`` and ``paper``) and the other files are named as each verdict's
    sources."""
    conv = conv or Conventions()
    devs = {n: deviations(ours, paper, n) for n in OPTIONS}
    norms = [n for n in OPTIONS if devs[n]]  # the published columns with a mesh of ours
    out: list[tuple[str, Verdict]] = []
    if not norms:
        text = "the rendered meshes share no mesh width with the published Table 1: no cell to compare"
        return [("Table 1", Verdict(text, "by construction", tables))]
    for norm in norms:
        chosen = conv.h12_form if norm == "H12" else conv.quadrature
        verdict = agreement_verdict(devs[norm], rule_dependence(conventions_csv, norm, conv), chosen)
        out.append((norm, replace(verdict, sources=(*tables, str(conventions_csv)))))
    rows: dict[str, list[str]] = {}
    for norm in norms:
        for row in outlier_rows(devs[norm]):
            rows.setdefault(row, []).append(norm)
    for row, where in rows.items():
        cells = "; ".join(
            f"{label_md(n)} {100 * devs[n][row]:+.2f} % (other rows: at most {_rest(devs[n], row):.2f} %)"
            for n in where
        )
        out.append((f"h = {row}", Verdict(f"stands out: {cells}", "open", tables)))
    offsets = {n: steady_offset(devs[n]) for n in norms}
    for norm, offset in offsets.items():
        if offset is not None:
            finest = sorted(devs[norm], key=lambda r: int(r.split("/")[1]))[-STEADY_ROWS:]
            out.append(
                (
                    norm,
                    Verdict(
                        f"a steady offset of {100 * offset[0]:+.2f} % … {100 * offset[1]:+.2f} % "
                        f"on {rows_label(finest)} (one sign, spread below half its mean)",
                        "open",
                        tables,
                    ),
                )
            )
    if load_rule_csv is not None:
        out.append(("load vector", replace(load_rule_verdict(load_rule_csv), sources=(str(load_rule_csv),))))
    if h12_csv is not None and "H12" in norms:
        split = boundary_split_verdict(h12_csv, offsets.get("H12"))
        out.append(("H12", replace(split, sources=(str(h12_csv), *tables))))
    return out
