"""The error near the free point (``signorini.studies.paper.free_point``): the point sets give the
conventions' maxima bit for bit, the sampled maximum approaches the true norm from below, the
verdicts and windows follow from the computed values (checked on perturbed ones), the heat maps
tile the triangles, the stage writes the figure."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.norms.conventions import Conventions
from signorini.fem.problem import Problem
from signorini.pipeline.artifacts import save_npz
from signorini.studies.paper.free_point import (
    ZOOM,
    Maximum,
    elements_in,
    errors_at,
    free_point_figure,
    free_point_panel,
    free_point_stage,
    largest,
    max_function,
    max_norm,
    max_parts,
    panel,
    panels,
    point_set,
    sampled_maximum,
    sub_triangles,
    summary_lines,
    window_around,
    windows,
)
from signorini.studies.scene.store import SceneMesh

N = 9  # x0 = 0.5 = 4.5 h: the free point is an edge midpoint, as on the paper's meshes
PROBLEM = Problem()


@pytest.fixture(scope="module")
def case():
    """The mesh and a u_h: the interpolant of u, damped and perturbed (no solve needed)."""
    mesh = friedrichs_keller(N)
    rng = np.random.default_rng(1)
    u_h = 0.9 * PROBLEM.u(mesh.p) + 1e-3 * rng.standard_normal(mesh.p.shape[1])
    return mesh, u_h


@pytest.fixture(scope="module")
def norms(case):
    mesh, u_h = case
    return [max_norm(PROBLEM, mesh, u_h, Conventions(), name) for name in ("Linf", "W1inf")]


@pytest.mark.parametrize(
    "conventions",
    [
        Conventions(),
        Conventions(quadrature="dunavant8", linf_points="vertices", w1inf_points="all", w1p_form="gradient"),
        Conventions(quadrature="stroud4_right", linf_points="midpoints", w1inf_points="midpoints", w1p_form="seminorm"),
    ],
)
def test_the_point_set_maxima_are_the_conventions_norms_bit_for_bit(case, conventions):
    mesh, u_h = case
    expected = evaluate_norms(PROBLEM, mesh, u_h, ["Linf", "W1inf"], conventions)
    for name, which in (("Linf", conventions.linf_points), ("W1inf", conventions.w1inf_points)):
        pts = point_set(PROBLEM, mesh, u_h, conventions, which)
        assert largest(pts, max_parts(name, conventions.w1p_form)).value == expected[name]


def test_the_point_kinds_and_the_parts_of_the_w1inf_function(case):
    mesh, u_h = case
    pts = point_set(PROBLEM, mesh, u_h, Conventions(), "all")
    per_kind = {kind: int(np.sum(pts.kind == kind)) for kind in ("vertex", "edge midpoint", "quadrature point")}
    assert per_kind == {"vertex": 3 * 2 * N * N, "edge midpoint": 3 * 2 * N * N, "quadrature point": 16 * 2 * N * N}
    assert [p for p, _ in max_parts("W1inf", "components")] == ["|e|", "|∂₁e|", "|∂₂e|"]
    assert [p for p, _ in max_parts("W1inf", "seminorm")] == ["|∇e|"]
    with pytest.raises(ValueError):
        max_parts("L4", "components")


def test_the_sampled_maximum_approaches_the_true_norm_from_below(norms):
    for norm in norms:
        assert norm.sampled.value <= norm.true_value + norm.true_error
        assert norm.sampled.value >= norm.true_value * (1.0 - 1e-3)
        assert norm.point_max.value <= norm.true_value + norm.true_error


def test_the_sampled_maximum_refines_the_triangles_of_the_largest_samples(case):
    mesh, u_h = case
    parts = max_parts("Linf", "components")
    coarse = sampled_maximum(PROBLEM, mesh, u_h, parts, m=4, fine=4)
    fine = sampled_maximum(PROBLEM, mesh, u_h, parts, m=4, fine=64)
    assert fine.value >= coarse.value and fine.kind == "sample"


def test_the_verdict_follows_the_gap_to_the_true_norm(norms):
    norm = norms[1]
    box = window_around(PROBLEM.singular_points()[:, 0], 1.0 / N)
    hit = dataclasses.replace(norm, point_max=dataclasses.replace(norm.point_max, value=norm.true_value))
    miss = dataclasses.replace(norm, point_max=dataclasses.replace(norm.point_max, value=0.95 * norm.true_value))
    assert hit.attains and not miss.attains and miss.gap == pytest.approx(-0.05)
    item = lambda n: dataclasses.replace(_panel_stub(n, box), norm=n)  # noqa: E731
    assert "it equals it to the true norm's accuracy" in summary_lines(item(hit))
    assert "it misses it by -5.00 %" in summary_lines(item(miss))
    above = dataclasses.replace(norm, point_max=dataclasses.replace(norm.point_max, value=1.05 * norm.true_value))
    assert not above.attains and "it exceeds it by +5.00 %" in summary_lines(item(above))


def _panel_stub(norm, box):
    from signorini.studies.paper.free_point import Panel

    empty = np.zeros((2, 3, 0))
    return Panel(norm, box, "", empty, np.zeros(0), empty, np.zeros(2), norm.point_max, norm.sampled, False)


def test_the_windows_follow_where_the_maxima_lie(norms):
    h, free = 1.0 / N, PROBLEM.singular_points()[:, 0]
    norm = norms[0]
    at_free = Maximum(norm.true_value, free.copy(), "|e|", "sample")
    far = Maximum(norm.true_value, np.array([0.9, 0.8]), "|e|", "sample")
    hit = dataclasses.replace(norm, point_max=dataclasses.replace(norm.point_max, value=norm.true_value))
    assert [w[1] for w in windows(dataclasses.replace(hit, sampled=at_free), free, h)] == ["near the free point"]
    assert [w[1] for w in windows(dataclasses.replace(hit, sampled=far), free, h)][1] == "around its sampled maximum"
    low = dataclasses.replace(norm.point_max, value=0.5 * norm.true_value)
    miss = dataclasses.replace(hit, sampled=far, point_max=low)
    found = windows(miss, free, h)
    assert len(found) == 3 and found[2][2] == 1.0 / ZOOM
    zoom = found[2][0]
    assert zoom[1] - zoom[0] == pytest.approx(2 * 3.0 * ZOOM * h)


def test_a_window_stays_in_the_unit_square_at_its_size():
    box = window_around(np.array([0.99, 0.0]), 0.1)
    assert box[1] == 1.0 and box[0] == pytest.approx(0.4) and box[2] == 0.0 and box[3] == pytest.approx(0.3)


def _area(v):
    return 0.5 * np.abs((v[0, 1] - v[0, 0]) * (v[1, 2] - v[1, 0]) - (v[0, 2] - v[0, 0]) * (v[1, 1] - v[1, 0]))


def test_the_heat_map_tiles_the_triangles_with_the_function_at_the_centroids(case, norms):
    mesh, u_h = case
    norm = norms[1]
    box = window_around(PROBLEM.singular_points()[:, 0], 1.0 / N)
    item = panel(PROBLEM, mesh, u_h, norm, box, "t", m=4)
    assert sub_triangles(4).shape == (2, 3, 16)
    assert _area(item.faces).sum() == pytest.approx(_area(item.triangles).sum(), rel=1e-12)
    pts = errors_at(PROBLEM, mesh, u_h, sub_triangles(4).mean(axis=1), mesh.t[:, elements_in(mesh, box)])
    np.testing.assert_allclose(pts.x, item.faces.mean(axis=1), rtol=0, atol=1e-15)
    np.testing.assert_array_equal(item.values, max_function(norm.parts, pts.e, pts.de)[0])


def test_the_panels_mark_the_norms_maxima_or_the_largest_in_the_window(case, norms):
    mesh, u_h = case
    items = panels(PROBLEM, mesh, u_h, norms, 1.0 / N)
    assert items[0].norm.name == "Linf" and items[-1].norm.name == "W1inf"
    for item in items:
        if item.local:
            assert item.point_max.value <= item.norm.point_max.value
            assert any("in it" in line for line in summary_lines(item))
        else:
            assert item.point_max is item.norm.point_max
    ax = free_point_panel(items[0])
    assert ax.get_title() == items[0].title and ax.texts
    fig = free_point_figure(items, N)
    assert sum(ax.get_visible() for ax in fig.axes if ax.get_label() != "<colorbar>") >= len(items)


def test_the_stage_writes_the_figure(case, tmp_path):
    mesh, u_h = case
    at = SceneMesh(PROBLEM.as_dict(), N, "sw_ne")
    save_npz(tmp_path / "solution.npz", u=u_h)
    outs = {"pdf": tmp_path / "f.pdf", "png": tmp_path / "f.png"}
    free_point_stage(at, tmp_path / "solution.npz", {}, outs)
    assert outs["pdf"].read_bytes().startswith(b"%PDF") and outs["png"].stat().st_size > 10_000
