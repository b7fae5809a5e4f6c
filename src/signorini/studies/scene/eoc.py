"""Stage ``eoc``: the scene's ``eoc.csv`` (the columns of ``errors.csv``; one EOC row per ``N``
after the first, labelled by the finer mesh, then a ``regression`` row with ``h`` empty)."""

from __future__ import annotations

import math
import os

from signorini.pipeline.artifacts import CorruptArtifactError, atomic_write_csv
from signorini.studies.scene.store import read_errors_csv


def eoc_stage(errors_csv: str | os.PathLike, out_csv: str | os.PathLike) -> None:
    """``eoc.csv`` from ``errors.csv``: EOCs of consecutive meshes and the regression slope."""
    import numpy as np
    import pandas as pd

    from signorini.fem.convergence import eoc, regression_slope

    err = read_errors_csv(errors_csv)
    norms = list(err.columns[2:])
    h = err["h"].to_numpy(dtype=float)
    if np.isnan(err[norms].to_numpy(dtype=float)).any():
        raise CorruptArtifactError(f"{errors_csv}: missing values")
    if len(h) < 2:
        raise ValueError(f"{errors_csv}: orders of convergence need at least two meshes, the scene has {len(h)}")
    rows = pd.DataFrame({"N": err["N"].iloc[1:].to_list(), "h": h[1:]})
    regr: dict[str, object] = {"N": "regression", "h": math.nan}
    for name in norms:
        e = err[name].to_numpy(dtype=float)
        if not np.all(e > 0.0):
            where = err["N"][e <= 0].tolist()
            raise ValueError(f"{errors_csv}: the {name} error vanishes on a mesh (N = {where}): no EOC")
        rows[name] = eoc(h, e)[1:]
        regr[name] = regression_slope(h, e)
    atomic_write_csv(pd.concat([rows, pd.DataFrame([regr])], ignore_index=True), out_csv)
