"""ParaView/VisIt files of a discrete solution: the P1 triangulation with nodal fields as a VTK XML
unstructured grid (``.vtu``), written by meshio (the mesh I/O library of scikit-fem and the
ecosystem, whose writers its project tests against VTK's readers)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING

import meshio
import numpy as np

from signorini.pipeline.artifacts import atomic_write_bytes

if TYPE_CHECKING:
    from skfem import MeshTri


def vtu_mesh(mesh: MeshTri, point_data: Mapping[str, np.ndarray]) -> meshio.Mesh:
    """A meshio mesh of the triangles ``mesh.t`` on the nodes ``mesh.p`` with nodal ``point_data``."""
    n_points = mesh.p.shape[1]
    fields = {}
    for name, values in point_data.items():
        values = np.asarray(values, dtype=np.float64)
        if values.shape != (n_points,):
            raise ValueError(f"point data {name!r} has shape {values.shape}, expected ({n_points},)")
        fields[name] = values
    points = np.vstack([mesh.p, np.zeros(n_points)]).T
    return meshio.Mesh(points, [("triangle", mesh.t.T.astype(np.int64))], point_data=fields)


def write_vtu(path: str | os.PathLike, mesh: MeshTri, point_data: Mapping[str, np.ndarray]) -> None:
    """Write the ``.vtu`` file atomically (meshio writes only to a file name: it writes into a
    temporary directory, the bytes are then renamed into place like every artifact)."""
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / "solution.vtu"
        meshio.write(scratch, vtu_mesh(mesh, point_data), file_format="vtu", binary=True)
        atomic_write_bytes(path, scratch.read_bytes())


def solution_fields(problem, mesh: MeshTri, u_h: np.ndarray, lam: np.ndarray, active: np.ndarray) -> dict:
    """The nodal fields of a solution: ``u_h``, the exact ``u``, the error ``u - u_h``, the multiplier
    ``lambda`` (on the constrained boundary nodes, 0 elsewhere) and the contact set (1 where ``u_h = 0``
    is enforced)."""
    from signorini.fem.mesh import boundary_nodes

    u = problem.u(mesh.p)
    multiplier = np.zeros_like(u_h)
    multiplier[boundary_nodes(mesh)] = lam
    contact = np.zeros_like(u_h)
    contact[active] = 1.0
    return {"u_h": u_h, "u": u, "error": u - u_h, "lambda": multiplier, "contact": contact}
