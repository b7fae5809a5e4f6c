"""Stage ``summary``: the findings of every study in one page (``paper_figures/summary.md``).

Every statement is chosen by a condition on the committed CSVs, carries its strength and names the
files its numbers come from; a study whose outputs are missing is said to be so. The per-topic
functions return ``Verdict`` lists (``studies.paper.deviations``), so that tests check each
condition on perturbed data.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd

from signorini.formatting import markdown_text
from signorini.pipeline.artifacts import atomic_write_text
from signorini.published import TABLE2_NORMS, expected_rate, label_md
from signorini.studies.paper.deviations import table1_verdicts
from signorini.studies.paper.eoc_figure import eoc_series, read_errors
from signorini.studies.paper.reference import read_table_csv, relative_deviation
from signorini.studies.verdict import Verdict

STRENGTHS = (
    "Each finding is chosen by a condition computed from the files it names and carries its strength: "
    "*by construction* = true because of how the comparison was set up; *measured* = read off the data "
    "by that condition; *explained* = measured, and a measured cause accounts for it; *open* = measured, "
    "no cause established. Terms are defined in `docs/glossary.md`."
)
RATE_TOLERANCE = 0.01  # an EOC "attains" its a priori order when within this of it
POINT_SET_GAP = 1e-3  # a published maximum is "below the true norm" beyond this relative gap
EOC_SHIFT = 0.02  # two EOCs "differ" beyond this


def _h(label: str) -> int:
    return int(str(label).split("/")[1])


def _pct(x: float) -> str:
    return f"{100 * x:+.2f} %"


def _true_cells(table1_true: str, *finer: str | None) -> pd.DataFrame:
    """Published, convention and true errors per (N, norm), from h = 1/101 to the finest mesh: the
    paper's meshes, then the finer meshes' tables that exist (``table1_fine``, ``table1_finest``;
    a mesh in two tables is read from the first)."""
    return read_errors(*(p for p in (table1_true, *finer) if p and Path(p).exists()))


def _eocs(cells: pd.DataFrame, norm: str, column: str) -> list[tuple[int, float]]:
    """``(N, EOC)`` of one column between consecutive meshes (N of the finer mesh)."""
    h, rates = eoc_series(cells, norm, column)
    return [(round(1.0 / hk), float(r)) for hk, r in zip(h, rates, strict=True)]


def point_set_findings(cells: pd.DataFrame, sources: tuple[str, ...]) -> list[Verdict]:
    """The published maxima against the true norms, and the first L^∞ EOC."""
    out = []
    for norm in ("Linf", "W1inf"):
        rows = cells[(cells["norm"] == norm) & cells["paper"].notna()]
        if rows.empty:  # no published cell on these meshes
            continue
        gap = ((rows["paper"] - rows["true"]) / rows["true"]).to_numpy()
        conv = ((rows["convention"] - rows["true"]) / rows["true"]).to_numpy()
        below = gap < -POINT_SET_GAP
        text = (
            f"the published {label_md(norm)} column lies {_pct(gap.min())} … {_pct(gap.max())} from the true norm "
            f"(h = 1/{rows['N'].min()} … 1/{rows['N'].max()})"
        )
        if not below.any():
            out.append(Verdict(text, "measured", sources))
            continue
        meshes = ", ".join(f"1/{n}" for n in rows["N"].to_numpy()[below])
        text += (
            f", below it by more than {100 * POINT_SET_GAP:.1f} % on h = {meshes}: "
            "a maximum over finite point sets misses the supremum"
        )
        same = bool((np.abs(gap - conv)[below] < 0.5 * np.abs(gap[below])).all())
        if same:
            span = f"{_pct(conv[below].min())} … {_pct(conv[below].max())}"
            text += f"; the conventions' point sets give the same gap there ({span})"
        out.append(Verdict(text, "explained" if same else "measured", sources))
    paper_first = [e for N, e in _eocs(cells[cells["paper"].notna()], "Linf", "paper")][:1]
    true_first = [e for N, e in _eocs(cells, "Linf", "true")][:1]
    conv_first = [e for N, e in _eocs(cells, "Linf", "convention")][:1]
    if paper_first and true_first and abs(paper_first[0] - true_first[0]) > EOC_SHIFT:
        explained = abs(paper_first[0] - conv_first[0]) < EOC_SHIFT
        out.append(
            Verdict(
                f"the first published {label_md('Linf')} EOC ({paper_first[0]:.2f}, h = 1/101 → 1/201) is "
                f"{'an artifact of the point set' if explained else 'not that of the true norm'}: the true norm's is "
                f"{true_first[0]:.2f}, the conventions' {conv_first[0]:.2f}",
                "explained" if explained else "measured",
                sources,
            )
        )
    return out


def l16_findings(cells: pd.DataFrame, sources: tuple[str, ...]) -> list[Verdict]:
    """The 16-point rule against the true L¹⁶ norm, and where its EOC reaches the a priori order."""
    rows = cells[cells["norm"] == "L16"]
    if rows.empty:
        return []
    gap = (rows["convention"] - rows["true"]) / rows["true"]
    order = expected_rate("L16")
    conv, true = _eocs(cells, "L16", "convention"), _eocs(cells, "L16", "true")
    inflated = [(N, c - t) for (N, c), (_, t) in zip(conv, true, strict=True) if N <= 501]
    reached = [N for N, e in true if abs(e - order) <= RATE_TOLERANCE]
    text = (
        f"the 16-point rule underestimates {label_md('L16')} by {-100 * gap.max():.2f} % … {-100 * gap.min():.2f} % "
        f"(h = 1/{rows['N'].min()} … 1/{rows['N'].max()})"
    )
    if inflated:
        worst = max(inflated, key=lambda x: x[1])
        text += f", so its EOCs on the paper's meshes are inflated by up to {worst[1]:+.3f} (at h = 1/{worst[0]})"
    if reached:
        text += f"; the true EOC comes within {RATE_TOLERANCE} of {order:.3f} only from h = 1/{min(reached)} on"
    return [Verdict(text, "measured", sources)]


def log_factor_fit(N: np.ndarray, e: np.ndarray, order: float) -> tuple[float, float]:
    """The exponent β of a fit ``e ≈ C h^order |log h|^β`` and its largest relative misfit."""
    h = 1.0 / np.asarray(N, float)
    A = np.vstack([np.ones_like(h), np.log(np.abs(np.log(h)))]).T
    coef, *_ = np.linalg.lstsq(A, np.log(e) - order * np.log(h), rcond=None)
    fitted = np.exp(A @ coef + order * np.log(h))
    return float(coef[1]), float(np.max(np.abs(fitted / e - 1.0)))


def rate_findings(cells: pd.DataFrame, sources: tuple[str, ...]) -> list[Verdict]:
    """Each true norm's EOC on its finest mesh against the a priori order of Theorem 6.1 (a norm
    computed on fewer meshes than the finest is named with its own); H^{1/2}'s log factor."""
    last = {n: _eocs(cells, n, "true")[-1] for n in TABLE2_NORMS if len(cells[cells["norm"] == n]) > 1}
    if not last:
        return []
    N = max(m for m, _ in last.values())

    def at_mesh(n: str) -> str:  # a norm whose finest mesh is coarser than N says so
        return "" if last[n][0] == N else f" (h = 1/{last[n][0]})"

    at = [n for n, (m, e) in last.items() if abs(e - expected_rate(n)) <= RATE_TOLERANCE]
    below = [n for n, (m, e) in last.items() if n not in at]
    listed = ", ".join(f"{label_md(n)} {last[n][1]:.3f}{at_mesh(n)}" for n in at)
    out = [
        Verdict(
            f"at h = 1/{N} the EOCs of the true norms attain their a priori orders within {RATE_TOLERANCE}: {listed}",
            "measured",
            sources,
        )
    ]
    for n in below:
        (m, e), order = last[n], expected_rate(n)
        text = (
            f"{label_md(n)}: EOC {e:.3f} at h = 1/{m}, {order - e:.3f} below {order:g} (consistent with {order:g} − ε)"
        )
        if n == "H12":
            text += _h12_trend(cells, order)
        out.append(Verdict(text, "open" if n == "H12" else "measured", sources))
    return out


