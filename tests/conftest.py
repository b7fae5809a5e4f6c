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
from helpers import PROBLEM, TEST_PEER_PYTHON, copy_repo, snakemake  # noqa: E402

from signorini.fem.discrete import build  # noqa: E402
from signorini.fem.problem import Problem  # noqa: E402
from signorini.fem.solve import solve_discrete  # noqa: E402

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


# --- the workflow, built once ---------------------------------------------------------------

# Small versions of the studies beyond the paper (what `tests/test_theory.py`,
# `test_work_precision.py` and `test_stability.py` check end to end), next to the smoke scene
# and a scene added by the user.  They replace the shipped scenes in the built copy.
TEST_SCENES = {
    "mine": {"N": [8, 16], "norms": ["L2", "H1"], "solver": "active_set", "problem": PROBLEM},
    "theory": {
        "N": [9, 17, 33],
        "norms": ["L2", "L4", "L8", "Linf", "W12", "W14", "W1inf", "H1", "H12", "L4plus", "L4minus", "L4_true",
                  "W1inf_true"],
        "solver": "active_set",
        "problem": PROBLEM,
    },
    "work_precision": {
        "N": [11, 21],
        "norms": ["L4", "W14"],
        "solver": "active_set",
        "problem": PROBLEM,
        "study": {
            "source": "smoke",
            "tolerances": [1e-2, 1e-8],
            "time_limit_s": 30,
            "figure_N": [11, 21],
            # the timing protocol without waiting for a quiet machine (the test machine is shared)
            "timing": {"wait_s": 0, "retries": 0, "min_repeats": 1, "budget_s": 1},
            "same_warm_start": True,
            "configs": {
                "active_set": {"solver": "active_set", "label": "active set"},
                "active_set_cold": {
                    "solver": "active_set",
                    "label": "active set (cold)",
                    "options": {"warm_start": None},
                },
                # a PETSc peer: certified rows with petsc4py under /usr/bin/python3, skipped rows without
                "petsc_tron": {
                    "solver": "petsc_tao",
                    "label": "TAO TRON",
                    "options": {"tao_type": "tron", "pc_type": "cholesky", "pc_factor_mat_solver_type": "cholmod"},
                },
            },
            "qp_solvers": ["OSQP"],
            "peer_python": TEST_PEER_PYTHON,
        },
    },
    "stability": {
        "N": [9],
        "norms": ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12"],
        "solver": "active_set",
        "problem": PROBLEM,
        "atlas": {
            "timeout_s": 60,
            "solvers": {
                "active_set": {"solver": "active_set"},
                "osqp": {"solver": "cvxpy_osqp", "options": {"normalize": True, "tol": 1e-8, "time_limit": 60}},
                "osqp_raw": {"solver": "cvxpy_osqp", "options": {"tol": 1e-8, "time_limit": 60}},
            },
            "default_solvers": ["active_set", "osqp", "osqp_raw"],
            "cases": [
                {"name": "A_1e-9", "group": "scaling", "N": 9, "problem": {"A": 1e-9}, "reference": "A_1"},
                {"name": "A_1", "group": "scaling", "N": 9, "problem": {"A": 1.0}},
                {"name": "c_1e-06", "group": "reaction", "N": 9, "problem": {"c": 1e-6}},
                {"name": "c_1e+06", "group": "reaction", "N": 9, "problem": {"c": 1e6}},
                {"name": "N2", "group": "mesh", "N": 2, "solvers": ["active_set", "osqp"]},
                {"name": "jitter", "group": "mesh", "N": 9, "jitter": 0.2, "solvers": ["active_set"]},
                {"name": "f_zero", "group": "degenerate", "N": 9, "problem": {"A": 0.0}},
                {"name": "bad_spd", "group": "bad_input", "N": 9, "corrupt": "non_spd", "solvers": ["active_set"]},
            ],
        },
    },
}
# shipped scenes the built copy keeps as they are: the second manufactured case is tested as shipped
SHIPPED_SCENES = ("paper", "smoke", "case2")
# every target of the built copy: the paper's outputs and true norms from the smoke scene, the three
# studies, the second case
BUILT_TARGETS = (
    "all",
    "theory",
    "work_precision",
    "stability",
    "results/mine/errors.csv",
    "results/mine/eoc.csv",
    "results/case2/eoc.csv",
    "true_norms",
)


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
    config["figures_scene"] = "smoke"
    path.write_text(yaml.safe_dump(config, sort_keys=False))
    t0 = time.perf_counter()
    snakemake(repo, "-c2", *targets, timeout=3600)  # a loaded 2-core machine needs more than 10 min
    print(f"built repository copy: {time.perf_counter() - t0:.1f} s")
    return repo
