"""The command line (``python -m signorini solve``) and the ParaView export (``.vtu``, also the
workflow's opt-in ``vtk`` rule)."""

from __future__ import annotations

import base64
import subprocess
import sys
import xml.etree.ElementTree as ET

import numpy as np
import pytest
from helpers import clone_built, planned, snakemake

from signorini.fem.discrete import build
from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.norms import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import load_npz

DTYPES = {"Float64": np.float64, "Int64": np.int64, "UInt8": np.uint8}


def read_vtu(path) -> dict[str, np.ndarray]:
    """Every DataArray of a binary (base64, UInt64 header) .vtu file, by name (points: ``Points``)."""
    root = ET.parse(path).getroot()
    assert root.get("type") == "UnstructuredGrid" and root.get("header_type") == "UInt64"
    out = {}
    for parent in root.iter():
        for array in parent.findall("DataArray"):
            raw = base64.b64decode(array.text)
            size = int(np.frombuffer(raw[:8], dtype="<u8")[0])
            assert size == len(raw) - 8
            values = np.frombuffer(raw[8:], dtype=np.dtype(DTYPES[array.get("type")]).newbyteorder("<"))
            out[array.get("Name") or parent.tag] = values.reshape(-1, int(array.get("NumberOfComponents")))
    piece = root.find("UnstructuredGrid/Piece")
    out["_sizes"] = np.array([int(piece.get("NumberOfPoints")), int(piece.get("NumberOfCells"))])
    return out


def test_solve_command_prints_certificate_norms_and_writes_vtu(tmp_path):
    vtu = tmp_path / "s.vtu"
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "signorini",
            "solve",
            "--N",
            "11",
            "--c",
            "2",
            "--norms",
            "L4,W14",
            "--vtk",
            str(vtu),
            "--verbose",
        ],
        capture_output=True,
        text=True,
        check=True,
    )
    problem = Problem(c=2.0)
    disc = build(problem, 11)
    result = solve_discrete(disc)
    norms = evaluate_norms(problem, disc.mesh, result.u, ["L4", "W14"])
    assert "144 unknowns, 44 constrained" in proc.stdout and "KKT certificate: stationarity=" in proc.stdout
    assert f"L4 {norms['L4']:.6e}, W14 {norms['W14']:.6e}" in proc.stdout
    assert "iteration 1:" in proc.stderr  # --verbose: the Newton steps
    data = read_vtu(vtu)
    assert list(data["_sizes"]) == [144, 2 * 11 * 11]
    np.testing.assert_allclose(data["u_h"][:, 0], result.u, rtol=0, atol=1e-15)
    np.testing.assert_allclose(data["error"][:, 0], problem.u(disc.mesh.p) - result.u, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(data["connectivity"].reshape(-1, 3), disc.mesh.t.T)
    np.testing.assert_allclose(data["Points"][:, :2], disc.mesh.p.T)
    assert set(np.unique(data["types"])) == {5}  # VTK_TRIANGLE
    contact = np.flatnonzero(data["contact"][:, 0])
    np.testing.assert_array_equal(contact, np.sort(result.active))
    assert np.all(data["lambda"][np.setdiff1d(np.arange(144), boundary_nodes(disc.mesh)), 0] == 0)


def test_solve_command_rejects_bad_input():
    for args in (["--norms", "L4x"], ["--R", "0.6"]):
        proc = subprocess.run(
            [sys.executable, "-m", "signorini", "solve", "--N", "8", *args], capture_output=True, text=True
        )
        assert proc.returncode == 2 and proc.stderr.startswith("error:"), proc.stderr


@pytest.mark.slow
def test_vtk_rule_writes_a_scene_solution(built_repo, tmp_path):
    repo = clone_built(built_repo, tmp_path / "repo")
    target = "results/smoke/N21/solution.vtu"
    assert [rule for rule, _ in planned(snakemake(repo, "-n", target))] == ["vtk"]  # from the cached solution
    snakemake(repo, "-c1", target)
    data = read_vtu(repo / target)
    solution = load_npz(repo / "results/smoke/N21/solution.npz")
    np.testing.assert_array_equal(data["u_h"][:, 0], solution["u"])
    mesh = friedrichs_keller(21)
    np.testing.assert_array_equal(data["lambda"][boundary_nodes(mesh), 0], solution["lam"])
