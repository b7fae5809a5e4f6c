"""The multigrid route (``signorini.solvers.multigrid``): the same certified discrete solution
as the direct route (same contact set, max |Δu| ≤ 1e-12 max |u|), its Galerkin hierarchy kept
exact under changes of the active set, its stopping test, the edge cases and the named errors."""

from __future__ import annotations

import logging

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from signorini.fem.assembly import p1_basis, system_matrix
from signorini.fem.discrete import build, interpolate_fk
from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.problem import ConstantProblem, FullContactProblem, Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import KKTError, NotConvergedError, active_set_solve, multigrid_solve
from signorini.solvers.multigrid import GalerkinHierarchy, coarse_lines, fk_grid, fk_transfer, hierarchy, pcg
from signorini.solvers.pdas import clamped_values

AGREEMENT = 1e-12  # max |u_multigrid - u_direct| / max |u_direct|
SMALL_COARSE = 20  # a coarsest level this small gives the small meshes several levels


def assert_same_solution(mg, direct) -> None:
    assert mg.certificate.ok and mg.certificate.tol == 1e-10
    np.testing.assert_array_equal(np.sort(mg.active), np.sort(direct.active))
    scale = np.abs(direct.u).max()
    assert np.abs(mg.u - direct.u).max() <= AGREEMENT * scale if scale > 0 else np.array_equal(mg.u, direct.u)


def test_multigrid_gives_the_direct_solution_on_the_small_cases(small_case):
    """Cold start, several levels (coarsest ≤ 20 unknowns): the contact set and u of the direct route."""
    disc, direct = small_case
    mg = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=SMALL_COARSE)
    assert_same_solution(mg, direct)
    assert mg.info["levels"] >= 3
    assert mg.history[-1]["accurate"] and mg.history[-1]["changes"] == 0


@pytest.mark.parametrize(("N", "diagonal"), [(101, "sw_ne"), (101, "nw_se"), (201, "sw_ne")])
def test_multigrid_cascade_gives_the_direct_solution(N, diagonal):
    """Both routes with their cascade warm start (N // 4 first): same contact set, same u."""
    disc = build(Problem(), N, diagonal)
    direct = solve_discrete(disc, "active_set")
    mg = solve_discrete(disc, "multigrid")
    assert_same_solution(mg, direct)
    assert mg.solver == "multigrid" and mg.info["levels"] >= 4
    # every solve is an inexact step or an accurate one; the last is accurate and repeats the set
    assert all(row["cg_iterations"] <= 60 for row in mg.history)


def _long_double_solution(A: sp.csr_matrix, b: np.ndarray, active: np.ndarray) -> np.ndarray:
    """The clamped system of the final set solved by sparse LU with residuals in long double:
    accurate to a few units of round-off."""
    n = b.size
    free = np.ones(n, dtype=bool)
    free[active] = False
    rows = np.repeat(np.arange(n), np.diff(A.indptr))
    At = sp.csr_matrix((clamped_values(A, rows, free), A.indices, A.indptr), shape=A.shape)
    lu = spla.splu(At.tocsc())
    rhs = np.where(free, b, 0.0)
    x = lu.solve(rhs)
    AL, rhsL = At.astype(np.longdouble), rhs.astype(np.longdouble)
    for _ in range(3):
        x = x + lu.solve(np.asarray(rhsL - AL @ x.astype(np.longdouble), dtype=float))
    return x


def test_both_routes_are_accurate_to_round_off_at_N201():
    """Against the final set's system solved with long-double residuals: both routes within
    1e-13 max |u| (the direct route refines once, the multigrid route solves to ``tol = 1e-14``);
    a max-norm residual test would accept the unrefined Cholesky solve (1.2e-13)."""
    disc = build(Problem(), 201)
    A = sp.csr_matrix(disc.A)
    for result in (solve_discrete(disc, "active_set"), solve_discrete(disc, "multigrid")):
        truth = _long_double_solution(A, disc.b, result.active)
        assert np.abs(result.u - truth).max() <= 1e-13 * np.abs(truth).max(), result.solver


def test_no_contact_full_contact_and_zero_data():
    """f ≡ 1, c = 1: u ≡ 1, no contact; full contact (u = -sin sin); f ≡ 0: u = 0 with every
    boundary node biactive.  The two routes agree, on three levels."""
    for problem in (ConstantProblem(1.0, 1.0), FullContactProblem(), ConstantProblem(0.0, 1.0)):
        disc = build(problem, 41)
        direct = active_set_solve(disc.A, disc.b, disc.boundary)
        mg = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=SMALL_COARSE)
        assert_same_solution(mg, direct)
    assert direct.active.size == disc.boundary.size and np.all(mg.u == 0.0)


