"""Stage ``sample``: ``u`` and ``f`` on a grid of the unit square, the data of Figure 2."""

from __future__ import annotations

import os
from collections.abc import Mapping

import numpy as np

from signorini.fem.problem import ExactProblem, make_problem
from signorini.pipeline.artifacts import save_npz

GRID = 161  # points per side


def sample_fields(problem: ExactProblem, n: int = GRID) -> dict[str, np.ndarray]:
    """``x``, ``y`` and ``u``, ``f`` on an ``n × n`` grid of the unit square."""
    t = np.linspace(0.0, 1.0, int(n))
    X, Y = np.meshgrid(t, t, indexing="xy")
    x = np.stack([X, Y])
    return {"x": X, "y": Y, "u": problem.u(x), "f": problem.f(x)}


def sample_stage(problem_params: Mapping, n: int, out_npz: str | os.PathLike) -> None:
    """Stage ``sample``: ``sample_fields`` of the scene's problem, saved."""
    save_npz(out_npz, **sample_fields(make_problem(problem_params), n))
