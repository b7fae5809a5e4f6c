"""Stage ``load_rule``: Table 1's norms when the load vector is integrated by the norms' 16-point rule.

The paper states that one 16-point Gauss–Legendre-type rule evaluates both the norms and "the
integrals arising on the right-hand side of (S_h)". The workflow assembles ``b = ∫ f φ_i`` with
scikit-fem's 16-point degree-8 rule (``fem.assembly.load_vector``) and evaluates the norms with the
conventions' rule (``Conventions.quadrature``: Matlab's ``triquad(4, v)`` conical product). This
stage solves (S_h) again with ``b`` from the conventions' rule, collapsed at the same vertex, and
evaluates Table 1's norms of both solutions, so that ``reproduction.md`` reports what the choice
of the load rule changes, and how far round-off in the two solves can move each change (the sum of
the two values' algebraic-error uncertainties, ``studies.scene.norm.algebraic_uncertainties``,
relative to the default value): a change within it is not resolved.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence

import numpy as np
from skfem import MeshTri

from signorini.fem.discrete import DiscreteProblem
from signorini.fem.norms.conventional import evaluate_norms, p1_at_points, triangle_rule
from signorini.fem.norms.conventions import Conventions
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.formatting import csv_text
from signorini.pipeline.artifacts import atomic_write_text
from signorini.solvers.algebraic_error import linearised_error
from signorini.studies.scene.norm import algebraic_uncertainties
from signorini.studies.scene.store import SceneMesh, load_system, read_norm, read_uncertainty

COLUMNS = [
    "N",
    "h",
    "norm",
    "default_load",
    "rule_load",
    "relative_change",
    "change_uncertainty",
    "load_change",
    "kkt_worst",
    "quadrature",
]


def load_vector_by_rule(mesh: MeshTri, problem: Problem, quadrature: str) -> np.ndarray:
    """``b_i = ∫ f φ_i`` by the named triangle rule of the conventions (``Conventions.quadrature``),
    collapsed at the vertex the conventions' norms use: the right-hand side as the paper states it."""
    X, W, t = triangle_rule(mesh.p, mesh.t, quadrature)
    n = mesh.p.shape[1]
    x, _, _, det = p1_at_points(mesh.p, t, np.zeros(n), X)  # the points and |det J| of the rule
    lam = np.vstack([1.0 - X[0] - X[1], X[0], X[1]])  # (3, q): the P1 basis at the points
    local = (problem.f(x) * W * det[:, None]) @ lam.T  # (E, 3)
    return np.bincount(t.T.ravel(), local.ravel(), minlength=n)


def compare_load_rules(
    at: SceneMesh,
    system_npz: str | os.PathLike,
    ours: Mapping[str, tuple[float, float]],
    conv: Conventions,
) -> list[list]:
    """Table 1's norms of the scene's solution (``ours``: its norm artifacts' values and
    algebraic-error uncertainties) beside those of the solution with ``b`` by the norms' rule,
    solved on the scene's assembled system (``system_npz``): one row per norm (``COLUMNS``)."""
    A, b, boundary = load_system(system_npz, at.N)
    mesh = at.mesh()
    b_rule = load_vector_by_rule(mesh, at.problem, conv.quadrature)
    load_change = float(np.max(np.abs(b_rule - b)) / np.max(np.abs(b)))
    result = solve_discrete(DiscreteProblem(at.problem, at.N, at.diagonal, mesh, A, b_rule, boundary), "active_set")
    rule = evaluate_norms(at.problem, mesh, result.u, list(ours), conv)
    delta = linearised_error(A, b_rule, boundary, result.u, result.lam, result.active).delta
    rule_uncertainty = algebraic_uncertainties(at, mesh, delta, list(ours), conv)
    kkt = float(result.certificate.worst)
    rows = []
    for name, (value, uncertainty) in ours.items():
        change_uncertainty = (uncertainty + rule_uncertainty[name]["uncertainty"]) / value
        rows.append(
            [at.N, at.h, name, value, rule[name], (rule[name] - value) / value, change_uncertainty, load_change, kkt]
            + [conv.quadrature]
        )
    return rows


def load_rule_stage(
    meshes: Sequence[SceneMesh],
    systems: Sequence[str | os.PathLike],
    norm_jsons: Mapping[str, Sequence[str | os.PathLike]],
    conventions: Mapping,
    out_csv: str | os.PathLike,
) -> None:
    """One row per mesh and Table 1 norm (the names of ``norm_jsons``, each with its artifact per
    mesh): the norm with the default load vector and with ``b`` by the norms' rule, their relative
    change and how far round-off in the two solves can move it, the largest change of ``b``
    relative to ``max |b|`` and the certificate's worst relative KKT residual of the new solve."""
    conv = Conventions(**dict(conventions))
    rows = []
    for k, (at, system) in enumerate(zip(meshes, systems, strict=True)):
        ours = {
            name: (read_norm(paths[k], name, at.N), read_uncertainty(paths[k], name, at.N))
            for name, paths in norm_jsons.items()
        }
        rows += compare_load_rules(at, system, ours, conv)
    atomic_write_text(out_csv, csv_text(COLUMNS, rows))