def test_semicoercive_problems():
    """c = 0: the manufactured problem is solved (its contact set makes the system definite);
    f ≡ 0 gives u = 0; a load pushing the whole boundary inwards has no minimiser: a named error."""
    disc = build(Problem(c=0.0), 41)
    assert_same_solution(multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=SMALL_COARSE),
                         active_set_solve(disc.A, disc.b, disc.boundary))
    mesh = friedrichs_keller(12)
    basis = p1_basis(mesh, intorder=2)
    K, M = system_matrix(basis, 0.0), system_matrix(basis, 1.0) - system_matrix(basis, 0.0)
    zero = multigrid_solve(K, np.zeros(K.shape[0]), boundary_nodes(mesh), max_coarse=SMALL_COARSE)
    assert zero.certificate.ok and np.all(zero.u == 0.0)
    with pytest.raises(NotConvergedError, match="singular"):
        multigrid_solve(K, M @ np.ones(K.shape[0]), boundary_nodes(mesh), max_coarse=SMALL_COARSE)


@pytest.mark.parametrize("kind", ["geometric", "classical"])
def test_galerkin_updates_keep_every_coarse_operator_exact(rng, kind):
    """After a sequence of free sets (few and many changes, both directions), every level's
    operator is the Galerkin product of the level above, recomputed from scratch."""
    disc = build(Problem(), 41)
    A = sp.csr_matrix(disc.A)
    H = GalerkinHierarchy(A, kind, max_coarse=SMALL_COARSE)
    rows = np.repeat(np.arange(A.shape[0]), np.diff(A.indptr))
    B = disc.boundary
    free = np.ones(A.shape[0], dtype=bool)
    for flips in (1, 3, 40, B.size, 7):
        nodes = rng.choice(B, size=flips, replace=False)
        free[nodes] = ~free[nodes]
        H.update(free)
        fine = sp.csr_matrix((clamped_values(A, rows, free), A.indices, A.indptr), shape=A.shape)
        at = np.flatnonzero(rng.random(A.nnz) < 0.1)  # at given positions: their rows
        assert np.array_equal(clamped_values(A, rows[at], free, at), fine.data[at])
        assert abs(H.matrix.tocsr() - fine).max() == 0.0
        for level, coarse in zip(H.levels[:-1], H.levels[1:], strict=True):
            galerkin = level.R @ level.A.tocsr() @ level.P
            assert abs(coarse.A - galerkin).max() <= 1e-12 * abs(galerkin).max()
    assert len(H.levels) >= 3


@pytest.mark.parametrize("kind", ["geometric", "classical", "smoothed_aggregation"])
def test_the_restriction_read_off_the_prolongation_gives_the_v_cycle_of_its_own_csr_bit_for_bit(rng, kind):
    """The hierarchy keeps no copy of the restriction: ``Pᵀ`` read column-wise sums in the order of
    its CSR, so a V-cycle (and a solve) gives the same bits as with ``Pᵀ`` stored row-wise."""
    A = sp.csr_matrix(build(Problem(), 41).A)
    H = GalerkinHierarchy(A, kind, max_coarse=SMALL_COARSE)
    assert all(not sp.isspmatrix_csr(level.R) for level in H.levels[:-1])
    r = rng.normal(size=A.shape[0])
    by_columns = H(r)
    for level in H.levels[:-1]:
        level.R = level.P.T.tocsr()
    assert np.array_equal(H(r).view(np.uint64), by_columns.view(np.uint64))


def test_pcg_stops_at_the_energy_relative_accuracy():
    """The stopping ratio bounds the error: CG to 1e-10 is within 1e-9 (max norm) of a direct solve."""
    disc = build(Problem(), 60)
    A = sp.csr_matrix(disc.A)
    H = GalerkinHierarchy(A, "classical", max_coarse=SMALL_COARSE)
    x, iterations, ratio = pcg(A, disc.b, np.zeros_like(disc.b), H, 1e-10, 100)
    exact = spla.spsolve(A.tocsc(), disc.b)
    assert ratio <= 1e-10 and 3 <= iterations <= 30
    assert np.abs(x - exact).max() <= 1e-9 * np.abs(exact).max()
    with pytest.raises(NotConvergedError, match="did not reach"):
        pcg(A, disc.b, np.zeros_like(disc.b), H, 1e-14, 2)


