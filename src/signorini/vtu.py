"""ParaView/VisIt files of a discrete solution: the P1 triangulation with nodal fields as a VTK XML
unstructured grid (``.vtu``), written by meshio (the mesh I/O library of scikit-fem and the
ecosystem, whose writers its project tests against VTK's readers)."""

from __future__ import annotations

import os
import stat
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


class OutputPathError(ValueError):
    """A path ``write_vtu`` does not write to; the message says why and what to give instead."""


# what a path is when it is neither a regular file nor absent (stat's tests, in this order)
SPECIAL_FILES = (
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISFIFO, "a named pipe (FIFO)"),
    (stat.S_ISSOCK, "a socket"),
)


def output_target(path: str | os.PathLike) -> Path:
    """The file ``write_vtu`` writes for ``path``: ``path`` itself when it is a regular file or a
    new name in a writable directory, or, for a symbolic link, the file it points to (resolved
    explicitly: the link stays a link and its target gets the new content).  The bytes go to a
    temporary file renamed over the target, which would put a regular file in place of a device
    (``/dev/null``), a FIFO or a socket, or in place of the link itself: those are refused, as are
    a directory and a directory that cannot be written (``OutputPathError``)."""
    given = Path(path)
    target = Path(os.path.realpath(given)) if given.is_symlink() else given
    try:
        mode: int | None = target.stat().st_mode
    except FileNotFoundError:
        mode = None  # a new file (or a link to one)
    except OSError as err:  # a loop of links, a component that is no directory
        raise OutputPathError(f"{path} cannot be used: {err.strerror}") from None
    if mode is not None and stat.S_ISDIR(mode):
        raise OutputPathError(f"{path} is a directory; give a file name, e.g. {given / 'solution.vtu'}")
    if mode is not None and not stat.S_ISREG(mode):
        kind = next((name for test, name in SPECIAL_FILES if test(mode)), "a special file")
        raise OutputPathError(
            f"{path} is {kind}, not a regular file; the file is written under a temporary name and renamed "
            "into place, which would replace it: give a regular file or a new path"
        )
    if not target.parent.is_dir():
        raise OutputPathError(f"the directory {target.parent} does not exist")
    if not os.access(target.parent, os.W_OK | os.X_OK):
        raise OutputPathError(
            f"the directory {target.parent} is not writable (the file is written there under a temporary name "
            "first); give a path in a directory you can write"
        )
    return target


def write_vtu(path: str | os.PathLike, mesh: MeshTri, point_data: Mapping[str, np.ndarray]) -> Path:
    """Write the ``.vtu`` file atomically to ``output_target(path)`` and return that path (meshio
    writes only to a file name: it writes into a temporary directory, the bytes are then renamed
    into place like every artifact)."""
    target = output_target(path)
    with tempfile.TemporaryDirectory() as tmp:
        scratch = Path(tmp) / "solution.vtu"
        meshio.write(scratch, vtu_mesh(mesh, point_data), file_format="vtu", binary=True)
        atomic_write_bytes(target, scratch.read_bytes())
    return target


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
