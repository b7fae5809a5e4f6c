"""Settling a release on a patch (``signorini.solvers.local``): the patch, the local solve, when
the iteration hands a step to it, and what it changes in the multigrid route's solve (its steps
and V-cycles, never its answer)."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.sparse as sp

from signorini.fem.discrete import build
from signorini.fem.problem import Problem
from signorini.fem.solve import cascade_start, solve_discrete
from signorini.solvers import active_set_solve, multigrid_solve
from signorini.solvers.local import PATCH_MAX_FRACTION, neighbourhood, patch_problem
from signorini.solvers.pdas import MAX_SETTLES, initial_active, iterate, prepare_qp
from signorini.solvers.stencil import concatenated_ranges

log = logging.getLogger(__name__)
AGREEMENT = 1e-12  # max |u - u_direct| / max |u_direct|, as the multigrid route's tests


def _path(n: int) -> sp.csr_matrix:
    return sp.diags([-np.ones(n - 1), 2 * np.ones(n), -np.ones(n - 1)], [-1, 0, 1], format="csr")


def test_concatenated_ranges_are_the_rows_stored_entries():
    A = _path(6)
    rows = np.array([0, 3, 5])
    positions = concatenated_ranges(A.indptr[rows], A.indptr[rows + 1])
    assert positions.tolist() == [0, 1, 8, 9, 10, 14, 15]
    assert concatenated_ranges(np.array([2]), np.array([2])).size == 0


def test_the_patch_is_the_graph_neighbourhood_and_refuses_to_grow_past_its_limit():
    A = _path(20)

    def nodes(*args):
        return np.flatnonzero(neighbourhood(A, *args)).tolist()

    assert nodes(np.array([10]), 3, 20) == list(range(7, 14))
    assert nodes(np.array([0, 19]), 2, 20) == [0, 1, 2, 17, 18, 19]
    assert nodes(np.array([10]), 50, 20) == list(range(20))  # stops when nothing is new
    assert neighbourhood(A, np.array([10]), 5, 8) is None  # 11 nodes > 8


def _release_case(N: int = 201):
    """The paper's problem at N from the cascade start: its first Newton step only releases nodes
    (the start's set is too large at the degenerate end, on the right edge)."""
    disc = build(Problem(), N)
    A, b, B = prepare_qp(disc.A, disc.b, disc.boundary)
    return disc, A, b, B


def _systems(A, b, B, start, max_coarse=500):
    from signorini.solvers.multigrid import MultigridSystems

    options = dict(amg="geometric", tol=1e-14, inner_rtol=1e-8, max_cg_iter=500, max_coarse=max_coarse)
    return MultigridSystems(A, b, start, options | {"B": B, "kkt_tol": 1e-10})


def test_a_release_settled_on_its_patch_is_the_local_obstacle_problems_solution():
    """Settle the first step's release: the nodes outside the patch keep the iterate's values; the
    patch's values and contact set solve the obstacle problem there with them as Dirichlet data
    (its KKT conditions, checked directly), and the settled set is nearer the solution's."""
    disc, A, b, B = _release_case()
    direct = active_set_solve(A, b, B)
    start = cascade_start(disc, "multigrid")
    systems = _systems(A, b, B, start)
    calls = []

    def spy(u, before, after):
        calls.append((u.copy(), before.copy(), after.copy(), systems.settle(u, before, after)))
        return calls[-1][-1]

    iterate(systems, A, b, B, initial_active(A, b, B, start), 100, True, None, log, spy)
    assert calls, "the first step from the cascade start only releases"
    u, before, after, (settled_u, settled, row) = calls[0]
    assert not (after & ~before).any() and (before & ~after).any()  # a pure release was handed over
    changed = np.flatnonzero(settled_u != u)
    assert 0 < changed.size <= row["local_unknowns"] <= PATCH_MAX_FRACTION * b.size
    # the local KKT conditions where the patch changed anything: A u = b on free nodes, u = 0 and
    # λ = A u - b ≥ 0 on contact nodes
    residual, scale = A @ settled_u - b, np.abs(b).max()
    moved = np.union1d(changed, B[settled != after])
    contact = B[settled]
    assert np.abs(residual[np.setdiff1d(moved, contact)]).max() <= 1e-9 * scale
    assert np.all(settled_u[contact] == 0.0) and np.all(residual[np.intersect1d(moved, contact)] >= -1e-9 * scale)
    solution = np.isin(B, direct.active)
    assert np.count_nonzero(settled != solution) < np.count_nonzero(after != solution)


@pytest.mark.parametrize("N", [201, 401])
def test_settling_releases_saves_newton_steps_and_v_cycles_and_changes_no_answer(N):
    """From the cascade start on the paper's problem: the same contact set and u (to round-off) as
    the direct route and as the iteration without settling, in fewer Newton steps and V-cycles
    (a test on counts); each settled step's row says so."""
    disc = build(Problem(), N)
    direct = solve_discrete(disc, "active_set")
    plain = solve_discrete(disc, "multigrid", local_release=False)
    settled = solve_discrete(disc, "multigrid")
    for result in (plain, settled):
        np.testing.assert_array_equal(np.sort(result.active), np.sort(direct.active))
        assert np.abs(result.u - direct.u).max() <= AGREEMENT * np.abs(direct.u).max()
        assert result.certificate.ok
    assert plain.info["local_settles"] == 0 and 1 <= settled.info["local_settles"] <= MAX_SETTLES
    assert settled.iterations < plain.iterations and settled.info["v_cycles"] < plain.info["v_cycles"]
    rows = [row for row in settled.history if "local_unknowns" in row]
    assert len(rows) == settled.info["local_settles"] and all(not row["accurate"] for row in rows)
    assert settled.history[-1]["accurate"] and "local_unknowns" not in settled.history[-1]


def test_steps_that_add_nodes_are_never_settled():
    """A step that adds a node (here: from the plain cold start, where the set grows) is not
    handed over; the route's answer is the direct one's."""
    disc = build(Problem(), 41)
    A, b, B = prepare_qp(disc.A, disc.b, disc.boundary)
    seen = []

    def record(u, before, after):
        seen.append((before.copy(), after.copy()))
        return None

    systems = _systems(A, b, B, np.zeros_like(b), max_coarse=20)
    u, active, history = iterate(systems, A, b, B, initial_active(A, b, B, None), 100, True, None, log, record)
    grew = [row["changes"] for row in history if row["changes"]]
    assert grew  # the cold start moves the set
    assert all(not (after & ~before).any() and (before & ~after).any() for before, after in seen)
    direct = multigrid_solve(A, b, B, local_release=False, max_coarse=20)
    np.testing.assert_array_equal(np.sort(B[active]), np.sort(direct.active))


def test_the_patch_problem_is_the_submatrix_with_the_rest_as_dirichlet_data(rng):
    A = sp.random(30, 30, density=0.2, random_state=1, format="csr") + sp.eye(30, format="csr")
    A = (A + A.T).tocsr()
    b, u = rng.standard_normal(30), rng.standard_normal(30)
    patch = np.array([2, 5, 6, 11, 29])
    inside = np.isin(np.arange(30), patch)
    matrix, load = patch_problem(A, b, u, patch, inside)
    np.testing.assert_array_equal(matrix.toarray(), A.toarray()[np.ix_(patch, patch)])
    expected = b[patch] - A.toarray()[np.ix_(patch, np.flatnonzero(~inside))] @ u[~inside]
    np.testing.assert_allclose(load, expected, rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize("route", ["multigrid", "active_set"])
def test_a_first_reach_of_two_saves_a_growth_step_from_the_cascade_and_changes_no_answer(route):
    """At N = 101 the cascade's start is two nodes short at the contact zone's end near the free
    point: a first reach of two admits both in the first Newton step (``pdas.WARM_START_REACH``),
    one node per step takes a step more (a test on counts); the same contact set and u."""
    disc = build(Problem(), 101)
    one = solve_discrete(disc, route, warm_start_reach=1)
    two = solve_discrete(disc, route)
    assert two.iterations == one.iterations - 1
    if route == "multigrid":
        assert two.info["v_cycles"] < one.info["v_cycles"]
    np.testing.assert_array_equal(np.sort(two.active), np.sort(one.active))
    assert np.abs(two.u - one.u).max() <= AGREEMENT * np.abs(one.u).max() and two.certificate.ok


@pytest.mark.parametrize("route", ["multigrid", "active_set"])
def test_a_first_reach_below_one_node_is_refused(route):
    disc = build(Problem(), 21)
    with pytest.raises(ValueError, match="warm_start_reach >= 1"):
        solve_discrete(disc, route, warm_start_reach=0)
