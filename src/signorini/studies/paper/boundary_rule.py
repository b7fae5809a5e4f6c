"""Stage ``h12_boundary``: the ``H^{1/2}(∂Ω)`` error of every mesh of the rendered scene with the
boundary integrals over whole edges (8 Gauss points per edge, the rule before the split) and split
at the free point and at ``x0 ± R`` (``fem.boundary``, the rule of the ``H12`` norm), so that
``reproduction.md`` shows how the split moved the ``H^{1/2}`` column against the paper."""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np

from signorini.fem.norms.conventional import BOUNDARY_POINTS, boundary_error
from signorini.fem.norms.conventions import Conventions
from signorini.formatting import csv_text
from signorini.pipeline.artifacts import atomic_write_text
from signorini.studies.scene.store import SceneMesh

COLUMNS = ["N", "h", "whole_edges", "split"]


def h12_value(l2: float, semi: float, conv: Conventions) -> float:
    """The interpolation estimate ``‖e‖_{L²}^{1/2} ‖e‖_{H¹}^{1/2}`` in the form ``conv.h12_form``."""
    h1 = float(np.hypot(l2, semi)) if conv.h12_form == "geometric_full" else semi
    return float(np.sqrt(l2 * h1))


def h12_both_rules(at: SceneMesh, u_h: np.ndarray, conv: Conventions) -> tuple[float, float]:
    """``H12`` of ``u − u_h`` with the whole-edge rule and with the split rule."""
    mesh, out = at.mesh(), []
    for split in (False, True):
        eb, dteb, ds = boundary_error(at.problem, mesh, u_h, BOUNDARY_POINTS, split)
        out.append(h12_value(float(np.sqrt(np.sum(eb**2 * ds))), float(np.sqrt(np.sum(dteb**2 * ds))), conv))
    return out[0], out[1]


def h12_boundary_stage(
    meshes: Sequence[SceneMesh],
    solutions: Sequence[str | os.PathLike],
    conventions: Mapping,
    out_csv: str | os.PathLike,
) -> None:
    """One row per mesh: ``N``, ``h``, ``H12`` over whole edges, ``H12`` split."""
    conv = Conventions(**dict(conventions))
    rows = []
    for at, path in zip(meshes, solutions, strict=True):
        whole, split = h12_both_rules(at, at.load_solution(path), conv)
        rows.append([at.N, at.h, whole, split])
    atomic_write_text(out_csv, csv_text(COLUMNS, rows))
