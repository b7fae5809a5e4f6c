"""The stability atlas rendered: ``stability.csv`` (one row per case and solver), ``stability.md``
(summary numbers, one line per case) and ``stability.{pdf,png}`` (status grid and sweeps).

Rendering only, from the case artifacts of ``signorini.stability`` (kept apart so that editing
the report re-renders it without re-running the solves); the one computation here is the
comparison of a scaling case with its reference case (``atlas_table``).
"""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping, Sequence

import numpy as np

from signorini.stability import CORRUPTIONS, GROUPS, STATUSES

# --- the atlas: table, report and figure --------------------------------------------------------


def _fmt(x, digits: int = 1) -> str:
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "–"
    if isinstance(x, float) and math.isinf(x):
        return "∞"
    return f"{x:.{digits}e}"


def atlas_table(case_infos: Sequence[Mapping], case_arrays: Sequence[Mapping[str, np.ndarray]], norms: Sequence[str]):
    """One row per (case, solver), with the case's parameters, the condition estimates and,
    for cases with a ``reference``, the comparison with the reference case's solution
    scaled by the amplitude ratio (``‖u_h/A - u_h^ref/A_ref‖∞ / ‖u_h^ref/A_ref‖∞``), its
    contact set and its relative errors."""
    import pandas as pd

    by_name = {info["case"]["name"]: (info, arrays) for info, arrays in zip(case_infos, case_arrays, strict=True)}
    records = []
    for info, arrays in zip(case_infos, case_arrays, strict=True):
        case = info["case"]
        ref = case.get("reference")
        ref_info, ref_arrays = by_name.get(ref, (None, None)) if ref else (None, None)
        for row in info["rows"]:
            rec = {
                "case": case["name"],
                "group": case["group"],
                "N": case["N"],
                "diagonal": case["diagonal"],
                "jitter": case["jitter"],
                "problem": json.dumps(case["problem"], sort_keys=True),
                "corrupt": case["corrupt"] or "",
                "expected": info["expect"],
                **{k: v for k, v in row.items()},
                "cond_A": info["cond"].get("cond_A", math.nan),
                "cond_free": info["cond"].get("cond_free", math.nan),
                "lambda_min_A": info["cond"].get("lambda_min", math.nan),
            }
            if ref_info is not None:
                label = row["solver"]
                u, u_ref = arrays.get(f"u_{label}"), ref_arrays.get(f"u_{label}")
                s = float(case["problem"].get("A", 1.0)) / float(ref_info["case"]["problem"].get("A", 1.0))
                rec["reference"] = ref
                if u is not None and u_ref is not None and s > 0:
                    scale = max(np.abs(u_ref).max(initial=0.0), np.finfo(float).tiny)
                    rec["ref_diff_u"] = float(np.abs(u / s - u_ref).max(initial=0.0) / scale)
                    rec["ref_same_contact"] = bool(
                        np.array_equal(arrays[f"active_{label}"], ref_arrays[f"active_{label}"])
                    )
                    ref_row = next(r for r in ref_info["rows"] if r["solver"] == label)
                    diffs = [
                        abs(row[f"err_{n}"] - ref_row[f"err_{n}"]) / ref_row[f"err_{n}"]
                        for n in norms
                        if ref_row.get(f"err_{n}") and f"err_{n}" in row
                    ]
                    rec["ref_err_rel_change"] = max(diffs) if diffs else math.nan
            records.append(rec)
    df = pd.DataFrame.from_records(records)
    front = [
        "case",
        "group",
        "N",
        "diagonal",
        "jitter",
        "problem",
        "corrupt",
        "expected",
        "solver",
        "status",
        "as_expected",
        "reason",
        "iterations",
        "factorizations",
        "solve_s",
        "norms_s",
        "total_s",
        "kkt_worst",
        "kkt_threshold",
        "kkt_stationarity",
        "kkt_primal",
        "kkt_dual",
        "kkt_complementarity",
        "nan_inf",
        "fp_warnings",
        "n_active",
        "errors_relative",
        "absolute_norms",
        *[f"err_{n}" for n in norms],
        "diff_to_active_set",
        "same_contact_as_active_set",
        "reference",
        "ref_diff_u",
        "ref_same_contact",
        "ref_err_rel_change",
        "cond_A",
        "cond_free",
        "lambda_min_A",
    ]
    for col in front:
        if col not in df.columns:
            df[col] = math.nan
    return df[front + [c for c in df.columns if c not in front]]


