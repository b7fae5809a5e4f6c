"""Stage ``eoc_against_h``: the experimental orders of convergence (EOCs) of Table 2's seven norms
against the mesh width, from the paper's meshes (``table1_true.csv``, h = 1/101 … 1/501) on to the
scene ``fine``'s (``table1_fine.csv``, h = 1/501 … 1/4001), for the true norms (``<norm>_true``,
``fem.norms.true``) and the paper's conventions, beside the orders of the a priori estimates.

The EOC of a pair of consecutive meshes is ``fem.convergence.eoc`` (the paper's (27)),
``log(e_k/e_{k−1}) / log(h_k/h_{k−1})``, drawn at the finer mesh's ``h_k`` (the row label of
Table 2).  The two tables share the mesh h = 1/501; its row is read from the first.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from signorini.fem.convergence import eoc
from signorini.plotting import new_figure, save, style, styled
from signorini.published import TABLE2_NORMS, expected_rate, label_tex

if TYPE_CHECKING:  # pandas and matplotlib are imported where they are used
    import pandas as pd
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

# the panels: one per family of norms, its title and its norms (in Table 2's order)
PANELS = (
    (r"$L^p(\Omega)$ errors", ("L4", "L16", "Linf")),
    (r"$W^{1,p}(\Omega)$ errors", ("W14", "W116", "W1inf")),
    (r"$H^{1/2}(\partial\Omega)$ estimate", ("H12",)),
)
COLORS = {"L4": "C0", "L16": "C1", "Linf": "C2", "W14": "C0", "W116": "C1", "W1inf": "C2", "H12": "C3"}
KINDS = {  # column of the tables: how it is drawn and named (the conventions first: the true norms on top)
    "convention": {"linestyle": "--", "marker": "s", "markersize": 7, "label": "paper's convention (open squares)"},
    "true": {"linestyle": "-", "marker": "o", "markersize": 4, "label": "true norm (filled circles)"},
}


def read_errors(*table1_csvs: str | os.PathLike) -> pd.DataFrame:
    """The errors of the tables (columns ``h`` = ``1/N``, ``norm``, ``paper``, ``convention``,
    ``true``) as one frame with ``N`` and ``h`` as numbers and ``table``, the index of the table a row
    is read from, sorted by ``N``; a mesh in several tables is read from the first that holds it."""
    import pandas as pd

    frames = [
        pd.read_csv(path, usecols=["h", "norm", "paper", "convention", "true"], encoding="utf-8").assign(table=k)
        for k, path in enumerate(table1_csvs)
    ]
    frame = pd.concat(frames, ignore_index=True)
    frame["N"] = [int(label.split("/")[1]) for label in frame["h"]]
    frame["h"] = 1.0 / frame["N"]
    frame = frame.drop_duplicates(subset=["N", "norm"], keep="first")
    return frame.sort_values(["N", "norm"], kind="stable").reset_index(drop=True)


def eoc_series(frame: pd.DataFrame, norm: str, column: str) -> tuple[np.ndarray, np.ndarray]:
    """The finer mesh width of each pair of consecutive meshes and the EOC (``fem.convergence.eoc``)
    of ``column`` (``true`` or ``convention``) of ``norm`` between them."""
    sub = frame[frame["norm"] == norm].sort_values("N")
    h = sub["h"].to_numpy(dtype=float)
    return h[1:], eoc(h, sub[column].to_numpy(dtype=float))[1:]


def style_handles() -> list:
    """Legend entries of the line styles: the true norms, the conventions, the expected orders."""
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color="0.3", markerfacecolor="0.3" if column == "true" else "white", **kind)
        for column, kind in KINDS.items()
    ]
    handles.append(Line2D([], [], color="0.3", linestyle=":", label="expected order minus ε (Table 2, row theo.)"))
    return handles


@styled
def eoc_panel(frame: pd.DataFrame, norms: Sequence[str], ax: Axes | None = None, title: str = "") -> Axes:
    """The EOCs of ``norms`` against ``h`` (log scale) on ``ax``: the true norms solid with filled
    circles, the conventions dashed with open squares, the expected order of each norm
    (``published.expected_rate``) a dotted horizontal line over the same ``h``; a legend of the
    norms' colours.  Returns the axes."""
    if ax is None:
        ax = new_figure(figsize=(5.0, 4.0)).subplots()
    for norm in norms:
        color = COLORS.get(norm, "k")
        for column, kind in KINDS.items():
            h, rates = eoc_series(frame, norm, column)
            face = color if column == "true" else "white"
            line_label = label_tex(norm, domain=False) if column == "true" else None
            ax.plot(h, rates, color=color, markerfacecolor=face, linewidth=1.3, **{**kind, "label": line_label})
        order = expected_rate(norm)
        if order is not None:
            ax.plot(h[[0, -1]], [order, order], color=color, linestyle=":", linewidth=1.2)
    ax.set_xscale("log")
    ticks = np.sort(frame["h"].unique())[:-1]  # the finer mesh of each pair
    ax.set_xticks(ticks, [f"1/{round(1.0 / h)}" for h in ticks], rotation=45, fontsize=8)
    ax.minorticks_off()
    ax.set_xlabel("mesh width $h$ (the finer mesh of each pair)")
    ax.set_ylabel("EOC")
    ax.set_title(title)
    ax.grid(True, which="both", linewidth=0.3, alpha=0.6)
    ax.legend(loc="center left", fontsize=9)
    return ax


