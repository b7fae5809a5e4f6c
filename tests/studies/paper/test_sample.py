"""Stage ``sample`` (``signorini.studies.paper.sample``): ``u`` and ``f`` on a grid of the unit
square, the data of Figure 2."""

from __future__ import annotations

import numpy as np
from helpers import PROBLEM

from signorini.fem.problem import Problem
from signorini.pipeline.artifacts import load_npz
from signorini.studies.paper.sample import sample_fields, sample_stage


def test_the_fields_are_the_problem_on_the_grid(tmp_path):
    problem = Problem.from_params(PROBLEM)
    fields = sample_fields(problem, 11)
    t = np.linspace(0.0, 1.0, 11)
    np.testing.assert_array_equal(fields["x"][0], t)  # x along the rows, y down the columns
    np.testing.assert_array_equal(fields["y"][:, 0], t)
    points = np.stack([fields["x"], fields["y"]])
    np.testing.assert_array_equal(fields["u"], problem.u(points))
    np.testing.assert_array_equal(fields["f"], problem.f(points))
    assert np.all(fields["u"][:, -1] == 0.0)  # x₁ = 1 lies outside the support (|x − (x0, 0)| > R)
    assert fields["u"].min() < 0.0 < fields["u"][0].max()  # u > 0 on the free part of the bottom edge
    sample_stage(PROBLEM, 11, tmp_path / "fields.npz")
    saved = load_npz(tmp_path / "fields.npz")
    for key in ("x", "y", "u", "f"):
        np.testing.assert_array_equal(saved[key], fields[key])
