"""Stage ``vtk`` (opt-in): one solution of a scene as ``solution.vtu`` for ParaView, with ``u_h``,
the exact ``u``, the error, the multiplier ``λ`` on the boundary and the contact set."""

from __future__ import annotations

import os

from signorini.studies.scene.store import SceneMesh
from signorini.vtu import solution_fields, write_vtu


def vtk_stage(at: SceneMesh, solution_npz: str | os.PathLike, out_vtu: str | os.PathLike) -> None:
    """Write the solution of one mesh of a scene as a VTK unstructured grid."""
    sol = at.solution(solution_npz)
    mesh = at.mesh()
    write_vtu(out_vtu, mesh, solution_fields(at.problem, mesh, sol["u"], sol["lam"], sol["active"]))
