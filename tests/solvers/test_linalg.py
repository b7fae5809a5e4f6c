"""Sparse factorisations (``signorini.solvers.linalg``): backends, blocks of right-hand sides,
the positive-definiteness test, in-place refactorisation."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from signorini.fem.problem import Problem
from signorini.solvers.linalg import backend_name, factorize, is_positive_definite
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

# ---------------------------------------------------------------------------------
# sparse factorisation
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("backend", ["auto", "superlu"])
def test_factorize_solves_spd_systems(cache, backend):
    A = sp.csc_matrix(cache.discrete({}, 21).A)
    rng = np.random.default_rng(0)
    y = rng.normal(size=A.shape[0])
    solve_ = factorize(A, backend)
    x = solve_(y)
    np.testing.assert_allclose(x, spla.spsolve(A, y), rtol=0, atol=1e-12 * np.abs(x).max())
    Y = rng.normal(size=(A.shape[0], 3))
    X = np.column_stack([solve_(Y[:, k]) for k in range(3)])
    np.testing.assert_allclose(A @ X, Y, atol=1e-10)


def test_factorisation_backend_names():
    from signorini.solvers.linalg import available_backends

    assert backend_name("superlu") == "superlu"
    assert backend_name("auto") == available_backends()[0]
    with pytest.raises(ValueError):
        backend_name("mumps")


@pytest.mark.parametrize("backend", ["cholmod", "superlu"])
def test_factorize_solves_blocks_of_right_hand_sides(cache, backend):
    """(n, k) blocks are solved column by column in one call (the bordered columns rely on it)."""
    from signorini.solvers.linalg import available_backends

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    A = cache.discrete({}, 21).A
    Y = np.random.default_rng(1).normal(size=(A.shape[0], 4))
    X = factorize(A, backend)(Y)
    assert X.shape == Y.shape
    np.testing.assert_allclose(A @ X, Y, atol=1e-10)


@pytest.mark.parametrize("n", [50, 40_000])  # CHOLMOD: simplicial LDLᵀ, supernodal LLᵀ
@pytest.mark.parametrize("backend", ["cholmod", "superlu"])
def test_positive_definiteness_on_shifted_laplacians(n, backend):
    """The 1D Laplacian tridiag(-1, 2, -1) has eigenvalues in (0, 4): ``T + s I`` is positive
    definite for s > 0 and indefinite for -4 < s < 0, whatever factorisation CHOLMOD picks."""
    from signorini.solvers.linalg import available_backends, is_positive_definite

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    T = sp.diags([-1.0, 2.0, -1.0], [-1, 0, 1], shape=(n, n), format="csr")
    assert is_positive_definite(T + 0.5 * sp.identity(n), backend)
    assert not is_positive_definite(T - 0.5 * sp.identity(n), backend)
    assert not is_positive_definite(T - 3.0 * sp.identity(n), backend)


def test_an_older_in_place_factor_refuses_to_solve(cache):
    """CHOLMOD refactorises in place (one symbolic analysis per pattern): after a second
    factorisation the first ``solve`` would silently use the new numbers, so it raises."""
    from signorini.solvers.linalg import Factorizer, available_backends

    if "cholmod" not in available_backends():
        pytest.skip("cholmod not installed")
    A = sp.csr_matrix(cache.discrete({}, 11).A)
    factorizer = Factorizer(A, "cholmod")
    first = factorizer(A.data)
    y = np.ones(A.shape[0])
    np.testing.assert_allclose(A @ first(y), y, atol=1e-12)
    second = factorizer(2.0 * A.data)
    np.testing.assert_allclose(2.0 * (A @ second(y)), y, atol=1e-12)
    with pytest.raises(RuntimeError, match="stale"):
        first(y)


@pytest.mark.parametrize("backend", ["cholmod", "superlu"])
def test_positive_definiteness_test(backend):
    from signorini.solvers.linalg import available_backends

    if backend not in available_backends():
        pytest.skip(f"{backend} not installed")
    mesh = stab_cases.build_case(stab_atlas.Case("j", "mesh", Problem().as_dict(), 21, jitter=0.2)).mesh
    from signorini.fem.assembly import p1_basis, system_matrix

    basis = p1_basis(mesh, intorder=2)
    K = system_matrix(basis, 0.0)
    assert is_positive_definite(system_matrix(basis, 1.0), backend)
    assert not is_positive_definite(system_matrix(basis, -1.0), backend)
    # (K itself is singular: whether its factorisation breaks down is up to round-off)
    assert is_positive_definite(K + 1e-8 * sp.diags(K.diagonal()), backend)