def _h12_trend(cells: pd.DataFrame, order: float) -> str:
    """The H^{1/2} EOCs from h = 1/1001 on (where there are three or more) and the fit of a log factor."""
    rows = cells[cells["norm"] == "H12"]
    fine = [(m, e) for m, e in _eocs(cells, "H12", "true") if m > 1000]
    text = ""
    if len(fine) >= 3:
        text = f"; the EOCs from h = 1/{fine[0][0]} to 1/{fine[-1][0]}: {', '.join(f'{e:.4f}' for _, e in fine)}"
    beta, misfit = log_factor_fit(rows["N"].to_numpy(), rows["true"].to_numpy(float), order)
    return text + (
        f"; a fit C·h^{order:g}·|log h|^β over h = 1/{rows['N'].min()} … 1/{rows['N'].max()} gives "
        f"β = {beta:.2f} within {100 * misfit:.2f} %, which suggests a logarithmic factor at the r^{{1/2}} kink"
    )


def qp_tolerance_finding(work_precision: str, ours: Mapping, paper: Mapping, sources: tuple[str, ...]) -> list[Verdict]:
    """Whether any swept (solver, tolerance) run brings the outlying published L⁴ cell closer."""
    frame = pd.read_csv(work_precision, encoding="utf-8")
    devs = {
        row: relative_deviation(ours[row]["L4"], vals["L4"])
        for row, vals in paper.items()
        if row.startswith("1/") and "L4" in vals and "L4" in ours.get(row, {})
    }
    if not devs:
        return []
    row = max(devs, key=lambda r: abs(devs[r]))
    runs = frame[(frame["N"] == _h(row)) & (frame["tol_label"] != "exact") & frame["total_L4"].notna()]
    if runs.empty:
        return []
    run_devs = runs["total_L4"] / paper[row]["L4"] - 1.0
    best = runs.loc[run_devs.abs().idxmin()]
    best_dev = float(run_devs.loc[best.name])
    explains = abs(best_dev) < 0.5 * abs(devs[row])
    text = (
        f"the largest deviation of the L⁴ column ({_pct(devs[row])} at h = {row}) is "
        f"{'' if explains else 'not '}reproduced by an inexactly solved QP: of {len(runs)} runs of the "
        f"work-precision study's solvers at tolerances 1e-2 … 1e-10 and their defaults, the closest "
        f"({best['label']}, {best['tol_label']}) gives {_pct(best_dev)}"
    )
    return [Verdict(text, "measured", sources)]


