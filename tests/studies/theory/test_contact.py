"""The discrete and exact contact sets (``signorini.studies.theory.contact``): the unrolled
boundary, the components of ``Ã_h``, the exact sets against u and ∂_n u, and the verdicts on
condition (A_h) and on the Hausdorff distance, each flipped by perturbed data."""

from __future__ import annotations

import math

import numpy as np
import pandas as pd
import pytest

from signorini.fem.problem import Problem
from signorini.studies.scene.store import SceneMesh
from signorini.studies.theory.contact import (
    PERIMETER,
    Arc,
    arc_length,
    boundary_loop,
    components,
    condition_ah,
    contact_distances,
    contact_set_stage,
    contact_table,
    decrease_verdict,
    directed_distance,
    end_families,
    end_rate_covered,
    exact_sets,
    free_end_verdict,
    hausdorff_verdicts,
    mesh_ends,
    points,
    zero_threshold,
)

PARAMS = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}


def test_arc_length_and_points_invert_each_other_counter_clockwise_from_the_origin():
    s = np.array([0.0, 0.25, 1.0, 1.5, 2.0, 2.75, 3.0, 3.5])
    p = points(s)
    np.testing.assert_allclose(p[:, [1, 3, 5, 7]], [[0.25, 1.0, 0.25, 0.0], [0.0, 0.5, 1.0, 0.5]])
    np.testing.assert_allclose(arc_length(p), s)
    np.testing.assert_allclose(points([4.25]), points([0.25]))  # modulo the perimeter


def test_an_arc_wraps_through_the_origin_and_samples_its_corners():
    arc = Arc(3.5, 1.0)  # the left edge's lower half, then the bottom edge's left half
    assert arc.end == pytest.approx(0.5)
    assert list(arc.contains([3.6, 0.2, 0.6, 2.0])) == [True, True, False, False]
    samples = arc.samples(0.3)
    assert np.max(np.diff(samples)) <= 0.3 + 1e-12 and 4.0 in samples  # the corner (0, 0) is a sample
    assert Arc(1.0, 0.0).ends == [1.0] and Arc(0.0, PERIMETER).ends == [] and Arc(3.5, 1.0).ends == [3.5, 0.5]


def test_components_are_the_runs_of_contact_nodes_cyclically():
    s = np.arange(8) * 0.5  # 8 nodes on the loop, h = 0.5
    contact = np.array([1, 1, 0, 1, 0, 0, 1, 1], bool)
    arcs = components(s, contact)
    # the run 3.0, 3.5, 0.0, 0.5 wraps through s = 0; node 1.5 is a single node
    assert [(a.start, a.length, a.nodes) for a in arcs] == [(1.5, 0.0, 1), (3.0, 1.5, 4)]
    assert components(s, np.ones(8, bool)) == [Arc(0.0, PERIMETER, 8)]
    assert components(s, np.zeros(8, bool)) == []


def test_the_boundary_loop_of_a_mesh_is_ordered_by_arc_length():
    mesh = SceneMesh(PARAMS, 4, "sw_ne").mesh()
    nodes, s = boundary_loop(mesh.p)
    assert nodes.size == 16 and np.all(np.diff(s) > 0)
    np.testing.assert_allclose(s, np.arange(16) / 4)
    np.testing.assert_allclose(arc_length(mesh.p[:, nodes]), s)


def test_the_zero_threshold_is_the_certificates_rounding_floor():
    from signorini.solvers.certificate import ROUNDOFF_FACTOR

    assert zero_threshold(np.array([0.0, -2.0, 1.0])) == ROUNDOFF_FACTOR * np.finfo(float).eps * 2.0


@pytest.mark.parametrize("problem", [Problem(), Problem(x0=0.4, R=0.3, A=2.0)])
def test_the_exact_sets_are_where_u_and_its_normal_derivative_vanish(problem):
    """Sampling u and ∂_n u on ∂Ω: u = 0 exactly on the contact set and > 0 off it, ∂_n u > 0 on
    the strict part's interior, ∂_n u = 0 on the biactive set."""
    sets = exact_sets(problem)
    s = np.linspace(0.0, PERIMETER, 4001, endpoint=False) + 1e-4
    p = points(s)
    u, grad = problem.u(p), problem.grad_u(p)
    normal = np.choose(np.minimum(np.floor(s).astype(int), 3), [-grad[1], grad[0], grad[1], -grad[0]])
    contact, strict = sets["exact"][0].contains(s), sets["strict"][0].contains(s)
    biactive = np.any([a.contains(s) for a in sets["biactive"]], axis=0)
    assert np.all(u[contact] == 0.0) and np.all(u[~contact] > 0.0)
    interior = strict & (np.abs(s - problem.x0) > 1e-3) & (np.abs(s - problem.x0 - problem.R) > 1e-3)
    assert np.all(normal[interior] > 0.0)
    assert np.all(np.abs(normal[biactive]) < 1e-12) and np.all(biactive | strict | ~contact)
    assert sets["biactive"][0] == Arc(problem.x0, 0.0)  # the free point itself


