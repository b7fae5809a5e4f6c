"""Helpers of the tests (imported as ``from helpers import ...``): repository copies, Snakemake
runs and dry-run parsing, the test workflow's scenes, and the comparisons and small data that
test modules of several source modules share.

Workflow runs happen in a temporary copy of the repository (Snakefile, workflow/, src/), so
the real tree and its results/ cache are never touched.
"""

from __future__ import annotations

import importlib.util
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import meshio
import numpy as np
from snakemake_server import Server

from signorini.peers import PEER_PYTHON
from signorini.pipeline.config import load_config
from signorini.pipeline.paths import PEER_DRIVER
from signorini.published import PAPER_NORMS
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
PROBLEM = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}
# the PETSc peers' interpreter of the tests (default: the study's, /usr/bin/python3); .ci/run sets
# one without numpy for a second pass, so that the "skipped, with the reason" route is tested too
TEST_PEER_PYTHON = os.environ.get("SIGNORINI_TEST_PEER_PYTHON") or PEER_PYTHON
PEER_DRIVER_FILE = ROOT / PEER_DRIVER
# the paper's norms, and the smoke scene's meshes in the shipped config
NORMS = list(PAPER_NORMS)
SMOKE_N = [11, 21, 41]
# an errors.csv of three meshes and one norm
ERRORS = "N,h,L4\n11,0.0909,0.04\n21,0.0476,0.012\n41,0.0244,0.0035\n"


def benchmark(name: str):
    """The script ``benchmarks/<name>.py`` as a module."""
    spec = importlib.util.spec_from_file_location(name, ROOT / "benchmarks" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def copy_repo(dest: Path) -> Path:
    """Snakefile, workflow/ and src/ (the rules' code inputs) and the reference data the rules read
    (``paths.REFERENCES``) into ``dest``; mtimes preserved."""
    from signorini.pipeline.paths import REFERENCES

    shutil.copy2(ROOT / "Snakefile", dest / "Snakefile")
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    shutil.copytree(ROOT / "workflow", dest / "workflow", ignore=ignore)
    shutil.copytree(ROOT / "src", dest / "src", ignore=ignore)
    for path in REFERENCES.values():  # those outside workflow/ (docs/evidence/conventions.csv)
        (dest / path).parent.mkdir(parents=True, exist_ok=True)
        if not (dest / path).exists():
            shutil.copy2(ROOT / path, dest / path)
    return dest


def clone_built(repo: Path, dest: Path) -> Path:
    """A copy of a built repository copy (results, outputs, Snakemake's metadata), mtimes kept,
    for a test that edits or damages it."""
    shutil.copytree(repo, dest, symlinks=True, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))
    return dest


_SERVER = Server()


def snakemake(workdir: Path, *args: str, check: bool = True, timeout: float = 600) -> subprocess.CompletedProcess:
    """``snakemake args...`` run in ``workdir`` (by a child of ``snakemake_server``: the command without
    its import time); raises with the output's tail when it fails and ``check``."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    proc = _SERVER.run(SNAKEMAKE, list(args), workdir, env, timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-6000:]}")
    return proc


def planned_jobs(text: str) -> list[tuple[str, dict[str, str]]]:
    """(rule, wildcards) of every job in a dry run's output."""
    jobs: list[tuple[str, dict[str, str]]] = []
    for line in text.splitlines():
        if m := re.match(r"^\s*(?:local)?rule (\w+):$", line):  # a group job's are indented
            jobs.append((m.group(1), {}))
        elif (m := re.match(r"^\s+wildcards: (.*)$", line)) and jobs:
            jobs[-1][1].update(kv.split("=", 1) for kv in m.group(1).split(", "))
    return jobs


def planned(proc: subprocess.CompletedProcess) -> list[tuple[str, dict[str, str]]]:
    return planned_jobs(proc.stdout + proc.stderr)


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    return {rule for rule, _ in planned(proc)} - {"all"}


