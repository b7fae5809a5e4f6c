"""Figures 2 and 3 of the paper.

Rendering only: ``figure2`` plots the sampled ``u`` and ``f`` (artifact of the
workflow's ``sample`` stage), ``figure3`` the ``L⁴`` and ``W^{1,4}`` errors read
from the norm artifacts.  Outputs are written atomically, with fixed metadata so
that a rerun on the same data gives the same files.
"""

from __future__ import annotations

import io
import os
from collections.abc import Mapping, Sequence

import numpy as np

from signorini.artifacts import atomic_write_bytes

FIGURE3_NORMS = ("L4", "W14")
FIGURE3_LABELS = {"L4": r"$\|u-u_h\|_{L^4(\Omega)}$", "W14": r"$\|u-u_h\|_{W^{1,4}(\Omega)}$"}
REFERENCE_SLOPES = {"L4": 2.0, "W14": 1.0}  # the expected orders, drawn as h² and h¹


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"svg.hashsalt": "signorini", "font.size": 10})
    return plt


def _save(fig, path: str | os.PathLike) -> None:
    """Save atomically; PDF/PNG metadata without dates, so reruns are byte-stable."""
    fmt = os.path.splitext(str(path))[1].lstrip(".").lower()
    metadata = {"CreationDate": None, "ModDate": None} if fmt == "pdf" else {"Software": None}
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=150, metadata=metadata)
    atomic_write_bytes(path, buf.getvalue())


def figure2(fields: Mapping, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """Surface plots of ``u`` (left) and ``f`` (right) on the unit square, like the paper's Fig. 2."""
    plt = _pyplot()
    X, Y = fields["x"], fields["y"]
    fig = plt.figure(figsize=(11.0, 4.6))
    for k, (key, title) in enumerate((("u", "solution $u$"), ("f", "right-hand side $f = -\\Delta u + c\\,u$"))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        Z = fields[key]
        ax.plot_surface(X, Y, Z, cmap="viridis", rstride=2, cstride=2, linewidth=0.1, edgecolor="k", antialiased=True)
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        ax.set_title(title)
        ax.view_init(elev=28, azim=-125)
        ax.set_box_aspect((1.0, 1.0, 0.6))
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.04, top=0.92, wspace=0.08)
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)


def figure3(errors, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """``L⁴`` and ``W^{1,4}`` errors against ``h`` (double-logarithmic) with reference slopes h² and h¹.

    ``errors``: a frame with columns ``h``, ``L4``, ``W14``.
    """
    plt = _pyplot()
    h = errors["h"].to_numpy(dtype=float)
    fig, ax = plt.subplots(figsize=(6.0, 4.5))
    markers = {"L4": "o", "W14": "s"}
    for norm in FIGURE3_NORMS:
        e = errors[norm].to_numpy(dtype=float)
        (line,) = ax.loglog(h, e, marker=markers[norm], label=FIGURE3_LABELS[norm])
        # reference line through the coarsest point, shifted down by a factor of two
        order = REFERENCE_SLOPES[norm]
        ref = 0.5 * e[h.argmax()] * (h / h.max()) ** order
        slope = "h^2" if order == 2 else "h"
        ax.loglog(h, ref, linestyle="--", color=line.get_color(), alpha=0.7, label=f"${slope}$ (reference)")
    ax.set_xlabel("mesh width $h$")
    ax.set_ylabel("error")
    ax.set_title(r"$L^4$- and $W^{1,4}$-errors")
    ax.grid(True, which="both", linewidth=0.3, alpha=0.6)
    ax.legend(loc="best", fontsize=9)
    fig.tight_layout()
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)


# --- work-precision study ----------------------------------------------------------------------

WP_LABELS = {"L4": r"$L^4$", "W14": r"$W^{1,4}$"}
WP_TOL_MARKERS = {"exact": "P", "default": "*", "1e-02": "o", "1e-04": "s", "1e-06": "^", "1e-08": "D", "1e-10": "v"}


def _wp_marker(label: str) -> str:
    return WP_TOL_MARKERS.get(label, "h")