def stability_findings(stability: str, sources: tuple[str, ...]) -> list[Verdict]:
    """The atlas's counts: runs, statuses, surprises, non-finite values, the exact route."""
    frame = pd.read_csv(stability, encoding="utf-8")
    counts = frame["status"].value_counts()
    unexpected = frame[~frame["as_expected"].astype(bool)]
    exact = frame[frame["route"] == "active_set"]
    text = (
        f"{len(frame)} runs ({frame['case'].nunique()} cases × up to {frame['solver'].nunique()} solvers): "
        + ", ".join(f"{int(counts.get(k, 0))} {k}" for k in ("ok", "inaccurate", "failed"))
        + f"; {len(frame) - len(unexpected)} as expected"
        + f"; the exact route is {'never' if exact['as_expected'].astype(bool).all() else 'sometimes'} unexpected"
        + f"; {int(frame['nan_inf'].astype(bool).sum())} runs with NaN or Inf"
    )
    return [Verdict(text, "measured", sources)]


def meshes_findings(meshes: str, sources: tuple[str, ...]) -> list[Verdict]:
    """The mesh-family study's headline (``studies.meshes.report.headline``) from its ``meshes.csv``."""
    from signorini.studies.meshes.report import headline

    table = pd.read_csv(meshes, encoding="utf-8")
    reference = str(table.loc[table["reference"].astype(bool), "scene"].iloc[0])
    verdict = headline(table, reference, sources)
    return [replace(verdict, text=verdict.text.rstrip("."))]


# the committed figures and the caption (workflow/report/<name>.rst) each is shown with
FIGURE_CAPTIONS = {
    "figure2.png": "figure2",
    "figure3.png": "figure3",
    "theory_rates.png": "theory",
    "theory_extra.png": "theory",
    "contact_set.png": "contact_set",
    "eoc_against_h.png": "eoc_against_h",
    "free_point_error.png": "free_point_error",
    "work_precision.png": "work_precision",
    "cost_of_accuracy.png": "work_precision",
    "stability.png": "stability",
    "meshes_rates.png": "meshes",
}


