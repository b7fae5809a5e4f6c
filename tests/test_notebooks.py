"""The notebooks in notebooks/ run headless, without error, on the smoke scene.

A copy of the built repository (``conftest.built_repo``: the smoke scene and the small versions
of the studies beyond the paper) gets the notebooks; they are converted with jupytext and executed with
nbclient in a kernel running this interpreter (a kernelspec written to a temporary
``JUPYTER_PATH``, so nothing needs to be registered on the machine). ``SIGNORINI_ROOT`` and
``SIGNORINI_SCENE`` point them at the copy, so the developer's ``results/`` is never read.
"""

from __future__ import annotations

import asyncio
import json
import math
import os
import shutil
import sys
import time
from pathlib import Path

import jupytext
import numpy as np
import pytest
from helpers import clone_built
from nbclient import NotebookClient

from signorini import explore
from signorini.pipeline.jobenv import THREAD_VARIABLES

ROOT = Path(__file__).resolve().parents[1]
NOTEBOOKS = sorted((ROOT / "notebooks").glob("[0-9][0-9]_*.py"))
KERNEL = "signorini-notebook-test"
TIMEOUT_PER_CELL = 180


def test_notebooks_are_present_and_paired():
    assert [p.stem for p in NOTEBOOKS] == ["01_problem", "02_convergence", "03_solvers", "04_stability"]
    config = (ROOT / "notebooks" / "jupytext.toml").read_text()
    assert 'formats = "ipynb,py:percent"' in config
    for path in NOTEBOOKS:
        nb = jupytext.read(path)
        assert nb.metadata["jupytext"]["formats"] == "ipynb,py:percent", path.name
        assert nb.cells[0].cell_type == "markdown" and nb.cells[0].source.startswith("# 0"), path.name
        # saving from Jupyter rewrites the script: it must come back unchanged (no churn in git)
        assert jupytext.writes(nb, fmt="py:percent") == path.read_text(), f"{path.name}: not in jupytext's layout"
    assert "notebooks/*.ipynb" in (ROOT / ".gitignore").read_text().splitlines()


# --- the helpers the notebooks call ----------------------------------------------------------------


def test_expected_orders_match_table2_theory():
    from signorini.paper import THEORETICAL_ORDERS

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


# --- the notebooks, executed -----------------------------------------------------------------------


@pytest.fixture(scope="module")
def notebook_env(tmp_path_factory, built_repo):
    """A copy of the built repository (the smoke scene and the small studies) with the notebooks,
    and a kernelspec for this interpreter."""
    repo = clone_built(built_repo, tmp_path_factory.mktemp("nbrepo"))
    ignore = shutil.ignore_patterns("__pycache__", "*.ipynb", ".ipynb_checkpoints")
    shutil.copytree(ROOT / "notebooks", repo / "notebooks", ignore=ignore)

    jupyter = tmp_path_factory.mktemp("jupyter")
    spec = jupyter / "kernels" / KERNEL
    spec.mkdir(parents=True)
    argv = [sys.executable, "-m", "ipykernel_launcher", "-f", "{connection_file}"]
    (spec / "kernel.json").write_text(json.dumps({"argv": argv, "display_name": KERNEL, "language": "python"}))
    env = {
        "JUPYTER_PATH": str(jupyter),
        explore.ROOT_ENV: str(repo),
        explore.SCENE_ENV: "smoke",
        **{name: "1" for name in THREAD_VARIABLES},
        "PYTHONDONTWRITEBYTECODE": "1",
    }
    with pytest.MonkeyPatch.context() as mp:  # the kernel inherits the environment
        for key, value in env.items():
            mp.setenv(key, value)
        yield repo


@pytest.fixture(scope="module")
def executed(notebook_env):
    """Every notebook executed once, all concurrently (one kernel each): {name: (notebook, error, seconds)}."""

    async def run(path: Path):
        nb = jupytext.read(notebook_env / "notebooks" / path.name)
        client = NotebookClient(
            nb,
            kernel_name=KERNEL,
            timeout=TIMEOUT_PER_CELL,
            resources={"metadata": {"path": str(notebook_env / "notebooks")}},
        )
        t0 = time.perf_counter()
        try:
            await client.async_execute()  # raises CellExecutionError at the first failing cell
            error = None
        except Exception as exc:  # reported by the notebook's own test
            error = exc
        return path.name, (nb, error, time.perf_counter() - t0)

    async def run_all():
        return dict(await asyncio.gather(*(run(path) for path in NOTEBOOKS)))

    t0 = time.perf_counter()
    results = asyncio.run(run_all())
    print(
        f"notebooks executed concurrently in {time.perf_counter() - t0:.1f} s: "
        + ", ".join(f"{name} {sec:.1f} s" for name, (_, _, sec) in results.items())
    )
    return results


@pytest.mark.slow
@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_executes(path, executed):
    nb, error, _ = executed[path.name]
    if error is not None:
        pytest.fail(f"{path.name} failed:\n{error}", pytrace=False)
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    assert any("image/png" in o.get("data", {}) for o in outputs), "no figure produced"
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    assert "scene 'smoke'" in text  # the notebook read the copy's smoke scene, not the developer's results/


@pytest.mark.slow
def test_convergence_notebook_on_a_users_scene(notebook_env, monkeypatch):
    """Notebook 02 on the user's scene ``mine`` (other meshes, norms L2 and H1 only): no published
    value, no paper row, an expected order for every norm, no Figure 3 (it has no L4/W14)."""
    monkeypatch.setenv(explore.SCENE_ENV, "mine")
    path = notebook_env / "notebooks" / "02_convergence.py"
    nb = jupytext.read(path)
    NotebookClient(nb, kernel_name=KERNEL, timeout=TIMEOUT_PER_CELL,
                   resources={"metadata": {"path": str(path.parent)}}).execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.get("outputs", [])]
    assert not [o for o in outputs if o.get("output_type") == "error"]
    text = "".join(o.get("text", "") for o in outputs if o.get("output_type") == "stream")
    plain = [o.get("data", {}).get("text/plain", "") for o in outputs]
    assert "scene 'mine'" in text and "no published values: scene 'mine'" in text
    assert not any("paper" in p for p in plain if "ours" in p)  # the tables hold ours only
    assert not any("1/101" in p for p in plain)  # no row of the paper's meshes
    summary = next(p for p in plain if "regression slope" in p)
    assert "NaN" not in summary and "no theory" not in summary  # L2: 2, H1: 1
    assert "no Figure 3" in text