def dry_run_jobs(text: str) -> list[dict]:
    """Every job block of a dry run's output: ``rule``, ``wildcards``, ``input``, ``output``, ``log``."""
    jobs: list[dict] = []
    for line in text.splitlines():
        if m := re.match(r"^\s*(?:local)?rule (\w+):$", line):  # a group job's are indented
            jobs.append({"rule": m.group(1), "wildcards": {}, "input": [], "output": [], "log": []})
        elif jobs and (m := re.match(r"^\s+(input|output|log|wildcards): (.*)$", line)):
            key, value = m.groups()
            if key == "wildcards":
                jobs[-1]["wildcards"].update(kv.split("=", 1) for kv in value.split(", "))
            else:  # a path with its flags as Snakemake prints them: "paper_figures/table1.csv (update)"
                jobs[-1][key] = [re.sub(r" \([a-z, ]+\)$", "", item) for item in value.split(", ")]
    return jobs


def job_key(job: dict) -> tuple[str, tuple]:
    return job["rule"], tuple(sorted(job["wildcards"].items()))


# --- the test workflow (``conftest.built_repo``) -----------------------------------------------

# Small versions of the studies beyond the paper (what `tests/end_to_end/test_studies.py` and
# `tests/studies/work_precision/test_measure.py` check end to end), next to the smoke scene and a
# scene added by the user.  They replace the shipped scenes in the built copy.
TEST_SCENES = {
    "mine": {"N": [8, 16], "norms": ["L2", "H1"], "solver": "active_set", "problem": PROBLEM},
    "theory": {
        "N": [9, 17, 33],
        "norms": ["L2", "L4", "L8", "Linf", "W12", "W14", "W1inf", "H1", "H12", "L4plus", "L4minus", "L4_true",
                  "W1inf_true"],
        "solver": "active_set",
        "problem": PROBLEM,
        "norm_jobs": "per_mesh",  # as shipped: the convention norms of a mesh in one job
    },
    "fine": {  # Table 2 continued (shipped: N = 501 ... 4001)
        "N": [9, 17],
        "norms": ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12", "L4_true", "L16_true", "Linf_true", "W14_true",
                  "W116_true", "W1inf_true", "H12_true"],
        "solver": "active_set",
        "problem": PROBLEM,
        "norm_jobs": "per_mesh",
    },
    "finest": {  # Table 2 one mesh further (shipped: N = 2001, 4001, 8001 and three of its norms)
        "N": [9, 17],
        "norms": ["L4", "W14", "H12", "L4_true", "W14_true", "H12_true"],
        "solver": "active_set",
        "problem": PROBLEM,
        "norm_jobs": "per_mesh",
    },
    "work_precision": {
        "N": [11, 21],
        "norms": ["L4", "W14"],
        "solver": "active_set",
        "problem": PROBLEM,
        "study": {
            "source": "smoke",
            "tolerances": [1e-2, 1e-8],
            "time_limit_s": 30,
            "figure_N": [11, 21],
            # the timing protocol without waiting for a quiet machine (the test machine is shared)
            "timing": {"wait_s": 0, "retries": 0, "min_repeats": 1, "budget_s": 1},
            "same_warm_start": True,
            "configs": {
                "active_set": {"solver": "active_set", "label": "active set"},
                "active_set_cold": {
                    "solver": "active_set",
                    "label": "active set (cold)",
                    "options": {"warm_start": None},
                },
                # a PETSc peer: certified rows with petsc4py under /usr/bin/python3, skipped rows without
                "petsc_tron": {
                    "solver": "petsc_tao",
                    "label": "TAO TRON",
                    "options": {"tao_type": "tron", "pc_type": "cholesky", "pc_factor_mat_solver_type": "cholmod"},
                },
            },
            "qp_solvers": ["cvxpy_osqp"],
            "peer_python": TEST_PEER_PYTHON,
        },
    },
    "stability": {
        "N": [9],
        "norms": ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12"],
        "solver": "active_set",
        "problem": PROBLEM,
        "atlas": {
            "timeout_s": 60,
            "solvers": {
                "active_set": {"solver": "active_set"},
                "osqp": {"solver": "cvxpy_osqp", "options": {"normalize": True, "tol": 1e-8, "time_limit": 60}},
                "osqp_raw": {"solver": "cvxpy_osqp", "options": {"tol": 1e-8, "time_limit": 60}},
            },
            "default_solvers": ["active_set", "osqp", "osqp_raw"],
            "cases": [
                {"name": "A_1e-9", "group": "scaling", "N": 9, "problem": {"A": 1e-9}, "reference": "A_1"},
                {"name": "A_1", "group": "scaling", "N": 9, "problem": {"A": 1.0}},
                {"name": "c_1e-06", "group": "reaction", "N": 9, "problem": {"c": 1e-6}},
                {"name": "c_1e+06", "group": "reaction", "N": 9, "problem": {"c": 1e6}},
                {"name": "N2", "group": "mesh", "N": 2, "solvers": ["active_set", "osqp"]},
                {"name": "jitter", "group": "mesh", "N": 9, "jitter": 0.2, "solvers": ["active_set"]},
                {"name": "delaunay", "group": "mesh", "N": 9, "mesh": {"family": "delaunay"},
                 "solvers": ["active_set"]},
                {"name": "f_zero", "group": "degenerate", "N": 9, "problem": {"A": 0.0}},
                {"name": "bad_spd", "group": "bad_input", "N": 9, "corrupt": "non_spd", "solvers": ["active_set"]},
            ],
        },
    },
}
# a small mesh-family study (shipped: up to 1 M unknowns per family): the reference, a Delaunay family
# of two seeds and a graded family
# (as shipped, the convention norms of a mesh in one job)
_MESH_SCENE = {"N": [9, 17, 33], "norms": ["L4", "W14", "H12", "L4_true"], "solver": "active_set", "problem": PROBLEM,
               "norm_jobs": "per_mesh"}
