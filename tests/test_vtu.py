"""ParaView files of a discrete solution (``signorini.vtu``): the triangulation with nodal fields,
the doubles themselves read back, and the fields of a solution."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import read_vtu

from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import Problem
from signorini.vtu import solution_fields, vtu_mesh, write_vtu


def test_a_field_is_written_bit_for_bit_on_the_triangles(tmp_path):
    mesh = friedrichs_keller(3, jitter=0.2)
    field = np.sin(7.0 * mesh.p[0]) + 1e-300 * mesh.p[1]
    write_vtu(tmp_path / "f.vtu", mesh, {"f": field})
    data = read_vtu(tmp_path / "f.vtu")
    np.testing.assert_array_equal(data["f"], field)
    np.testing.assert_array_equal(data["Points"], np.vstack([mesh.p, np.zeros(16)]).T)
    np.testing.assert_array_equal(data["triangles"], mesh.t.T)
    assert [p.name for p in tmp_path.iterdir()] == ["f.vtu"]  # no scratch file left beside it
    with pytest.raises(ValueError, match="'g' has shape"):
        vtu_mesh(mesh, {"g": field[:-1]})


def test_solution_fields_put_the_multiplier_on_the_boundary_and_mark_the_contact_set():
    mesh, problem = friedrichs_keller(4), Problem()
    B = boundary_nodes(mesh)
    u_h = np.linspace(0.0, 1.0, mesh.p.shape[1])
    lam = np.arange(1.0, B.size + 1.0)
    fields = solution_fields(problem, mesh, u_h, lam, B[:3])
    np.testing.assert_array_equal(fields["error"], problem.u(mesh.p) - u_h)
    np.testing.assert_array_equal(fields["lambda"][B], lam)
    assert np.all(np.delete(fields["lambda"], B) == 0.0)
    np.testing.assert_array_equal(np.flatnonzero(fields["contact"]), B[:3])
