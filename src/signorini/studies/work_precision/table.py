"""Stage ``work_precision_table``: every measurement record in one table,
``paper_figures/work_precision.csv``, and how the other renderers read and order it."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING

from signorini.pipeline.artifacts import CorruptArtifactError, atomic_write_csv, load_json
from signorini.studies.work_precision.study import EXACT_LABEL

if TYPE_CHECKING:
    import pandas as pd

ID_COLUMNS = [
    "N",
    "h",
    "n_dofs",
    "config",
    "solver",
    "label",
    "tol",
    "tol_label",
    "is_default",
    "status",
    "reason",
    "start",
    "time_s",
    "wall_s",
    "time_ref",
    "ref_s",
    "cpu_share",
    "spread",
    "time_runs",
    "calls",
    "rejected",
    "loaded",
    "time_stop",
    "times",
    "start_s",
    "solver_time_s",
    "setup_s",
    "converged_reason",
    "peer_info",
    "iterations",
    "n_active",
    "kkt_stationarity",
    "kkt_primal",
    "kkt_dual",
    "kkt_complementarity",
    "kkt_worst",
    "kkt_required",
    "build_s",
    "job_wall_s",
    "job_started",
    "load1",
    "load1_max",
    "machine",
]


def table_stage(jsons: Sequence[str | os.PathLike], out_csv: str | os.PathLike) -> pd.DataFrame:
    """``work_precision.csv``: every record of the measurement artifacts, one row each, columns
    ``ID_COLUMNS`` then ``alg_<norm>``, ``total_<norm>``, ``disc_<norm>`` (norm order kept)."""
    import pandas as pd

    rows = []
    for path in jsons:
        rows.extend(load_json(path)["records"])
    df = pd.DataFrame(rows)
    norms = [c.removeprefix("disc_") for c in df.columns if c.startswith("disc_")]
    columns = ID_COLUMNS + [f"{kind}_{n}" for kind in ("alg", "total", "disc") for n in norms]
    for c in columns:
        if c not in df.columns:
            df[c] = math.nan
    df = df[columns].sort_values(["N", "config"], kind="stable").reset_index(drop=True)
    atomic_write_csv(df, out_csv)
    return df


def read_measurements(path: str | os.PathLike) -> pd.DataFrame:
    """``work_precision.csv`` as a DataFrame (``reason``/``times``/``machine`` as strings; a table
    measured before the ``machine`` column gets it empty)."""
    import pandas as pd

    try:
        text = ("reason", "times", "tol_label", "converged_reason", "peer_info", "start", "machine")
        dtype = dict.fromkeys(text, str)
        df = pd.read_csv(path, dtype=dtype, keep_default_na=True, encoding="utf-8")
    except (OSError, ValueError) as err:
        raise CorruptArtifactError(f"{path}: unreadable CSV ({err})") from err
    for name in ("reason", "converged_reason", "peer_info", "machine"):
        df[name] = df[name].fillna("") if name in df.columns else ""
    return df


def tolerance_order(df: pd.DataFrame) -> list[tuple[str, str]]:
    """(config, tol_label) pairs in plotting order: configs as they appear, the exact solver's
    single run, then each QP solver's default followed by its tolerances loose to tight."""
    out = []
    for config in dict.fromkeys(df["config"]):
        sub = df[df["config"] == config]
        labels = list(dict.fromkeys(sub["tol_label"]))
        rest = sorted((lab for lab in labels if lab not in ("default", EXACT_LABEL)), key=float, reverse=True)
        out += [(config, lab) for lab in labels if lab in ("default", EXACT_LABEL)] + [(config, lab) for lab in rest]
    return out
