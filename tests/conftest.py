"""Shared fixtures: the numerical core's small cases and the built repository copy.

Everything here is small (N ≤ 101) so that the whole suite stays fast; expensive
objects (assembled systems, exact discrete solutions, the built workflow) are built once
per session.
"""

from __future__ import annotations

import os

# The environment every job computes in (one BLAS/OpenMP thread, freed memory reused), for this
# process's BLAS and the processes the tests start (docs/evidence/design-measurements.md#one-thread-per-job).
# Must happen before numpy is imported.
from signorini.pipeline.jobenv import job_environment  # noqa: E402

job_environment()

from pathlib import Path  # noqa: E402

import built_copy  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from helpers import BUILT_TARGETS, PROBLEM  # noqa: E402

from signorini.fem.discrete import build  # noqa: E402
from signorini.fem.problem import Problem  # noqa: E402
from signorini.fem.solve import solve_discrete  # noqa: E402
from signorini.studies.scene.discretise import discretise_stage  # noqa: E402
from signorini.studies.scene.solve import solve_stage  # noqa: E402
from signorini.studies.scene.store import SceneMesh  # noqa: E402

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


@pytest.fixture(scope="module")
def solved(tmp_path_factory):
    """The default problem discretised and solved on N = 8 by the scene's stages: (directory, mesh)."""
    d = tmp_path_factory.mktemp("faults")
    at = SceneMesh(PROBLEM, 8, "sw_ne")
    discretise_stage(at, d / "system.npz", d / "system.json")
    solve_stage(at, d / "system.npz", "active_set", d / "solution.npz", d / "solution.json")
    return d, at


# --- the workflow, built once ---------------------------------------------------------------

def _built_targets() -> list[str]:
    return os.environ.get("SIGNORINI_TEST_BUILT_TARGETS", "").split() or list(BUILT_TARGETS)


def _shared_directory(tmp_path_factory) -> Path:
    """The run's directory common to its pytest-xdist workers (the run's own one without xdist)."""
    base = tmp_path_factory.getbasetemp()
    return base.parent if os.environ.get("PYTEST_XDIST_WORKER") else base


def pytest_collection_modifyitems(config, items):
    """The end-to-end tests last, the files that use the built copy after the others (with
    ``--no-loadscope-reorder``, which the Makefile passes, xdist hands out files in this order): the
    built copy is built in the background meanwhile (``built_copy``)."""
    built = {item.path for item in items if "built_repo" in getattr(item, "fixturenames", ())}
    items.sort(key=lambda item: ("end_to_end" in item.path.parts, item.path in built))


@pytest.fixture(scope="session", autouse=True)
def _start_the_built_copy(request, tmp_path_factory):
    """Start building the built copy at the beginning of a run that has a test needing it."""
    if any("built_repo" in getattr(item, "fixturenames", ()) for item in request.session.items):
        built_copy.start(_shared_directory(tmp_path_factory), _built_targets())


@pytest.fixture(scope="session")
def built_repo(tmp_path_factory):
    """A repository copy whose config holds the shipped scenes ``SHIPPED_SCENES``, ``TEST_SCENES`` and
    ``figures_scene: smoke``, with every target of ``BUILT_TARGETS`` built (or of the targets named
    in ``SIGNORINI_TEST_BUILT_TARGETS``, space-separated, for a run of a few test files that need
    fewer).  Built once per run, in the background from the run's start (``built_copy``); tests that
    edit or damage it work on ``helpers.clone_built`` copies."""
    return built_copy.ensure(_shared_directory(tmp_path_factory), _built_targets())
