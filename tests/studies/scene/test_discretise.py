"""Stage ``discretise`` (``signorini.studies.scene.discretise``): the assembled system saved once per
mesh, read back by the solve and the work-precision study as built."""

from __future__ import annotations

import numpy as np
from helpers import PROBLEM

from signorini.fem.discrete import build
from signorini.pipeline.artifacts import load_json
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.store import SceneMesh, load_system


def test_the_saved_system_is_the_built_one(tmp_path):
    at = SceneMesh(PROBLEM, 6, "nw_se")
    info = discretise_stage(at, tmp_path / "system.npz", tmp_path / "system.json")
    A, b, boundary = load_system(tmp_path / "system.npz", 6)
    disc = build(at.problem, 6, "nw_se")
    assert abs(A - disc.A).max() == 0.0 and A.nnz == disc.A.nnz
    np.testing.assert_array_equal(b, disc.b)
    np.testing.assert_array_equal(boundary, disc.boundary)
    assert {k: v for k, v in load_json(tmp_path / "system.json").items() if not k.startswith("_")} == info
    assert (info["n_dofs"], info["n_constrained"], info["nnz"]) == (49, 24, A.nnz)
    assert info["diagonal"] == "nw_se" and info["problem"] == at.problem.as_dict() and info["timings"]["build_s"] > 0
