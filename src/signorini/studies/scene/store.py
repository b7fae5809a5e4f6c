"""Reading the scene chain's artifacts back, checked: the assembled system, the solution,
the norm values and the ``errors.csv``/``eoc.csv`` tables.

Kept apart from the stages that write them, so that a reader (a norm job, a renderer) does not
run the solver's code.  The CSV contract (``errors.csv``: one row per ``N``, columns ``N``, ``h``,
then one column per norm of the scene; ``eoc.csv`` the same columns, one row per ``N`` after the
first and a final ``regression`` row) is checked in one place, ``pipeline.integrity``.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.fem.mesh import Triangles, fk_triangles, friedrichs_keller, mesh_width
from signorini.fem.mesh_families import check_mesh_spec, mesh_from_spec, mesh_size, paper_mesh
from signorini.fem.problem import ExactProblem, make_problem
from signorini.pipeline.artifacts import CorruptArtifactError, load_json, load_npz, npz_provenance
from signorini.pipeline.integrity import table_defect

if TYPE_CHECKING:
    import pandas as pd
    import scipy.sparse as sp
    from skfem import MeshTri


@dataclass(frozen=True)
class SceneMesh:
    """One mesh of a scene, what a per-mesh job works on: the scene's problem parameters, the mesh
    parameter ``N`` (cells per side), the diagonal of the Friedrichs–Keller mesh and the scene's
    ``mesh`` block (``fem.mesh_families``: the family and its parameters; none is the paper's
    Friedrichs–Keller mesh).  The paper's mesh is built where it is needed (two integers define
    it); any other is the ``mesh`` stage's artifact ``mesh_npz`` (built here when none is given)."""

    problem_params: Mapping
    N: int
    diagonal: str
    mesh_spec: Mapping = field(default_factory=dict)
    mesh_npz: str | None = None

    @classmethod
    def of_job(cls, job: Any) -> SceneMesh:
        """From a Snakemake job object (``params.problem``, ``params.diagonal``, ``wildcards.N``, and
        where the scene names a mesh family, ``params.mesh`` and ``input.mesh``)."""
        spec = dict(getattr(job.params, "mesh", None) or {})
        given = getattr(job.input, "mesh", None)
        mesh_npz = str(given) if isinstance(given, (str, os.PathLike)) else None
        return cls(dict(job.params.problem), int(job.wildcards.N), str(job.params.diagonal), spec, mesh_npz)

    @property
    def problem(self) -> ExactProblem:
        return make_problem(self.problem_params)

    @property
    def family(self) -> str:
        return check_mesh_spec(self.mesh_spec)[0]

    @property
    def paper_mesh(self) -> bool:
        """Whether the mesh is the paper's Friedrichs–Keller mesh of ``N`` and the diagonal."""
        return paper_mesh(self.mesh_spec)

    @property
    def h(self) -> float:
        """The ``h`` the rates are measured against: ``1/N`` on the paper's mesh (its legs), the
        longest edge on any other (``fem.mesh_families.mesh_size``)."""
        return mesh_width(self.N) if self.paper_mesh else self._family[1]

    def mesh(self) -> MeshTri:
        return friedrichs_keller(self.N, self.diagonal) if self.paper_mesh else self._family_mesh

    def triangles(self) -> Triangles:
        """The mesh's vertices and triangles alone (``fem.mesh.Triangles``), the same arrays as
        ``mesh()``'s, without scikit-fem where the mesh is the paper's or read from ``mesh_npz``."""
        return fk_triangles(self.N, self.diagonal) if self.paper_mesh else self._family[0]

    def build_mesh(self) -> MeshTri:
        """The mesh built from its definition (what the ``mesh`` stage writes)."""
        return mesh_from_spec(self.N, self.mesh_spec, self.diagonal)

    @cached_property
    def _family(self) -> tuple[Triangles, float]:
        """A family mesh's arrays and its ``h``: read from ``mesh_npz`` (checked), else built."""
        if self.mesh_npz is None:
            mesh = self._family_mesh
            return Triangles(mesh.p, mesh.t), mesh_size(mesh)
        return load_mesh_arrays(self.mesh_npz, self.N, self.family)

    @cached_property
    def _family_mesh(self) -> MeshTri:
        """A family mesh: built from ``mesh_npz``'s arrays, else from its definition."""
        if self.mesh_npz is None:
            return self.build_mesh()
        from skfem import MeshTri

        return MeshTri(*self._family[0], sort_t=False)

    @property
    def n_vertices(self) -> int:
        return (self.N + 1) ** 2 if self.paper_mesh else int(self._family[0].p.shape[1])

    def solution(self, solution_npz: str | os.PathLike) -> dict[str, np.ndarray]:
        """The arrays of a solve artifact (``u``, ``lam``, ``active``), read once and checked against
        this mesh: a truncated file, a wrong length, another diagonal or another problem (the one
        the job that wrote it recorded) raises ``CorruptArtifactError``."""
        sol = load_npz(solution_npz)
        u_h, n = sol["u"], self.n_vertices
        if u_h.shape != (n,):
            raise CorruptArtifactError(f"{solution_npz}: u has shape {u_h.shape}, expected ({n},) for N={self.N}")
        if "diagonal" in sol and str(sol["diagonal"]) != self.diagonal:
            raise CorruptArtifactError(f"{solution_npz}: solved with diagonal {sol['diagonal']}, not {self.diagonal}")
        recorded = (npz_provenance(sol) or {}).get("params", {}).get("problem")
        if recorded is not None and make_problem(recorded) != self.problem:
            raise CorruptArtifactError(
                f"{solution_npz}: solves the problem {make_problem(recorded).as_dict()}, "
                f"not {self.problem.as_dict()}"
            )
        return sol

    def load_solution(self, solution_npz: str | os.PathLike) -> np.ndarray:
        """``u_h`` of this mesh from a solve artifact, checked (``solution``)."""
        return self.solution(solution_npz)["u"]


