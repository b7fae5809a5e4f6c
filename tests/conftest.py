"""Shared fixtures: the numerical core's small cases and the built repository copy.

Everything here is small (N ≤ 101) so that the whole suite stays fast; expensive
objects (assembled systems, exact discrete solutions, the built workflow) are built once
per session.
"""

from __future__ import annotations

import os

# One BLAS/OpenMP thread unless the caller says otherwise: the tests use small meshes,
# where threads buy nothing, and on a loaded 2-core machine busy-waiting BLAS threads
# slowed the (then PCG-based) active-set solver 5-20x (N = 101 cold start: 25 s vs 1.1 s).
# Must happen before numpy is imported.
from signorini.pipeline.jobenv import single_threaded  # noqa: E402

single_threaded()

import fcntl  # noqa: E402
import shutil  # noqa: E402
import time  # noqa: E402

import numpy as np  # noqa: E402
import pytest  # noqa: E402
import yaml  # noqa: E402
from helpers import BUILT_TARGETS, PROBLEM, SHIPPED_SCENES, TEST_SCENES, copy_repo, snakemake  # noqa: E402

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

@pytest.fixture(scope="session")
def built_repo(tmp_path_factory):
    """A repository copy whose config holds the shipped scenes ``SHIPPED_SCENES``, ``TEST_SCENES`` and
    ``figures_scene: smoke``, with every target of ``BUILT_TARGETS`` built (or of the targets named
    in ``SIGNORINI_TEST_BUILT_TARGETS``, space-separated, for a run of a few test files that need
    fewer).  Built once per run: under pytest-xdist the first worker that asks builds it under a
    file lock in the run's shared temporary directory, and the others wait for it and use it.
    Tests that edit or damage it work on ``helpers.clone_built`` copies."""
    targets = os.environ.get("SIGNORINI_TEST_BUILT_TARGETS", "").split() or list(BUILT_TARGETS)
    if not os.environ.get("PYTEST_XDIST_WORKER"):
        return _build_repo(tmp_path_factory.mktemp("built"), targets)
    shared = tmp_path_factory.getbasetemp().parent  # one directory per run, common to its workers
    with open(shared / "built.lock", "w", encoding="utf-8") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        repo, done = shared / "built", shared / "built.done"
        if not done.exists():
            shutil.rmtree(repo, ignore_errors=True)  # a build another worker failed
            repo.mkdir()
            _build_repo(repo, targets)
            done.touch()
    return repo


def _build_repo(dest, targets: list[str]):
    repo = copy_repo(dest)
    path = repo / "workflow/config.yaml"
    config = yaml.safe_load(path.read_text())
    config["scenes"] = {name: config["scenes"][name] for name in SHIPPED_SCENES} | TEST_SCENES
    # the second case's EOC test reads its three finest EOCs: its four finest meshes give them
    # unchanged (each mesh is solved on its own), at two thirds of the jobs
    config["scenes"]["case2"]["N"] = config["scenes"]["case2"]["N"][-4:]
    # and its convention norms in a job per mesh (the smoke scene keeps a job per norm, which the
    # fault tests damage one at a time): a quarter of its jobs, the same values
    config["scenes"]["case2"]["norm_jobs"] = "per_mesh"
    config["figures_scene"] = "smoke"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    t0 = time.perf_counter()
    snakemake(repo, "-c2", *targets, timeout=3600)  # a loaded 2-core machine needs more than 10 min
    if "all" in targets and len(targets) > 1:
        # the summary (in `all`) reads the other studies' outputs, which this run wrote after it:
        # rendered again from them, as the next `snakemake all` of a user would
        snakemake(repo, "-c2", "all")
    print(f"built repository copy: {time.perf_counter() - t0:.1f} s")
    return repo
