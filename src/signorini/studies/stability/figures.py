"""The stability atlas as a figure: the case × solver status grid and the scaling and
stiff-reaction sweeps, drawn on given axes (or a new figure) and returned."""

from __future__ import annotations

import json
import math
import re
from collections.abc import Sequence

import numpy as np

from signorini.plotting import new_figure, styled

STATUS_COLOURS = {
    "ok": "#4caf50",
    "inaccurate": "#ffb300",
    "failed": "#e53935",
    "rejected": "#42a5f5",
    "not run": "#eeeeee",
}


def _isnan(x) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def _cell(sel) -> tuple[str, str]:
    """Status colour key and text of one grid cell."""
    if sel.empty:
        return "not run", ""
    r = sel.iloc[0]
    rejected = r["status"] == "failed" and r["expected"] == "error" and r["as_expected"]
    status = "rejected" if rejected else r["status"]
    if r["status"] == "failed":
        # the error class, without "Error", split at its words so that it fits the cell
        name = str(r["reason"]).split(":", 1)[0].replace("Error", "")
        words = re.findall(r"[A-Z]+[a-z0-9]*|[a-z0-9]+", name) or [name]
        return status, "\n".join(words) if len(name) > 11 else name
    e = r.get("err_L4")
    etxt = f"e {e:.0e}" if not _isnan(e) else ""
    return status, f"k {r['kkt_worst']:.0e}\n{etxt}"


@styled
def status_grid(df, solvers: Sequence[str], ax=None):
    """Case × solver grid coloured by status (blue: bad input rejected with a clear error, as it
    should be), annotated with the worst relative KKT residual (k) and the relative L⁴ error (e)
    or the error class.  Returns the axes."""
    from matplotlib.patches import Patch, Rectangle

    ax = ax if ax is not None else new_figure(figsize=(9.0, 10.0)).subplots()
    cases = list(dict.fromkeys(df["case"]))
    for i, case in enumerate(cases):
        for j, solver in enumerate(solvers):
            status, text = _cell(df[(df["case"] == case) & (df["solver"] == solver)])
            ax.add_patch(Rectangle((j, i), 1, 1, facecolor=STATUS_COLOURS[status], edgecolor="white", lw=1.5))
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
    labels = {"rejected": "rejected (clear error, expected)"}
    ax.legend(
        handles=[Patch(color=c, label=labels.get(s, s)) for s, c in STATUS_COLOURS.items()],
        loc="upper center",
        bbox_to_anchor=(0.5, -0.005),
        ncol=5,
        fontsize=7.5,
        frameon=False,
    )
    return ax


def _sweep(df, group: str, key: str):
    sub = df[df["group"] == group].copy()
    sub["x"] = [json.loads(p).get(key, math.nan) for p in sub["problem"]]
    return sub.sort_values("x")


def scaling_panels(df, markers: dict, ax_kkt, ax_diff) -> None:
    """The scaling sweep: worst KKT residual and Δ(u/A) against the amplitude."""
    scal = _sweep(df, "scaling", "A")
    for solver, sub in scal.groupby("solver", sort=False):
        y = sub["kkt_worst"].where(sub["status"] != "failed")
        ax_kkt.loglog(sub["x"], y.clip(lower=1e-17), marker=markers[solver], label=solver, lw=1)
        ax_diff.loglog(sub["x"], sub["ref_diff_u"].clip(lower=1e-17), marker=markers[solver], label=solver, lw=1)
    ax_kkt.set_title("scaling: worst relative KKT residual against the amplitude A", fontsize=9)
    ax_kkt.set_ylabel("KKT residual")
    ax_kkt.legend(fontsize=6.5, ncol=2)
    ref = r"u_h^{\mathrm{ref}}/A_{\mathrm{ref}}"
    ax_diff.set_title(
        rf"scaling: $\|u_h/A - {ref}\|_\infty \,/\, \|{ref}\|_\infty$ (failed: no point)", fontsize=9
    )
    ax_diff.set_ylabel(r"$\Delta(u/A)$")
    ax_diff.set_xlabel("amplitude A")


def reaction_panels(df, markers: dict, ax_err, ax_cond) -> None:
    """The stiff-reaction sweep: errors and distances to the exact solution; condition numbers
    and iterations against c."""
    reac = _sweep(df, "reaction", "c")
    reac = reac[reac["x"] > 0]
    exact = reac[reac["solver"] == "active_set"]
    for n, mk in (("L4", "o"), ("W14", "s"), ("Linf", "^"), ("H12", "D")):
        if f"err_{n}" in exact:
            ax_err.loglog(exact["x"], exact[f"err_{n}"], marker=mk, label=f"rel. {n} error (active set)", lw=1)
    for solver, sub in reac.groupby("solver", sort=False):
        if solver != "active_set" and not solver.endswith("_raw"):
            ax_err.loglog(sub["x"], sub["diff_to_active_set"].clip(lower=1e-17), ls=":", marker=markers[solver],
                          label=f"Δu {solver} vs exact", lw=1, ms=3)
    ax_err.set_title("stiff reaction: errors and distance of the other solvers to the exact solution", fontsize=9)
    ax_err.legend(fontsize=6, ncol=2)
    ax_cond.loglog(exact["x"], exact["cond_A"], marker="o", label=r"$\kappa_2(A)$, $A = K + cM$")
    ax_cond.loglog(exact["x"], exact["cond_free"], marker="s", label=r"$\kappa_2(A_{FF})$, free block")
    ax_cond.set_xlabel("reaction coefficient c")
    ax_cond.set_ylabel("condition number")
    twin = ax_cond.twinx()
    for solver, sub in reac.groupby("solver", sort=False):
        if solver in ("active_set", "osqp", "clarabel"):
            twin.semilogx(sub["x"], sub["iterations"], ls="--", marker=markers[solver], ms=3, lw=0.8,
                          label=f"iterations {solver}")
    twin.set_ylabel("iterations")
    h1, l1 = ax_cond.get_legend_handles_labels()
    h2, l2 = twin.get_legend_handles_labels()
    ax_cond.legend(h1 + h2, l1 + l2, fontsize=6, ncol=2, loc="upper right")
    ax_cond.set_title("stiff reaction: condition numbers and iterations", fontsize=9)


@styled
def atlas_figure(df, solver_order: Sequence[str] = (), fig=None):
    """Left: ``status_grid``.  Right: ``scaling_panels`` and ``reaction_panels``.  Returns the figure."""
    cases = list(dict.fromkeys(df["case"]))
    present = list(dict.fromkeys(df["solver"]))
    solvers = [s for s in solver_order if s in present] + [s for s in present if s not in solver_order]
    fig = fig if fig is not None else new_figure(figsize=(17.0, max(9.0, 0.34 * len(cases) + 2.0)))
    # right: room for the twin axis of the last panel (its tick labels and "iterations"), which
    # the axes' box leaves out; at 0.98 the saved figure cut them off
    gs = fig.add_gridspec(
        4, 2, width_ratios=[1.45, 1.0], hspace=0.55, wspace=0.18, left=0.125, right=0.95, top=0.95, bottom=0.05
    )
    status_grid(df, solvers, fig.add_subplot(gs[:, 0]))
    markers = dict(zip(solvers, "osD^v<>ph*", strict=False))
    panels = [fig.add_subplot(gs[k, 1]) for k in range(4)]
    scaling_panels(df, markers, panels[0], panels[1])
    reaction_panels(df, markers, panels[2], panels[3])
    for a in panels:
        a.grid(True, which="major", lw=0.3, alpha=0.6)
        a.tick_params(labelsize=7)
    return fig