def caption(figure: str, rst: str | os.PathLike) -> str:
    """The caption of a figure: the paragraphs of its ``.rst`` that start with the figure's name,
    or the whole file, in Markdown."""
    paragraphs = [p.strip() for p in Path(rst).read_text(encoding="utf-8").split("\n\n") if p.strip()]
    stem = Path(figure).stem
    own = [p for p in paragraphs if p.startswith(f"``{stem}``")]
    text = " ".join(" ".join(p.split()) for p in (own or paragraphs))
    return text.replace("``", "`")


def figures_section(captions_dir: str | os.PathLike) -> list[str]:
    """One entry per figure of the studies (``FIGURE_CAPTIONS``, all committed in ``paper_figures/``):
    its file and its caption. The list does not depend on which figures a run has drawn so far."""
    lines = ["## Figures", ""]
    for figure, name in FIGURE_CAPTIONS.items():
        lines += [f"- [`{figure}`]({figure}): {caption(figure, Path(captions_dir) / f'{name}.rst')}", ""]
    return lines


INTRO = """\
# Findings

Generated by the workflow (`snakemake -c2 all`) from the committed outputs of every study; do not
edit by hand. {strengths}
"""


def _bullets(verdicts: list[Verdict]) -> list[str]:
    lines = []
    for v in verdicts:
        files = ", ".join(f"`{s}`" for s in v.sources)
        lines.append(f"- *{v.strength}*: {v.text}." + (f" Source: {files}." if files else ""))
    return lines


def target_of(path: str) -> str:
    """The target whose rules write ``path`` (``paths.TARGETS``)."""
    from signorini.pipeline.paths import FIGURES, TARGETS

    return next(t for t, rules in TARGETS.items() if any(path in FIGURES[r].values() for r in rules))


def _missing(sources: Mapping[str, str], keys: tuple[str, ...]) -> list[Verdict]:
    gone = [sources[k] for k in keys if not Path(sources[k]).exists()]
    return [
        Verdict(f"not available here: `{path}` is missing (`snakemake -c2 {target_of(path)}` writes it)", "open")
        for path in gone
    ]


def sections(inputs: Mapping[str, str], sources: Mapping[str, str]) -> list[tuple[str, list[Verdict]]]:
    """The page's sections as ``(title, verdicts)``; a section whose sources are missing says so."""
    ours, paper = read_table_csv(inputs["table1"]), read_table_csv(inputs["paper_table1"])
    verdicts = table1_verdicts(
        ours,
        paper,
        inputs["conventions"],
        inputs["load_rule"],
        inputs["h12_boundary"],
        tables=(inputs["table1"], inputs["paper_table1"]),
    )
    table1 = [replace(v, text=f"{label_md(t) if t in ours.get('1/101', {}) else t}: {v.text}") for t, v in verdicts]
    wp = sources["work_precision"]
    table1 += _missing(sources, ("work_precision",)) or qp_tolerance_finding(wp, ours, paper, (wp, inputs["table1"]))
    out = [("The published Tables 1–2 reproduced", table1)]
    true_keys = ("table1_true", "table1_fine")
    wrong = _missing(sources, true_keys)
    if Path(sources["table1_true"]).exists():
        # the finest meshes (a 17 GB solve) only where their table exists: not a missing source
        cells = _true_cells(sources["table1_true"], sources["table1_fine"], sources.get("table1_finest"))
        used = tuple(sources[k] for k in true_keys if Path(sources[k]).exists())
        finest = tuple(p for p in [sources.get("table1_finest")] if p and Path(p).exists())
        wrong = [*point_set_findings(cells, used), *l16_findings(cells, used), *wrong]
        out.append(("What the published tables get wrong", wrong))
        out.append(("Rates to the finest mesh against Theorem 6.1", rate_findings(cells, used + finest)))
    else:
        out.append(("What the published tables get wrong", wrong))
    out.append(("The contact set and condition (A_h)", contact_findings(sources)))
    out.append(("Solvers: time to Table 1's digits", race_findings(sources)))
    stab = sources["stability"]
    out.append(("Stability atlas", _missing(sources, ("stability",)) or stability_findings(stab, (stab,))))
    meshes = sources.get("meshes")
    if meshes is not None:
        found = _missing(sources, ("meshes",)) or meshes_findings(meshes, (meshes,))
        out.append(("Theorem 6.1 on other meshes", found))
    return out