def _mark_paper_meshes(ax: Axes, frame: pd.DataFrame, paper_finest: int) -> None:
    """Shade the EOCs between the paper's meshes: those drawn at ``h ≥ 1/paper_finest`` (the coarsest
    mesh has no EOC)."""
    drawn = np.sort(frame["h"].unique())[:-1]  # the finer mesh of each pair
    paper = drawn[drawn >= 1.0 / paper_finest]
    if paper.size:
        ax.axvspan(paper.min() / 1.08, paper.max() * 1.08, color="0.92", zorder=0)


@styled
def eoc_figure(frame: pd.DataFrame, panels: Sequence = PANELS, paper_finest: int = 501) -> Figure:
    """One panel per family of norms (``PANELS``): ``eoc_panel`` of each, the EOCs of the paper's
    meshes (h ≥ 1/``paper_finest``) shaded.  Returns the figure."""
    fig = new_figure(figsize=(15.0, 5.2))
    axes = fig.subplots(1, len(panels))
    for ax, (title, norms) in zip(np.atleast_1d(axes), panels, strict=True):
        eoc_panel(frame, norms, ax=ax, title=title)
        _mark_paper_meshes(ax, frame, paper_finest)
    fig.suptitle(
        r"EOC $= \log(e_k/e_{k-1})\,/\,\log(h_k/h_{k-1})$ of the errors $e_k = \|u-u_h\|$ on consecutive "
        f"meshes; shaded: the pairs of the paper's meshes ($h \\geq 1/{paper_finest}$)",
        fontsize=11,
    )
    fig.legend(handles=style_handles(), loc="lower center", ncol=3, fontsize=9, frameon=False)
    return fig


def eoc_against_h_stage(
    true_table1_csv: str | os.PathLike, fine_table1_csv: str | os.PathLike, outputs: Mapping[str, str | os.PathLike]
) -> None:
    """Stage ``eoc_against_h``: ``eoc_figure`` of the two tables' errors, saved to ``outputs``
    (keys ``pdf``, ``png``)."""
    frame = read_errors(true_table1_csv, fine_table1_csv)
    missing = sorted(set(TABLE2_NORMS) - set(frame["norm"]))
    if missing:
        raise ValueError(f"{true_table1_csv}, {fine_table1_csv}: no rows of the norms {missing}")
    fig = eoc_figure(frame, paper_finest=int(frame["N"][frame["table"] == 0].max()))
    with style():
        fig.tight_layout(rect=(0.0, 0.06, 1.0, 0.95))
    save(fig, outputs["pdf"], outputs["png"])
