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


def test_the_solve_on_the_paper_mesh_does_not_build_its_triangles(tmp_path, monkeypatch):
    """What the cascade needs of the paper's mesh is its vertices (``DiscreteProblem.vertices``, the
    built mesh's bit for bit: ``tests/fem/test_discrete.py``)."""
    import signorini.studies.scene.store as store

    at = SceneMesh(PROBLEM, 101, "sw_ne")
    discretise_stage(at, tmp_path / "system.npz", tmp_path / "system.json")
    monkeypatch.setattr(store, "friedrichs_keller", lambda *a, **k: pytest.fail("the paper mesh was built"))
    info = solve_stage(at, tmp_path / "system.npz", "multigrid", tmp_path / "s.npz", tmp_path / "s.json")
    assert info["summary"]["cascade"]["N"] == 101 // 4  # the cascade ran, on the vertices alone


def test_the_multigrid_stage_solves_with_the_matrix_as_its_stencil(tmp_path, monkeypatch):
    """On a grid large enough for the compiled kernels the multigrid stage holds the matrix as its
    stencil operator (``multigrid.compact``): the archive it writes is the CSR matrix's, bit for bit."""
    import numpy as np

    import signorini.studies.scene.solve as stage
    from signorini.solvers import certificate
    from signorini.solvers.stencil import StencilOperator

    at = SceneMesh(PROBLEM, 101, "sw_ne")
    discretise_stage(at, tmp_path / "system.npz", tmp_path / "system.json")
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)
    given, compact = [], stage.compact
    monkeypatch.setattr(stage, "compact", lambda A: given.append(compact(A)) or given[-1])
    stage.solve_stage(at, tmp_path / "system.npz", "multigrid", tmp_path / "stencil.npz", tmp_path / "stencil.json")
    assert isinstance(given[0], StencilOperator)
    monkeypatch.setattr(stage, "compact", lambda A: A)
    stage.solve_stage(at, tmp_path / "system.npz", "multigrid", tmp_path / "csr.npz", tmp_path / "csr.json")
    with np.load(tmp_path / "stencil.npz") as got, np.load(tmp_path / "csr.npz") as expected:
        for name in ("u", "lam", "active", "algebraic_error"):
            assert got[name].tobytes() == expected[name].tobytes(), name
