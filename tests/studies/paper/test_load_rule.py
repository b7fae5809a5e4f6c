"""The load vector by the norms' rule: exact where both rules are, and the stage's table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from signorini.fem.assembly import load_vector
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.norms.conventions import Conventions
from signorini.fem.problem import Problem, ProblemBase
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import save_npz
from signorini.published import TABLE1_NORMS
from signorini.studies.paper.load_rule import COLUMNS, compare_load_rules, load_rule_stage, load_vector_by_rule
from signorini.studies.scene.store import SceneMesh

PARAMS = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}


class _Quadratic(ProblemBase):
    """A stand-in problem whose f·φ is a polynomial of degree 3: every rule here integrates it exactly."""

    @staticmethod
    def f(x: np.ndarray) -> np.ndarray:
        return 1.0 + 2.0 * x[0] - x[1] + 3.0 * x[0] * x[1]


@pytest.mark.parametrize("quadrature", ["stroud4_acute1", "stroud4_right", "dunavant8"])
def test_exact_for_polynomials(quadrature):
    mesh = friedrichs_keller(7, "sw_ne")
    b = load_vector_by_rule(mesh, _Quadratic(), quadrature)
    np.testing.assert_allclose(b, load_vector(mesh, _Quadratic()), rtol=0, atol=1e-15)


def test_rules_differ_for_the_manufactured_load():
    """For the paper's f (not a polynomial) the two 16-point rules give different vectors, by little."""
    mesh, problem = friedrichs_keller(21, "sw_ne"), Problem.from_params(PARAMS)
    b_rule, b = load_vector_by_rule(mesh, problem, "stroud4_acute1"), load_vector(mesh, problem)
    change = np.max(np.abs(b_rule - b)) / np.max(np.abs(b))
    assert 0 < change < 1e-2


def test_stage_table(tmp_path):
    """On the assembled system: the default column is what was given, the change is computed."""
    at = SceneMesh(PARAMS, 21, "sw_ne")
    disc = build(at.problem, at.N, at.diagonal)
    system = tmp_path / "system.npz"
    save_npz(
        system,
        N=np.array(at.N),
        data=disc.A.data,
        indices=disc.A.indices,
        indptr=disc.A.indptr,
        shape=np.array(disc.A.shape),
        b=disc.b,
        boundary=disc.boundary,
    )
    u = solve_discrete(disc, "active_set").u
    values = evaluate_norms(at.problem, disc.mesh, u, list(TABLE1_NORMS), Conventions())
    ours = {name: (value, 1e-3 * value) for name, value in values.items()}  # a stated uncertainty of 0.1 %
    rows = compare_load_rules(at, system, ours, Conventions())
    assert [r[2] for r in rows] == list(TABLE1_NORMS) and [r[3] for r in rows] == list(values.values())
    for row in rows:
        record = dict(zip(COLUMNS, row, strict=True))
        assert record["relative_change"] == pytest.approx((record["rule_load"] - record["default_load"]) / row[3])
        assert 0 < abs(record["relative_change"]) < 0.05 and record["kkt_worst"] < 1e-8
        assert 0 < record["load_change"] < 1e-2
        # the default value's 0.1 % plus the rule solve's own round-off, far below it
        assert 1e-3 <= record["change_uncertainty"] < 1e-3 * (1 + 1e-6)


def test_stage_reads_each_meshs_norm_artifacts(tmp_path, monkeypatch):
    import signorini.studies.paper.load_rule as stage

    meshes = [SceneMesh(PARAMS, N, "sw_ne") for N in (11, 21)]
    seen = []
    monkeypatch.setattr(stage, "read_norm", lambda path, name, N: float(N))
    monkeypatch.setattr(stage, "read_uncertainty", lambda path, name, N: N / 4)
    monkeypatch.setattr(
        stage,
        "compare_load_rules",
        lambda at, system, ours, conv: seen.append((system, ours)) or [[at.N, at.h, "L4", 1, 1, 0, 0, 0, 0, "q"]],
    )
    out = tmp_path / "load_rule.csv"
    load_rule_stage(meshes, ["s11", "s21"], {"L4": ["a", "b"]}, {}, out)
    frame = pd.read_csv(out)
    assert list(frame.columns) == COLUMNS and list(frame.N) == [11, 21]
    assert seen == [("s11", {"L4": (11.0, 2.75)}), ("s21", {"L4": (21.0, 5.25)})]
