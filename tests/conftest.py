"""Shared fixtures for the numerical-core tests.

Everything here is small (N ≤ 101) so that the whole suite stays fast; expensive
objects (assembled systems, exact discrete solutions) are built once per session.
"""

from __future__ import annotations

import os

# One BLAS/OpenMP thread unless the caller says otherwise: the tests use small meshes,
# where threads buy nothing, and on a loaded 2-core machine busy-waiting BLAS threads
# slowed the (then PCG-based) active-set solver 5-20x (N = 101 cold start: 25 s vs 1.1 s).
# Must happen before numpy is imported.
for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
import pytest  # noqa: E402

from signorini import Problem  # noqa: E402
from signorini.discrete import build, solve_discrete  # noqa: E402

# (problem parameters, N, diagonal): the small meshes every solver test uses.  The
# free points are chosen so that no boundary vertex coincides with (x0, 0).
SMALL_CASES = {
    "default-N11": (dict(), 11, "sw_ne"),
    "default-N21": (dict(), 21, "sw_ne"),
    "x0=0.47,c=3-N11": (dict(x0=0.47, c=3.0), 11, "sw_ne"),
    "x0=0.47,c=3-N21": (dict(x0=0.47, c=3.0), 21, "sw_ne"),
    "x0=0.4,R=0.3,c=0-N21-nw_se": (dict(x0=0.4, R=0.3, c=0.0), 21, "nw_se"),
}


class _Cache:
    """Builds and solves each (problem, N, diagonal) once."""

    def __init__(self) -> None:
        self._discrete: dict = {}
        self._solution: dict = {}

    def discrete(self, params: dict, N: int, diagonal: str = "sw_ne"):
        key = (tuple(sorted(params.items())), N, diagonal)
        if key not in self._discrete:
            self._discrete[key] = build(Problem(**params), N, diagonal)
        return self._discrete[key]

    def solution(self, params: dict, N: int, diagonal: str = "sw_ne"):
        """The exact (active-set) solution, solved cold so it does not depend on the cascade."""
        key = (tuple(sorted(params.items())), N, diagonal)
        if key not in self._solution:
            self._solution[key] = solve_discrete(self.discrete(params, N, diagonal), "active_set", warm_start=None)
        return self._solution[key]


@pytest.fixture(scope="session")
def cache() -> _Cache:
    return _Cache()


@pytest.fixture(params=sorted(SMALL_CASES), scope="session")
def small_case(request, cache):
    """(DiscreteProblem, exact active-set SolveResult) for each small case."""
    params, N, diagonal = SMALL_CASES[request.param]
    return cache.discrete(params, N, diagonal), cache.solution(params, N, diagonal)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20240607)
