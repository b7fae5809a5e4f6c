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
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from signorini.fem.mesh import friedrichs_keller, mesh_width
from signorini.fem.problem import ExactProblem, make_problem
from signorini.pipeline.artifacts import CorruptArtifactError, load_json, load_npz, npz_provenance
from signorini.pipeline.integrity import table_defect

if TYPE_CHECKING:
    import pandas as pd
    import scipy.sparse as sp
    from skfem import MeshTri


@dataclass(frozen=True)
class SceneMesh:
    """One mesh of a scene, what a per-mesh job works on: the scene's problem parameters, the
    cells per side ``N`` and the diagonal of the Friedrichs–Keller mesh."""

    problem_params: Mapping
    N: int
    diagonal: str

    @classmethod
    def of_job(cls, job: Any) -> SceneMesh:
        """From a Snakemake job object (``params.problem``, ``params.diagonal``, ``wildcards.N``)."""
        return cls(dict(job.params.problem), int(job.wildcards.N), str(job.params.diagonal))

    @property
    def problem(self) -> ExactProblem:
        return make_problem(self.problem_params)

    @property
    def h(self) -> float:
        return mesh_width(self.N)

    def mesh(self) -> MeshTri:
        return friedrichs_keller(self.N, self.diagonal)

    def solution(self, solution_npz: str | os.PathLike) -> dict[str, np.ndarray]:
        """The arrays of a solve artifact (``u``, ``lam``, ``active``), read once and checked against
        this mesh: a truncated file, a wrong length, another diagonal or another problem (the one
        the job that wrote it recorded) raises ``CorruptArtifactError``."""
        sol = load_npz(solution_npz)
        u_h, n = sol["u"], (self.N + 1) ** 2
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
    read from the per-norm JSON artifacts; ``norm_jsons[name][k]`` belongs to ``scene_N[k]``."""
    import pandas as pd

    Ns = [int(N) for N in scene_N]
    data: dict[str, list] = {"N": Ns, "h": [mesh_width(N) for N in Ns]}
    for name, paths in norm_jsons.items():
        if len(paths) != len(Ns):
            raise ValueError(f"norm {name}: {len(paths)} artifacts for {len(Ns)} meshes")
        data[name] = [read_norm(path, name, N) for N, path in zip(Ns, paths, strict=True)]
    return pd.DataFrame(data)


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
