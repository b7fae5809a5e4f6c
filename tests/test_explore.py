"""The notebooks' helpers (``signorini.explore``) that decide what a scene is compared with."""

from __future__ import annotations

import math

import pytest

from signorini import explore
from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.fem.norm_names import parse_norm_name
from signorini.fem.norms import Conventions
from signorini.fem.problem import Problem
from signorini.paper import THEORETICAL_ORDERS, expected_rate

PAPER_NS = [101, 201, 301, 401, 501]


def test_published_values_belong_to_the_papers_scene_only():
    assert explore.published_mismatch(Problem(), DEFAULT_DIAGONAL, Conventions(), PAPER_NS, PAPER_NS) is None
    assert explore.published_mismatch(Problem(A=10), DEFAULT_DIAGONAL, Conventions(), PAPER_NS, PAPER_NS) is None
    others = {
        "problem": (Problem(x0=0.55, R=0.4), DEFAULT_DIAGONAL, Conventions(), PAPER_NS),
        "triangulation": (Problem(), "nw_se", Conventions(), PAPER_NS),
        "conventions": (Problem(), DEFAULT_DIAGONAL, Conventions(linf_points="vertices"), PAPER_NS),
        "meshes": (Problem(), DEFAULT_DIAGONAL, Conventions(), [11, 21, 41]),
    }
    for what, (problem, diagonal, conventions, Ns) in others.items():
        reason = explore.published_mismatch(problem, diagonal, conventions, Ns, PAPER_NS)
        assert reason is not None and what in reason, (what, reason)
    # a subset of the paper's meshes is not the paper's scene either: its regr. slope differs
    assert "meshes" in explore.published_mismatch(Problem(), DEFAULT_DIAGONAL, Conventions(), PAPER_NS[:3], PAPER_NS)


@pytest.mark.parametrize(
    "norm, order",
    [("L2", 2.0), ("L4", 2.0), ("L6", 1.5 + 2 / 6), ("Linf", 1.5), ("W12", 1.0), ("W1inf", 0.5), ("H1", 1.0),
     ("H12", 1.5), ("L4plus", 2.0), ("L4_true", 2.0), ("L2boundary", None)],
)
def test_expected_rate_of_every_family_of_the_grammar(norm, order):
    parse_norm_name(norm)  # in the grammar
    got = expected_rate(norm)
    assert got == (pytest.approx(order) if order is not None else None)
    if norm in THEORETICAL_ORDERS:
        assert math.isclose(THEORETICAL_ORDERS[norm], got)


@pytest.mark.slow
def test_a_scene_reads_through_the_store_and_shows_the_tables_cells(built_repo, tmp_path):
    """``Scene`` reads what the stages read, with their checks, and its tables are the cells of
    the committed tables (the built copy renders paper_figures/ from the smoke scene)."""
    import numpy as np
    import pandas as pd
    from helpers import clone_built

    from signorini.pipeline.artifacts import CorruptArtifactError, load_npz, save_npz

    scene = explore.Scene("smoke", built_repo)
    for table in (1, 2):
        ours = explore.ours_table(scene, table)
        written = pd.read_csv(built_repo / f"paper_figures/table{table}.csv", index_col="h")
        rows = [lab for lab in ours.index if lab != "theo."]
        np.testing.assert_array_equal(ours.loc[rows].to_numpy(), written.loc[rows, ours.columns].to_numpy(dtype=float))
    assert scene.cached_norm(21, "L4") == pytest.approx(explore.ours_table(scene, 1).loc["1/21", "L4"], rel=1e-4)
    fields = scene.fields()
    assert set(fields) >= {"x", "y", "u", "f"}
    # a solution of another mesh under this mesh's name is refused, as the stages refuse it
    repo = clone_built(built_repo, tmp_path / "repo")
    path = repo / "results/smoke/N21/solution.npz"
    other = load_npz(repo / "results/smoke/N11/solution.npz")
    save_npz(path, **{k: v for k, v in other.items() if not k.startswith("_")})
    with pytest.raises(CorruptArtifactError):
        explore.Scene("smoke", repo).solution(21)
