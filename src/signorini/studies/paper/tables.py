"""Tables 1 and 2 in the paper's layout (CSV, Markdown, LaTeX): the stages ``table1`` and
``table2``.  Rendering only: the values are the norm artifacts and ``eoc.csv`` of the scene."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

from signorini.formatting import csv_text, h_label, md_table, sci_md, sci_tex, tex_h, tex_table
from signorini.paper import TABLE1_NORMS, TABLE2_NORMS, THEORETICAL_ORDERS, label_md, label_tex
from signorini.pipeline.artifacts import atomic_write_text

TABLE1_CAPTION = (
    "Absolute error u − u_h between the analytic solution u and the finite element "
    "approximation u_h for different mesh widths h in various norms."
)
TABLE2_CAPTION = (
    "Experimental orders of convergence (EOCs) for different mesh widths h; "
    "regr. = least-squares slope of log e against log h, theo. = expected order (minus ε)."
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


def table1(errors, out_csv: str | os.PathLike, out_md: str | os.PathLike, out_tex: str | os.PathLike) -> None:
    """Table 1 from a frame with columns ``N``, ``h`` and at least ``TABLE1_NORMS``."""
    _require(errors, TABLE1_NORMS, "Table 1")
    labels = [h_label(N) for N in errors["N"]]
    values = [[float(errors[n].iloc[i]) for n in TABLE1_NORMS] for i in range(len(labels))]
    rows = list(zip(labels, values, strict=True))
    md_rows = [[lab, *(sci_md(v) for v in row)] for lab, row in rows]
    tex_rows = [[tex_h(lab), *(sci_tex(v) for v in row)] for lab, row in rows]
    _write(
        {"csv": out_csv, "md": out_md, "tex": out_tex},
        csv_text(["h", *TABLE1_NORMS], [[lab, *row] for lab, row in rows]),
        f"**Table 1.** {TABLE1_CAPTION}\n\n" + md_table(["h", *map(label_md, TABLE1_NORMS)], md_rows),
        tex_table(["$h$", *map(label_tex, TABLE1_NORMS)], tex_rows, TABLE1_CAPTION_TEX, "tab:errors"),
    )


def table2(
    eoc,
    scene_N: Sequence[int],
    out_csv: str | os.PathLike,
    out_md: str | os.PathLike,
    out_tex: str | os.PathLike,
) -> None:
    """Table 2 from ``eoc.csv`` (EOC rows labelled by the finer ``N``, then ``regression``);
    the coarsest mesh ``scene_N[0]`` gets the paper's row of dashes in the Markdown/LaTeX layout."""
    _require(eoc, TABLE2_NORMS, "Table 2")
    labels = ["regr." if str(N) == "regression" else h_label(N) for N in eoc["N"]]
    values = [[float(eoc[n].iloc[i]) for n in TABLE2_NORMS] for i in range(len(labels))]
    rows = list(zip(labels, values, strict=True))
    theo = [THEORETICAL_ORDERS[n] for n in TABLE2_NORMS]
    first = h_label(min(int(N) for N in scene_N))
    dashes = len(TABLE2_NORMS)
    md_rows = [[first, *(["–"] * dashes)], *([lab, *(f"{v:.4f}" for v in row)] for lab, row in rows)]
    md_rows.append(["theo.", *(f"{x:g} − ε" for x in theo)])
    tex_rows = [[tex_h(first), *(["--"] * dashes)], *([tex_h(lab), *(f"{v:.4f}" for v in row)] for lab, row in rows)]
    tex_rows.append(["theo.", *(f"${x:g} - \\varepsilon$" for x in theo)])
    _write(
        {"csv": out_csv, "md": out_md, "tex": out_tex},
        csv_text(["h", *TABLE2_NORMS], [*([lab, *row] for lab, row in rows), ["theo.", *theo]]),
        f"**Table 2.** {TABLE2_CAPTION}\n\n" + md_table(["h", *map(label_md, TABLE2_NORMS)], md_rows),
        tex_table(["$h$", *map(label_tex, TABLE2_NORMS)], tex_rows, TABLE2_CAPTION_TEX, "tab:eoc"),
    )


def table1_stage(scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str]], outs: Mapping[str, str]) -> None:
    """Stage ``table1``: Table 1 from the norm artifacts of the rendered scene."""
    from signorini.studies.scene.store import read_errors

    table1(read_errors(scene_N, norm_jsons), outs["csv"], outs["md"], outs["tex"])


def table2_stage(eoc_csv: str | os.PathLike, scene_N: Sequence[int], outs: Mapping[str, str]) -> None:
    """Stage ``table2``: Table 2 from the rendered scene's ``eoc.csv``."""
    from signorini.studies.scene.store import read_errors_csv

    table2(read_errors_csv(eoc_csv), scene_N, outs["csv"], outs["md"], outs["tex"])
