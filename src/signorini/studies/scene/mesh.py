"""Stage ``mesh``: the triangulation of one scene and mesh parameter ``N`` when the scene names a
mesh family (``fem.mesh_families``), as an artifact the later stages read.

Writes ``mesh.npz`` (vertices ``p``, triangles ``t``, ``N``, the family and ``h``; read back by
``studies.scene.store.load_mesh_arrays``), ``mesh.json`` (the family and its parameters, ``h``, the
sizes, the shortest and longest edge, the smallest angle, whether the problem's singular points
are vertices, the build time) and ``mesh.vtu`` (for ParaView).  The paper's Friedrichs–Keller mesh
needs no artifact: its two integers define it, and each stage builds it in well under the time
reading it would take.
"""

from __future__ import annotations

import logging
import os
import time

from signorini.fem.mesh_families import check_mesh_spec, describe_mesh, mesh_size
from signorini.pipeline.artifacts import save_json, save_npz
from signorini.studies.scene.store import SceneMesh
from signorini.vtu import write_vtu

log = logging.getLogger(__name__)


def mesh_stage(
    at: SceneMesh, out_npz: str | os.PathLike, out_json: str | os.PathLike, out_vtu: str | os.PathLike
) -> dict:
    """Build the mesh of ``at`` from its definition; save it, what it is and how long it took."""
    family, params = check_mesh_spec(at.mesh_spec)
    t0 = time.perf_counter()
    mesh = at.build_mesh()
    build_s = time.perf_counter() - t0
    h = mesh_size(mesh)
    save_npz(out_npz, p=mesh.p, t=mesh.t, N=at.N, family=family, h=h)
    singular = at.problem.singular_points()
    described = describe_mesh(mesh, [tuple(point) for point in singular.T])
    info = {
        "N": at.N,
        "family": family,
        "params": params,
        "h": h,
        **described,
        "problem": at.problem.as_dict(),
        "load1": os.getloadavg()[0],
        "timings": {"build_s": build_s, "note": "perf_counter around SceneMesh.build_mesh"},
    }
    save_json(out_json, info)
    write_vtu(out_vtu, mesh, {})
    log.info(
        "N=%d %s %s: %d vertices, %d triangles, h = %.3e, smallest angle %.1f°, built in %.2f s",
        at.N,
        family,
        params,
        described["n_vertices"],
        described["n_triangles"],
        h,
        described["min_angle_deg"],
        build_s,
    )
    return info
