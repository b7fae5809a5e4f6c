"""The findings of the work-precision study (``signorini.studies.work_precision.findings``): which
run keeps Table 1's digits fastest, how runs are ranked and started, which rows are peers.

``findings`` on a synthetic table is tested in ``tests/studies/work_precision/test_measure.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from signorini.studies.work_precision.findings import (
    fastest_to_digits,
    is_peer,
    measured_under_protocol,
    pd_numeric,
    printed,
    starts,
)


def test_the_fastest_run_that_keeps_table_1s_digits_per_configuration(measurements):
    """At 1e-02 the QP solver's L⁴ cells change; 1e-06 keeps them; the failed solver has none."""
    fastest = fastest_to_digits(measurements, 40, ["L4", "W14"])
    assert fastest == {
        "exact": {"tol_label": "exact", "time_s": 0.04, "rank": 0.04},
        "qp": {"tol_label": "1e-06", "time_s": 0.12, "rank": 0.12},
    }
    assert printed(0.1 / 40**2) == "6.2500·10⁻⁵" and printed(math.nan) == "—"


def test_ranks_starts_peers_and_numeric_columns(measurements):
    timed = measurements.assign(time_ref=2.0 * measurements["time_s"])
    assert not measured_under_protocol(measurements) and measured_under_protocol(timed)
    assert set(starts(measurements[measurements["config"] == "exact"])) == {"cascade"}
    assert set(starts(measurements[measurements["config"] != "exact"])) == {"cold"}
    cold = measurements.assign(label=measurements["label"].replace({"AS": "AS (cold)"}))
    assert set(starts(cold)) == {"cold"}
    assert not is_peer(measurements).any()
    peers = measurements.assign(solver=np.where(measurements["config"] == "qp", "petsc_tao", measurements["solver"]))
    assert list(is_peer(peers)) == list(peers["config"] == "qp")
    flags = measurements.assign(loaded=["True", False, True, None] * 3)
    np.testing.assert_array_equal(pd_numeric(flags, "loaded")[:4], [1.0, 0.0, 1.0, math.nan])
    assert np.isnan(pd_numeric(measurements, "no_such_column")).all()


def test_concurrent_jobs_counts_the_largest_overlap_of_job_intervals():
    """Back-to-back jobs (one ends as the next starts) never ran together; nested ones did."""
    from signorini.studies.work_precision.findings import concurrent_jobs

    one_core = np.array([0.0, 10.0, 25.0]), np.array([10.0, 25.0, 30.0])
    assert concurrent_jobs(*one_core) == 1
    # [0, 11) and [1, 12) overlap, as do [12, 20) and [13, 14); a NaN (a skipped job) is left out
    two_cores = np.array([0.0, 1.0, 12.0, 13.0, np.nan]), np.array([11.0, 12.0, 20.0, 14.0, np.nan])
    assert concurrent_jobs(*two_cores) == 2
    assert concurrent_jobs(np.array([0.0, 1.0, 2.0]), np.array([9.0, 9.0, 9.0])) == 3


def test_kernel_spread_is_the_largest_range_of_the_job_medians_of_one_mesh():
    import pandas as pd

    from signorini.studies.work_precision.findings import kernel_spread

    rows = [  # N, config, ref_s per run: job medians 1.0 and 1.1 at N = 11, 2.0 and 2.0 at N = 21
        (11, "a", 1.0), (11, "a", 1.0), (11, "a", 5.0), (11, "b", 1.1),
        (21, "a", 2.0), (21, "b", 2.0), (21, "c", np.nan),
    ]
    df = pd.DataFrame(rows, columns=["N", "config", "ref_s"])
    assert kernel_spread(df) == pytest.approx(0.1 / 1.05)
    assert math.isnan(kernel_spread(df[df["N"] == 21].iloc[:1]))