def test_history_and_callback_report_each_newton_step(cache):
    disc = cache.discrete({}, 21)
    rows: list[dict] = []
    mg = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=SMALL_COARSE, callback=rows.append)
    assert rows == mg.history and len(rows) == mg.iterations
    assert [r["iteration"] for r in rows] == list(range(1, mg.iterations + 1))
    assert rows[-1]["accurate"] and rows[-1]["changes"] == 0 and rows[-1]["active"] == mg.active.size
    assert sum(r["cg_iterations"] for r in rows) == mg.info["cg_iterations"]
    assert mg.summary()["history"] == rows  # JSON-ready, next to the counters


def test_bad_options_and_truncated_solves_raise_named_errors(cache):
    disc = cache.discrete({}, 21)
    A, b, B = disc.A, disc.b, disc.boundary
    with pytest.raises(ValueError, match="algebraic multigrid"):
        multigrid_solve(A, b, B, amg="unknown")
    with pytest.raises(ValueError, match="inner_rtol"):
        multigrid_solve(A, b, B, tol=1e-6, inner_rtol=1e-8)
    with pytest.raises(NotConvergedError, match="conjugate gradients"):
        multigrid_solve(A, b, B, max_coarse=SMALL_COARSE, max_cg_iter=1)
    with pytest.raises(NotConvergedError, match="max_iter"):
        multigrid_solve(A, b, B, max_coarse=SMALL_COARSE, max_iter=1)
    with pytest.raises(KKTError, match="multigrid"):
        multigrid_solve(A, b, B, max_coarse=SMALL_COARSE, kkt_tol=0.0)
    with pytest.raises(ValueError, match="warm start"):
        multigrid_solve(A, b, B, warm_start=np.zeros(b.size - 1))


def test_smoothed_aggregation_gives_the_same_solution(cache):
    disc, direct = cache.discrete({}, 21), cache.solution({}, 21)
    mg = multigrid_solve(disc.A, disc.b, disc.boundary, amg="smoothed_aggregation", max_coarse=SMALL_COARSE)
    assert_same_solution(mg, direct)
    assert mg.info["amg"] == "smoothed_aggregation" and mg.info["levels"] >= 2


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_the_grid_is_read_off_the_matrix(diagonal):
    """A Friedrichs–Keller matrix gives its N and diagonal (a 5-point stencil, c = 0: either
    serves, ``sw_ne``); anything else gives None, and the hierarchy is then algebraic."""
    assert fk_grid(build(Problem(), 13, diagonal).A) == (13, diagonal)
    assert fk_grid(build(Problem(c=0.0), 13, diagonal).A) == (13, "sw_ne")
    assert fk_grid(sp.identity(15, format="csr")) is None  # not (N + 1)² unknowns
    both = sp.csr_matrix(build(Problem(), 13, "sw_ne").A + build(Problem(), 13, "nw_se").A)
    assert fk_grid(both) is None  # both diagonals: a 9-point stencil
    wide = sp.diags([1.0, 1.0, 1.0], [-20, 0, 20], shape=(196, 196), format="csr")
    assert fk_grid(wide) is None  # couplings beyond the neighbouring grid lines
    algebraic = [level.A.shape for level in hierarchy(both, "classical", max_coarse=20).levels]
    assert [level.A.shape for level in hierarchy(both, "geometric", max_coarse=20).levels] == algebraic


