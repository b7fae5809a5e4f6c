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


def _norm_artifact(path, norm, N, h, value=1.0):
    save_json(path, {"norm": norm, "N": N, "h": h, "value": value})
    return path


def test_the_error_table_takes_each_meshs_h_from_its_norm_artifacts(tmp_path):
    """The paper's mesh records h = 1/N, a family mesh its longest edge: the table carries either."""
    jsons = {
        "L4": [_norm_artifact(tmp_path / f"L4_{N}.json", "L4", N, h) for N, h in ((10, 0.13), (20, 0.066))],
        "H12": [_norm_artifact(tmp_path / f"H12_{N}.json", "H12", N, h) for N, h in ((10, 0.13), (20, 0.066))],
    }
    frame = read_errors([10, 20], jsons)
    assert list(frame.columns) == ["N", "h", "L4", "H12"] and frame["h"].tolist() == [0.13, 0.066]
    _norm_artifact(jsons["H12"][1], "H12", 20, 0.05)  # one mesh, two widths: a damaged artifact
    with pytest.raises(CorruptArtifactError, match="N=20 record different mesh widths"):
        read_errors([10, 20], jsons)
