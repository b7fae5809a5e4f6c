"""The notebooks in notebooks/: paired with jupytext, and run headless, without error, on the smoke
scene; ``explore.Scene`` on the built copy.

A copy of the built repository (``conftest.built_repo``: the smoke scene and the small versions
of the studies beyond the paper) gets the notebooks; they are converted with jupytext and executed with
nbclient in a kernel running this interpreter (a kernelspec written to a temporary
``JUPYTER_PATH``, so nothing needs to be registered on the machine). ``SIGNORINI_ROOT`` and
``SIGNORINI_SCENE`` point them at the copy, so the developer's ``results/`` is never read.
"""

from __future__ import annotations

import asyncio
import json
import shutil
import sys
import time
from pathlib import Path

import jupytext
import pytest
from helpers import ROOT, clone_built
from nbclient import NotebookClient
from traitlets.config import Config

from signorini import explore
from signorini.pipeline.jobenv import THREAD_VARIABLES

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


# --- the notebooks, executed -----------------------------------------------------------------------


def notebook_client(nb, path: Path, sockets: Path) -> NotebookClient:
    """A client for the notebook at ``path`` whose kernel talks over Unix-domain sockets named
    after the notebook in ``sockets``: TCP ports are chosen by binding to port 0 and releasing
    it before the kernel binds, a window in which any other process on the machine can take the
    port and the kernel dies at start-up; socket files named per notebook cannot collide."""
    config = Config({"KernelManager": {"transport": "ipc", "ip": str(sockets / path.stem)}})
    return NotebookClient(
        nb,
        kernel_name=KERNEL,
        timeout=TIMEOUT_PER_CELL,
        resources={"metadata": {"path": str(path.parent)}},
        config=config,
    )


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
def executed(notebook_env, tmp_path_factory):
    """Every notebook executed once, all concurrently (one kernel each): {name: (notebook, error, seconds)}."""
    sockets = tmp_path_factory.mktemp("sockets")

    async def run(path: Path):
        copy = notebook_env / "notebooks" / path.name
        nb = jupytext.read(copy)
        client = notebook_client(nb, copy, sockets)
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
def test_convergence_notebook_on_a_users_scene(notebook_env, monkeypatch, tmp_path):
    """Notebook 02 on the user's scene ``mine`` (other meshes, norms L2 and H1 only): no published
    value, no paper row, an expected order for every norm, no Figure 3 (it has no L4/W14)."""
    monkeypatch.setenv(explore.SCENE_ENV, "mine")
    path = notebook_env / "notebooks" / "02_convergence.py"
    nb = jupytext.read(path)
    notebook_client(nb, path, tmp_path).execute()
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
