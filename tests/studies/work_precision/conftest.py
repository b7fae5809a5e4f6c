"""Synthetic measurement tables (the runs of ``work_precision.csv``) for the tests of the selection,
the findings, the report and the figures.

``run_row`` makes one run as the timing protocol records it (its samples, the median of which is
its time; the stop of its sampling; discretisation errors L⁴ ∝ h² and W^{1,4} ∝ h on the mesh
N = 1/h).  ``measurements``: the exact solver, a QP solver at two tolerances and one that fails, on
N = 10, 20, 40.  ``changed``: runs with some fields changed where others have given values."""

from __future__ import annotations

import dataclasses
import math
import statistics
from collections.abc import Mapping, Sequence

import pytest

from signorini.studies.work_precision.study import INACCURATE
from signorini.studies.work_precision.table import Run
from signorini.timing import spread

REASONS = {"ok": "", "inaccurate": INACCURATE, "failed": "solver status infeasible"}


def _row(
    N: int,
    config: str,
    tol_label: str,
    times: Sequence[float],
    *,
    start: str = "cold",
    status: str = "ok",
    rel: float = 0.0,
    stop: str = "spread",
    **extra,
) -> Run:
    """One run: ``rel`` is the relative change of its L⁴ error against the exact one's; no answer
    (no total errors) unless ``ok`` or ``inaccurate``."""
    disc = {"L4": 0.1 / N**2, "W14": 0.2 / N}
    answered = status in ("ok", "inaccurate")
    median = statistics.median(times)
    return Run.of({
        "N": N,
        "h": 1 / N,
        "n_dofs": (N + 1) ** 2,
        "config": config,
        "solver": "active_set" if tol_label == "exact" else "OSQP",
        "label": config,
        "tol_label": tol_label,
        "status": status,
        "reason": REASONS[status],
        "start": start,
        "time_s": median,
        "times": " ".join(f"{t:.6g}" for t in times),
        "time_runs": len(times),
        "spread": spread(times),
        "time_stop": stop,
        "calls": 1,
        "rejected": 0,
        "loaded": False,
        "cpu_share": 1.0,
        "time_ref": 2.0 * median,
        "ref_s": 0.5,
        "converged_reason": "",
        "peer_info": "",
        "build_s": 0.01 * N,
        "job_wall_s": 1.0,
        "job_started": 0.0,
        "load1": 1.0,
        "machine": "",
        **{f"disc_{n}": e for n, e in disc.items()},
        "total_L4": disc["L4"] * (1 + rel) if answered else math.nan,
        "alg_L4": rel * disc["L4"],
        "total_W14": disc["W14"] if answered else math.nan,
        "alg_W14": 0.0,
        **extra,
    })


@pytest.fixture
def run_row():
    """``_row``: one run's row of a synthetic ``work_precision.csv``."""
    return _row


def around(t: float, k: int = 3, width: float = 0.02) -> list[float]:
    """``k`` samples spread evenly over ``t`` ± ``width`` (relative); their median is ``t``."""
    return [t * (1 - width + 2 * width * j / (k - 1)) for j in range(k)] if k > 1 else [t]


@pytest.fixture
def samples_around():
    """``around``: samples whose median is a given time."""
    return around


def _changed(runs: Sequence[Run], where: Mapping, **values) -> list[Run]:
    """``runs`` with ``values`` set in those whose fields have the values of ``where``."""
    def matches(run: Run) -> bool:
        return all(getattr(run, k) == v for k, v in where.items())

    return [dataclasses.replace(r, **values) if matches(r) else r for r in runs]


@pytest.fixture
def changed():
    """``_changed``: runs with some fields changed."""
    return _changed


@pytest.fixture
def measurements() -> list[Run]:
    rows = []
    for N in (10, 20, 40):
        rows += [
            _row(N, "exact", "exact", around(0.001 * N), start="cascade", label="AS"),
            _row(N, "qp", "1e-02", around(0.002 * N), rel=1e-2, label="QP", stop="budget"),
            _row(N, "qp", "1e-06", around(0.003 * N), rel=1e-7, label="QP", stop="max_repeats"),
            _row(N, "scs", "1e-06", [0.004 * N], status="failed", label="SCS", solver="SCS", stop="answer rejected"),
        ]
    return rows
