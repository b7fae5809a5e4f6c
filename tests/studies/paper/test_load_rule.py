"""The load vector by the norms' rule: exact where both rules are, and the stage's table."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from signorini.fem.assembly import load_vector
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventions import Conventions
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.published import TABLE1_NORMS
from signorini.studies.paper.load_rule import COLUMNS, compare_load_rules, load_rule_stage, load_vector_by_rule
from signorini.studies.scene.store import SceneMesh

PARAMS = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}


class _Quadratic:
    """A stand-in problem whose f·φ is a polynomial of degree 3: every rule here integrates it exactly."""

    @staticmethod
    def f(x: np.ndarray) -> np.ndarray:
        return 1.0 + 2.0 * x[0] - x[1] + 3.0 * x[0] * x[1]


@pytest.mark.parametrize("quadrature", ["stroud4_acute1", "stroud4_right", "dunavant8"])
def test_exact_for_polynomials(quadrature):
    mesh = friedrichs_keller(7, "sw_ne")
    b = load_vector_by_rule(mesh, _Quadratic, quadrature)
    np.testing.assert_allclose(b, load_vector(mesh, _Quadratic), rtol=0, atol=1e-15)


def test_rules_differ_for_the_manufactured_load():
    """For the paper's f (not a polynomial) the two 16-point rules give different vectors, by little."""
    mesh, problem = friedrichs_keller(21, "sw_ne"), Problem.from_params(PARAMS)
    b_rule, b = load_vector_by_rule(mesh, problem, "stroud4_acute1"), load_vector(mesh, problem)
    change = np.max(np.abs(b_rule - b)) / np.max(np.abs(b))
    assert 0 < change < 1e-2


def test_stage_table():
    at = SceneMesh(PARAMS, 21, "sw_ne")
    u = solve_discrete(build(at.problem, at.N, at.diagonal), "active_set").u
    rows = compare_load_rules(at, u, Conventions())
    assert [r[2] for r in rows] == list(TABLE1_NORMS)
    for row in rows:
        assert row[5] == pytest.approx((row[4] - row[3]) / row[3])
        assert abs(row[5]) < 0.05 and row[7] < 1e-8


def test_stage_writes_every_mesh(tmp_path, monkeypatch):
    import signorini.studies.paper.load_rule as stage

    meshes = [SceneMesh(PARAMS, N, "sw_ne") for N in (11, 21)]
    monkeypatch.setattr(SceneMesh, "load_solution", lambda self, path: np.zeros((self.N + 1) ** 2))
    monkeypatch.setattr(stage, "compare_load_rules", lambda at, u, conv: [[at.N, at.h, "L4", 1, 1, 0, 0, 0, "q"]])
    out = tmp_path / "load_rule.csv"
    load_rule_stage(meshes, ["a", "b"], {}, out)
    frame = pd.read_csv(out)
    assert list(frame.columns) == COLUMNS and list(frame.N) == [11, 21]
