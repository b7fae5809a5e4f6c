"""The norm stage (``signorini.studies.scene.norm``): what it refuses, and the norm that bounds the
change of a norm under a perturbation of u_h."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PROBLEM, solve_chain

from signorini.fem.mesh import friedrichs_keller
from signorini.pipeline.artifacts import CorruptArtifactError, save_npz
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.store import SceneMesh


@pytest.mark.parametrize("bad", [np.nan, np.inf, -1.0])
def test_a_non_finite_norm_value_fails_the_norm_job(solved, monkeypatch, tmp_path, bad):
    import signorini.studies.scene.norm as stage

    d, at = solved
    monkeypatch.setattr(stage, "evaluate_named_norms", lambda *args, **kwargs: {"L4": bad})
    with pytest.raises(ValueError, match="not a finite non-negative number"):
        norm_stage(at, d / "solution.npz", "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()


def test_a_solution_of_another_problem_is_refused(solved, tmp_path):
    """A well-formed solution artifact copied over from a scene with another problem (A = 20)."""
    from signorini.pipeline.artifacts import load_npz, recording, save_npz

    d, at = solved
    foreign = tmp_path / "solution.npz"
    with recording({"rule": "solve", "code": "x", "params": {"problem": {**PROBLEM, "A": 20}}}):
        save_npz(foreign, **load_npz(d / "solution.npz"))
    with pytest.raises(CorruptArtifactError, match="solves the problem"):
        norm_stage(at, foreign, "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()


def test_norm_stage_refuses_corrupt_solution(tmp_path):
    npz = tmp_path / "solution.npz"
    solve_chain(tmp_path, 8)
    data = npz.read_bytes()
    npz.write_bytes(data[: len(data) // 2])
    with pytest.raises(CorruptArtifactError):
        norm_stage(SceneMesh(PROBLEM, 8, "sw_ne"), npz, "L4", tmp_path / "L4.json", {})
    assert not (tmp_path / "L4.json").exists()
    with pytest.raises(CorruptArtifactError, match="shape"):  # a solution of another mesh
        save_npz(npz, u=np.zeros(10))
        norm_stage(SceneMesh(PROBLEM, 8, "sw_ne"), npz, "L4", tmp_path / "L4.json", {})


NAMES_OF_THE_GRAMMAR = ["L2", "L4", "L16", "Linf", "L4plus", "Linfminus", "W14", "W116", "W1inf", "H1", "H12"]


@pytest.mark.parametrize("name", NAMES_OF_THE_GRAMMAR)
def test_a_perturbation_of_u_h_moves_each_norm_by_at_most_its_uncertainty_norm(name):
    """What the tables' digits rest on: ``|‖u − (u_h + δ)‖ − ‖u − u_h‖| ≤ ‖δ‖`` for the discrete norm
    (``studies.scene.norm.uncertainty_norm``: the two-sided norm for a one-sided one), also for
    the geometric-mean ``H^{1/2}`` estimate, for random and for worst-sign perturbations."""
    from dataclasses import replace

    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem
    from signorini.studies.scene.norm import uncertainty_norm

    problem, N = Problem(), 16
    mesh = friedrichs_keller(N)
    u_h = problem.u(mesh.p) * 0.97
    base = evaluate_norms(problem, mesh, u_h, [name])[name]
    rng = np.random.default_rng(11)
    other = uncertainty_norm(name)
    for scale in (1e-3, 1e-9):
        for delta in (rng.uniform(-1, 1, u_h.size), -np.sign(problem.u(mesh.p) - u_h + 1e-300)):
            delta = scale * np.abs(u_h).max() * delta
            moved = evaluate_norms(problem, mesh, u_h + delta, [name])[name]
            bound = evaluate_norms(replace(problem, A=0.0), mesh, -delta, [other])[other]
            assert abs(moved - base) <= bound * (1 + 1e-12) + 1e-15 * base


def test_uncertainty_norm_names():
    from signorini.studies.scene.norm import uncertainty_norm

    assert [uncertainty_norm(n) for n in ("L4", "L4plus", "Linfminus", "W14_true", "H12_true", "L4plus_true")] == [
        "L4",
        "L4",
        "Linf",
        "W14",
        "H12",
        "L4",
    ]


# the norms of a job without the true maximum norms, whose polish needs scipy.optimize
LIGHT_NORMS = [
    "L2", "L4", "Linf", "W14", "W1inf", "H1", "H12", "L4plus", "L2boundary", "L4_true", "W14_true", "H12_true",
]
NORM_JOB = """
import json, sys
from signorini.fem.problem import Problem
from signorini.studies.scene.norm import norms_stage
from signorini.studies.scene.store import SceneMesh
at = SceneMesh(json.loads(sys.argv[1]), int(sys.argv[2]), "sw_ne", json.loads(sys.argv[3]), sys.argv[4] or None)
norms_stage(at, sys.argv[5], {n: f"{sys.argv[6]}/{n}.json" for n in json.loads(sys.argv[7])}, {})
print(json.dumps(sorted(m for m in ("scipy", "skfem") if m in sys.modules)))
"""


@pytest.mark.parametrize("family", [{}, {"family": "graded", "grading": 2.0}])
def test_a_norm_job_imports_neither_scipy_nor_scikit_fem_and_gives_the_same_bits(family, tmp_path):
    """A norm job reads the mesh's arrays (``SceneMesh.triangles``) and the tabulated quadrature
    rules (``fem.quadrature_tables``): its process never imports SciPy or scikit-fem, whose imports
    were most of its time, and each value is bit for bit the one computed on scikit-fem's mesh."""
    import json
    import subprocess
    import sys

    from helpers import ROOT

    from signorini.fem.norms.evaluate import evaluate_named_norms
    from signorini.studies.scene.discretise import discretise_stage
    from signorini.studies.scene.mesh import mesh_stage
    from signorini.studies.scene.solve import solve_stage

    at = SceneMesh(PROBLEM, 12, "sw_ne", family)
    if family:
        mesh_stage(at, tmp_path / "mesh.npz", tmp_path / "mesh.json", tmp_path / "mesh.vtu")
        at = SceneMesh(PROBLEM, 12, "sw_ne", family, str(tmp_path / "mesh.npz"))
    discretise_stage(at, tmp_path / "system.npz", tmp_path / "system.json")
    solve_stage(at, tmp_path / "system.npz", "active_set", tmp_path / "solution.npz", tmp_path / "solution.json")
    args = [json.dumps(PROBLEM), "12", json.dumps(family), at.mesh_npz or "", str(tmp_path / "solution.npz"),
            str(tmp_path), json.dumps(LIGHT_NORMS)]
    proc = subprocess.run([sys.executable, "-c", NORM_JOB, *args], capture_output=True, text=True, cwd=ROOT, check=True)
    assert json.loads(proc.stdout.splitlines()[-1]) == []
    u_h = at.solution(tmp_path / "solution.npz")["u"]
    on_skfem_mesh = evaluate_named_norms(at.problem, at.mesh(), u_h, LIGHT_NORMS)
    for name in LIGHT_NORMS:
        assert json.loads((tmp_path / f"{name}.json").read_text(encoding="utf-8"))["value"] == on_skfem_mesh[name], name
