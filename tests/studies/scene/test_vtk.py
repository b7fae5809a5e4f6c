"""Stage ``vtk`` (``signorini.studies.scene.vtk``): one solution of a scene for ParaView."""

from __future__ import annotations

import numpy as np
from helpers import read_vtu

from signorini.fem.mesh import boundary_nodes
from signorini.pipeline.artifacts import load_npz
from signorini.studies.scene.vtk import vtk_stage


def test_the_vtu_holds_the_solution_its_error_the_multiplier_and_the_contact_set(solved, tmp_path):
    d, at = solved
    vtk_stage(at, d / "solution.npz", tmp_path / "solution.vtu")
    data, solution = read_vtu(tmp_path / "solution.vtu"), load_npz(d / "solution.npz")
    mesh = at.mesh()
    np.testing.assert_array_equal(data["u_h"], solution["u"])
    np.testing.assert_array_equal(data["error"], at.problem.u(mesh.p) - solution["u"])
    np.testing.assert_array_equal(data["lambda"][boundary_nodes(mesh)], solution["lam"])
    np.testing.assert_array_equal(np.flatnonzero(data["contact"]), np.sort(solution["active"]))
    np.testing.assert_array_equal(data["triangles"], mesh.t.T)
