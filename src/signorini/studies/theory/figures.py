"""Figures of the theory scene, drawn on given axes (or a new figure) and returned: the rate
against ``1/p`` with the theoretical curves, and supercloseness / ``H^{1/2}`` / one-sided ``L⁴``
/ contact set against ``h``."""

from __future__ import annotations

import numpy as np

from signorini.fem.convergence import regression_slope
from signorini.plotting import new_figure, styled
from signorini.published import CRITICAL_P, expected_order


@styled
def rate_figure(rates, ax=None):
    """Measured slope against 1/p (regression over all meshes and over the finest three) with the
    theoretical curves (kink at the critical p = 4).  ``rates``: ``report.rate_rows``.  Returns the axes."""
    if ax is None:
        ax = new_figure(figsize=(6.4, 4.4)).subplots()
    q = np.linspace(0.0, 0.5, 201)
    p = np.divide(1.0, q, out=np.full_like(q, np.inf), where=q > 0)
    for family, color, label in (("L", "C0", r"$L^p$: $2$, $3/2+2/p$"), ("W1", "C1", r"$W^{1,p}$: $1$, $1/2+2/p$")):
        ax.plot(q, [expected_order(family, x) for x in p], f"{color}--", lw=1, label=f"theory {label}")
    finest = [c for c in rates.columns if c.startswith("slope_finest")][0]
    for prefix, color, label in (("L", "C0", "$L^p$"), ("W1", "C1", "$W^{1,p}$")):
        sel = rates[rates["norm"].str.match(rf"^{prefix}(inf|\d)")].sort_values("p")
        x = 1.0 / sel["p"].to_numpy()
        ax.plot(x, sel["slope_all"], "o-", color=color, label=f"{label}: regression, all meshes")
        ax.plot(x, sel[finest], "s:", color=color, mfc="none", label=f"{label}: regression, finest 3")
    ax.axvline(1.0 / CRITICAL_P, color="0.6", lw=0.8)
    ax.text(1.0 / CRITICAL_P + 0.002, 0.45, f"p = {CRITICAL_P:g}", color="0.4", fontsize=8)
    ax.set_xlabel("1/p")
    ax.set_ylabel("order of convergence")
    ax.set_xlim(-0.01, 0.51)
    ax.set_ylim(0.4, 2.2)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="lower right")
    ax.set_title("Rate against p (theory: Theorem 6.1, Remark 6.2)")
    ax.figure.tight_layout()
    return ax


def _loglog_panel(ax, table, curves, refs) -> None:
    """Curves (column, label) against h with their slopes, and reference slopes h^r through the
    finest value of a column (r, column)."""
    h = table["h"].to_numpy()
    for col, label in curves:
        y = table[col].to_numpy()
        ax.loglog(h, y, "o-", label=f"{label} (slope {regression_slope(h, y):.2f})")
    for r, anchor in refs:
        # the reference line h^r lies below its curve (0.7 of its finest value); its label sits
        # right of the coarsest end, in the margin the wider x-range leaves, not on the lines
        y0 = 0.7 * table[anchor].iloc[-1]
        ref = y0 * (h / h[-1]) ** r
        ax.loglog(h, ref, "k--", lw=0.8, alpha=0.6)
        ax.annotate(f"$h^{{{r:g}}}$", (h.max(), ref[h.argmax()]), xytext=(6, 0), textcoords="offset points",
                    ha="left", va="center", fontsize="medium", color="0.3")
    ax.set_xlim(h.min() / 1.25, h.max() * 1.8)
    ax.set_xlabel("mesh width $h$")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")


@styled
def extra_figure(table, fig=None):
    """Three panels: supercloseness against the H¹ error; the discrete and interpolation
    ``H^{1/2}`` values and the one-sided ``L⁴`` parts; the end of the contact set at the free
    point.  ``table``: ``report.theory_table``.  Returns the figure."""
    fig = fig if fig is not None else new_figure(figsize=(13.0, 4.0))
    axes = fig.subplots(1, 3)
    _loglog_panel(
        axes[0],
        table,
        [("H1", r"$\|u-u_h\|_{H^1}$"), ("supercloseness_H1", r"$\|R_hu-u_h\|_{H^1}$")],
        [(1.0, "H1"), (1.5, "supercloseness_H1")],
    )
    axes[0].set_title("Supercloseness (Theorem 3.6)")
    _loglog_panel(
        axes[1],
        table,
        [
            ("H12_interpolation", r"$H^{1/2}$ by interpolation"),
            ("H12_discrete", r"$H^{1/2}$ discrete norm"),
            ("L4plus", r"$\|(u-u_h)^+\|_{L^4}$"),
            ("L4minus", r"$\|(u-u_h)^-\|_{L^4}$"),
        ],
        [(1.5, "H12_discrete"), (2.0, "L4plus")],
    )
    axes[1].set_title(r"$H^{1/2}(\partial\Omega)$ and one-sided $L^4$")
    h = table["h"].to_numpy()
    ax = axes[2]
    ax.loglog(h, np.abs(table["free_point_offset"]), "o-", label=r"end of the contact set: $|x_{\mathrm{end}} - x_0|$")
    ax.loglog(h, h, "k--", lw=0.8, label="$h$")
    ax.set_xlabel("mesh width $h$")
    ax.set_title("Contact set near the free point")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")
    fig.tight_layout()
    return fig
