"""The notebooks' helpers (``signorini.explore``): what a scene is compared with, the expected
orders, locating a scene, the boundary trace, the active-set history and the artifacts' display."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest

from signorini import explore
from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.fem.norms.conventional import Conventions
from signorini.fem.problem import Problem

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


# --- the helpers the notebooks call ----------------------------------------------------------------


def test_expected_orders_match_table2_theory():
    from signorini.published import THEORETICAL_ORDERS

    assert explore.expected_orders(2) == (2.0, 1.0) and explore.expected_orders(4) == (2.0, 1.0)
    assert explore.expected_orders(16) == (THEORETICAL_ORDERS["L16"], THEORETICAL_ORDERS["W116"])
    assert explore.expected_orders(math.inf) == (THEORETICAL_ORDERS["Linf"], THEORETICAL_ORDERS["W1inf"])
    assert explore.norm_names(6) == ("L6", "W16") and explore.norm_names(2.5) == ("L2.5", "W12.5")
    assert explore.norm_names(math.inf) == ("Linf", "W1inf")
    with pytest.raises(ValueError):
        explore.expected_orders(0.5)


def test_locate_scene_prefers_paper_then_smoke(tmp_path, monkeypatch):
    monkeypatch.delenv(explore.SCENE_ENV, raising=False)
    with pytest.raises(FileNotFoundError):
        explore.locate_scene(root=tmp_path, build=False)
    for scene in ("smoke", "paper"):
        d = tmp_path / "results" / scene
        d.mkdir(parents=True)
        (d / "errors.csv").write_text("N,h,L4\n11,0.09,0.04\n21,0.047,0.01\n")
        (d / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\nregression,,1.9\n")
        assert explore.locate_scene(root=tmp_path, build=False).name == scene
    monkeypatch.setenv(explore.SCENE_ENV, "smoke")
    assert explore.locate_scene(root=tmp_path, build=False).name == "smoke"
    (tmp_path / "results/smoke/eoc.csv").write_text("N,h,L4\n21,0.047,1.9\n")  # truncated: not built
    with pytest.raises(FileNotFoundError):
        explore.locate_scene(root=tmp_path, build=False)


def test_boundary_arclength_inverts_boundary_trace():
    from signorini.fem.problem import Problem

    trace = explore.boundary_trace(Problem(), n=50)
    np.testing.assert_allclose(explore.boundary_arclength(trace["x"]), trace["s"], atol=1e-12)
    assert trace["u"].min() >= 0.0 and trace["dn_u"].min() >= -1e-12  # Signorini conditions


def test_active_set_history_matches_result():
    from signorini.fem.discrete import build
    from signorini.fem.problem import Problem

    result, history = explore.active_set_history(build(Problem(), 16), warm_start=None)
    assert list(history["iteration"]) == list(range(1, result.iterations + 1))
    assert history["changes"].iloc[-1] == 0 and history["active"].iloc[-1] == result.active.size


def test_display_artifacts(tmp_path):
    from IPython.display import Image, Markdown

    (tmp_path / "a.md").write_text("# findings\n")
    (tmp_path / "a.csv").write_text("# comment\nsolver,tol\nosqp,1e-3\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, _ = plt.subplots()
    fig.savefig(tmp_path / "a.png")
    plt.close(fig)
    paths = explore.existing(tmp_path, "a.md", "a.csv", "a.png", "missing.csv")
    assert list(paths) == ["a.md", "a.csv", "a.png"]
    objs = explore.display_artifacts(paths)
    assert isinstance(objs[1], Markdown) and isinstance(objs[5], Image)
    assert list(objs[3].columns) == ["solver", "tol"]
    assert os.fspath(paths["a.png"]).endswith("a.png")
