"""The published Tables 1 and 2 (transcribed in ``workflow/reference/``) and the comparison of a
cell of ours with the published one."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping
from pathlib import Path


def read_table_csv(path: str | os.PathLike) -> dict[str, dict[str, float]]:
    """A table CSV (ours or the transcribed published one; ``#`` lines are comments) as
    ``{row label: {column: value}}``; empty cells are left out."""
    rows: dict[str, dict[str, float]] = {}
    text = Path(path).read_text(encoding="utf-8")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    header = [c.strip() for c in lines[0].split(",")]
    for line in lines[1:]:
        cells = [c.strip() for c in line.split(",")]
        rows[cells[0]] = {col: float(v) for col, v in zip(header[1:], cells[1:], strict=True) if v != ""}
    return rows


def by_mesh(table: Mapping[str, Mapping[str, float]], norm: str) -> dict[int, float]:
    """``{N: value}`` of one column over the rows labelled ``1/N``."""
    return {int(k.split("/")[1]): v[norm] for k, v in table.items() if k.startswith("1/") and norm in v}


def relative_deviation(ours: float, paper: float) -> float:
    """(ours − paper) / |paper|."""
    return (ours - paper) / abs(paper) if paper != 0 else math.nan
