"""Stage ``work_precision_table``: every measurement record in one table,
``paper_figures/work_precision.csv``, one ``Run`` per row; how the other renderers read and order it."""

from __future__ import annotations

import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields

from signorini import intervals
from signorini.pipeline.artifacts import CorruptArtifactError, atomic_write_csv, load_json
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.study import kind_of, table_route, tolerance_key

NAN = math.nan
ERRORS = ("alg", "total", "disc")  # the errors by norm: columns alg_<norm>, total_<norm>, disc_<norm>


@dataclass(frozen=True)
class Run:
    """One row of ``work_precision.csv``: one configuration at one tolerance on one mesh, as
    ``measure`` records it (docs/work-precision.md says what each column holds).  A field the run did
    not record is NaN (a number), None (a count or a flag) or "" (a text); ``alg``, ``total`` and
    ``disc`` are the algebraic, total and discretisation errors by norm."""

    N: int
    h: float
    n_dofs: int
    config: str
    solver: str
    label: str
    tol: float = NAN
    tol_label: str = ""
    is_default: bool | None = None
    status: str = ""
    reason: str = ""
    start: str = ""
    time_s: float = NAN
    wall_s: float = NAN
    time_ref: float = NAN
    ref_s: float = NAN
    cpu_share: float = NAN
    spread: float = NAN
    time_runs: int | None = None
    calls: int | None = None
    rejected: int | None = None
    loaded: bool | None = None
    time_stop: str = ""
    times: str = ""
    start_s: float = NAN
    solver_time_s: float = NAN
    setup_s: float = NAN
    converged_reason: str = ""
    peer_info: str = ""
    iterations: int | None = None
    n_active: int | None = None
    kkt_stationarity: float = NAN
    kkt_primal: float = NAN
    kkt_dual: float = NAN
    kkt_complementarity: float = NAN
    kkt_worst: float = NAN
    kkt_required: float = NAN
    build_s: float = NAN
    job_wall_s: float = NAN
    job_started: float = NAN
    load1: float = NAN
    load1_max: float = NAN
    machine: str = ""
    alg: dict[str, float] = field(default_factory=dict)
    total: dict[str, float] = field(default_factory=dict)
    disc: dict[str, float] = field(default_factory=dict)

    @classmethod
    def of(cls, record: Mapping) -> Run:
        """A run from a measurement record or a row of the table (other keys left out)."""
        values = {name: _value(kind, record[name]) for name, kind in _KINDS.items() if name in record}
        norms = [key.removeprefix("disc_") for key in record if key.startswith("disc_")]
        errors = {kind: {n: float(record.get(f"{kind}_{n}", NAN)) for n in norms} for kind in ERRORS}
        return cls(**values, **errors)

    def row(self) -> dict:
        """The run as a row of the table: ``ID_COLUMNS``, then its errors by norm."""
        row = {name: getattr(self, name) for name in _KINDS}
        return row | {f"{kind}_{n}": v for kind in ERRORS for n, v in getattr(self, kind).items()}

    def time_estimate(self) -> intervals.Estimate:
        """The run's time (``time_s``) and the bootstrap of the median of its samples
        (``intervals.median``, keyed by mesh, configuration and tolerance), shifted by what ``time_s``
        adds to that median (a cascade start's cost; the samples' rounding)."""
        return intervals.median(intervals.samples(self.times), (self.N, self.config, self.tol_label), self.time_s)

    @property
    def kind(self) -> Kind:
        """Exact, QP or peer (``study.kind_of`` of the route the table's solver name stands for)."""
        return kind_of(table_route(self.solver))


_KINDS = {f.name: f.type for f in fields(Run) if f.name not in ERRORS}  # name → annotation
ID_COLUMNS = list(_KINDS)


def _value(kind: str, value: object) -> object:
    """A field's value as its annotation says (a missing one: NaN, "" or None)."""
    missing = value is None or (isinstance(value, float) and math.isnan(value))
    if kind == "float":
        return NAN if missing else float(value)
    if kind == "str":
        return "" if missing else str(value)
    if missing:
        return None
    if kind.startswith("bool"):
        return value == "True" if isinstance(value, str) else bool(value)
    return int(value)


def table_stage(jsons: Sequence[str | os.PathLike], out_csv: str | os.PathLike) -> list[Run]:
    """``work_precision.csv``: every record of the measurement artifacts, one row each, sorted by
    mesh and configuration (``write_runs``)."""
    runs = [Run.of(record) for path in jsons for record in load_json(path)["records"]]
    runs.sort(key=lambda run: (run.N, run.config))
    write_runs(runs, out_csv)
    return runs


def write_runs(runs: Sequence[Run], out_csv: str | os.PathLike) -> None:
    """The runs as ``work_precision.csv``: columns ``ID_COLUMNS``, then ``alg_<norm>``,
    ``total_<norm>``, ``disc_<norm>`` in the order the runs name the norms; a missing value empty."""
    import pandas as pd

    norms = list(dict.fromkeys(n for run in runs for n in run.disc))
    columns = ID_COLUMNS + [f"{kind}_{n}" for kind in ERRORS for n in norms]
    atomic_write_csv(pd.DataFrame([run.row() for run in runs], columns=columns), out_csv)


def read_runs(path: str | os.PathLike) -> list[Run]:
    """The runs of ``work_precision.csv`` (a table measured before the ``machine`` column: each
    with an empty one)."""
    import pandas as pd

    try:
        dtype = {name: str for name, kind in _KINDS.items() if kind == "str"}
        frame = pd.read_csv(path, dtype=dtype, keep_default_na=True, encoding="utf-8")
    except (OSError, ValueError) as err:
        raise CorruptArtifactError(f"{path}: unreadable CSV ({err})") from err
    return [Run.of(row) for row in frame.to_dict("records")]


def sweeps(runs: Sequence[Run]) -> dict[tuple[str, str], dict[int, Run]]:
    """Each (config, tol_label)'s runs by N, in plotting order: configs as they appear, each with its
    exact or default runs first, then its tolerances loose to tight (``study.tolerance_key``)."""
    out: dict[tuple[str, str], dict[int, Run]] = {}
    for run in runs:
        out.setdefault((run.config, run.tol_label), {})[run.N] = run
    configs = list(dict.fromkeys(config for config, _ in out))
    return {key: out[key] for key in sorted(out, key=lambda k: (configs.index(k[0]), tolerance_key(k[1])))}
