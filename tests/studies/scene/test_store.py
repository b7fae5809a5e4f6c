"""Reading a scene's artifacts (``signorini.studies.scene.store``)."""

from __future__ import annotations

import pytest

from signorini.pipeline.artifacts import CorruptArtifactError, load_json, save_json
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.store import read_errors


def test_a_nan_norm_artifact_never_reaches_a_table(solved, tmp_path):
    d, at = solved
    norm_stage(at, d / "solution.npz", "L4", tmp_path / "L4.json", {})
    art = load_json(tmp_path / "L4.json")
    save_json(tmp_path / "L4.json", {**art, "value": float("nan")})  # a well-formed artifact with NaN
    with pytest.raises(CorruptArtifactError, match="not a finite non-negative number"):
        read_errors([8], {"L4": [tmp_path / "L4.json"]})
