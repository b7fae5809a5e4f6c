"""The active-set iteration both exact routes share (``signorini.solvers.pdas``): the per-step
history and callback, the protocol of inexact and accurate solves, and frontier growth."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.sparse as sp

from signorini.solvers import NotConvergedError, active_set_solve
from signorini.solvers.active_set import DirectSystems
from signorini.solvers.pdas import CREEP_STEPS, WARM_START_REACH, Frontier, initial_active, iterate, prepare_qp

log = logging.getLogger(__name__)


def test_direct_route_reports_its_history_and_calls_back(cache):
    disc = cache.discrete({}, 21)
    rows: list[dict] = []
    result = active_set_solve(disc.A, disc.b, disc.boundary, callback=rows.append)
    assert rows == result.history and len(rows) == result.iterations > 1
    assert [r["iteration"] for r in rows] == list(range(1, result.iterations + 1))
    assert rows[-1]["changes"] == 0 and rows[-1]["active"] == result.active.size
    assert rows[-1]["factorizations"] == result.info["factorizations"]
    assert all(r["elapsed_s"] >= 0.0 for r in rows)


class Recorded(DirectSystems):
    """Exact solves that claim to be inexact unless asked for accuracy; records the requests."""

    exact = False

    def __init__(self, *args, wrong_until: int = 0):
        super().__init__(*args)
        self.requests: list[bool] = []
        self.wrong_until = wrong_until  # inexact solves before this many calls report a wrong u

    def __call__(self, free: np.ndarray, accurate: bool) -> np.ndarray:
        self.requests.append(accurate)
        u = super().__call__(free, accurate)
        if not accurate and len(self.requests) <= self.wrong_until:
            return -np.abs(u) - 1.0  # every free node looks violated
        return u

    def counters(self) -> dict:
        return {"accurate": self.requests[-1]}


def _run(disc, systems, max_iter=100):
    A, b, B = prepare_qp(disc.A, disc.b, disc.boundary)
    return iterate(systems, A, b, B, initial_active(A, b, B, None), max_iter, True, None, log)


def test_a_set_that_repeats_on_an_inexact_solve_is_solved_again_accurately(cache):
    disc, exact = cache.discrete({}, 21), cache.solution({}, 21)
    A, b, _ = prepare_qp(disc.A, disc.b, disc.boundary)
    systems = Recorded(A, b, 40, "auto")
    u, active, history = _run(disc, systems)
    assert systems.requests[-1] and not systems.requests[-2]  # the repeat, then its accurate solve
    assert history[-1]["accurate"] and history[-2]["changes"] == 0
    assert np.array_equal(np.sort(disc.boundary[active]), np.sort(exact.active))


def test_wrong_inexact_steps_go_on_until_an_accurate_solve_settles(cache):
    """Inexact solves that mislead the set (here: two that report every node violated) cost
    steps, never the answer: the iteration ends on an accurate solve with the exact solution.
    The path differs, so a biactive node (u = λ = 0: the corner (1, 0), where f vanishes) may
    end on the other side: a KKT point either way."""
    disc, exact = cache.discrete({}, 21), cache.solution({}, 21)
    A, b, B = prepare_qp(disc.A, disc.b, disc.boundary)
    systems = Recorded(A, b, 40, "auto", wrong_until=2)
    u, active, history = _run(disc, systems)
    assert history[-1]["accurate"] and history[-1]["changes"] == 0
    assert np.abs(u - exact.u).max() <= 1e-12 * np.abs(exact.u).max()
    differ = np.setxor1d(B[active], exact.active)
    residual = A @ u - b
    assert np.all(u[differ] == 0.0) and np.all(np.abs(residual[differ]) <= 1e-14 * np.abs(b).max())
    with pytest.raises(NotConvergedError, match="max_iter"):
        _run(disc, Recorded(A, b, 40, "auto"), max_iter=2)


@pytest.mark.parametrize("route", ["active_set", "multigrid"])
def test_a_route_uses_a_canonical_matrix_as_it_is_and_changes_none(cache, route):
    """A CSR matrix with sorted, summed indices is not copied (prepare_qp hands it on), and no
    route writes to it or to b; any other matrix is copied before it is put in that form."""
    import scipy.sparse as sp

    from signorini.solvers import solve

    disc = cache.discrete({}, 21)
    A, b = disc.A.tocsr(), disc.b.copy()
    assert A.has_canonical_format
    assert np.shares_memory(prepare_qp(A, b, disc.boundary)[0].data, A.data)
    before = (A.data.copy(), A.indices.copy(), A.indptr.copy(), b.copy())
    solve(route, A, b, disc.boundary, warm_start=None)
    for now, then in zip((A.data, A.indices, A.indptr, b), before, strict=True):
        np.testing.assert_array_equal(now, then)
    # each row's entries reversed: not canonical, so prepare_qp sorts a copy
    order = np.concatenate([np.arange(A.indptr[i], A.indptr[i + 1])[::-1] for i in range(A.shape[0])])
    messy = sp.csr_matrix((A.data[order], A.indices[order], A.indptr.copy()), shape=A.shape)
    assert not messy.has_canonical_format
    kept = messy.indices.copy()
    tidy = prepare_qp(messy, b, disc.boundary)[0]
    assert not np.shares_memory(tidy.data, messy.data) and (tidy != A).nnz == 0
    np.testing.assert_array_equal(messy.indices, kept)


def _path_adjacency(n: int) -> sp.csr_matrix:
    """The boundary nodes 0, …, n-1 of an open line, each next to its two neighbours."""
    return sp.diags([np.ones(n - 1), np.ones(n - 1)], [-1, 1], format="csr")


def _grown_sizes(frontier: Frontier, n: int) -> list[int]:
    """The contact set's size after each step on a line of ``n`` nodes, every node violated, from
    the middle node."""
    active = np.zeros(n, dtype=bool)
    active[n // 2] = True
    sizes = []
    while not active.all():
        active = active | frontier.restrict(~active, active)
        sizes.append(int(active.sum()))
    return sizes


@pytest.mark.parametrize("first_reach", [1, WARM_START_REACH])
def test_frontier_creeps_one_node_per_end_then_doubles_its_reach(first_reach):
    """A contact set in the middle of a line of 201 nodes, every node violated: ``first_reach``
    nodes per end in the first step, one per end and step in the next ones, then a reach that
    doubles, so the line is covered in ``CREEP_STEPS + log₂ 100`` steps or so instead of 100."""
    n = 201
    sizes = _grown_sizes(Frontier(_path_adjacency(n), first_reach), n)
    expected, size = [], 1
    while size < n:  # first_reach, then 1 up to CREEP_STEPS held steps, then 2, 4, 8, … at both ends
        reach = first_reach if not expected else 2 ** max(0, len(expected) - CREEP_STEPS)
        size = min(n, size + 2 * reach)
        expected.append(size)
    assert sizes == expected and len(sizes) <= CREEP_STEPS + 8
    assert sizes[:3] == ([3, 5, 7] if first_reach == 1 else [5, 7, 9])


def test_frontier_takes_the_full_step_when_no_violated_node_is_near():
    """No violated node within reach: every violated node enters (PDAS's own step)."""
    n = 50
    frontier, active, grow = Frontier(_path_adjacency(n)), np.zeros(n, dtype=bool), np.zeros(n, dtype=bool)
    active[:3], grow[30:40] = True, True
    np.testing.assert_array_equal(frontier.restrict(grow, active), grow)
    assert frontier.held == 0


def test_a_step_releases_only_when_it_drops_nodes_and_adds_none():
    from signorini.solvers.pdas import releases_only

    before = np.array([True, True, False, False])
    assert releases_only(before, np.array([True, False, False, False]))
    assert not releases_only(before, before)  # nothing changed
    assert not releases_only(before, np.array([True, False, True, False]))  # one released, one added
    assert not releases_only(before, np.array([True, True, True, False]))  # only added
