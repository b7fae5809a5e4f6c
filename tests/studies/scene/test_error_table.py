"""The errors stage (``signorini.studies.scene.error_table``) at the end of the scene's chain of stages."""

from __future__ import annotations

import csv

import pytest
from helpers import PROBLEM, solve_chain

from signorini.fem.mesh import mesh_width
from signorini.pipeline.artifacts import load_json, load_npz
from signorini.studies.scene.eoc import eoc_stage
from signorini.studies.scene.error_table import errors_stage
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.store import SceneMesh


def test_stage_chain_and_csv_contract(tmp_path):
    npz, sjson = tmp_path / "solution.npz", tmp_path / "solution.json"
    norm_jsons = {n: [] for n in ("L4", "W14")}
    for N in (8, 16):
        solve_chain(tmp_path, N)
        info = load_json(sjson)
        assert info["summary"]["certificate"]["ok"] and info["N"] == N
        assert set(load_npz(npz)) >= {"u", "lam", "active"}
        assert load_json(tmp_path / f"system{N}.json")["n_dofs"] == (N + 1) ** 2
        for n in norm_jsons:
            out = tmp_path / f"N{N}_{n}.json"
            norm_stage(SceneMesh(PROBLEM, N, "sw_ne"), npz, n, out, {})
            norm_jsons[n].append(out)
    errors_stage([8, 16], norm_jsons, tmp_path / "errors.csv")
    eoc_stage(tmp_path / "errors.csv", tmp_path / "eoc.csv")
    rows = list(csv.DictReader((tmp_path / "errors.csv").open()))
    assert list(rows[0]) == ["N", "h", "L4", "W14"]
    assert [int(r["N"]) for r in rows] == [8, 16] and float(rows[1]["h"]) == mesh_width(16)
    eoc = list(csv.DictReader((tmp_path / "eoc.csv").open()))
    assert [r["N"] for r in eoc] == ["16", "regression"] and eoc[1]["h"] == ""
    assert float(eoc[0]["L4"]) == pytest.approx(float(eoc[1]["L4"]))  # two points: EOC = slope