def summary_stage(
    inputs: Mapping[str, str], sources: Mapping[str, str], captions_dir: str | os.PathLike, out_md: str | os.PathLike
) -> None:
    """``summary.md``: every section's findings, then the studies' figures with their captions
    (``captions_dir``: the report's ``.rst`` files)."""
    lines = [INTRO.format(strengths=STRENGTHS)]
    for title, verdicts in sections(inputs, sources):
        lines += [f"## {title}", "", *_bullets(verdicts), ""]
    lines += figures_section(captions_dir)
    atomic_write_text(out_md, markdown_text("\n".join(lines).rstrip() + "\n"))


def _two(x: float) -> str:
    """Two significant digits, trailing zeros kept: 2.0, 0.67, 11."""
    return f"{x:.0f}" if abs(x) >= 10 else f"{x:.1f}" if abs(x) >= 1 else f"{x:.2f}"


def _ratio_text(r: Mapping) -> str:
    span = f" ({_two(r['lo'])}–{_two(r['hi'])})" if r.get("interval") else ""
    return f"×{_two(r['value'])}{span}"


def _sides(rows: list[dict]) -> str:
    """Per verdict, the meshes on which it holds: ``ours faster at N = …; …``."""
    names = {"above": "ours faster", "below": "the other faster", "tie": "a tie", "undetermined": "undetermined"}
    parts = []
    for key, name in names.items():
        Ns = [str(r["N"]) for r in rows if r["ratio"]["verdict"] == key]
        if Ns:
            parts.append(f"{name} at N = {', '.join(Ns)}")
    return "; ".join(parts)


def race_findings(sources: Mapping[str, str]) -> list[Verdict]:
    """The work-precision study's race to Table 1's digits, with the intervals of its ratios."""
    from signorini.published import TABLE1_NORMS
    from signorini.studies.work_precision.findings import findings
    from signorini.studies.work_precision.table import read_runs

    if missing := _missing(sources, ("work_precision",)):
        return missing
    path = sources["work_precision"]
    runs = read_runs(path)
    found = findings(runs, TABLE1_NORMS)
    label = {r.config: r.label for r in runs}
    out = []
    for key, what in (("same_warm_start", "from the same warm start"), ("cold_against_cold", "cold against cold")):
        rows = found["fair"].get(key, [])
        if rows:
            ratios = ", ".join(f"N = {r['N']} {_ratio_text(r['ratio'])}" for r in rows)
            out.append(
                Verdict(
                    f"{what}, the fastest other solver's time to Table 1's digits over our fastest exact "
                    f"configuration's (95 % bootstrap intervals; a tie when the interval contains 1): {ratios}; "
                    f"{_sides(rows)}",
                    "measured",
                    (path,),
                )
            )
    fastest = found["fastest"]
    if fastest:
        first = fastest[0]
        ours = next((f for f in fastest if f["tol_label"] == "exact"), None)
        text = (
            f"fastest to Table 1's digits at N = {found['N'][-1]}: {label[first['config']]} "
            f"({first['tol_label']}), {_two(first['value'])} s"
        )
        if ours is not None and ours is not first:
            text += f"; ours ({label[ours['config']]}) {_two(ours['value'])} s, {_ratio_text(ours['vs_fastest'])} of it"
        if unrecorded := found["software"]["unrecorded"]:
            text += f"; CPU seconds, and {unrecorded} of the {len(runs)} runs do not record the machine's CPU model"
        out.append(Verdict(text, "measured", (path,)))
    return out


def _plain(v: Verdict, sources: tuple[str, ...]) -> Verdict:
    """A verdict of another page with its inline strength taken out (the summary prints it apart)."""
    text = v.text.replace(f" ({v.strength})", "").rstrip(".")
    return Verdict(text, v.strength, sources, v.holds)


def contact_findings(sources: Mapping[str, str]) -> list[Verdict]:
    """Condition (A_h) and the Hausdorff convergence of the discrete contact sets (``contact_set.csv``)."""
    from signorini.studies.theory import contact

    if missing := _missing(sources, ("contact_set",)):
        return missing
    path = sources["contact_set"]
    table = pd.read_csv(path, encoding="utf-8")
    ah, _ = contact.condition_ah(table)
    used = (path,)
    return [
        _plain(ah, used),
        *(_plain(v, used) for v in contact.hausdorff_verdicts(contact.contact_distances(table))),
    ]
