"""Tables 1 and 2 in the paper's layout (CSV, Markdown, LaTeX): the stages ``table1`` and
``table2``.  Rendering only: the values are the norm artifacts and ``eoc.csv`` of the scene.

Each value is written with the digits its uncertainty certifies (``signorini.formatting``): an
error with ``certified_digits(e, δe)`` significant digits (at most 5), where ``δe`` is the
norm artifact's algebraic-error uncertainty; an EOC with ``certified_decimals`` of its
propagated uncertainty (``fem.convergence.eoc_uncertainty``, ``regression_uncertainty``; at
most 4).  CSV, Markdown and LaTeX carry the same rounded numbers."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np

from signorini.formatting import (
    certified_decimals,
    certified_errors,
    csv_text,
    h_label,
    md_table,
    sci_md,
    sci_tex,
    sig_csv,
    tex_h,
    tex_table,
)
from signorini.pipeline.artifacts import atomic_write_text
from signorini.published import TABLE1_NORMS, TABLE2_NORMS, THEORETICAL_ORDERS, label_md, label_tex

TABLE1_CAPTION = (
    "Absolute error u − u_h between the analytic solution u and the finite element "
    "approximation u_h for different mesh widths h in various norms."
)
TABLE2_CAPTION = (
    "Experimental orders of convergence (EOCs) for different mesh widths h; "
    "regr. = least-squares slope of log e against log h, theo. = expected order (minus ε)."
)
DIGITS_NOTE = (
    "Every value carries the digits that round-off in u_h cannot change (at most the paper's 5 significant "
    "digits), from the algebraic-error estimate recorded with it."
)
DIGITS_NOTE_EOC = (
    "Every EOC carries the decimals that round-off in u_h cannot change (at most the paper's 4), "
    "from the propagated algebraic-error estimates of the errors."
)
TABLE1_CAPTION_TEX = (
    r"Absolute error $u - u_h$ between the analytic solution $u$ and the finite element "
    r"approximation $u_h$ for different mesh widths $h$ in various norms."
)
TABLE2_CAPTION_TEX = (
    r"Experimental orders of convergence (EOCs) for different mesh widths $h$; "
    r"regr.\ = least-squares slope of $\log e$ against $\log h$, theo.\ = expected order (minus $\varepsilon$)."
)


def _require(frame, norms: Sequence[str], table: str) -> None:
    missing = [n for n in norms if n not in frame.columns]
    if missing:
        raise KeyError(f"{table} needs the norms {missing}")


def _write(outs: Mapping[str, str | os.PathLike], csv: str, md: str, tex: str) -> None:
    atomic_write_text(outs["csv"], csv)
    atomic_write_text(outs["md"], md)
    atomic_write_text(outs["tex"], tex)


def error_rows(errors, uncertainties, norms: Sequence[str]) -> tuple[list[str], list[list[tuple[float, int]]]]:
    """Table 1's layout: the row labels (``1/N``) and per row and norm ``(value rounded to its
    certified digits, those digits)``; every format (and the notebooks) renders these cells."""
    values, digits = certified_errors(errors, uncertainties, norms)
    cells = [list(zip(v, d, strict=True)) for v, d in zip(values, digits, strict=True)]
    return [h_label(N) for N in errors["N"]], cells


def eoc_rows(eoc, uncertainty, norms: Sequence[str]) -> tuple[list[str], list[list[tuple[float, int]]]]:
    """Table 2's layout: the row labels (``1/N`` of the finer mesh, then ``regr.``) and per row and
    norm ``(EOC, its certified decimals)`` (``uncertainty``: ``eoc_uncertainties``; ``None``: 4)."""
    labels = ["regr." if str(N) == "regression" else h_label(N) for N in eoc["N"]]
    cells = [
        [
            (float(eoc[n].iloc[i]), certified_decimals(0.0 if uncertainty is None else float(uncertainty[n][i])))
            for n in norms
        ]
        for i in range(len(labels))
    ]
    return labels, cells


def table1(
    errors,
    out_csv: str | os.PathLike,
    out_md: str | os.PathLike,
    out_tex: str | os.PathLike,
    uncertainties=None,
) -> None:
    """Table 1 from a frame with columns ``N``, ``h`` and at least ``TABLE1_NORMS``; ``uncertainties``
    (the same shape, ``studies.scene.store.read_uncertainties``) decides each value's digits."""
    _require(errors, TABLE1_NORMS, "Table 1")
    labels, cells = error_rows(errors, uncertainties, TABLE1_NORMS)
    md_rows = [[lab, *(sci_md(v, k - 1) for v, k in row)] for lab, row in zip(labels, cells, strict=True)]
    tex_rows = [[tex_h(lab), *(sci_tex(v, k - 1) for v, k in row)] for lab, row in zip(labels, cells, strict=True)]
    csv_rows = [[lab, *(sig_csv(v, k) for v, k in row)] for lab, row in zip(labels, cells, strict=True)]
    _write(
        {"csv": out_csv, "md": out_md, "tex": out_tex},
        csv_text(["h", *TABLE1_NORMS], csv_rows),
        f"**Table 1.** {TABLE1_CAPTION} {DIGITS_NOTE}\n\n"
        + md_table(["h", *map(label_md, TABLE1_NORMS)], md_rows),
        tex_table(["$h$", *map(label_tex, TABLE1_NORMS)], tex_rows, TABLE1_CAPTION_TEX, "tab:errors"),
    )