def _case_line(case: Mapping, sub, norms: Sequence[str], info: Mapping) -> str:
    """The one-line finding of a case (markdown)."""
    p = case["problem"]
    what = ", ".join(f"{k} = {v:g}" if isinstance(v, float) else f"{k} = {v}" for k, v in p.items())
    mesh = f"N = {case['N']}" + (f", {case['diagonal']}" if case["diagonal"] != "sw_ne" else "")
    mesh += f", jitter {case['jitter']:g} h" if case["jitter"] else ""
    head = f"- **{case['name']}** ({mesh}; {what}"
    head += f"; {CORRUPTIONS[case['corrupt']]})" if case["corrupt"] else ")"
    head += f" — {case['note']}" if case.get("note") else ""
    parts = []
    reasons = set(sub["reason"]) if (sub["status"] == "failed").all() else set()
    if len(reasons) == 1:  # every solver stopped with the same error: say it once
        verdict = "as required" if sub["as_expected"].astype(bool).all() else "UNEXPECTEDLY"
        parts.append(f"all {len(sub)} solvers failed {verdict} with {reasons.pop()}")
        sub = sub.iloc[:0]
    for _, r in sub.iterrows():
        if r["status"] == "failed":
            reason = str(r["reason"])
            reason = reason if len(reason) <= 90 else reason[:87] + "…"
            parts.append(f"{r['solver']} failed ({reason})")
            continue
        bits = [f"{r['solver']} {r['status']}", f"{int(r['iterations'])} it", f"KKT {_fmt(r['kkt_worst'])}"]
        absolute = str(r.get("absolute_norms") or "").split()
        errs = [
            f"{n} {_fmt(r[f'err_{n}'], 2)}" + (" (abs.)" if n in absolute else "")
            for n in ("L4", "W14", "H12")
            if f"err_{n}" in r and not _isnan(r[f"err_{n}"])
        ]
        if errs and r["solver"] == "active_set":
            bits.append("err " + " / ".join(errs))
        if r["solver"] != "active_set" and not _isnan(r.get("diff_to_active_set")):
            bits.append(f"Δu vs exact {_fmt(r['diff_to_active_set'])}")
        if not _isnan(r.get("ref_diff_u")):
            same = "same" if r["ref_same_contact"] else "DIFFERENT"
            bits.append(f"vs {r['reference']}: Δ(u/A) {_fmt(r['ref_diff_u'])}, {same} contact set")
        if r["solver"] == "active_set":
            bits.append(f"{int(r['n_active'])}/{_n_constrained(case)} in contact")
        if r["nan_inf"]:
            bits.append("NaN/Inf!")
        parts.append(" ".join(bits[:1]) + " (" + ", ".join(bits[1:]) + ")")
    cond = info.get("cond") or {}
    if "cond_A" in cond:
        parts.append(f"κ₂(A) {_fmt(cond['cond_A'])}, κ₂(A_FF) {_fmt(cond.get('cond_free'))}")
    return head + ": " + "; ".join(parts) + "."


def _isnan(x) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def _n_constrained(case: Mapping) -> int:
    return 0 if case.get("corrupt") == "empty_constraints" else 4 * int(case["N"])


