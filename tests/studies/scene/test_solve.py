"""The solve stage (``signorini.studies.scene.solve``)."""

from __future__ import annotations

import pytest
from helpers import PROBLEM

from signorini.pipeline.artifacts import CorruptArtifactError
from signorini.pipeline.joblog import job_log
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh


def test_solve_refuses_the_system_of_another_mesh(tmp_path):
    discretise_stage(SceneMesh(PROBLEM, 8, "sw_ne"), tmp_path / "system.npz", tmp_path / "system.json")
    with pytest.raises(CorruptArtifactError, match="N=8, not N=9"):
        solve_stage(
            SceneMesh(PROBLEM, 9, "sw_ne"),
            tmp_path / "system.npz",
            "active_set",
            tmp_path / "s.npz",
            tmp_path / "s.json",
        )
    assert not (tmp_path / "s.npz").exists()


def test_failed_certificate_writes_nothing_and_logs_residuals(tmp_path, monkeypatch):
    import signorini.studies.scene.solve
    from signorini.solvers import Certificate, KKTError

    def failing(*args, **kwargs):
        raise KKTError("test solver", Certificate(1e-3, 0.0, 0.0, 0.0, 1e-10))

    monkeypatch.setattr(signorini.studies.scene.solve, "solve_discrete", failing)
    log = tmp_path / "solve.log"
    discretise_stage(SceneMesh(PROBLEM, 8, "sw_ne"), tmp_path / "system.npz", tmp_path / "system.json")
    with pytest.raises(KKTError), job_log(log):
        solve_stage(
            SceneMesh(PROBLEM, 8, "sw_ne"),
            tmp_path / "system.npz",
            "active_set",
            tmp_path / "s.npz",
            tmp_path / "s.json",
        )
    assert not (tmp_path / "s.npz").exists() and not (tmp_path / "s.json").exists()
    assert "stationarity=1.00e-03" in log.read_text()