def eoc_uncertainties(errors, uncertainties, norms: Sequence[str]) -> dict[str, list[float]]:
    """Per norm: the uncertainty of each EOC row (finer meshes in order) and of the regression slope."""
    from signorini.fem.convergence import eoc_uncertainty, regression_uncertainty

    h = errors["h"].to_numpy(dtype=float)
    out = {}
    for n in norms:
        e = errors[n].to_numpy(dtype=float)
        de = np.zeros_like(e) if uncertainties is None else uncertainties[n].to_numpy(dtype=float)
        out[n] = [*eoc_uncertainty(h, e, de)[1:], regression_uncertainty(h, e, de)]
    return out


def table2(
    eoc,
    scene_N: Sequence[int],
    out_csv: str | os.PathLike,
    out_md: str | os.PathLike,
    out_tex: str | os.PathLike,
    uncertainty: Mapping[str, Sequence[float]] | None = None,
) -> None:
    """Table 2 from ``eoc.csv`` (EOC rows labelled by the finer ``N``, then ``regression``);
    the coarsest mesh ``scene_N[0]`` gets the paper's row of dashes in the Markdown/LaTeX layout.
    ``uncertainty``: per norm, one uncertainty per row of ``eoc`` (``eoc_uncertainties``) that
    decides its decimals; ``None``: the paper's 4."""
    _require(eoc, TABLE2_NORMS, "Table 2")
    labels, rows = eoc_rows(eoc, uncertainty, TABLE2_NORMS)
    cells = [[f"{v:.{k}f}" for v, k in row] for row in rows]
    theo = [THEORETICAL_ORDERS[n] for n in TABLE2_NORMS]
    first = h_label(min(int(N) for N in scene_N))
    dashes = len(TABLE2_NORMS)
    body = list(zip(labels, cells, strict=True))
    md_rows = [[first, *(["–"] * dashes)], *([lab, *row] for lab, row in body)]
    md_rows.append(["theo.", *(f"{x:g} − ε" for x in theo)])
    tex_rows = [[tex_h(first), *(["--"] * dashes)], *([tex_h(lab), *row] for lab, row in body)]
    tex_rows.append(["theo.", *(f"${x:g} - \\varepsilon$" for x in theo)])
    _write(
        {"csv": out_csv, "md": out_md, "tex": out_tex},
        csv_text(["h", *TABLE2_NORMS], [*([lab, *row] for lab, row in body), ["theo.", *theo]]),
        f"**Table 2.** {TABLE2_CAPTION} {DIGITS_NOTE_EOC}\n\n"
        + md_table(["h", *map(label_md, TABLE2_NORMS)], md_rows),
        tex_table(["$h$", *map(label_tex, TABLE2_NORMS)], tex_rows, TABLE2_CAPTION_TEX, "tab:eoc"),
    )


def table1_stage(scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str]], outs: Mapping[str, str]) -> None:
    """Stage ``table1``: Table 1 from the norm artifacts of the rendered scene."""
    from signorini.studies.scene.store import read_errors, read_uncertainties

    errors, unc = read_errors(scene_N, norm_jsons), read_uncertainties(scene_N, norm_jsons)
    table1(errors, outs["csv"], outs["md"], outs["tex"], uncertainties=unc)


def table2_stage(
    eoc_csv: str | os.PathLike,
    scene_N: Sequence[int],
    norm_jsons: Mapping[str, Sequence[str]],
    outs: Mapping[str, str],
) -> None:
    """Stage ``table2``: Table 2 from the rendered scene's ``eoc.csv``, its decimals from the
    uncertainties of the norm artifacts."""
    from signorini.studies.scene.store import read_errors, read_errors_csv, read_uncertainties

    errors, unc = read_errors(scene_N, norm_jsons), read_uncertainties(scene_N, norm_jsons)
    uncertainty = eoc_uncertainties(errors, unc, TABLE2_NORMS)
    table2(read_errors_csv(eoc_csv), scene_N, outs["csv"], outs["md"], outs["tex"], uncertainty=uncertainty)