def atlas_report(df, case_infos: Sequence[Mapping], norms: Sequence[str]) -> str:
    """``stability.md``: summary numbers, then one line per case."""
    lines = [
        "# Numerical stability atlas",
        "",
        "Generated by `snakemake stability` (`signorini.stability`); one row per (case, solver) in "
        "`stability.csv`. Status: **ok** = finite solution whose relative KKT residuals "
        "(`solvers.certificate`) are ≤ the solver's tolerance (active set 1e-10, cvxpy 1e-6; or the "
        "rounding floor 16 ε ‖|A||u|‖∞/σ when larger); **inaccurate** = finite but above it; **failed** = "
        "exception, time limit, crash, or NaN/Inf (the reason is recorded). Errors are relative to ‖u‖ in "
        "the same norm (absolute where ‖u‖ = 0 in that norm). κ₂ from ARPACK's extreme eigenvalues "
        "(Lanczos; shift-invert at σ = −1e-10 λ_max), A = K + cM the whole matrix, A_FF its block on the "
        "free nodes of the exact solution (not estimated above `cond_max_dofs` unknowns). Columns "
        "`*_raw`: the cvxpy route as shipped (the QP solvers' "
        "absolute tolerances); the other cvxpy columns use `normalize=True` (A/max A_ii, u/‖u_D‖∞: "
        "`solvers.cvxpy_qp`). Δu vs exact = ‖u − u_active_set‖∞/‖u_active_set‖∞ on the same mesh.",
        "",
        "## Summary",
        "",
    ]
    total = len(df)
    lines.append(
        f"- {total} runs ({df['case'].nunique()} cases × up to {df['solver'].nunique()} solvers): "
        + ", ".join(f"{(df['status'] == s).sum()} {s}" for s in STATUSES)
        + f"; {int(df['as_expected'].sum())} as expected."
    )
    nan_runs = df[df["nan_inf"].astype(bool)]
    lines.append(
        f"- NaN/Inf in any output: {len(nan_runs)} runs"
        + (" (" + ", ".join(f"{r.case}/{r.solver}" for r in nan_runs.itertuples()) + ")" if len(nan_runs) else "")
        + "."
    )
    exact = df[df["solver"] == "active_set"]
    bad = exact[~exact["as_expected"].astype(bool)]
    lines.append(
        "- Exact solver (active_set) not as expected: "
        + (", ".join(f"{r.case} ({r.status}: {r.reason})" for r in bad.itertuples()) if len(bad) else "none")
        + "."
    )
    scal = df[(df["group"] == "scaling") & df["reference"].notna()]
    for solver, sub in scal.groupby("solver", sort=False):
        solved = sub.dropna(subset=["ref_diff_u"])
        changed = solved[~solved["ref_same_contact"].astype(bool)]["case"].tolist()
        contact = "contact set identical" if not changed else f"contact set differs in {', '.join(changed)}"
        statuses = ", ".join(f"{r.case} {r.status}" for r in sub.itertuples())
        lines.append(
            f"- scaling, {solver} ({statuses}): over the {len(solved)} solved amplitudes max Δ(u/A) vs the "
            f"reference {_fmt(solved['ref_diff_u'].max())}, max relative change of the errors "
            f"{_fmt(solved['ref_err_rel_change'].max())}, {contact}."
        )
    unexpected = df[(df["solver"] != "active_set") & ~df["as_expected"].astype(bool)]
    if len(unexpected):
        lines.append(
            "- Other solvers not ok: "
            + "; ".join(
                f"{r.case}/{r.solver} {r.status}" + (f" ({str(r.reason)[:60]})" if r.reason else "")
                for r in unexpected.itertuples()
            )
            + "."
        )
    lines += ["", "## Findings per case", ""]
    for group in GROUPS:
        infos = [i for i in case_infos if i["case"]["group"] == group]
        if not infos:
            continue
        lines += [f"### {group}", ""]
        for info in infos:
            sub = df[df["case"] == info["case"]["name"]]
            lines.append(_case_line(info["case"], sub, norms, info))
        lines.append("")
    return "\n".join(lines)


STATUS_COLOURS = {
    "ok": "#4caf50",
    "inaccurate": "#ffb300",
    "failed": "#e53935",
    "rejected": "#42a5f5",
    "not run": "#eeeeee",
}


