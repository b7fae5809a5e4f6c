"""The mesh families beyond the paper's (``signorini.fem.mesh_families``): each a conforming,
shape-regular triangulation of the unit square with its boundary on the square, of size about 1/N."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from signorini.fem.mesh import boundary_edges, friedrichs_keller
from signorini.fem.mesh_families import MESH_FAMILIES, build_mesh, graded, mesh_size, min_angle, union_jack

FAMILIES = [("friedrichs_keller", {}), ("union_jack", {}), ("graded", {"grading": 2.0}), ("delaunay", {"seed": 2})]


def _areas(mesh) -> np.ndarray:
    v = mesh.p[:, mesh.t]
    return 0.5 * np.abs((v[0, 1] - v[0, 0]) * (v[1, 2] - v[1, 0]) - (v[0, 2] - v[0, 0]) * (v[1, 1] - v[1, 0]))


@pytest.mark.parametrize("N", [5, 12])
@pytest.mark.parametrize(("family", "params"), FAMILIES)
def test_every_family_is_a_conforming_shape_regular_triangulation_of_the_square(family, params, N):
    mesh = build_mesh(family, N, **params)
    assert abs(_areas(mesh).sum() - 1.0) < 1e-12 and _areas(mesh).min() > 0.0
    edges = Counter(tuple(sorted(e)) for k in range(3) for e in mesh.t[[k, (k + 1) % 3]].T)
    assert set(edges.values()) <= {1, 2}  # conforming: no hanging node, no overlap
    once = np.array(sorted(e for e, count in edges.items() if count == 1)).T
    assert np.array_equal(once, boundary_edges(mesh))  # the edges of one triangle are the boundary's
    length = np.hypot(*(mesh.p[:, once[1]] - mesh.p[:, once[0]])).sum()
    assert abs(length - 4.0) < 1e-12
    assert min_angle(mesh) > 14.0
    assert 0.99 / N < mesh_size(mesh) < 2.5 / N


def test_friedrichs_keller_with_n_even_has_the_free_point_as_a_vertex():
    for N, expected in ((10, True), (11, False)):
        p = build_mesh("friedrichs_keller", N).p
        assert bool(np.any((p[0] == 0.5) & (p[1] == 0.0))) == expected


def test_union_jack_alternates_the_diagonals():
    """Vertex (i, j) of an even i + j inside has eight neighbours, of an odd one four."""
    N = 6
    mesh = union_jack(N)
    neighbours = Counter(int(v) for k in range(3) for v in mesh.t[[k, (k + 1) % 3]].ravel())
    degree = {v: c // 2 for v, c in neighbours.items()}  # each edge counted from both triangles
    for i, j in ((2, 2), (3, 3), (2, 3), (1, 2)):
        assert degree[i * (N + 1) + j] == (8 if (i + j) % 2 == 0 else 4)


def test_the_graded_mesh_refines_toward_its_point_at_a_bounded_cost():
    """Grading 1 leaves the Friedrichs–Keller mesh; above, the triangles within ``h`` of the point
    shrink relative to those far from it as the mesh is refined (their areas in units of ``h²``
    halve with every halving of ``h`` for grading 2), and the triangles per N² stay bounded."""
    assert np.array_equal(graded(8, grading=1.0).t, friedrichs_keller(8).t)
    counts, near = [], []
    for N in (8, 16, 32):
        mesh = graded(N, grading=2.0, x0=0.37)
        centroid = mesh.p[:, mesh.t].mean(axis=1)
        r = np.hypot(centroid[0] - 0.37, centroid[1])
        near.append(_areas(mesh)[r < 1.0 / N].max() * N**2)
        assert _areas(mesh)[r > 0.5].min() * N**2 >= 4.0 * near[-1]
        counts.append(mesh.t.shape[1] / N**2)
    assert near[2] <= near[1] / 2.0 <= near[0] / 4.0
    assert max(counts) < 1.3 * min(counts)


def test_delaunay_meshes_are_reproducible_by_seed():
    a, b, c = (build_mesh("delaunay", 10, seed=s) for s in (1, 1, 2))
    assert np.array_equal(a.p, b.p) and np.array_equal(a.t, b.t) and not np.array_equal(a.p, c.p)


def test_an_unknown_family_or_parameter_is_refused():
    with pytest.raises(ValueError, match="unknown mesh family"):
        build_mesh("hexagonal", 4)
    with pytest.raises(ValueError, match="grading"):
        build_mesh("graded", 4, grading=0.5)
    with pytest.raises(ValueError, match="jitter"):
        build_mesh("delaunay", 4, jitter=0.6)
    assert set(MESH_FAMILIES) == {name for name, _ in FAMILIES}


@pytest.mark.parametrize(("family", "params"), FAMILIES)
def test_the_convention_norms_of_the_interpolation_error_converge_on_every_family(family, params):
    """The norms under the paper's conventions run on every family (the rule placed on triangles
    that are not Friedrichs–Keller ones) and the interpolation error of the manufactured solution
    falls on refinement at about the interpolation orders in L² (2) and W^{1,2} (1)."""
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem

    problem, values = Problem(), []
    for N in (12, 24):
        mesh = build_mesh(family, N, **params)
        values.append((mesh_size(mesh), evaluate_norms(problem, mesh, problem.u(mesh.p), ["L2", "W12", "H12"])))
    (h0, coarse), (h1, fine) = values
    for name, order in (("L2", 2.0), ("W12", 1.0)):
        rate = np.log(coarse[name] / fine[name]) / np.log(h0 / h1)
        assert rate > order - 0.6, (name, rate)


def test_a_scene_mesh_block_is_checked_against_its_family():
    from signorini.fem.mesh_families import check_mesh_spec, family_parameters, paper_mesh

    assert check_mesh_spec({}) == ("friedrichs_keller", {})
    assert check_mesh_spec({"family": "graded", "grading": 3}) == ("graded", {"grading": 3})
    assert family_parameters("delaunay") == {"jitter": 0.25, "seed": 0}
    assert paper_mesh({}) and paper_mesh({"family": "friedrichs_keller"})
    assert not paper_mesh({"family": "friedrichs_keller", "jitter": 0.1}) and not paper_mesh({"family": "union_jack"})
    for spec, message in [
        ({"family": "delaunay", "grading": 2.0}, "no parameter 'grading'"),
        ({"family": "delaunay", "seed": 1.5}, "seed=1.5 must be a int"),
        ({"family": "graded", "grading": True}, "grading=True"),
        ({"family": "friedrichs_keller", "diagonal": "nw_se"}, "no parameter 'diagonal'"),
        ({"family": "voronoi"}, "unknown mesh family"),
    ]:
        with pytest.raises(ValueError, match=message):
            check_mesh_spec(spec)


def test_describe_mesh_counts_edges_angles_and_whether_the_free_point_is_a_vertex():
    from signorini.fem.mesh_families import describe_mesh

    even, odd = describe_mesh(friedrichs_keller(4), [(0.5, 0.0)]), describe_mesh(friedrichs_keller(5), [(0.5, 0.0)])
    assert even["points_are_vertices"] == [True] and odd["points_are_vertices"] == [False]
    assert (odd["n_vertices"], odd["n_triangles"]) == (36, 50)
    assert odd["longest_edge"] == pytest.approx(np.sqrt(2) / 5) and odd["shortest_edge"] == pytest.approx(0.2)
    assert odd["min_angle_deg"] == pytest.approx(45.0)
    plain = describe_mesh(union_jack(4))
    assert plain["n_triangles"] == 32 and "points_are_vertices" not in plain


def test_a_mesh_block_defines_the_same_mesh_for_a_scene_and_an_atlas_case():
    """``mesh_from_spec`` is the one reading of a ``mesh`` block: the paper's mesh for an empty one
    (with its diagonal), a family with its parameters otherwise; scenes and atlas cases build
    exactly its arrays."""
    import numpy as np

    from signorini.fem.mesh import friedrichs_keller
    from signorini.fem.mesh_families import build_mesh, mesh_from_spec
    from signorini.fem.problem import Problem
    from signorini.studies.scene.store import SceneMesh
    from signorini.studies.stability.atlas import Case
    from signorini.studies.stability.cases import build_case

    paper = mesh_from_spec(8, {}, "nw_se")
    np.testing.assert_array_equal(paper.t, friedrichs_keller(8, "nw_se").t)
    spec = {"family": "delaunay", "seed": 1}
    mesh = mesh_from_spec(9, spec)
    np.testing.assert_array_equal(mesh.p, build_mesh("delaunay", 9, seed=1).p)
    scene = SceneMesh({"x0": 0.5, "R": 0.45, "A": 10, "c": 1}, 9, "sw_ne", mesh_spec=spec).build_mesh()
    case = build_case(Case("d", "mesh", Problem().as_dict(), 9, mesh=spec)).mesh
    for other in (scene, case):
        np.testing.assert_array_equal(other.p, mesh.p)
        np.testing.assert_array_equal(other.t, mesh.t)
