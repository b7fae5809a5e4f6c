"""Figures of the work-precision study, drawn from its runs (``table.Run``) on a given figure (or a
new one) and returned; the stage ``work_precision_figures`` saves them."""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from signorini import intervals
from signorini.peers import PEER_SOLVERS
from signorini.plotting import new_figure, save, styled
from signorini.published import PAPER_NORMS, label_tex
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.study import FIGURE_NORMS
from signorini.studies.work_precision.table import Run, sweeps

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

# by tolerance label; any other tolerance: "h"
TOL_MARKERS = {"exact": "P", "default": "*", "1e-02": "o", "1e-04": "s", "1e-06": "^", "1e-08": "D", "1e-10": "v"}
# Okabe & Ito's colour-blind-safe palette, in an order whose neighbours differ most; its yellow
# (#F0E442), too weak on white for hollow markers, replaced by a mid grey
OKABE_ITO = ["#0072B2", "#E69F00", "#009E73", "#D55E00", "#CC79A7", "#56B4E9", "#000000", "#8C8C8C"]
MAX_SERIES = len(OKABE_ITO)
FAMILIES = {"snes": "PETSc SNES VI", "tao": "PETSc TAO"}  # by the kind of PETSc object (peers.PEER_SOLVERS)
TIME_LABEL = "solve time [CPU s]"
# the time panel's series beyond the figure's palette (exact configurations the work-precision figure
# leaves out): Paul Tol's wine, teal, olive and indigo, none of them an Okabe–Ito colour
EXTRA_COLORS = ["#882255", "#44AA99", "#999933", "#332288"]
MARKERS = ("o", "^", "D", "v", "P", "X", "<", ">", "p", "h", "d", "*")  # one per series ("s": the assembly)
ASSEMBLY = {"color": "0.3", "marker": "s"}


def family(run: Run) -> str:
    """A run's solver family: PETSc SNES, PETSc TAO (a peer, by its kind of PETSc object) or the
    solver as the table names it."""
    return FAMILIES[PEER_SOLVERS[run.solver]] if run.kind is Kind.PEER else run.solver


def _fastest_by_config(runs: Sequence[Run]) -> dict[str, float]:
    """Config → its fewest CPU seconds among ``runs`` (NaN: none timed), configs sorted."""
    times: dict[str, list[float]] = {}
    for r in runs:
        times.setdefault(r.config, []).append(r.time_s)
    return {c: min((t for t in times[c] if not math.isnan(t)), default=math.nan) for c in sorted(times)}


def figure_series(runs: Sequence[Run], table1_norms: Sequence[str] | None = None) -> list[str]:
    """The configurations drawn: every exact one, and per other solver family the configuration
    whose selected run on the finest mesh (``selection``) is the fastest (none has a selected
    tolerance: the family's fastest run of status ok there; its first configuration otherwise).
    A family none of whose runs is ``ok`` is left out: its failures are in the report.  Beyond
    ``MAX_SERIES`` (the palette), only the first exact configuration of each route and start stays
    (a backend variant goes, another route such as multigrid stays), and if that is still too many,
    the fastest exact configuration of each start on the finest mesh; their runs are in the CSV and
    the report."""
    from signorini.studies.work_precision.selection import selected_runs, table1_norms_of

    exact = list(dict.fromkeys(r.config for r in runs if r.kind is Kind.EXACT))
    finest = max(r.N for r in runs)
    keeps = {r.config: r.time_s for r in selected_runs(runs, table1_norms_of(runs, table1_norms)) if r.N == finest}
    last = [r for r in runs if r.N == finest and r.status == "ok"]
    chosen = list(exact)
    others = [r for r in runs if r.config not in exact]
    for fam in dict.fromkeys(family(r) for r in others):
        members = list(dict.fromkeys(r.config for r in others if family(r) == fam))
        if not any(r.status == "ok" for r in others if r.config in members):
            continue  # nothing but failures and skips: in the report, not on the axes
        candidates = {c: keeps[c] for c in members if c in keeps}
        if not candidates:
            ok = [r for r in last if r.config in members]
            candidates = _fastest_by_config(ok) if ok else {members[0]: 0.0}
        chosen.append(min(candidates, key=candidates.get))
    if len(chosen) > MAX_SERIES:
        start = {r.config: r.start for r in runs}
        solver = {r.config: r.solver for r in runs}
        seconds = _fastest_by_config([r for r in runs if r.N == finest])
        fastest_first = sorted(exact, key=lambda c: seconds.get(c, float("inf")))
        # by route and start (the first configuration: the default backend), then by start (the fastest)
        for group, order in ((lambda c: (solver[c], start[c]), exact), (lambda c: start[c], fastest_first)):
            if len(chosen) > MAX_SERIES:
                first = {group(c): c for c in reversed(order)}
                chosen = [c for c in chosen if c not in exact or first.get(group(c)) == c]
    return chosen


