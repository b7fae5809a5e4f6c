"""Figures 2 and 3 of the paper, drawn on a given figure/axes (or a new one) and returned;
the stages ``figure2`` and ``figure3`` save them.

``figure2`` plots the sampled ``u`` and ``f`` (the ``sample`` stage's artifact), ``figure3`` the
``L⁴`` and ``W^{1,4}`` errors against ``h`` with reference slopes of the expected orders.

The stages draw rounded data, so that round-off of another processor cannot move a single
coordinate in the PDF: Figure 3 the errors as Table 1 prints them (``formatting.certified_errors``),
Figure 2 the sampled fields to ``FIELD_DIGITS`` significant digits.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

from signorini.plotting import new_figure, save, style, styled
from signorini.published import FIGURE3_NORMS, error_label_tex, expected_rate

MARKERS = {"L4": "o", "W14": "s"}
# u and f are exact functions: only a libm's last bits can differ between processors; 6 digits are
# far below a pixel, and a last-bit change crosses a rounding boundary of one of the 2 · 161² values
# with probability ~1e-5 (10 digits: ~0.1, and the PDF writes coordinates to 10 decimals)
FIELD_DIGITS = 6
# the right-hand side, with its constant defined: c is the coefficient of the zero-order term of
# -Δu + c u (fem.problem.Problem.c; the paper's problem (S) has c = 1, its form being the H¹ inner product)
F_TITLE = "right-hand side $f = -\\Delta u + c\\,u$ ($c$: the reaction coefficient)"


@styled
def figure2(fields: Mapping, fig=None):
    """Surface plots of ``u`` (left) and ``f`` (right) on the unit square, like the paper's Fig. 2.

    ``fields``: arrays ``x``, ``y``, ``u``, ``f`` on a grid; ``fig``: a matplotlib figure to
    draw on (default: a new 11 × 4.6 in figure).  Returns the figure.
    """
    fig = fig if fig is not None else new_figure(figsize=(11.0, 4.6))
    X, Y = fields["x"], fields["y"]
    for k, (key, title) in enumerate((("u", "solution $u$"), ("f", F_TITLE))):
        ax = fig.add_subplot(1, 2, k + 1, projection="3d")
        ax.plot_surface(
            X, Y, fields[key], cmap="viridis", rstride=2, cstride=2, linewidth=0.1, edgecolor="k", antialiased=True
        )
        ax.set_xlabel("$x_1$")
        ax.set_ylabel("$x_2$")
        ax.set_title(title)
        ax.view_init(elev=28, azim=-125)
        ax.set_box_aspect((1.0, 1.0, 0.6))
    fig.subplots_adjust(left=0.02, right=0.98, bottom=0.04, top=0.92, wspace=0.08)
    return fig


@styled
def figure3(errors, ax=None, norms: Sequence[str] = FIGURE3_NORMS):
    """The errors in ``norms`` (the paper's ``L⁴`` and ``W^{1,4}``) against ``h``, double-logarithmic,
    each with a reference line ``h^r`` of its expected order ``r`` through the coarsest point,
    halved.  ``errors``: a frame with columns ``h`` and the norms.  Returns the axes."""
    if ax is None:
        ax = new_figure(figsize=(6.0, 4.5)).subplots()
    h = errors["h"].to_numpy(dtype=float)
    for norm in norms:
        e = errors[norm].to_numpy(dtype=float)
        (line,) = ax.loglog(h, e, marker=MARKERS.get(norm, "o"), label=error_label_tex(norm))
        order = expected_rate(norm)
        ref = 0.5 * e[h.argmax()] * (h / h.max()) ** order
        slope = "h" if order == 1 else f"h^{order:g}"
        ax.loglog(h, ref, linestyle="--", color=line.get_color(), alpha=0.7, label=f"${slope}$ (reference)")
    ax.set_xlabel("mesh width $h$")
    ax.set_ylabel("error")
    ax.set_title(r"$L^4$- and $W^{1,4}$-errors")
    ax.grid(True, which="both", linewidth=0.3, alpha=0.6)
    ax.legend(loc="best", fontsize=9)
    return ax


def rounded_fields(fields: Mapping, digits: int = FIELD_DIGITS) -> dict:
    """The sampled arrays rounded to ``digits`` significant digits (decimal rounding, as printed)."""
    import numpy as np

    def rnd(a):
        a = np.asarray(a, dtype=float)
        return np.array([float(f"{v:.{digits - 1}e}") for v in a.ravel()]).reshape(a.shape)

    return {k: rnd(v) if np.asarray(v).dtype.kind == "f" else v for k, v in fields.items()}


def figure2_stage(fields_npz: str | os.PathLike, out_pdf: str | os.PathLike, out_png: str | os.PathLike) -> None:
    """Stage ``figure2``: Figure 2 from the sampled fields (rounded: ``rounded_fields``)."""
    from signorini.pipeline.artifacts import load_npz

    save(figure2(rounded_fields(load_npz(fields_npz))), out_pdf, out_png)


def figure3_stage(
    scene_N: Sequence[int],
    norm_jsons: Mapping[str, Sequence[str]],
    out_pdf: str | os.PathLike,
    out_png: str | os.PathLike,
) -> None:
    """Stage ``figure3``: Figure 3 from the norm artifacts of the rendered scene, each error rounded
    to the digits Table 1 prints."""
    from signorini.formatting import certified_errors
    from signorini.studies.scene.store import read_errors, read_uncertainties

    errors = read_errors(scene_N, norm_jsons)
    names = list(norm_jsons)
    values, _ = certified_errors(errors, read_uncertainties(scene_N, norm_jsons), names)
    for j, name in enumerate(names):
        errors[name] = [row[j] for row in values]
    ax = figure3(errors)
    with style():  # the layout measures the tick labels: in the style they are drawn in
        ax.figure.tight_layout()
    save(ax.figure, out_pdf, out_png)
