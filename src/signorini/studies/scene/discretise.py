"""Stage ``discretise``: mesh and assemble (S_h) once per scene and ``N``.

Writes ``system.npz`` (``A`` as CSR arrays, ``b``, the constrained nodes, ``N``, the diagonal)
and ``system.json`` (problem, sizes and the assembly time), read by ``solve`` and by the
work-precision study (``studies.scene.store.load_system``).
"""

from __future__ import annotations

import logging
import os
import time

from signorini.fem.discrete import build
from signorini.pipeline.artifacts import save_json, save_npz
from signorini.studies.scene.store import SceneMesh

log = logging.getLogger(__name__)


def discretise_stage(at: SceneMesh, out_npz: str | os.PathLike, out_json: str | os.PathLike) -> dict:
    """Mesh and assemble (S_h) on one mesh of a scene; save the system and the build time."""
    problem, N, diagonal = at.problem, at.N, at.diagonal
    t0 = time.perf_counter()
    disc = build(problem, N, diagonal, mesh=None if at.paper_mesh else at.mesh())
    build_s = time.perf_counter() - t0
    A = disc.A.tocsr()
    save_npz(
        out_npz,
        data=A.data,
        indices=A.indices,
        indptr=A.indptr,
        shape=A.shape,
        b=disc.b,
        boundary=disc.boundary,
        N=N,
        diagonal=diagonal,
    )
    info = {
        "N": N,
        "h": at.h,
        "diagonal": diagonal,
        **({} if at.paper_mesh else {"mesh": dict(at.mesh_spec)}),
        "problem": problem.as_dict(),
        "n_dofs": int(disc.b.size),
        "n_constrained": int(disc.boundary.size),
        "nnz": int(A.nnz),
        "load1": os.getloadavg()[0],
        "timings": {
            "build_s": build_s,
            "note": "perf_counter around signorini.fem.discrete.build (mesh, assembly, boundary nodes; a family "
            "mesh read before it)",
        },
    }
    save_json(out_json, info)
    log.info("N=%d: %d unknowns, %d nonzeros, built in %.2f s", N, disc.b.size, A.nnz, build_s)
    return info