@pytest.mark.parametrize("N", [16, 17, 21])
@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_the_grid_transfer_is_p1_interpolation(N, diagonal):
    """Every other line, the last one kept; the prolongation is the coarse P1 function's value at
    the fine vertices: for even N it equals ``interpolate_fk`` on the mesh with N / 2 cells, and at
    any N it keeps constants and linear functions exactly (rows of nonnegative weights summing to 1)."""
    lines = np.arange(N + 1)
    coarse = coarse_lines(lines)
    assert coarse[0] == 0 and coarse[-1] == N and coarse.size == N // 2 + 1
    assert np.isin(coarse, lines).all() and np.diff(coarse).max() <= 3
    P = fk_transfer(lines, coarse, diagonal)
    assert P.shape == ((N + 1) ** 2, coarse.size**2) and P.data.min() > 0.0
    X, Y = np.meshgrid(coarse, coarse, indexing="ij")
    x, y = np.meshgrid(lines, lines, indexing="ij")
    np.testing.assert_allclose(P @ (2.0 * X + 3.0 * Y + 1.0).ravel(), (2.0 * x + 3.0 * y + 1.0).ravel(), atol=1e-12)
    if N % 2 == 0:
        values = np.random.default_rng(N).random(coarse.size**2)
        points = friedrichs_keller(N, diagonal).p
        np.testing.assert_allclose(P @ values, interpolate_fk(N // 2, diagonal, values, points), atol=1e-14)
        assert P.getnnz(axis=1).max() == 2  # nested: each fine vertex on a coarse edge or vertex


def test_the_compiled_grid_reading_gives_numpys_answer(monkeypatch):
    """The grid read off the matrix in one compiled pass: the same answer as numpy's for both
    diagonals, the 5-point stencil of c = 0, a jittered mesh's matrix and matrices of no grid."""
    from signorini.solvers import certificate

    cases = [(c, diagonal) for c in (0.0, 1.0) for diagonal in ("sw_ne", "nw_se")]
    matrices = [sp.csr_matrix(build(Problem(c=c), 21, diagonal).A) for c, diagonal in cases]
    matrices += [sp.csr_matrix(system_matrix(friedrichs_keller(21, jitter=0.3, seed=2), 1.0))]
    matrices += [sp.random(484, 484, density=0.02, random_state=1, format="csr"), sp.eye(484, format="csr")]
    expected = [fk_grid(M) for M in matrices]
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)
    assert [fk_grid(M) for M in matrices] == expected
    # c = 0 stores no diagonal coupling: either diagonal serves, sw_ne is named
    assert expected[:4] == [(21, "sw_ne"), (21, "sw_ne"), (21, "sw_ne"), (21, "nw_se")]
    assert expected[-2] is None


@pytest.mark.parametrize("N", [16, 17, 21, 40])
@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_the_compiled_grid_transfer_has_the_same_arrays(monkeypatch, N, diagonal):
    """The transfer built row by row in a compiled kernel (large grids) is numpy's, array for array
    and bit for bit, odd grids' three-cell last interval and the second coarsening included."""
    from signorini.solvers import certificate

    lines = np.arange(N + 1)
    pairs = [(lines, coarse_lines(lines)), (coarse_lines(lines), coarse_lines(coarse_lines(lines)))]
    expected = [fk_transfer(fine, coarse, diagonal) for fine, coarse in pairs]
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)
    for (fine, coarse), P in zip(pairs, expected, strict=True):
        Q = fk_transfer(fine, coarse, diagonal)
        for name in ("indptr", "indices", "data"):
            a, b = getattr(P, name), getattr(Q, name)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes(), name


def test_geometric_levels_are_cheaper_and_give_the_same_solution(cache):
    """On a Friedrichs–Keller matrix the geometric hierarchy halves the grid down to the coarsest
    level, with an operator complexity near 4/3 (classical AMG: above 2), and the route gives the
    direct solution with it."""
    disc, direct = cache.discrete({}, 21), cache.solution({}, 21)
    geometric = hierarchy(sp.csr_matrix(disc.A), "geometric", max_coarse=SMALL_COARSE)
    assert [level.A.shape[0] for level in geometric.levels] == [22**2, 11**2, 6**2, 3**2]
    classical = hierarchy(sp.csr_matrix(disc.A), "classical", max_coarse=SMALL_COARSE)
    assert geometric.operator_complexity() < 1.5 < classical.operator_complexity()
    mg = multigrid_solve(disc.A, disc.b, disc.boundary, max_coarse=SMALL_COARSE)
    assert mg.info["amg"] == mg.info["hierarchy"] == "geometric" and mg.info["grid"] == [21, "sw_ne"]
    assert_same_solution(mg, direct)


def test_a_cold_start_solves_the_coarse_grids_problem_first():
    """Without a warm start the route solves the problem on its first coarse grid (operator
    R A P, load R b, constrained on the coarse boundary; recursively) and starts from its
    prolongation: the direct solution, in fewer Newton steps and CG iterations than the plain
    cold start, which grows the contact set from the nodes pushed outwards."""
    from signorini.solvers import multigrid

    disc = build(Problem(), 101)
    direct = solve_discrete(disc, "active_set")
    nested = multigrid_solve(disc.A, disc.b, disc.boundary)
    assert nested.info["nested_start"] and nested.info["grid"] == [101, "sw_ne"]
    assert_same_solution(nested, direct)
    H = GalerkinHierarchy(sp.csr_matrix(disc.A))
    start = multigrid.nested_start(H, disc.b, disc.boundary, {})
    assert start is not None and start[disc.boundary].min() >= 0.0  # feasible: P v ≥ 0 where v ≥ 0
    with pytest.MonkeyPatch.context() as patch:  # the plain cold start, for comparison
        patch.setattr(multigrid, "NESTED_MIN_CELLS", 10**6)
        cold = multigrid_solve(disc.A, disc.b, disc.boundary, max_iter=200)
    assert not cold.info["nested_start"]
    assert_same_solution(cold, direct)
    assert nested.iterations < cold.iterations and nested.info["cg_iterations"] < cold.info["cg_iterations"]


