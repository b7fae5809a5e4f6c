"""Which runs count for Table 1's digits: the one selection behind every time, ratio, ranking and
exponent that ``work_precision.md`` and the figures state.

- A run *keeps Table 1's digits* when its status is ``ok`` (its worst relative KKT residual meets the
  tolerance it was asked for) and each of its total errors in Table 1's norms prints, to 5
  significant digits (``formatting.sci_md``), like the exact discrete solution's on its mesh.
- A configuration's *selected tolerance* is the loosest of its swept tolerances at which its run
  keeps Table 1's digits on every mesh of the table; an exact configuration has one run per mesh
  (tolerance ``exact``) and the same condition.  The solver's default is not a swept tolerance: it
  differs from solver to solver and is not ordered with the swept values.  A configuration with no
  such tolerance has no selected tolerance and enters no comparison of times.
- Its *selected runs* are its runs at the selected tolerance, one per mesh.

The tolerance is fixed per configuration across the meshes, not chosen per mesh after the fact.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING

import numpy as np

from signorini.formatting import sci_md
from signorini.studies.work_precision.study import EXACT_LABEL

if TYPE_CHECKING:
    import pandas as pd

DEFAULT_LABEL = "default"  # the tolerance label of a solver's own default tolerance


def printed(x: float) -> str:
    """A cell of Table 1 as printed (5 significant digits, ``formatting.sci_md``)."""
    return sci_md(x) if np.isfinite(x) else "—"


def digits_unchanged(row: Mapping, norms: Sequence[str]) -> bool | None:
    """Whether the run's total errors print like the exact ones in every Table 1 column
    (None: the run has no answer)."""
    if not norms or not np.isfinite(float(row[f"total_{norms[0]}"])):
        return None
    return all(printed(float(row[f"total_{n}"])) == printed(float(row[f"disc_{n}"])) for n in norms)


def keeps_digits(row: Mapping, norms: Sequence[str]) -> bool:
    """Status ``ok`` and Table 1's digits unchanged."""
    return str(row["status"]) == "ok" and digits_unchanged(row, norms) is True


def swept(labels: Sequence[str]) -> list[str]:
    """The tolerance labels a configuration may be selected at, loosest first (``exact``, or the
    swept tolerances; not ``default``)."""
    rest = [lab for lab in dict.fromkeys(labels) if lab not in (DEFAULT_LABEL, EXACT_LABEL)]
    exact = [EXACT_LABEL] if EXACT_LABEL in labels else []
    return exact + sorted(rest, key=float, reverse=True)


def selected_tolerances(df: pd.DataFrame, norms: Sequence[str]) -> dict[str, str | None]:
    """Per configuration (in table order), its selected tolerance (None: none)."""
    meshes = {int(N) for N in df["N"].unique()}
    keeps = np.array([keeps_digits(r, norms) for _, r in df.iterrows()], dtype=bool)
    chosen: dict[str, str | None] = {}
    for config in dict.fromkeys(df["config"]):
        mine = df["config"] == config
        chosen[config] = next(
            (
                label
                for label in swept(list(df.loc[mine, "tol_label"]))
                if {int(N) for N in df.loc[mine & (df["tol_label"] == label) & keeps, "N"]} == meshes
            ),
            None,
        )
    return chosen


def selected_runs(df: pd.DataFrame, norms: Sequence[str]) -> pd.DataFrame:
    """The selected runs of every configuration that has a selected tolerance (table order kept)."""
    chosen = selected_tolerances(df, norms)
    return df[[chosen.get(c) == lab for c, lab in zip(df["config"], df["tol_label"], strict=True)]]
