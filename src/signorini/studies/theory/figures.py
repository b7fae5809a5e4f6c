"""Figures of the theory scene, drawn on given axes (or a new figure) and returned: the rate
against ``1/p`` with the expected orders; supercloseness, ``H^{1/2}``, one-sided ``L⁴`` and the ends
of the discrete contact set against ``h``; the contact sets along the unrolled boundary."""

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
    ax.set_title(
        "Rate against p. Expected: Theorem 6.1 for p = 4, ∞ (p < 4 by Hölder),\n"
        "inverse estimates from p = 4 for 4 < p < ∞ (Table 2's note)",
        fontsize="medium",
    )
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
        ax.annotate(
            f"$h^{{{r:g}}}$",
            (h.max(), ref[h.argmax()]),
            xytext=(6, 0),
            textcoords="offset points",
            ha="left",
            va="center",
            fontsize="medium",
            color="0.3",
        )
    ax.set_xlim(h.min() / 1.25, h.max() * 1.8)
    ax.set_xlabel("mesh width $h$")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small")


@styled
def extra_figure(table, ends=None, marks=(), fig=None):
    """Supercloseness against the H¹ error; the ``H^{1/2}`` values and the one-sided ``L⁴`` parts;
    with ``ends`` (``contact.ends_frame``) a third panel, the ends of the discrete contact set
    against h (``ends_panel``, with ``marks``).  ``table``: ``report.theory_table``.  Returns the figure."""
    panels = 2 if ends is None else 3
    fig = fig if fig is not None else new_figure(figsize=(4.4 * panels, 4.0))
    axes = fig.subplots(1, panels)
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
            ("H12_interpolation", r"$H^{1/2}$ estimate of $u-u_h$"),
            ("H12_discrete", r"$H^{1/2}$ norm of $I_{h/2}u-u_h$"),
            ("L4plus", r"$\|(u-u_h)^+\|_{L^4}$"),
            ("L4minus", r"$\|(u-u_h)^-\|_{L^4}$"),
        ],
        [(1.5, "H12_interpolation"), (2.0, "L4plus")],
    )
    axes[1].set_title(r"$H^{1/2}(\partial\Omega)$ and one-sided $L^4$")
    if ends is not None:
        ends_panel(ends, marks, axes[2])
        axes[2].set_title("Ends of the discrete contact set")
    fig.tight_layout()
    return fig


# --- the contact sets along the unrolled boundary (``contact.contact_table``) ----------------------

PERIMETER = 4.0  # the unit square's boundary, unrolled by arc length s from (0, 0) counter-clockwise
CORNERS = {0.0: "(0, 0)", 1.0: "(1, 0)", 2.0: "(1, 1)", 3.0: "(0, 1)", 4.0: "(0, 0)"}
# the edges in the order of the arc length, with the point at arc length s
EDGES = (("bottom", "$(s, 0)$"), ("right", "$(1, s - 1)$"), ("top", "$(3 - s, 1)$"), ("left", "$(0, 4 - s)$"))


def _pieces(start: float, length: float) -> list[tuple[float, float]]:
    """(start, length) pieces of an arc on the unrolled boundary [0, 4], split where it wraps."""
    if start + length <= PERIMETER:
        return [(start, length)]
    return [(start, PERIMETER - start), (0.0, start + length - PERIMETER)]


def _arcs(table, name: str, N: int | None = None) -> list[tuple[float, float]]:
    """(start, length) of the arcs of one set of the table (``N``: of that mesh)."""
    sel = table[(table["set"] == name) & (table["N"] == N if N is not None else True)]
    sel = sel[sel["s_start"].notna()]
    return list(zip(sel["s_start"].astype(float), sel["length"].astype(float), strict=True))


def _draw_arcs(ax, arcs, y, **style) -> None:
    """Arcs as bars on row ``y`` (a point as a vertical tick), one legend entry for all of them."""
    for start, length in arcs:
        if length == 0.0:
            ax.plot([start], [y], "|", ms=12, mew=2.5, color=style.get("facecolors", "k"), label=style.get("label"))
        else:
            ax.broken_barh(_pieces(start, length), (y - 0.3, 0.6), **style)
        style = {k: v for k, v in style.items() if k != "label"}


def _draw_sets(ax, table, Ns) -> None:
    """The exact set on row 0 (strict part filled, biactive part hatched and shaded across the
    rows) and the discrete set of each mesh ``Ns[k]`` on row ``k + 1``."""
    for start, length in _arcs(table, "biactive"):
        for a, w in _pieces(start, length):
            ax.axvspan(a, a + w, color="C2", alpha=0.12, lw=0)
    _draw_arcs(ax, _arcs(table, "strict"), 0, facecolors="C0", label="strict contact: $u = 0 < \\partial_n u$")
    biactive = [a for a in _arcs(table, "biactive") if a[1] > 0]
    style = {"facecolors": "none", "edgecolors": "C2", "hatch": "////"}
    _draw_arcs(ax, biactive, 0, label="biactive: $u = \\partial_n u = 0$", **style)
    labels = {"bar": "discrete contact set $\\tilde A_h$", "node": "single contact node"}  # one legend entry each
    for y, N in enumerate(Ns, start=1):
        arcs = _arcs(table, "discrete", N)
        bars, nodes = [a for a in arcs if a[1] > 0], [a for a in arcs if a[1] == 0]
        _draw_arcs(ax, bars, y, facecolors="0.15", label=labels.pop("bar") if bars and "bar" in labels else None)
        _draw_arcs(ax, nodes, y, facecolors="C3", label=labels.pop("node") if nodes and "node" in labels else None)


