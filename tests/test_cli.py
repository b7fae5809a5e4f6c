"""The command line (``python -m signorini solve``) and the ParaView export (``.vtu``, also the
workflow's opt-in ``vtk`` rule)."""

from __future__ import annotations

import subprocess
import sys

import meshio
import numpy as np
import pytest
from helpers import clone_built, planned, snakemake

from signorini.fem.discrete import build
from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.norms import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import load_npz


def read_vtu(path) -> dict[str, np.ndarray]:
    """The nodal fields of a .vtu file read back by meshio, with ``Points`` and the triangles."""
    mesh = meshio.read(path)
    assert [block.type for block in mesh.cells] == ["triangle"]
    return {**mesh.point_data, "Points": mesh.points, "triangles": mesh.cells[0].data}


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
    assert data["Points"].shape == (144, 3) and data["triangles"].shape == (2 * 11 * 11, 3)
    np.testing.assert_array_equal(data["u_h"], result.u)  # binary: the doubles themselves
    np.testing.assert_array_equal(data["error"], problem.u(disc.mesh.p) - result.u)
    np.testing.assert_array_equal(data["triangles"], disc.mesh.t.T)
    np.testing.assert_array_equal(data["Points"][:, :2], disc.mesh.p.T)
    contact = np.flatnonzero(data["contact"])
    np.testing.assert_array_equal(contact, np.sort(result.active))
    assert np.all(data["lambda"][np.setdiff1d(np.arange(144), boundary_nodes(disc.mesh))] == 0)


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
    np.testing.assert_array_equal(data["u_h"], solution["u"])
    mesh = friedrichs_keller(21)
    np.testing.assert_array_equal(data["lambda"][boundary_nodes(mesh)], solution["lam"])
