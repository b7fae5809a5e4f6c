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

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from signorini.formatting import sci_md
from signorini.published import TABLE1_NORMS
from signorini.studies.work_precision.study import DEFAULT_LABEL, tolerance_key

if TYPE_CHECKING:
    from signorini.studies.work_precision.table import Run


def table1_norms_of(runs: Sequence[Run], norms: Sequence[str] | None = None) -> list[str]:
    """Table 1's norms (``norms``, default the paper's) that the runs have errors in."""
    return [n for n in (norms or TABLE1_NORMS) if runs and n in runs[0].total]


def printed(x: float) -> str:
    """A cell of Table 1 as printed (5 significant digits, ``formatting.sci_md``)."""
    return sci_md(x) if np.isfinite(x) else "—"


def digits_unchanged(run: Run, norms: Sequence[str]) -> bool | None:
    """Whether the run's total errors print like the exact ones in every Table 1 column
    (None: the run has no answer)."""
    if not norms or not np.isfinite(run.total[norms[0]]):
        return None
    return all(printed(run.total[n]) == printed(run.disc[n]) for n in norms)


def keeps_digits(run: Run, norms: Sequence[str]) -> bool:
    """Status ``ok`` and Table 1's digits unchanged."""
    return run.status == "ok" and digits_unchanged(run, norms) is True


def swept(labels: Sequence[str]) -> list[str]:
    """The tolerance labels a configuration may be selected at, loosest first (``exact``, or the
    swept tolerances; not ``default``)."""
    return sorted((lab for lab in dict.fromkeys(labels) if lab != DEFAULT_LABEL), key=tolerance_key)


def selected_tolerances(runs: Sequence[Run], norms: Sequence[str]) -> dict[str, str | None]:
    """Per configuration (in table order), its selected tolerance (None: none)."""
    meshes = {run.N for run in runs}
    chosen: dict[str, str | None] = {}
    for config in dict.fromkeys(run.config for run in runs):
        mine = [run for run in runs if run.config == config]
        keeping = {(run.tol_label, run.N) for run in mine if keeps_digits(run, norms)}
        labels = swept([run.tol_label for run in mine])
        chosen[config] = next((lab for lab in labels if {N for t, N in keeping if t == lab} == meshes), None)
    return chosen


def selected_runs(runs: Sequence[Run], norms: Sequence[str]) -> list[Run]:
    """The selected runs of every configuration that has a selected tolerance (table order kept)."""
    chosen = selected_tolerances(runs, norms)
    return [run for run in runs if chosen.get(run.config) == run.tol_label]