def _colors(configs: Sequence[str]) -> dict[str, str]:
    """One Okabe–Ito colour per drawn configuration (cycled beyond eight)."""
    return {c: OKABE_ITO[k % len(OKABE_ITO)] for k, c in enumerate(configs)}


def _run_points(ax, runs: Sequence[Run], color: str, norm: str, floor: float, line: str) -> None:
    """One configuration's runs on one panel, loose to tight: a marker per tolerance, a line
    (``line``: its style) through the sweep."""
    from matplotlib.transforms import blended_transform_factory

    top = blended_transform_factory(ax.transData, ax.transAxes)
    line_x, line_y = [], []
    for r in runs:
        t, e, marker = r.time_s, r.alg[norm], TOL_MARKERS.get(r.tol_label, "h")
        if r.status == "failed" and np.isfinite(t):
            ax.plot([t], [0.96], marker="x", color=color, markersize=7, transform=top, clip_on=False)
        elif np.isfinite(t) and np.isfinite(e):
            y, face = max(e, floor), "white" if r.status == "inaccurate" else color
            ax.plot([t], [y], marker=marker, color=color, markerfacecolor=face, markersize=9 if marker == "*" else 6,
                    linestyle="none", clip_on=False, zorder=3)
            if r.tol_label != "default":
                line_x.append(t)
                line_y.append(y)
    if len(line_x) > 1:
        ax.plot(line_x, line_y, color=color, linewidth=0.9, alpha=0.7, zorder=2, linestyle=line)


def _legend_handles(labels: dict[str, str], colors: dict[str, str], lines: dict[str, str], tolerances) -> tuple:
    """(one handle per drawn configuration, the marker and line keys)."""
    from matplotlib.lines import Line2D

    solvers = [Line2D([], [], color=colors[c], marker="o", linestyle=lines[c], label=labels[c]) for c in colors]
    names = {"exact": "exact (active set)", "default": "solver default"}
    keys = [
        Line2D([], [], color="0.3", marker=TOL_MARKERS.get(t, "h"), linestyle="none", label=names.get(t, f"tol {t}"))
        for t in tolerances
    ]
    keys += [
        Line2D([], [], color="0.3", marker="o", markerfacecolor="white", linestyle="none", label="inaccurate"),
        Line2D([], [], color="0.3", marker="x", linestyle="none", label="failed (at top)"),
        Line2D([], [], color="0.2", linewidth=1.2, label="discretisation error"),
        Line2D([], [], color="0.2", linewidth=0.8, linestyle=":", label=r"$10^{-4}\times$ discr. error"),
    ]
    return solvers, keys


