"""The rates and verdicts of the mesh-family study (``signorini.studies.meshes.rates``) on made-up
errors of known slopes: each verdict follows the data and flips when the data do."""

from __future__ import annotations

import numpy as np
import pytest

from signorini.studies.meshes.rates import rates_table, seed_groups, tolerances

N = np.array([50, 100, 200, 400])


def test_slopes_against_h_and_the_unknowns_are_the_made_up_rates(scene):
    rates = scene("ref").rates().set_index("norm")
    assert rates.loc["L4_true", "slope_h"] == pytest.approx(2.0) and rates.loc[
        "W1inf_true", "last_eoc"
    ] == pytest.approx(0.5)
    # n = (N + 1)² is not exactly h⁻²: the order against n is the slope up to that offset
    assert rates.loc["L4_true", "order_n"] == pytest.approx(2.0, abs=0.02)
    assert rates.loc["L4_true", "expected"] == 2.0 and rates.loc["W1inf_true", "expected"] == 0.5


def test_the_verdicts_follow_the_data(scene):
    table = rates_table(
        [scene("ref"), scene("slow", "delaunay", {"seed": 0}, {"L4_true": 1.8, "W1inf_true": 0.5})], "ref"
    ).set_index(["scene", "norm"])
    assert (
        table.loc[("ref", "L4_true"), "vs_expected"] == "agrees"
        and table.loc[("ref", "L4_true"), "vs_reference"] == "same"
    )
    assert (
        table.loc[("slow", "L4_true"), "vs_expected"] == "slower"
        and table.loc[("slow", "L4_true"), "vs_reference"] == "worse"
    )
    assert table.loc[("slow", "W1inf_true"), "vs_expected"] == "agrees"
    faster = rates_table([scene("ref"), scene("fast", rates={"L4_true": 2.2, "W1inf_true": 0.5})], "ref")
    assert faster.set_index(["scene", "norm"]).loc[("fast", "L4_true"), "vs_reference"] == "better"


def test_the_seed_spread_widens_the_tolerance_of_its_norm_only(scene):
    seeds = [
        scene(f"s{k}", "delaunay", {"seed": k}, {"L4_true": 2.0 + d, "W1inf_true": 0.5})
        for k, d in enumerate((0.0, 0.1, -0.05))
    ]
    assert [len(g) for g in seed_groups([scene("ref"), *seeds])] == [3]
    tol = tolerances([scene("ref"), *seeds])
    assert tol["L4_true"] == pytest.approx(0.15) and tol["W1inf_true"] == 0.03
    # within the seeds' spread a slope 0.1 off the reference is the same
    table = rates_table([scene("ref"), *seeds], "ref").set_index(["scene", "norm"])
    assert table.loc[("s1", "L4_true"), "vs_reference"] == "same"
    other_meshes = scene("s9", "delaunay", {"seed": 9}, N=N * 2)  # other meshes: not the same group
    assert [len(g) for g in seed_groups([*seeds, other_meshes])] == [3]


def test_a_graded_family_is_judged_against_the_unknowns(scene):
    graded = scene(
        "graded", "graded", {"grading": 2.0}, {"L4_true": 2.0, "W1inf_true": 1.0}, n_factor=5.0, ratio_growth=8.0
    )
    assert not graded.quasi_uniform and scene("ref").quasi_uniform
    table = rates_table([scene("ref"), graded], "ref").set_index(["scene", "norm"])
    assert table.loc[("graded", "W1inf_true"), "vs_reference"] == "better"
    assert table.loc[("graded", "W1inf_true"), "vs_expected"] == "faster"  # order against n, not the slope against h


def test_labels_name_the_family_its_parameters_and_an_even_n(scene):
    assert scene("a", "delaunay", {"seed": 1}).label == "Delaunay (seed 1)"
    assert scene("b", "graded", {"grading": 2.0}).label == "graded (grading 2)"
    assert scene("c").label == "Friedrichs–Keller, N even" and scene("d", N=N + 1).label == "Friedrichs–Keller"
    assert scene("e", "new_family").label == "new family"