TEST_SCENES |= {
    "meshes_fk": _MESH_SCENE,
    "meshes_delaunay": {**_MESH_SCENE, "mesh": {"family": "delaunay", "seed": 0}},
    "meshes_delaunay_seed1": {**_MESH_SCENE, "mesh": {"family": "delaunay", "seed": 1}},
    "meshes_graded": {**_MESH_SCENE, "N": [8, 16], "mesh": {"family": "graded", "grading": 2.0}},
}
MESHES_STUDY = ["meshes_fk", "meshes_delaunay", "meshes_delaunay_seed1", "meshes_graded"]
# shipped scenes the built copy keeps as they are: the second manufactured case is tested as shipped
SHIPPED_SCENES = ("paper", "smoke", "case2")
# every target of the built copy: the paper's outputs and true norms from the smoke scene, the three
# studies, the second case
BUILT_TARGETS = (
    "all",
    "theory",
    "work_precision",
    "stability",
    "results/mine/errors.csv",
    "results/mine/eoc.csv",
    "results/case2/eoc.csv",
    "true_norms",
    "fine",
    "finest",
    "meshes",
)


# --- the scene's stages and artifacts -------------------------------------------------------------


def solve_chain(d, N: int, npz="solution.npz", json="solution.json") -> None:
    """discretise + solve of the default problem on mesh N into directory d."""
    discretise_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / f"system{N}.npz", d / f"system{N}.json")
    solve_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / f"system{N}.npz", "active_set", d / npz, d / json)


def read_vtu(path) -> dict[str, np.ndarray]:
    """The nodal fields of a .vtu file read back by meshio, with ``Points`` and the triangles."""
    mesh = meshio.read(path)
    assert [block.type for block in mesh.cells] == ["triangle"]
    return {**mesh.point_data, "Points": mesh.points, "triangles": mesh.cells[0].data}


