"""Redraw the figures of the expensive studies from their committed tables, without their
measurements: ``.venv/bin/python scripts/rerender_figures.py [theory] [stability] [work_precision]``.

The theory (about 1 h), work-precision (about 1 h) and stability studies draw their figures from
cached artifacts in ``results/`` that a fresh clone does not have.  Their figures need no more
than the committed tables, so after an edit of a figure's code or of ``plotting.STYLE`` they can be
redrawn here by the same figure functions the rules call:

- ``theory_extra.{pdf,png}`` from ``theory.csv`` (``theory_table``, written to 7 digits) and
  ``contact_set.csv`` (the ends of the discrete contact sets);
- ``stability.{pdf,png}`` from ``stability.csv`` (``atlas_table``, floats round-trip);
- ``work_precision.{pdf,png}`` and ``cost_of_accuracy.{pdf,png}`` from ``work_precision.csv``
  (the rule's own input).

``theory_rates.{pdf,png}`` needs the theory scene's ``errors.csv`` (not committed): only
``snakemake -c2 theory`` redraws it.  A full run of a study redraws all of its figures from its
artifacts and replaces these.
"""

from __future__ import annotations

import sys

import pandas as pd
import yaml

from signorini.pipeline.config import DEFAULT_CONFIG
from signorini.pipeline.paths import FIGURES
from signorini.plotting import save


def theory() -> None:
    from signorini.studies.theory import contact
    from signorini.studies.theory.figures import extra_figure

    outs = FIGURES["theory_report"]
    table = pd.read_csv(FIGURES["contact_set"]["csv"], encoding="utf-8")
    figure = extra_figure(
        pd.read_csv(outs["csv"], encoding="utf-8"), contact.ends_frame(table), contact.figure_marks(table)
    )
    save(figure, outs["extra_pdf"], outs["extra_png"])


def stability() -> None:
    from signorini.studies.stability import atlas
    from signorini.studies.stability.figures import atlas_figure

    with open(DEFAULT_CONFIG, encoding="utf-8") as f:
        solvers = list(atlas.scene_atlas(yaml.safe_load(f), "stability").solvers)
    outs = FIGURES["stability_atlas"]
    save(atlas_figure(pd.read_csv(outs["csv"]), solvers), outs["pdf"], outs["png"])


def work_precision() -> None:
    from signorini.studies.work_precision.figures import figures_stage

    with open(DEFAULT_CONFIG, encoding="utf-8") as f:
        study = yaml.safe_load(f)["scenes"]["work_precision"]["study"]
    figures_stage(FIGURES["work_precision_table"]["csv"], study.get("figure_N", []),
                  FIGURES["work_precision_figures"])


STUDIES = {"theory": theory, "stability": stability, "work_precision": work_precision}

if __name__ == "__main__":
    for name in sys.argv[1:] or STUDIES:
        STUDIES[name]()
        print(f"{name}: redrawn from its committed table")
