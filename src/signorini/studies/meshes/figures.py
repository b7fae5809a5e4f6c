"""The figure of the mesh-family study, drawn on given axes (or a new figure) and returned: each
norm's rate on each family beside the order of Theorem 6.1, and the errors against the number of
unknowns (the paper's Figure 3, per family)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from signorini.plotting import new_figure, styled
from signorini.studies.meshes.rates import FamilyScene

MARKERS = "osD^v<>ph*"
ERROR_NORMS = ("L4_true", "W14_true")  # the paper's Figure 3 plots L⁴ and W^{1,4}


def _rates_panel(ax, table: pd.DataFrame, scenes: Sequence[FamilyScene], column: str, uniform_only: bool) -> None:
    norms = list(dict.fromkeys(table["norm"]))
    x = np.arange(len(norms))
    width = 0.8 / max(len(scenes), 1)
    for k, s in enumerate(scenes):
        if uniform_only and not s.quasi_uniform:
            continue
        sel = table[table["scene"] == s.scene].set_index("norm").reindex(norms)
        offset = (k - (len(scenes) - 1) / 2) * width
        ax.plot(x + offset, sel[column], MARKERS[k % len(MARKERS)], color=f"C{k}", ms=5, ls="none", label=s.label)
    expected = table.drop_duplicates("norm").set_index("norm").reindex(norms)["expected"].to_numpy(dtype=float)
    ax.hlines(expected, x - 0.45, x + 0.45, colors="k", lw=1.2, label="Theorem 6.1 (order − ε)")
    ax.set_xticks(x, norms, rotation=45, ha="right", fontsize=8)
    ax.set_xlim(-0.6, len(norms) - 0.4)
    ax.set_ylabel("order of convergence")
    ax.grid(axis="y", alpha=0.3)


def _errors_panel(ax, scenes: Sequence[FamilyScene], norm: str) -> None:
    for k, s in enumerate(scenes):
        if norm in s.norms:
            n, e = s.meshes["n_vertices"].to_numpy(dtype=float), s.errors[norm].to_numpy(dtype=float)
            ax.loglog(n, e, MARKERS[k % len(MARKERS)] + "-", color=f"C{k}", ms=4, lw=1, label=s.label)
    ax.set_xlabel("unknowns n")
    ax.set_ylabel(f"error ({norm})")
    ax.grid(alpha=0.3, which="both")


@styled
def rates_figure(table: pd.DataFrame, scenes: Sequence[FamilyScene], axes=None):
    """Top: the slope against h on the quasi-uniform families, and the order against the unknowns
    on every family (``table``: ``rates.rates_table``); bottom: the errors in ``ERROR_NORMS``
    against the unknowns.  ``axes``: a 2 × 2 array.  Returns it."""
    if axes is None:
        axes = new_figure(figsize=(11.0, 8.4)).subplots(2, 2)
    (slopes, orders), lower = axes
    _rates_panel(slopes, table, scenes, "slope_h", uniform_only=True)
    _rates_panel(orders, table, scenes, "order_n", uniform_only=False)
    slopes.set_title("slope of log e against log h (quasi-uniform families)", fontsize="medium")
    orders.set_title("order against the unknowns n: −2 d log e / d log n", fontsize="medium")
    for ax, norm in zip(lower, ERROR_NORMS, strict=True):
        _errors_panel(ax, scenes, norm)
    lower[0].set_title("error against the unknowns (the paper's Figure 3, per family)", fontsize="medium")
    # one legend below the panels, where it hides no marker
    handles, labels = orders.get_legend_handles_labels()
    fig = slopes.figure
    fig.legend(handles, labels, loc="lower center", ncol=4, fontsize=8, frameon=False)
    fig.tight_layout(rect=(0.0, 0.08, 1.0, 1.0))
    return axes