def _table(ends_by_N: dict[int, list[tuple[float, float, int]]], problem: Problem | None = None) -> pd.DataFrame:
    """A contact table with given discrete arcs (start, length, nodes) per N and the exact sets."""
    from signorini.studies.theory.contact import _rows

    rows = []
    for N, arcs in ends_by_N.items():
        rows += _rows("discrete", [Arc(*a) for a in arcs], N, 1.0 / N, sign_margin=1e6)
    for name, arcs in exact_sets(problem or Problem()).items():
        rows += _rows(name, arcs)
    table = pd.DataFrame(rows)
    table["N"] = table["N"].astype("Int64")
    return table


def _settled(N: int) -> tuple[float, float, int]:
    """The theory scene's shape: one component from x0 + h/2 to (1, ≈ 0.225) on the right edge."""
    start, stop = (math.ceil(0.5 * N) / N), 1.0 + round(0.225 * N) / N
    return (start, stop - start, round((stop - start) * N) + 1)


MESHES = (101, 201, 401, 801)


def test_condition_ah_holds_for_ends_that_settle_away_from_corners_and_each_other():
    verdict, fam = condition_ah(_table({N: [_settled(N)] for N in MESHES}))
    assert verdict.holds and verdict.strength == "measured"
    assert verdict.text.startswith("Consistent with condition (A_h) on these meshes (measured)")
    assert "the corner(s) (1, 0) lie inside Ã_h on every mesh" in verdict.text
    assert list(fam["nearest_corner"]) == ["(1, 0)", "(1, 0)"] and (fam["corner_gap"] > 0.2).all()
    assert fam.loc[0, "spread"] == pytest.approx(1 / 202 - 1 / 1602)


def test_condition_ah_fails_for_a_single_node_component():
    table = _table({N: [_settled(N), *([(2.5, 0.0, 1)] if N == 401 else [])] for N in MESHES})
    verdict, _ = condition_ah(table)
    assert not verdict.holds and "single node" in verdict.text and "N = 401" in verdict.text
    assert "number of ends" in verdict.text  # the single node also adds an end on one mesh


def test_condition_ah_fails_for_an_end_that_moves_into_a_corner():
    """The far end at s = 1 + 5h: it approaches the corner (1, 0) like h."""
    table = _table({N: [(0.5 + 0.5 / N, 0.5 + 4.5 / N, 0)] for N in MESHES})
    verdict, fam = condition_ah(table)
    assert not verdict.holds and "reaches the corner (1, 0)" in verdict.text
    assert fam.loc[1, "corner_gap"] == 0.0


def test_condition_ah_fails_when_two_ends_approach_each_other():
    """Two components whose facing ends meet as h → 0 (a gap of 20 h between them)."""
    table = _table({N: [(0.5, 0.2, 0), (0.7 + 20 / N, 0.2, 0)] for N in MESHES})
    verdict, _ = condition_ah(table)
    assert not verdict.holds and "meets another end's" in verdict.text


def test_an_end_family_covers_the_limit_of_an_end_converging_at_the_covered_rate():
    h = 1.0 / np.array(MESHES, dtype=float)
    beta = end_rate_covered(h)
    assert beta == pytest.approx(math.log(2) / math.log(801 / 101))
    s = 1.5 + h**beta  # converges to 1.5 at exactly that rate: 1.5 is the neighbourhood's edge
    table = _table({N: [(0.25, si - 0.25, 0)] for N, si in zip(MESHES, s, strict=True)})
    fam = end_families(table)
    assert fam.loc[1, "lo"] == pytest.approx(1.5)
    assert mesh_ends(table)[101] == [0.25, pytest.approx(s[0])]


def test_directed_distances_between_arcs():
    bottom, top = [Arc(0.0, 1.0)], [Arc(2.0, 1.0)]
    d, at = directed_distance(bottom, top, 1e-3)
    assert d == pytest.approx(1.0) and directed_distance(bottom, [], 0.1)[0] == math.inf
    # the farthest points of ∂Ω from [0.4, 0.6] × {0}: the corners (1, 1) (s = 2) and (0, 1) (s = 3)
    d, at = directed_distance([Arc(0.0, 4.0)], [Arc(0.4, 0.2)], 1e-3)
    assert d == pytest.approx(math.hypot(0.4, 1.0), abs=1e-3) and min(abs(at - 2.0), abs(at - 3.0)) < 1e-3