def load_mesh_arrays(path: str | os.PathLike, N: int, family: str) -> tuple[Triangles, float]:
    """``(Triangles(p, t), h)`` from a ``mesh`` archive, checked to hold ``family`` at ``N``."""
    d = load_npz(path)
    if int(d["N"]) != int(N) or str(d["family"]) != family:
        raise CorruptArtifactError(
            f"{path}: holds the {d['family']} mesh of N={int(d['N'])}, not the {family} mesh of N={N}"
        )
    return Triangles(d["p"], d["t"]), float(d["h"])


def load_system(path: str | os.PathLike, N: int | None = None) -> tuple[sp.csr_matrix, np.ndarray, np.ndarray]:
    """``(A, b, constrained nodes)`` from a ``discretise`` archive (checked against ``N`` if given)."""
    import scipy.sparse as sp

    d = load_npz(path)
    if N is not None and int(d["N"]) != int(N):
        raise CorruptArtifactError(f"{path}: holds the system of N={int(d['N'])}, not N={N}")
    A = sp.csr_matrix((d["data"], d["indices"], d["indptr"]), shape=tuple(int(s) for s in d["shape"]))
    return A, d["b"], d["boundary"]


def read_norm(path: str | os.PathLike, norm: str, N: int) -> float:
    """The value of one norm artifact, checked to hold ``norm`` at ``N``."""
    art = load_json(path)
    if art.get("norm") != norm or int(art.get("N", -1)) != int(N):
        raise CorruptArtifactError(f"{path}: holds {art.get('norm')} at N={art.get('N')}, not {norm} at N={N}")
    value = float(art["value"])
    if not np.isfinite(value) or value < 0.0:
        raise CorruptArtifactError(f"{path}: {norm} = {value} is not a finite non-negative number")
    return value


def read_uncertainty(path: str | os.PathLike, norm: str, N: int) -> float:
    """How far round-off in ``u_h`` can move the value of one norm artifact (its
    ``algebraic_error.uncertainty``, ``studies.scene.norm.algebraic_uncertainty``), checked."""
    read_norm(path, norm, N)
    record = load_json(path).get("algebraic_error")
    value = float(record.get("uncertainty", np.nan)) if isinstance(record, dict) else np.nan
    if not np.isfinite(value) or value < 0.0:
        raise CorruptArtifactError(
            f"{path}: {norm} at N={N} records no algebraic-error uncertainty (written before it was "
            "recorded? delete the artifact or rerun its solve job)"
        )
    return value


def read_quadrature_error(path: str | os.PathLike, norm: str, N: int) -> dict:
    """The recorded accuracy of a ``_true`` norm artifact (``error_estimate``, ``rtol``, ``converged``,
    ``levels``), checked to hold ``norm`` at ``N``."""
    read_norm(path, norm, N)
    accuracy = load_json(path).get("quadrature_error")
    if not isinstance(accuracy, dict) or not np.isfinite(float(accuracy.get("error_estimate", np.nan))):
        raise CorruptArtifactError(f"{path}: {norm} at N={N} has no finite quadrature error estimate")
    return accuracy


def read_errors(scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str | os.PathLike]]) -> pd.DataFrame:
    """A DataFrame with columns ``N``, ``h`` and one column per norm (in the order of ``norm_jsons``),
    read from the per-norm JSON artifacts; ``norm_jsons[name][k]`` belongs to ``scene_N[k]``.  ``h``
    is the mesh's as its norm artifacts record it (``SceneMesh.h``), the same in each of them."""
    import pandas as pd

    Ns = [int(N) for N in scene_N]
    data: dict[str, list] = {"N": Ns}
    for name, paths in norm_jsons.items():
        if len(paths) != len(Ns):
            raise ValueError(f"norm {name}: {len(paths)} artifacts for {len(Ns)} meshes")
        data[name] = [read_norm(path, name, N) for N, path in zip(Ns, paths, strict=True)]
    data["h"] = [_mesh_h([paths[k] for paths in norm_jsons.values()], N) for k, N in enumerate(Ns)]
    return pd.DataFrame(data)[["N", "h", *norm_jsons]]


def _mesh_h(paths: Sequence[str | os.PathLike], N: int) -> float:
    """The ``h`` the norm artifacts of one mesh record, one value (``1/N`` without artifacts)."""
    values = {float(load_json(path)["h"]) for path in paths}
    if len(values) > 1:
        raise CorruptArtifactError(f"the norm artifacts of N={N} record different mesh widths h: {sorted(values)}")
    return values.pop() if values else mesh_width(N)


def read_uncertainties(
    scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str | os.PathLike]]
) -> pd.DataFrame:
    """``read_errors``' frame with each value replaced by its uncertainty (``read_uncertainty``)."""
    frame = read_errors(scene_N, norm_jsons)
    for name, paths in norm_jsons.items():
        frame[name] = [read_uncertainty(path, name, N) for N, path in zip(frame["N"], paths, strict=True)]
    return frame


def read_errors_csv(path: str | os.PathLike) -> pd.DataFrame:
    """``errors.csv`` (or ``eoc.csv``) as a DataFrame, ``N`` as text; a damaged file (the table
    contract of ``pipeline.integrity.table_defect``) raises ``CorruptArtifactError``."""
    import pandas as pd

    if (defect := table_defect(path)) is not None:
        raise CorruptArtifactError(f"{path}: {defect}")
    return pd.read_csv(path, dtype={"N": str}, encoding="utf-8")