def smoke_config(N: list[int]) -> dict:
    """The shipped config's smoke scene alone (its scene defaults filled in), on the meshes ``N``,
    rendered by the paper's outputs."""
    config = load_config(ROOT / "workflow/config.yaml")
    return {"figures_scene": "smoke", "scenes": {"smoke": {**config["scenes"]["smoke"], "N": N}}}


# --- comparisons -----------------------------------------------------------------------------------


def same_bits(x: np.ndarray, y: np.ndarray) -> bool:
    return x.dtype == y.dtype and x.shape == y.shape and np.array_equal(x.view(np.uint8), y.view(np.uint8))


def rel_max_diff(u: np.ndarray, v: np.ndarray) -> float:
    return float(np.abs(u - v).max() / np.abs(v).max())


def check_kkt_independently(A, b, B, u, lam, tol=1e-10):
    """The KKT conditions recomputed here, not through ``kkt_certificate``."""
    r = A @ u - b
    scale = max(np.abs(A @ u).max(), np.abs(b).max())
    free = np.setdiff1d(np.arange(b.size), B)
    assert np.abs(r[free]).max() <= tol * scale, "stationarity at free nodes"
    assert np.abs(r[B] - lam).max() <= tol * scale, "λ = (A u − b)_B"
    assert u[B].min() >= -tol * np.abs(u).max(), "u_B ≥ 0"
    assert lam.min() >= -tol * scale, "λ ≥ 0"
    assert np.abs(u[B] * lam).max() <= tol * np.abs(u).max() * scale, "complementarity"


def contact_table(meshes, right_end: float, single_on=()):
    """A ``contact_set.csv`` table of the scene's shape: per mesh N one component from the first
    node right of x0 = 1/2 to the arc length ``right_end`` (on the right edge), with a single node
    at s = 2.5 on the meshes ``single_on``; and the exact, strict and biactive sets."""
    import pandas as pd

    from signorini.fem.problem import Problem
    from signorini.studies.theory.contact import Arc, _rows, exact_sets

    rows = []
    for N in meshes:
        start = np.ceil(0.5 * N) / N
        arcs = [Arc(start, right_end - start, 0), *([Arc(2.5, 0.0, 1)] if N in single_on else [])]
        rows += _rows("discrete", arcs, N, 1.0 / N, sign_margin=1e6)
    for name, arcs in exact_sets(Problem()).items():
        rows += _rows(name, arcs)
    table = pd.DataFrame(rows)
    table["N"] = table["N"].astype("Int64")
    return table


def fake_interpreter(tmp: Path, kind: str) -> str:
    """A peer interpreter that cannot run the peers: missing, ours (numpy, no petsc4py), one
    without numpy (site-packages off), one whose petsc4py fails to import, one that crashes, not
    executable, one that prints something else than the probe's JSON."""
    if kind == "missing":
        return "/nonexistent/python3"
    if kind == "project":
        return sys.executable
    script = tmp / f"python-{kind}"
    body = {
        "no_numpy": f'exec "{sys.executable}" -S -I "$@"',
        "broken_petsc4py": f'PYTHONPATH="{tmp / "fake"}" exec "{sys.executable}" "$@"',
        "crash": "echo 'Segmentation fault' >&2; exit 139",
        "not_executable": "",
        "garbage": "echo 'Welcome to Python'",
    }[kind]
    fake = tmp / "fake/petsc4py"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("raise RuntimeError('petsc4py built against another PETSc')\n")
    script.write_text(f"#!/bin/sh\n{body}\n")
    script.chmod(0o644 if kind == "not_executable" else 0o755)
    return str(script)


FAKE_INTERPRETERS = {  # what the probe says of each fake_interpreter
    "missing": "not found",
    "project": "petsc4py not importable",
    "no_numpy": "numpy not importable",
    "broken_petsc4py": "RuntimeError: petsc4py built against another PETSc",
    "crash": "Segmentation fault",
    "not_executable": "PermissionError",
    "garbage": "not the probe's JSON answer: Welcome to Python",
}