def test_the_nested_start_settles_on_every_level_of_the_biactive_case(caplog):
    """R = 0.1 (u = ∂_ν u = 0 on most of the boundary): a coarse level's contact set, started from
    the next coarser one's, must grow by about a hundred nodes.  The frontier's doubling reach
    settles it in a few steps on every level, without the fallback to the plain cold start."""
    disc = build(Problem(R=0.1), 101)
    direct = solve_discrete(disc, "active_set")
    with caplog.at_level(logging.WARNING, logger="signorini.solvers.multigrid"):
        nested = multigrid_solve(disc.A, disc.b, disc.boundary)
    assert not [r for r in caplog.records if "did not settle" in r.getMessage()]
    assert nested.info["nested_start"] and nested.iterations <= 10
    assert_same_solution(nested, direct)


def test_a_nested_start_that_does_not_settle_falls_back_to_the_plain_cold_start(monkeypatch, caplog):
    """N = 50: one nested level (25 cells).  When the fine iteration from the nested start does
    not settle, the route solves again from the plain cold start and says so."""
    from signorini.solvers import multigrid

    disc = build(Problem(), 50)
    direct = solve_discrete(disc, "active_set")
    real, calls = multigrid.iterate, []

    def second_call_fails(*args, **kwargs):
        calls.append(1)
        if len(calls) == 2:  # the coarse grid's iteration first, then the fine one's
            raise NotConvergedError("active set did not repeat")
        return real(*args, **kwargs)

    monkeypatch.setattr(multigrid, "iterate", second_call_fails)
    with caplog.at_level("WARNING", logger=multigrid.__name__):
        mg = multigrid_solve(disc.A, disc.b, disc.boundary)
    assert len(calls) == 3 and "plain cold start" in caplog.text
    assert_same_solution(mg, direct)


def test_work_units_and_v_cycles_are_counted_and_bounded_on_a_mesh_sequence():
    """Each Newton step reports its V-cycles and fine-grid work units; they add up to the solve's;
    a V-cycle costs a few products with the fine operator (operator complexity 4/3, three passes
    per level, the transfers); and from the cascade the counts stay bounded as the mesh is refined
    (mesh independence, a test on counts)."""
    totals = {}
    for N in (101, 201, 401):
        result = solve_discrete(build(Problem(), N), "multigrid")
        info, steps = result.info, result.history
        assert sum(row["v_cycles"] for row in steps) == info["v_cycles"] > 0
        assert sum(row["work_units"] for row in steps) == pytest.approx(info["work_units"], rel=1e-12)
        per_cycle = (info["work_units"] - info["v_cycles"]) / info["v_cycles"]  # less ≤ 1 product each
        assert 3.0 < per_cycle < 7.0
        cascade = info["cascade"]
        assert cascade["N"] == N // 4 and 0.0 < cascade["work_units_fine"] < cascade["work_units"]
        assert info["work_units_total"] == pytest.approx(info["work_units"] + cascade["work_units_fine"])
        totals[N] = (info["v_cycles"], info["work_units_total"])
    assert max(cycles for cycles, _ in totals.values()) <= 40
    assert max(work for _, work in totals.values()) <= 2.0 * min(work for _, work in totals.values())


@pytest.mark.parametrize(("family", "params"), [("union_jack", {}), ("graded", {"grading": 2.0}), ("delaunay", {})])
def test_on_other_mesh_families_the_route_takes_classical_amg_and_gives_the_direct_solution(family, params):
    """A matrix that is not on a Friedrichs–Keller grid (alternating diagonals, a graded or an
    unstructured mesh, ``fem.mesh_families``) gets classical AMG, and the solve says so (``grid``
    None); the solution and the contact set are the direct route's."""
    from signorini.fem.assembly import assemble
    from signorini.fem.mesh_families import build_mesh

    mesh = build_mesh(family, 24, **params)
    A, b = assemble(mesh, Problem())
    direct = active_set_solve(A, b, boundary_nodes(mesh))
    mg = multigrid_solve(A, b, boundary_nodes(mesh))
    assert mg.info["grid"] is None and fk_grid(sp.csr_matrix(A)) is None
    assert mg.info["amg"] == "geometric" and mg.info["hierarchy"] == "classical"  # says what it took
    assert np.abs(mg.u - direct.u).max() <= 1e-12 * np.abs(direct.u).max()
    assert np.array_equal(mg.active, direct.active) and mg.certificate.ok
