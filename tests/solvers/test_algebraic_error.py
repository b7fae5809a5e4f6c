"""The algebraic error of a computed solution (``signorini.solvers.algebraic_error``)."""

from __future__ import annotations

import numpy as np
import pytest


def test_linearised_error_recovers_a_planted_algebraic_error(small_case):
    """``u = u* + δ`` with δ on the free nodes: ``linearised_error`` returns δ and its energy
    ``(δᵀAδ)^{1/2}``; the exact solution itself has an algebraic error at round-off."""
    from signorini.solvers.algebraic_error import linearised_error

    disc, res = small_case
    A, b, B = disc.A, disc.b, disc.boundary
    free = np.setdiff1d(np.arange(b.size), B)  # interior nodes: u_B and the contact set unchanged
    delta = np.zeros_like(res.u)
    delta[free] = 1e-6 * np.abs(res.u).max() * np.random.default_rng(5).uniform(-1.0, 1.0, free.size)
    lam = res.lam + np.where(np.isin(B, res.active), (A @ delta)[B], 0.0)  # λ absorbs the contact rows only
    got = linearised_error(A, b, B, res.u + delta, lam, res.active)
    assert np.abs(got.delta - delta).max() <= 1e-6 * np.abs(delta).max()
    assert got.energy == pytest.approx(np.sqrt(delta @ (A @ delta)), rel=1e-6)
    exact = linearised_error(A, b, B, res.u, res.lam, res.active)
    assert np.abs(exact.delta).max() <= 1e-12 * np.abs(res.u).max()
    assert np.all(exact.delta[res.active] == 0.0)
    summary = exact.summary(res.u)
    assert set(summary) == {"energy", "max", "relative_max"} and summary["relative_max"] < 1e-12


def test_the_multigrid_correction_agrees_with_the_factorised_one(small_case):
    """The large meshes' route of the algebraic error (CG with the multigrid hierarchy) gives the
    planted error to the accuracy an estimate needs, with the contact set's nodes untouched."""
    from signorini.solvers.algebraic_error import ESTIMATE_RTOL, linearised_error

    disc, res = small_case
    A, b, B = disc.A, disc.b, disc.boundary
    free = np.setdiff1d(np.arange(b.size), B)
    delta = np.zeros_like(res.u)
    delta[free] = 1e-6 * np.abs(res.u).max() * np.random.default_rng(7).uniform(-1.0, 1.0, free.size)
    lam = res.lam + np.where(np.isin(B, res.active), (A @ delta)[B], 0.0)
    direct = linearised_error(A, b, B, res.u + delta, lam, res.active, "active_set")
    multigrid = linearised_error(A, b, B, res.u + delta, lam, res.active, "multigrid")
    error = multigrid.delta - direct.delta
    assert np.sqrt(error @ (A @ error)) <= 10 * ESTIMATE_RTOL * direct.energy
    assert multigrid.energy == pytest.approx(direct.energy, rel=10 * ESTIMATE_RTOL)
    assert np.all(multigrid.delta[res.active] == 0.0)


def test_the_multigrid_correction_reuses_the_solvers_hierarchy(small_case, monkeypatch):
    """With the multigrid route's ``SolveResult.hierarchy`` (Galerkin for the final set) the
    estimate sets up no hierarchy of its own and agrees with the factorised correction."""
    from signorini.solvers import algebraic_error, multigrid_solve
    from signorini.solvers.algebraic_error import ESTIMATE_RTOL, linearised_error

    disc, direct_result = small_case
    A, b, B = disc.A, disc.b, disc.boundary
    res = multigrid_solve(A, b, B, max_coarse=20)
    assert res.hierarchy is not None and np.array_equal(~res.hierarchy.free[B], np.isin(B, res.active))
    free = np.setdiff1d(np.arange(b.size), B)
    delta = np.zeros_like(res.u)
    delta[free] = 1e-6 * np.abs(res.u).max() * np.random.default_rng(8).uniform(-1.0, 1.0, free.size)
    lam = res.lam + np.where(np.isin(B, res.active), (A @ delta)[B], 0.0)
    direct = linearised_error(A, b, B, res.u + delta, lam, res.active, "active_set")
    monkeypatch.setattr(algebraic_error, "GalerkinHierarchy", None)  # a second set-up would fail
    reused = linearised_error(A, b, B, res.u + delta, lam, res.active, "multigrid", res.hierarchy)
    error = reused.delta - direct.delta
    assert np.sqrt(error @ (A @ error)) <= 10 * ESTIMATE_RTOL * direct.energy