@styled
def work_precision_figure(runs: Sequence[Run], figure_N: Sequence[int] = (), fig: Figure | None = None) -> Figure:
    """Algebraic error ``‖u_h^solver − u_h^exact‖`` (rows: ``L⁴``, ``W^{1,4}``) against solve time,
    log-log, one panel column per ``N`` of ``figure_N`` (default: coarsest, middle, finest).

    Drawn (``figure_series``): every exact solver and the fastest configuration
    of each other solver family to Table 1's digits on the finest mesh, each with its whole
    tolerance sweep (a line through its tolerances loose to tight; dashed: PETSc), in the
    Okabe–Ito palette; one marker per tolerance (star: the solver's default); hollow markers:
    inaccurate (KKT residual above the tolerance); ×: failed, drawn at the top at the time of
    failure.  The discretisation error of the mesh is the solid horizontal line, 10⁻⁴ of it
    (Table 1's fifth digit) the dotted one; an algebraic error of exactly 0 (the pipeline's own
    solve) sits on the bottom edge.  The legends sit below the panels.  Every configuration's
    runs are in ``work_precision.csv`` and ``work_precision.md``.  ``runs``: the rows of
    ``work_precision.csv``.  Returns the figure.
    """
    from matplotlib.ticker import NullFormatter

    Ns = sorted({r.N for r in runs})
    cols = [int(N) for N in figure_N if int(N) in Ns] or sorted({Ns[0], Ns[len(Ns) // 2], Ns[-1]})
    configs = figure_series(runs)
    shown = [r for r in runs if r.config in configs]
    order = sweeps(shown)
    tolerances = list(dict.fromkeys(lab for _, lab in order))
    lines = {r.config: "--" if r.kind is Kind.PEER else "-" for r in shown}  # dashed: the PETSc peers
    ncol = 4 if len(cols) > 2 else 3
    solver_rows = -(-len(configs) // ncol) + 1  # the configurations and the legend's title
    key_rows = -(-(len(tolerances) + 4) // 6)
    height = 6.4 + 0.24 * (solver_rows + key_rows)
    fig = fig if fig is not None else new_figure(figsize=(4.2 * len(cols), height))
    colors = _colors(configs)
    axes = fig.subplots(len(FIGURE_NORMS), len(cols), squeeze=False, sharex="col")
    for i, norm in enumerate(FIGURE_NORMS):
        alg_all = np.array([r.alg[norm] for r in shown], dtype=float)
        positive = alg_all[np.isfinite(alg_all) & (alg_all > 0)]
        disc_min = float(np.nanmin([r.disc[norm] for r in runs]))
        floor = min(float(positive.min()) if positive.size else disc_min, 1e-4 * disc_min) / 10.0
        for j, N in enumerate(cols):
            ax, disc = axes[i, j], next(r.disc[norm] for r in runs if r.N == N)
            ax.axhline(disc, color="0.2", linewidth=1.2, zorder=1)
            ax.axhline(1e-4 * disc, color="0.2", linewidth=0.8, linestyle=":", zorder=1)
            for config in configs:
                mine = [by[N] for (c, _), by in order.items() if c == config and N in by]
                _run_points(ax, mine, colors[config], norm, floor, lines[config])
            ax.set(xscale="log", yscale="log", ylim=(floor / 1.5, None))
            ax.xaxis.set_minor_formatter(NullFormatter())
            ax.grid(True, which="major", linewidth=0.3, alpha=0.6)
            if i == 0:
                ax.set_title(f"$h = 1/{N}$")
            if i == len(FIGURE_NORMS) - 1:
                ax.set_xlabel(TIME_LABEL)
            if j == 0:
                ax.set_ylabel(f"algebraic error in {label_tex(norm, domain=False)}")
    solvers, keys = _legend_handles({r.config: r.label for r in shown}, colors, lines, tolerances)
    row = 0.24 / fig.get_figheight()  # one legend row, as a fraction of the figure's height
    title = "exact solvers and the fastest configuration of each solver family (every run: work_precision.csv)"
    below = {"loc": "lower center", "fontsize": 8, "frameon": False}
    fig.legend(handles=keys, bbox_to_anchor=(0.5, 0.0), ncol=6, **below)
    fig.legend(handles=solvers, bbox_to_anchor=(0.5, row * (key_rows + 0.3)), ncol=ncol, title=title, title_fontsize=8,
               **below)
    bottom = row * (solver_rows + key_rows + 0.8)
    fig.suptitle(r"Work precision: $\|u_h^{\mathrm{solver}} - u_h^{\mathrm{exact}}\|$ against solve time")
    fig.tight_layout(rect=(0, bottom, 1, 0.97))
    return fig


def _exact_runs(runs: Sequence[Run]) -> list[Run]:
    """The first exact configuration's runs (the pipeline's solver), sorted by N."""
    exact = [r for r in runs if r.kind is Kind.EXACT]
    return sorted((r for r in exact if r.config == exact[0].config), key=lambda r: r.N)


@styled
def cost_panel(runs: Sequence[Run], ax: Axes | None = None) -> Axes:
    """Total error ``‖u − u_h‖`` of the exact solver in every norm of the paper against total run
    time (assembly + solve) over the mesh sequence, log-log, with the fitted slope per norm (one
    colour and marker per norm)."""
    ax = ax if ax is not None else new_figure(figsize=(5.5, 4.6)).subplots()
    ex = _exact_runs(runs)
    total = np.array([r.build_s + r.time_s for r in ex])
    norms = [n for n in PAPER_NORMS if n in ex[0].total]
    values = np.array([[r.total[n] for n in norms] for r in ex])  # runs × norms
    for k, norm in enumerate(norms):
        e = values[:, k]
        slope = intervals.exponent(total, e).value  # the least-squares slope the findings fit too
        label = f"{label_tex(norm, domain=False)} (slope {slope:.2f})"
        ax.loglog(total, e, marker=MARKERS[k % len(MARKERS)], markersize=4, label=label)
    # each mesh's h above its largest error, horizontal; the limits leave room for these labels
    # (top), the legend (bottom) and the first and last label (left and right)
    # (every other one higher: neighbouring run times can be close)
    tops = np.nanmax(values, axis=1)
    for k, (t, e, N) in enumerate(zip(total, tops, [r.N for r in ex], strict=True)):
        ax.annotate(
            f"1/{N}", (t, e), textcoords="offset points", xytext=(0, 6 + 10 * (k % 2)), ha="center", fontsize="x-small"
        )
    ax.text(0.02, 0.98, "labels: mesh width $h$", transform=ax.transAxes, ha="left", va="top", fontsize="x-small")
    ax.set_ylim(np.nanmin(values) / 300.0, np.nanmax(values) * 8.0)
    ax.set_xlim(total.min() / 1.8, total.max() * 1.8)
    ax.set(xlabel="total run time: assembly + solve [s]", ylabel=r"total error $\|u - u_h\|$")
    ax.set_title(f"Cost of accuracy: {ex[0].label}")
    ax.grid(True, which="major", linewidth=0.3, alpha=0.6)
    ax.legend(fontsize=8, loc="lower left", ncol=2)
    return ax


def time_series(runs: Sequence[Run], table1_norms: Sequence[str] | None = None) -> dict[str, dict]:
    """The solve-time series of ``time_panel``: the selected runs (``selection``) of every exact
    configuration and of the PETSc peers ``figure_series`` draws, each with its times, their
    intervals (``yerr``: below and above), its exponent ``p`` (time ∝ unknowns^p), and a colour and
    marker of its own (the colours of ``work_precision_figure``; ``EXTRA_COLORS`` for the rest)."""
    from signorini.studies.work_precision.selection import selected_runs, table1_norms_of

    norms = table1_norms_of(runs, table1_norms)
    drawn = figure_series(runs, norms)
    palette = _colors(drawn)
    extra = itertools.cycle(EXTRA_COLORS)
    sel = selected_runs(runs, norms)
    exact = list(dict.fromkeys(r.config for r in sel if r.kind is Kind.EXACT))
    peers = [c for c in dict.fromkeys(r.config for r in sel if r.kind is Kind.PEER) if c in drawn]
    series = {}
    for k, config in enumerate(exact + peers):
        rows = sorted((r for r in sel if r.config == config), key=lambda r: r.N)
        times = [r.time_estimate() for r in rows]
        value = np.array([t.value for t in times])
        lo, hi = np.array([t.interval or (t.value, t.value) for t in times]).T
        n_dofs = np.array([r.n_dofs for r in rows], dtype=float)
        series[config] = {
            "label": rows[0].label,
            "peer": config in peers,
            "n_dofs": n_dofs,
            "time_s": value,
            "yerr": [value - lo, hi - value],
            "p": intervals.exponent(list(n_dofs), times).value,
            "color": palette.get(config) or next(extra),
            "marker": MARKERS[k % len(MARKERS)],
        }
    return series


@styled
def time_panel(runs: Sequence[Run], ax: Axes | None = None) -> Axes:
    """Where the time goes: assembly and the selected runs of the exact configurations against the
    unknowns; dashed: the drawn PETSc peers' selected runs, with their exponents (``time_series``);
    bars: the times' intervals (``intervals``); the legend below the axes."""
    ax = ax if ax is not None else new_figure(figsize=(5.5, 6.0)).subplots()
    ex = _exact_runs(runs)
    n = np.array([r.n_dofs for r in ex], dtype=float)
    build = np.array([r.build_s for r in ex])
    handles = ax.loglog(n, build, **ASSEMBLY, label="assembly (mesh, A, b)")
    for v in time_series(runs).values():
        label = f"{v['label']} ($p$ = {v['p']:.2f})" if v["peer"] else f"solve: {v['label']}"
        style = {"markersize": 4, "linestyle": "--"} if v["peer"] else {"markersize": 5, "linestyle": "-"}
        style |= {"color": v["color"], "marker": v["marker"], "capsize": 2, "label": label}
        handles.append(ax.errorbar(v["n_dofs"], v["time_s"], yerr=v["yerr"], **style))
    handles += ax.loglog(n, build[0] * n / n[0], linestyle=":", color="0.6", label=r"$\propto$ unknowns")
    ax.set(xlabel="unknowns $(N+1)^2$", ylabel=TIME_LABEL.replace("solve time", "time"), title="Where the time goes")
    ax.grid(True, which="major", linewidth=0.3, alpha=0.6)
    # below the axes: inside, the many lines of the peers leave no free corner
    ax.legend(
        handles=handles, fontsize="x-small", loc="upper center", bbox_to_anchor=(0.5, -0.16), ncol=2, frameon=False
    )
    return ax


@styled
def cost_of_accuracy(runs: Sequence[Run], fig: Figure | None = None) -> Figure:
    """``cost_panel`` (left) and ``time_panel`` (right) side by side.  ``runs``: ``work_precision.csv``."""
    from matplotlib.ticker import NullFormatter

    fig = fig if fig is not None else new_figure(figsize=(11.0, 5.6))
    ax, ax2 = fig.subplots(1, 2)
    cost_panel(runs, ax)
    time_panel(runs, ax2)
    rows = -(-len(ax2.get_legend_handles_labels()[0]) // 2)  # time_panel's legend below it
    fig.set_size_inches(11.0, 4.6 + 0.17 * rows)
    for a in (ax, ax2):
        a.xaxis.set_minor_formatter(NullFormatter())
    fig.tight_layout()
    return fig


def figures_stage(csv_path: str | os.PathLike, figure_N: Sequence[int], outs) -> None:
    """Stage ``work_precision_figures`` (``outs``: ``pdf``, ``png``, ``cost_pdf``, ``cost_png``)."""
    from signorini.studies.work_precision.table import read_runs

    runs = read_runs(csv_path)
    save(work_precision_figure(runs, figure_N), outs["pdf"], outs["png"])
    save(cost_of_accuracy(runs), outs["cost_pdf"], outs["cost_png"])
