"""Stage ``mesh`` (``signorini.studies.scene.mesh``): a family's mesh written once, read back by the
later stages (``store.load_mesh_arrays``) and by meshio, and the paper's mesh built where it is needed."""

from __future__ import annotations

import meshio
import numpy as np
import pytest
from helpers import PROBLEM

from signorini.fem.discrete import build
from signorini.fem.mesh import boundary_nodes, friedrichs_keller, mesh_width
from signorini.fem.mesh_families import build_mesh, mesh_size
from signorini.pipeline.artifacts import CorruptArtifactError, load_json
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.mesh import mesh_stage
from signorini.studies.scene.store import SceneMesh, load_mesh_arrays, load_system

DELAUNAY = {"family": "delaunay", "seed": 3}


def test_the_mesh_artifact_is_the_built_mesh_and_meshio_reads_it(tmp_path):
    at = SceneMesh(PROBLEM, 12, "sw_ne", DELAUNAY)
    info = mesh_stage(at, tmp_path / "mesh.npz", tmp_path / "mesh.json", tmp_path / "mesh.vtu")
    built = build_mesh("delaunay", 12, seed=3)
    mesh, h = load_mesh_arrays(tmp_path / "mesh.npz", 12, "delaunay")
    np.testing.assert_array_equal(mesh.p, built.p)
    np.testing.assert_array_equal(mesh.t, built.t)
    assert h == mesh_size(built) == info["h"]
    assert info["family"] == "delaunay" and info["params"] == {"seed": 3}
    assert info["points_are_vertices"] == [True]  # 13 equally spaced points on the bottom edge: one at 1/2
    assert info["n_vertices"] == built.p.shape[1] and 0.0 < info["min_angle_deg"] < 60.0
    assert {k: v for k, v in load_json(tmp_path / "mesh.json").items() if not k.startswith("_")} == info
    vtu = meshio.read(tmp_path / "mesh.vtu")
    np.testing.assert_array_equal(vtu.points[:, :2].T, built.p)
    np.testing.assert_array_equal(vtu.cells_dict["triangle"].T, built.t)


def test_a_mesh_of_another_family_or_size_is_refused(tmp_path):
    mesh_stage(SceneMesh(PROBLEM, 8, "sw_ne", DELAUNAY), tmp_path / "m.npz", tmp_path / "m.json", tmp_path / "m.vtu")
    with pytest.raises(CorruptArtifactError, match="not the graded mesh"):
        load_mesh_arrays(tmp_path / "m.npz", 8, "graded")
    with pytest.raises(CorruptArtifactError, match="N=9"):
        SceneMesh(PROBLEM, 9, "sw_ne", DELAUNAY, str(tmp_path / "m.npz")).mesh()


def test_a_scene_mesh_reads_its_family_mesh_and_assembles_on_it(tmp_path):
    at = SceneMesh(PROBLEM, 10, "sw_ne", {"family": "union_jack"})
    mesh_stage(at, tmp_path / "mesh.npz", tmp_path / "mesh.json", tmp_path / "mesh.vtu")
    reading = SceneMesh(PROBLEM, 10, "sw_ne", {"family": "union_jack"}, str(tmp_path / "mesh.npz"))
    assert not reading.paper_mesh and reading.h == pytest.approx(np.sqrt(2) / 10) and reading.n_vertices == 121
    info = discretise_stage(reading, tmp_path / "system.npz", tmp_path / "system.json")
    A, b, boundary = load_system(tmp_path / "system.npz", 10)
    disc = build(at.problem, 10, mesh=reading.mesh())
    assert abs(A - disc.A).max() == 0.0 and np.array_equal(b, disc.b)
    np.testing.assert_array_equal(boundary, boundary_nodes(reading.mesh()))
    assert info["mesh"] == {"family": "union_jack"} and info["n_dofs"] == 121


def test_the_paper_mesh_needs_no_artifact():
    at = SceneMesh(PROBLEM, 7, "nw_se", {"family": "friedrichs_keller"})
    assert at.paper_mesh and at.h == mesh_width(7) and at.n_vertices == 64
    fk = friedrichs_keller(7, "nw_se")
    assert np.array_equal(at.mesh().t, fk.t) and np.array_equal(at.build_mesh().p, fk.p)
    jittered = SceneMesh(PROBLEM, 7, "nw_se", {"family": "friedrichs_keller", "jitter": 0.2, "seed": 4})
    assert not jittered.paper_mesh
    np.testing.assert_array_equal(jittered.mesh().p, friedrichs_keller(7, "nw_se", 0.2, 4).p)


def test_the_chain_on_a_mesh_artifact_gives_the_paper_meshs_values_where_the_meshes_coincide(tmp_path):
    """``friedrichs_keller`` with ``jitter: 0.0`` is the paper's mesh read as an artifact and assembled
    by scikit-fem: the solution and every norm, under the conventions and true, agree with the
    paper's path to round-off."""
    from signorini.studies.scene.norm import norms_stage
    from signorini.studies.scene.solve import solve_stage

    norms = ["L4", "Linf", "W14", "W1inf", "H12", "L4_true", "W1inf_true"]
    values = []
    for name, spec in (("paper", {}), ("artifact", {"family": "friedrichs_keller", "jitter": 0.0})):
        d = tmp_path / name
        d.mkdir()
        at = SceneMesh(PROBLEM, 21, "sw_ne", spec)
        if spec:
            mesh_stage(at, d / "mesh.npz", d / "mesh.json", d / "mesh.vtu")
            at = SceneMesh(PROBLEM, 21, "sw_ne", spec, str(d / "mesh.npz"))
        assert at.paper_mesh == (name == "paper")
        discretise_stage(at, d / "system.npz", d / "system.json")
        solve_stage(at, d / "system.npz", "direct", d / "solution.npz", d / "solution.json")
        infos = norms_stage(at, d / "solution.npz", {n: d / f"{n}.json" for n in norms}, {})
        values.append({n: infos[n]["value"] for n in norms})
    paper, artifact = values
    for norm in norms:
        assert artifact[norm] == pytest.approx(paper[norm], rel=1e-9), norm
