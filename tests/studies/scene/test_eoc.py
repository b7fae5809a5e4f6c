"""The eoc stage (``signorini.studies.scene.eoc``)."""

from __future__ import annotations

import pytest
from helpers import ERRORS

from signorini.studies.scene.eoc import eoc_stage


def test_a_vanishing_error_or_a_single_mesh_stops_the_eoc_job(tmp_path):
    (tmp_path / "errors.csv").write_text(ERRORS.replace("0.012", "0.0"))
    with pytest.raises(ValueError, match="L4 error vanishes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    (tmp_path / "errors.csv").write_text("N,h,L4\n11,0.0909,0.04\n")
    with pytest.raises(ValueError, match="at least two meshes"):
        eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    assert not (tmp_path / "eoc.csv").exists()