def test_the_hausdorff_verdict_is_stuck_for_the_scene_and_flips_for_a_shrinking_distance():
    table = _table({N: [_settled(N)] for N in MESHES})
    dist = contact_distances(table)
    stuck = hausdorff_verdicts(dist)
    assert not stuck[0].holds and "does not converge" in stuck[0].text and stuck[0].strength == "measured"
    assert stuck[1].holds and stuck[1].strength == "explained" and "(0.000, 1.000)" in stuck[1].text
    np.testing.assert_allclose(dist["exact_to_discrete"], np.hypot(np.ceil(0.5 * np.array(MESHES)) / MESHES, 1.0))
    assert (dist["discrete_to_exact"] <= dist["spacing"]).all() and dist["farthest_biactive_free"].all()
    assert not stuck[2].holds  # nor close to the strict part: the far end sits on the right edge
    # Ã_h = the exact set but for a gap of 5 h at the free point: the distance shrinks like h
    growing = _table({N: [(0.5 + 5 / N, 3.55 - 5 / N, 0)] for N in MESHES})
    [shrinks] = hausdorff_verdicts(contact_distances(growing))
    assert shrinks.holds and "decreases (measured)" in shrinks.text


def test_the_explanation_is_open_when_the_farthest_point_is_not_biactive():
    """Ã_h covers all of the exact set but a piece of the strict part: no biactive cause."""
    table = _table({N: [(0.9, 3.15, 0), (0.5, 0.3, 0)] for N in MESHES})
    verdicts = hausdorff_verdicts(contact_distances(table))
    assert not verdicts[0].holds and verdicts[1].strength == "open" and not verdicts[1].holds


def test_a_rate_needs_two_mesh_widths():
    assert decrease_verdict(np.array([0.1]), np.array([1.0]), "d").strength == "open"
    assert decrease_verdict(np.array([0.1, 0.05]), np.array([1.0, 0.0]), "d").strength == "open"
    assert decrease_verdict(np.array([0.1, 0.05]), np.array([1.0, 0.0]), "d", floor=1e-3).holds


def test_the_free_end_verdict_checks_the_first_node_right_of_the_free_point():
    assert free_end_verdict(_table({N: [_settled(N)] for N in MESHES})).holds
    assert "0.50 h" in free_end_verdict(_table({N: [_settled(N)] for N in MESHES})).text
    moved = _table({N: [(_settled(N)[0] + (2 / N if N == 201 else 0), 0.5, 0)] for N in MESHES})
    verdict = free_end_verdict(moved)
    assert not verdict.holds and "N = 201" in verdict.text


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """Two small meshes of the paper's problem, solved and stored as the solve stage stores them."""
    from signorini.fem.discrete import build
    from signorini.fem.solve import solve_discrete
    from signorini.pipeline.artifacts import save_npz

    root = tmp_path_factory.mktemp("contact")
    meshes, paths = [], []
    for N in (21, 41):
        at = SceneMesh(PARAMS, N, "sw_ne")
        result = solve_discrete(build(at.problem, N, "sw_ne"))
        path = root / f"N{N}.npz"
        save_npz(path, u=result.u, lam=result.lam, active=result.active, N=N, diagonal="sw_ne")
        meshes.append(at)
        paths.append(path)
    return meshes, paths


def test_the_contact_table_of_solved_meshes(solved):
    meshes, paths = solved
    table = contact_table(meshes, paths)
    disc = table[table["set"] == "discrete"]
    assert set(table["set"]) == {"discrete", "exact", "strict", "biactive"}
    for at, path in zip(meshes, paths, strict=True):
        u_h = at.load_solution(path)
        nodes, _ = boundary_loop(at.mesh().p)
        rows = disc[disc["N"] == at.N]
        assert rows["nodes"].sum() == np.count_nonzero(u_h[nodes] == 0.0)  # the solver's exact zeros
        assert (rows["sign_margin"] > 1.0).all()
        assert rows["s_start"].min() == pytest.approx(math.ceil(0.5 * at.N) / at.N)
    verdict, _ = condition_ah(table)
    assert verdict.holds


def test_the_stage_writes_the_table_and_the_figure(solved, tmp_path):
    meshes, paths = solved
    outputs = {"csv": tmp_path / "contact_set.csv", "pdf": tmp_path / "c.pdf", "png": tmp_path / "c.png"}
    table = contact_set_stage(meshes, paths, outputs)
    back = pd.read_csv(outputs["csv"], encoding="utf-8", dtype={"N": "Int64", "nodes": "Int64"})
    assert list(back.columns) == list(table.columns) and len(back) == len(table)
    assert outputs["png"].stat().st_size > 10_000 and outputs["pdf"].stat().st_size > 1000
    assert condition_ah(back)[0] == condition_ah(table)[0]


def test_the_sign_margin_is_printed_as_its_order_of_magnitude():
    """The margins of one mesh on two processors (2.1e5 and 1.9e5: their uncertainties, a first-order
    estimate of round-off, differ) print alike; a margin below 1 shows as such."""
    from signorini.studies.theory.report import margin_text

    assert margin_text(205063.2) == margin_text(187994.97) == "≥ 1e+05"
    assert margin_text(1e5) == "≥ 1e+05" and margin_text(99999.9) == "≥ 1e+04"
    assert margin_text(0.3) == "≥ 1e-01" and margin_text(float("inf")) == "inf"
