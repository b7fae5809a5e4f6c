"""Stage ``h12_boundary`` (``signorini.studies.paper.boundary_rule``): the ``H^{1/2}(∂Ω)`` error
with the whole-edge and the split boundary rule."""

from __future__ import annotations

import csv
import math

import pytest
from helpers import PROBLEM, solve_chain

from signorini.fem.norms.conventions import Conventions
from signorini.studies.paper.boundary_rule import h12_boundary_stage, h12_value
from signorini.studies.scene.store import SceneMesh


def test_the_h12_estimate_in_both_forms():
    """‖e‖_{L²}^{1/2} ‖e‖_{H¹}^{1/2} with the full H¹ norm (hypot of 3 and 4: 5) or the seminorm."""
    assert h12_value(3.0, 4.0, Conventions(h12_form="geometric_full")) == pytest.approx(math.sqrt(15.0))
    assert h12_value(3.0, 4.0, Conventions(h12_form="geometric_semi")) == pytest.approx(math.sqrt(12.0))


def test_the_stage_writes_both_rules_per_mesh_and_the_split_moves_an_edge_with_the_kink(tmp_path):
    """N = 9: the free point x0 = 1/2 lies inside a bottom edge, where whole edges integrate across
    the kink of ∂_t u; N = 8: x0 is a node, the rules differ by less."""
    meshes, solutions = [], []
    for N in (8, 9):
        solve_chain(tmp_path, N, npz=f"solution{N}.npz", json=f"solution{N}.json")
        meshes.append(SceneMesh(PROBLEM, N, "sw_ne"))
        solutions.append(tmp_path / f"solution{N}.npz")
    out = tmp_path / "h12_boundary.csv"
    h12_boundary_stage(meshes, solutions, Conventions().as_dict(), out)
    rows = list(csv.DictReader(out.open(encoding="utf-8")))
    assert [r["N"] for r in rows] == ["8", "9"] and float(rows[1]["h"]) == pytest.approx(1 / 9)
    moved = [abs(float(r["split"]) / float(r["whole_edges"]) - 1.0) for r in rows]
    assert all(float(r["split"]) > 0 for r in rows) and 0.0 < moved[1] < 0.05
    assert moved[0] < moved[1]