@styled
def contact_strip(table, marks=(), ax=None, xlim=None):
    """The contact sets along the unrolled boundary ``s ∈ [0, 4]``: one row for the exact set (its
    strict part filled, its biactive part hatched) and one per mesh (the components of ``Ã_h``,
    single nodes as ticks), the biactive set shaded across the rows, the corners drawn and the
    points ``marks`` (arc length, label, line style; ``contact.figure_marks``) marked and labelled.
    ``table``: ``contact.contact_table``; ``xlim``: a zoom.  Returns the axes."""
    if ax is None:
        ax = new_figure(figsize=(11.0, 3.6)).subplots()
    Ns = sorted(int(N) for N in table.loc[table["set"] == "discrete", "N"].unique())
    _draw_sets(ax, table, Ns)
    lo, hi = xlim if xlim is not None else (0.0, PERIMETER)
    for s in CORNERS:
        if lo <= s <= hi:
            ax.axvline(s, color="0.35", lw=0.8)
    for s, label, ls in marks:
        if lo <= s <= hi:
            ax.axvline(s, color="0.35", lw=0.8, ls=ls)
            at = (s - lo) / (hi - lo)
            ha = "left" if at < 0.1 else ("right" if at > 0.9 else "center")
            box = {"boxstyle": "round,pad=0.15", "fc": "white", "ec": "none"}
            ax.annotate(label, (s, -1.0), ha=ha, va="center", fontsize="small", color="0.2", bbox=box)
    ax.set_yticks(range(len(Ns) + 1), ["exact: $u = 0$", *(f"$N = {N}$" for N in Ns)])
    ax.set_ylim(len(Ns) + 0.6, -1.5)
    ax.set_xlim(lo, hi)
    if xlim is None:
        ax.set_xlabel("arc length $s$ along $\\partial\\Omega$, counter-clockwise from $(0, 0)$")
        ticks = sorted([*CORNERS, *(c + 0.5 for c in range(4))])
        ax.set_xticks(ticks, [CORNERS.get(s) or EDGES[int(s)][0] for s in ticks])
    return ax


@styled
def contact_figure(table, marks=(), windows=(), fig=None):
    """The contact sets along the whole boundary (top, ``contact_strip``) and in each of the
    ``windows`` (arc-length ranges, ``contact.zoom_windows``: around the ends of ``Ã_h``; bottom).
    ``table``: ``contact.contact_table``; ``marks`` as for ``contact_strip``.  Returns the figure."""
    fig = fig if fig is not None else new_figure(figsize=(11.0, 7.4), layout="constrained")
    grid = fig.add_gridspec(2, max(1, len(windows)), height_ratios=(1.25, 1.0))
    top = contact_strip(table, marks, fig.add_subplot(grid[0, :]))
    top.set_title("Discrete contact sets $\\tilde A_h = \\{u_h = 0\\}$ against the exact contact set $\\{u = 0\\}$")
    top.legend(loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=4, fontsize="small", frameon=False)
    for k, window in enumerate(windows):
        ax = contact_strip(table, marks, fig.add_subplot(grid[1, k]), xlim=window)
        edge, point = EDGES[int(min(3.0, max(0.0, sum(window) / 2)))]
        ax.set_title(f"near end {k + 1} of $\\tilde A_h$, on the {edge} edge", fontsize="medium")
        ax.set_xlabel(f"arc length $s$ of the point {point}")
        if k:
            ax.set_yticklabels([])
    return fig


def ends_panel(ends, marks=(), ax=None):
    """The ends of ``Ã_h`` (arc length along ``∂Ω``) against h, with the corners and the ``marks``
    (as for ``contact_strip``) in range.  ``ends``: ``contact.ends_frame`` (``N``, ``h``, ``end``,
    ``s``).  Returns the axes."""
    if ax is None:
        ax = new_figure(figsize=(4.4, 4.0)).subplots()
    for k, one in ends.groupby("end", sort=True):
        edge = EDGES[int(one["s"].iloc[-1]) % 4][0]
        ax.semilogx(one["h"], one["s"], "o-", label=f"end {k + 1}, on the {edge} edge")
    lo, hi = (ends["s"].min() - 0.1, ends["s"].max() + 0.1) if len(ends) else (0.0, PERIMETER)
    for s, label, ls in [*((c, f"corner {name}", "-") for c, name in CORNERS.items()), *marks]:
        if lo <= s <= hi:
            ax.axhline(s, color="0.5", lw=0.8, ls=ls)
            # below its line: the ends lie at or above the exact ones they approach
            where = {"xycoords": ("axes fraction", "data"), "xytext": (0, -2), "textcoords": "offset points"}
            ax.annotate(label, (0.02, s), va="top", fontsize="small", color="0.3", **where)
    ax.set_ylim(lo, hi)
    if len(ends):
        ax.set_xlim(ends["h"].min() / 1.25, ends["h"].max() * 1.25)
    ax.set_xlabel("mesh width $h$")
    ax.set_ylabel("arc length $s$ of the end along $\\partial\\Omega$")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize="small", loc="center right")
    return ax
