"""ParaView/VisIt files of a discrete solution: a VTK XML unstructured grid (``.vtu``) of the
P1 triangulation with nodal fields, written without third-party packages (base64-encoded
binary arrays with 64-bit size headers, readable by ParaView ≥ 5 and ``vtkXMLUnstructuredGridReader``)."""

from __future__ import annotations

import base64
import os
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from signorini.pipeline.artifacts import atomic_write_text

if TYPE_CHECKING:
    from skfem import MeshTri

VTK_TRIANGLE = 5
_TYPES = {np.dtype(np.float64): "Float64", np.dtype(np.int64): "Int64", np.dtype(np.uint8): "UInt8"}


def _data_array(values: np.ndarray, name: str | None = None, components: int = 1) -> str:
    values = np.ascontiguousarray(values)
    raw = values.astype(values.dtype.newbyteorder("<"), copy=False).tobytes()
    payload = base64.b64encode(np.uint64(len(raw)).tobytes() + raw).decode("ascii")
    named = f' Name="{name}"' if name else ""
    return (
        f'<DataArray type="{_TYPES[values.dtype]}"{named} NumberOfComponents="{components}" format="binary">'
        f"{payload}</DataArray>"
    )


def vtu_text(mesh: MeshTri, point_data: Mapping[str, np.ndarray]) -> str:
    """The ``.vtu`` document of a triangle mesh (``mesh.p``, ``mesh.t``) with nodal ``point_data``."""
    n_points, n_cells = mesh.p.shape[1], mesh.t.shape[1]
    points = np.vstack([mesh.p, np.zeros(n_points)]).T.astype(np.float64)
    arrays = []
    for name, values in point_data.items():
        values = np.asarray(values)
        if values.shape != (n_points,):
            raise ValueError(f"point data {name!r} has shape {values.shape}, expected ({n_points},)")
        arrays.append(_data_array(values.astype(np.float64), name))
    cells = [
        _data_array(mesh.t.T.astype(np.int64).ravel(), "connectivity"),
        _data_array(np.arange(3, 3 * n_cells + 1, 3, dtype=np.int64), "offsets"),
        _data_array(np.full(n_cells, VTK_TRIANGLE, dtype=np.uint8), "types"),
    ]
    return "\n".join(
        [
            '<?xml version="1.0"?>',
            '<VTKFile type="UnstructuredGrid" version="1.0" byte_order="LittleEndian" header_type="UInt64">',
            "<UnstructuredGrid>",
            f'<Piece NumberOfPoints="{n_points}" NumberOfCells="{n_cells}">',
            "<PointData>",
            *arrays,
            "</PointData>",
            f"<Points>{_data_array(points, components=3)}</Points>",
            "<Cells>",
            *cells,
            "</Cells>",
            "</Piece>",
            "</UnstructuredGrid>",
            "</VTKFile>",
            "",
        ]
    )


def write_vtu(path: str | os.PathLike, mesh: MeshTri, point_data: Mapping[str, np.ndarray]) -> None:
    """Write ``vtu_text`` atomically."""
    atomic_write_text(path, vtu_text(mesh, point_data))


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
