"""``studies.paper.runtime``: the in-job timer of a job from its artifacts."""

from __future__ import annotations

import pytest

from signorini.studies.paper.runtime import _timer


def _artifact(norm_s: float, shared: list[str] | None = None, mesh_s: float = 1.0) -> dict:
    timings = {"mesh_s": mesh_s, "norm_s": norm_s}
    if shared:
        timings["norm_shared_by"] = shared
    return {"timings": timings}


def test_a_per_mesh_job_counts_a_shared_evaluation_once():
    """Norms evaluated together record their common time in each artifact; a true norm its own."""
    group = ["L4", "Linf", "W14"]
    artifacts = [_artifact(6.0, group), _artifact(6.0, group), _artifact(6.0, group), _artifact(40.0)]
    assert _timer("norms", artifacts) == pytest.approx(1.0 + 6.0 + 40.0)


def test_per_norm_jobs_and_unshared_artifacts_add_up():
    assert _timer("norm", [_artifact(2.5)]) == pytest.approx(3.5)  # mesh + norm
    assert _timer("norms", [_artifact(2.0), _artifact(3.0)]) == pytest.approx(1.0 + 5.0)