def atlas_figure(df, out_pdf: str | os.PathLike, out_png: str | os.PathLike, solver_order: Sequence[str] = ()) -> None:
    """Left: case × solver grid coloured by status (blue: bad input rejected with a clear error, as
    it should be), annotated with the worst relative KKT residual (k) and the relative L⁴ error (e)
    or the error class.  Right: the scaling sweep (KKT residual and Δ(u/A) against the
    amplitude) and the stiff-reaction sweep (errors, iterations and κ₂ against c)."""
    from matplotlib.patches import Patch

    from signorini.figures import _pyplot, _save

    plt = _pyplot()
    cases = list(dict.fromkeys(df["case"]))
    present = list(dict.fromkeys(df["solver"]))
    solvers = [s for s in solver_order if s in present] + [s for s in present if s not in solver_order]
    fig = plt.figure(figsize=(17.0, max(9.0, 0.34 * len(cases) + 2.0)))
    gs = fig.add_gridspec(
        4, 2, width_ratios=[1.45, 1.0], hspace=0.55, wspace=0.18, left=0.125, right=0.98, top=0.95, bottom=0.05
    )
    ax = fig.add_subplot(gs[:, 0])
    for i, case in enumerate(cases):
        for j, solver in enumerate(solvers):
            sel = df[(df["case"] == case) & (df["solver"] == solver)]
            if sel.empty:
                status, text = "not run", ""
            else:
                r = sel.iloc[0]
                status = (
                    "rejected"
                    if (r["status"] == "failed" and r["expected"] == "error" and r["as_expected"])
                    else r["status"]
                )
                if r["status"] == "failed":
                    text = str(r["reason"]).split(":", 1)[0].replace("Error", "")[:14]
                else:
                    e = r.get("err_L4")
                    etxt = f"e {e:.0e}" if not _isnan(e) else ""
                    text = f"k {r['kkt_worst']:.0e}\n{etxt}"
            ax.add_patch(plt.Rectangle((j, i), 1, 1, facecolor=STATUS_COLOURS[status], edgecolor="white", lw=1.5))
            ax.text(j + 0.5, i + 0.5, text, ha="center", va="center", fontsize=6.2)
    ax.set_xlim(0, len(solvers))
    ax.set_ylim(len(cases), 0)
    ax.xaxis.tick_top()
    ax.set_xticks(np.arange(len(solvers)) + 0.5, solvers, fontsize=8)
    groups = df.drop_duplicates("case").set_index("case")["group"]
    ax.set_yticks(np.arange(len(cases)) + 0.5, [f"{c}  [{groups[c]}]" for c in cases], fontsize=7.5)
    ax.tick_params(length=0)
    for i in range(1, len(cases)):
        if groups[cases[i]] != groups[cases[i - 1]]:
            ax.axhline(i, color="k", lw=1.2)
    ax.set_title(
        "stability atlas: status per case and solver (k = worst relative KKT residual, e = rel. L⁴ error)",
        fontsize=9,
        pad=18,
    )
    ax.legend(
        handles=[
            Patch(color=c, label=s if s != "rejected" else "rejected (clear error, expected)")
            for s, c in STATUS_COLOURS.items()
        ],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.005),
        ncol=5,
        fontsize=7.5,
        frameon=False,
    )

    def sweep(group: str, key: str):
        sub = df[df["group"] == group].copy()
        sub["x"] = [json.loads(p).get(key, math.nan) for p in sub["problem"]]
        return sub.sort_values("x")

    markers = dict(zip(solvers, "osD^v<>ph*", strict=False))
    scal = sweep("scaling", "A")
    ax1 = fig.add_subplot(gs[0, 1])
    for solver, sub in scal.groupby("solver", sort=False):
        y = sub["kkt_worst"].where(sub["status"] != "failed")
        ax1.loglog(sub["x"], y.clip(lower=1e-17), marker=markers[solver], label=solver, lw=1)
    ax1.set_title("scaling: worst relative KKT residual against the amplitude A", fontsize=9)
    ax1.set_ylabel("KKT residual")
    ax1.legend(fontsize=6.5, ncol=2)
    ax2 = fig.add_subplot(gs[1, 1])
    for solver, sub in scal.groupby("solver", sort=False):
        ax2.loglog(sub["x"], sub["ref_diff_u"].clip(lower=1e-17), marker=markers[solver], label=solver, lw=1)
    ax2.set_title("scaling: ‖u_h/A − u_h^ref/A_ref‖∞ / ‖u_h^ref/A_ref‖∞ (failed: no point)", fontsize=9)
    ax2.set_ylabel("Δ(u/A)")
    ax2.set_xlabel("amplitude A")
    reac = sweep("reaction", "c")
    reac = reac[reac["x"] > 0]
    ax3 = fig.add_subplot(gs[2, 1])
    exact = reac[reac["solver"] == "active_set"]
    for n, mk in (("L4", "o"), ("W14", "s"), ("Linf", "^"), ("H12", "D")):
        if f"err_{n}" in exact:
            ax3.loglog(exact["x"], exact[f"err_{n}"], marker=mk, label=f"rel. {n} error (active set)", lw=1)
    for solver, sub in reac.groupby("solver", sort=False):
        if solver != "active_set" and not solver.endswith("_raw"):
            ax3.loglog(
                sub["x"],
                sub["diff_to_active_set"].clip(lower=1e-17),
                ls=":",
                marker=markers[solver],
                label=f"Δu {solver} vs exact",
                lw=1,
                ms=3,
            )
    ax3.set_title("stiff reaction: errors and distance of the QP solvers to the exact solution", fontsize=9)
    ax3.legend(fontsize=6, ncol=2)
    ax4 = fig.add_subplot(gs[3, 1])
    ax4.loglog(exact["x"], exact["cond_A"], marker="o", label="κ₂(A), A = K + cM")
    ax4.loglog(exact["x"], exact["cond_free"], marker="s", label="κ₂(A_FF), free block")
    ax4.set_xlabel("reaction coefficient c")
    ax4.set_ylabel("condition number")
    ax4b = ax4.twinx()
    for solver, sub in reac.groupby("solver", sort=False):
        if solver in ("active_set", "osqp", "clarabel"):
            ax4b.semilogx(
                sub["x"], sub["iterations"], ls="--", marker=markers[solver], ms=3, lw=0.8, label=f"iterations {solver}"
            )
    ax4b.set_ylabel("iterations")
    h1, l1 = ax4.get_legend_handles_labels()
    h2, l2 = ax4b.get_legend_handles_labels()
    ax4.legend(h1 + h2, l1 + l2, fontsize=6, ncol=2, loc="upper right")
    ax4.set_title("stiff reaction: condition numbers and iterations", fontsize=9)
    for a in (ax1, ax2, ax3, ax4):
        a.grid(True, which="major", lw=0.3, alpha=0.6)
        a.tick_params(labelsize=7)
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)


def atlas_stage(
    norms: Sequence[str],
    solvers: Sequence[str],
    case_jsons: Sequence[str | os.PathLike],
    case_npzs: Sequence[str | os.PathLike],
    out_csv: str | os.PathLike,
    out_md: str | os.PathLike,
    out_pdf: str | os.PathLike,
    out_png: str | os.PathLike,
) -> None:
    """Stage of the rule ``stability_atlas``: collect the cases into the CSV, report and figure
    (``solvers``: the column order of the grid)."""
    import io

    from signorini.artifacts import atomic_write_text, load_json, load_npz

    infos = [load_json(p) for p in case_jsons]
    arrays = [load_npz(p) for p in case_npzs]
    df = atlas_table(infos, arrays, norms)
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")
    atomic_write_text(out_csv, buf.getvalue())
    atomic_write_text(out_md, atlas_report(df, infos, norms) + "\n")
    atlas_figure(df, out_pdf, out_png, solvers)