def work_precision_figure(df, figure_N: Sequence[int], out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """Algebraic error ``‖u_h^solver − u_h^exact‖`` (rows: ``L⁴``, ``W^{1,4}``) against solve time,
    log-log, one panel column per ``N`` of ``figure_N`` (default: coarsest, middle, finest).

    One colour and line per solver configuration (its tolerances loose to tight), one marker
    per tolerance (star: the solver's default); hollow markers: inaccurate (KKT residual above
    the tolerance); ×: failed, drawn at the top at the time of failure.  The discretisation
    error of the mesh is the solid horizontal line, 10⁻⁴ of it (Table 1's fifth digit) the
    dotted one; an algebraic error of exactly 0 (the pipeline's own solve) sits on the bottom edge.
    ``df``: the rows of ``work_precision.csv``.
    """
    from matplotlib.lines import Line2D
    from matplotlib.ticker import NullFormatter
    from matplotlib.transforms import blended_transform_factory

    from signorini.work_precision import FIGURE_NORMS
    from signorini.work_precision_report import tolerance_order

    plt = _pyplot()
    Ns = sorted(int(N) for N in df["N"].unique())
    cols = [int(N) for N in figure_N if int(N) in Ns] or sorted({Ns[0], Ns[len(Ns) // 2], Ns[-1]})
    configs = list(dict.fromkeys(df["config"]))
    colors = {c: plt.get_cmap("tab10")(k % 10) for k, c in enumerate(configs)}
    order = tolerance_order(df)
    fig, axes = plt.subplots(len(FIGURE_NORMS), len(cols), figsize=(4.1 * len(cols), 7.6), squeeze=False, sharex="col")
    for i, norm in enumerate(FIGURE_NORMS):
        alg_all = df[f"alg_{norm}"].to_numpy(dtype=float)
        positive = alg_all[np.isfinite(alg_all) & (alg_all > 0)]
        disc_min = float(df[f"disc_{norm}"].min())
        floor = min(float(positive.min()) if positive.size else disc_min, 1e-4 * disc_min) / 10.0
        for j, N in enumerate(cols):
            ax = axes[i, j]
            sub = df[df["N"] == N]
            disc = float(sub[f"disc_{norm}"].iloc[0])
            ax.axhline(disc, color="k", linewidth=1.2, zorder=1)
            ax.axhline(1e-4 * disc, color="k", linewidth=0.8, linestyle=":", zorder=1)
            top = blended_transform_factory(ax.transData, ax.transAxes)
            for config in configs:
                color = colors[config]
                runs = [sub[(sub["config"] == c) & (sub["tol_label"] == lab)] for c, lab in order if c == config]
                runs = [r.iloc[0] for r in runs if not r.empty]
                line_x, line_y = [], []
                for r in runs:
                    t, e, status = float(r["time_s"]), float(r[f"alg_{norm}"]), str(r["status"])
                    marker = _wp_marker(str(r["tol_label"]))
                    if status == "failed" and np.isfinite(t):
                        ax.plot([t], [0.96], marker="x", color=color, markersize=7, transform=top, clip_on=False)
                        continue
                    if not (np.isfinite(t) and np.isfinite(e)):
                        continue
                    y = max(e, floor)
                    hollow = status == "inaccurate"
                    ax.plot(
                        [t],
                        [y],
                        marker=marker,
                        color=color,
                        markerfacecolor="white" if hollow else color,
                        markersize=9 if marker == "*" else 6,
                        linestyle="none",
                        clip_on=False,
                        zorder=3,
                    )
                    if r["tol_label"] != "default":
                        line_x.append(t)
                        line_y.append(y)
                if len(line_x) > 1:
                    ax.plot(line_x, line_y, color=color, linewidth=0.9, alpha=0.7, zorder=2)
            ax.set_xscale("log")
            ax.set_yscale("log")
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.set_ylim(floor / 1.5, None)
            ax.grid(True, which="major", linewidth=0.3, alpha=0.6)
            if i == 0:
                ax.set_title(f"$h = 1/{N}$")
            if i == len(FIGURE_NORMS) - 1:
                ax.set_xlabel("solve time [s]")
            if j == 0:
                ax.set_ylabel(f"algebraic error in {WP_LABELS.get(norm, norm)}")
    handles = [
        Line2D([], [], color=colors[c], marker="o", label=str(df.loc[df["config"] == c, "label"].iloc[0]))
        for c in configs
    ]
    tol_labels = list(dict.fromkeys(lab for _, lab in order))
    names = {"exact": "exact (active set)", "default": "solver default"}
    handles += [
        Line2D([], [], color="0.3", marker=_wp_marker(lab), linestyle="none", label=names.get(lab, f"tol {lab}"))
        for lab in tol_labels
    ]
    handles += [
        Line2D([], [], color="0.3", marker="o", markerfacecolor="white", linestyle="none", label="inaccurate"),
        Line2D([], [], color="0.3", marker="x", linestyle="none", label="failed (at top)"),
        Line2D([], [], color="k", linewidth=1.2, label="discretisation error"),
        Line2D([], [], color="k", linewidth=0.8, linestyle=":", label=r"$10^{-4}\times$ discr. error"),
        Line2D([], [], color="none", label="error 0: bottom edge"),
    ]
    fig.legend(handles=handles, loc="lower center", ncol=6, fontsize=8, frameon=False)
    fig.suptitle(r"Work precision: $\|u_h^{\mathrm{solver}} - u_h^{\mathrm{exact}}\|$ against solve time")
    fig.tight_layout(rect=(0, 0.13, 1, 0.97))
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)


COST_NORMS = ("L4", "L16", "Linf", "W14", "W116", "W1inf", "H12")
COST_LABELS = {
    "L4": r"$L^4$",
    "L16": r"$L^{16}$",
    "Linf": r"$L^\infty$",
    "W14": r"$W^{1,4}$",
    "W116": r"$W^{1,16}$",
    "W1inf": r"$W^{1,\infty}$",
    "H12": r"$H^{1/2}(\partial\Omega)$",
}


def cost_of_accuracy(df, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """Left: total error ``‖u − u_h‖`` of the exact solver (the first ``exact`` configuration, the
    pipeline's) in every norm against total run time (assembly + solve) over the mesh sequence,
    log-log, with the fitted slope per norm.  Right: where the time goes, assembly and every
    exact solver configuration against the number of unknowns.  ``df``: ``work_precision.csv``."""
    from matplotlib.ticker import NullFormatter

    plt = _pyplot()
    exact = df[df["tol_label"] == "exact"]
    first = exact["config"].iloc[0]
    ex = exact[exact["config"] == first].sort_values("N")
    total = (ex["build_s"] + ex["time_s"]).to_numpy(dtype=float)
    fig, (ax, ax2) = plt.subplots(1, 2, figsize=(11.0, 4.6))
    for norm in COST_NORMS:
        if f"total_{norm}" not in ex.columns:
            continue
        e = ex[f"total_{norm}"].to_numpy(dtype=float)
        slope = np.polyfit(np.log(total), np.log(e), 1)[0] if len(e) > 1 else float("nan")
        ax.loglog(total, e, marker="o", markersize=4, label=f"{COST_LABELS.get(norm, norm)} (slope {slope:.2f})")
    e_top = ex[[f"total_{n}" for n in COST_NORMS if f"total_{n}" in ex.columns]].max(axis=1).to_numpy(dtype=float)
    for t, e, N in zip(total, e_top, ex["N"], strict=True):
        ax.annotate(f"1/{N}", (t, e), textcoords="offset points", xytext=(0, 6), ha="left", fontsize=8, rotation=40)
    e_all = ex[[f"total_{n}" for n in COST_NORMS if f"total_{n}" in ex.columns]].to_numpy(dtype=float)
    ax.set_ylim(np.nanmin(e_all) / 300.0, np.nanmax(e_all) * 4.0)  # room for the legend and the labels
    ax.set_xlabel("total run time: assembly + solve [s]")
    ax.set_ylabel(r"total error $\|u - u_h\|$")
    ax.set_title(f"Cost of accuracy: {ex['label'].iloc[0]}")
    ax.grid(True, which="major", linewidth=0.3, alpha=0.6)
    ax.legend(fontsize=8, loc="lower left", ncol=2)
    n = ex["n_dofs"].to_numpy(dtype=float)
    ax2.loglog(n, ex["build_s"], marker="s", color="0.3", label="assembly (mesh, A, b)")
    for config in dict.fromkeys(exact["config"]):
        sub = exact[exact["config"] == config].sort_values("N")
        ax2.loglog(sub["n_dofs"], sub["time_s"], marker="o", label=f"solve: {sub['label'].iloc[0]}")
    ref = float(ex["build_s"].iloc[0]) * n / n[0]
    ax2.loglog(n, ref, linestyle="--", color="0.6", label=r"$\propto$ unknowns")
    ax2.set_xlabel("unknowns $(N+1)^2$")
    ax2.set_ylabel("wall time [s]")
    ax2.set_title("Where the time goes")
    ax2.grid(True, which="major", linewidth=0.3, alpha=0.6)
    ax2.legend(fontsize=8, loc="upper left")
    for a in (ax, ax2):
        a.xaxis.set_minor_formatter(NullFormatter())
    fig.tight_layout()
    _save(fig, out_pdf)
    _save(fig, out_png)
    plt.close(fig)
