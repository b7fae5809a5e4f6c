"""The KKT certificate and the input checks (``signorini.solvers.certificate``)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from signorini.fem.discrete import build
from signorini.fem.problem import ConstantProblem, Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import active_set_solve, cvxpy_solve
from signorini.solvers.certificate import BadInputError, Certificate, kkt_certificate
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases


def test_certificate_detects_perturbed_solutions(small_case):
    disc, res = small_case
    A, b, B, u, lam = disc.A, disc.b, disc.boundary, res.u, res.lam
    assert kkt_certificate(A, b, B, u, lam, 1e-10).ok
    scale = np.abs(u).max()
    interior = np.setdiff1d(np.arange(u.size), B)

    v = u.copy()
    v[interior[interior.size // 2]] += 1e-6 * scale  # breaks stationarity
    cert = kkt_certificate(A, b, B, v, lam, 1e-10)
    assert not cert.ok and cert.stationarity > 1e-10

    v = u.copy()
    v[res.active[0]] = -1e-6 * scale  # infeasible
    assert kkt_certificate(A, b, B, v, lam, 1e-10).primal > 1e-10

    strong = np.argmax(lam)  # a node with a strictly positive multiplier
    assert lam[strong] > 0
    v = u.copy()
    v[B[strong]] += 1e-6 * scale  # lifts a contact node: stationarity and complementarity break
    cert = kkt_certificate(A, b, B, v, lam, 1e-10)
    assert not cert.ok and cert.complementarity > 1e-10

    cert = kkt_certificate(A, b, B, u, -lam, 1e-10)  # wrong sign of the multiplier
    assert not cert.ok and cert.dual > 1e-10

    assert not kkt_certificate(A, b, B, np.full_like(u, np.nan), lam, 1e-10).ok


def test_certificate_is_scale_invariant(small_case):
    disc, res = small_case
    c1 = kkt_certificate(disc.A, disc.b, disc.boundary, res.u, res.lam, 1e-10)
    c2 = kkt_certificate(disc.A, 1e5 * disc.b, disc.boundary, 1e5 * res.u, 1e5 * res.lam, 1e-10)
    for name in ("stationarity", "primal", "dual", "complementarity"):
        # residuals at round-off level differ by a few ulps after scaling
        assert getattr(c2, name) == pytest.approx(getattr(c1, name), rel=1e-6, abs=1e-14)


def _bad_inputs(disc):
    A, b, B = disc.A, disc.b, disc.boundary
    nan_b = b.copy()
    nan_b[3] = np.nan
    inf_A = A.copy().tolil()
    inf_A[2, 2] = np.inf
    neg = A.copy().tolil()
    neg[5, 5] = -neg[5, 5]
    zero = A.copy().tolil()
    zero[5, 5] = 0.0
    return {
        "nan in b": (A, nan_b, B),
        "inf in A": (inf_A.tocsr(), b, B),
        "short b": (A, b[:-1], B),
        "non-square A": (A[:, :-1], b, B),
        "negative diagonal": (neg.tocsr(), b, B),
        "zero diagonal": (zero.tocsr(), b, B),
        "index out of range": (A, b, np.append(B, b.size)),
        "negative index": (A, b, np.append(B, -1)),
    }


BAD_INPUT_NAMES = list(_bad_inputs(build(Problem(), 3)))


@pytest.mark.parametrize("which", BAD_INPUT_NAMES)
def test_active_set_rejects_bad_input(cache, which):
    A, b, B = _bad_inputs(cache.discrete({}, 11))[which]
    with pytest.raises(BadInputError):
        active_set_solve(A, b, B)


@pytest.mark.parametrize("which", BAD_INPUT_NAMES)
def test_cvxpy_rejects_bad_input(cache, which):
    A, b, B = _bad_inputs(cache.discrete({}, 11))[which]
    with pytest.raises(BadInputError):
        cvxpy_solve(A, b, B, solver="OSQP")


def test_bad_input_error_is_a_value_error():
    assert issubclass(BadInputError, ValueError)


def test_rounding_floor_is_capped():
    """The certificate's rounding floor ``16 ε ‖|A||u|‖∞/σ`` admits cancellation, not an
    exploded u: a residual of 0.5 is never certified, however large u is."""
    A = sp.csr_matrix(np.array([[1.0, -1.0], [-1.0, 1.0]]))  # K of one interval: A 1 = 0
    u = np.array([1e15, 1e15])  # A u cancels exactly; |A||u| = 2e15
    b = np.array([1.0, 1.0])  # relative stationarity ‖A u - b‖∞ / ‖b‖∞ = 1
    cert = kkt_certificate(A, b, np.array([0]), u, np.zeros(1), 1e-10)
    assert cert.floor > 1.0 and cert.stationarity == 1.0
    assert not cert.ok


def test_no_contact_is_certified_on_a_fine_mesh():
    """u ≡ 1 at N = 201: the load-relative stationarity of the exact solution is 5e-10 before
    iterative refinement (K 1 cancels, σ = ‖b‖∞ = h²); refinement and the rounding floor of the
    certificate (16 ε ‖|A||u|‖∞/σ) certify it."""
    disc = build(ConstantProblem(1.0, 1.0), 201)
    res = solve_discrete(disc)
    assert res.certificate.ok and res.certificate.floor > res.certificate.tol
    assert np.abs(res.u - 1.0).max() <= 1e-10


def test_semicoercive_matrix_passes_the_psd_check():
    """c = 0 (A = K singular, still convex) is a valid Signorini QP, also on a jittered mesh."""
    disc = stab_cases.build_case(stab_atlas.Case("j", "mesh", Problem(c=0.0).as_dict(), 21, jitter=0.2))
    res = solve_discrete(disc)
    assert res.certificate.ok


def test_certificate_never_certifies_nan():
    assert not Certificate(0.0, 0.0, 0.0, float("nan"), 1e-10).ok
    assert not Certificate(float("nan"), 0.0, 0.0, 0.0, 1e-10).ok
    assert Certificate(0.0, 0.0, 0.0, 0.0, 1e-10).ok


def _signed_random(n: int, seed: int) -> sp.csr_matrix:
    """A nonsymmetric CSR matrix (pattern and values) with an empty row."""
    signed = sp.random(n, n, density=0.05, random_state=seed) - sp.random(n, n, density=0.05, random_state=seed + 1)
    A = sp.lil_matrix(signed)
    A[7, :] = 0.0  # a row that stores nothing
    A = sp.csr_matrix(A)
    A.eliminate_zeros()
    return A


@pytest.mark.parametrize(("compiled_from", "chunk"), [(0, 1 << 20), (10**9, 1 << 20), (10**9, 64), (10**9, 7)])
def test_abs_product_is_the_product_with_the_absolute_matrix_bit_for_bit(monkeypatch, compiled_from, chunk):
    """``|A| y`` without forming ``|A|`` (compiled, or numpy a block of rows at a time, block edges
    included) equals the CSR product with ``|A|`` in every bit (the same summation order per row),
    an empty row included."""
    from signorini.solvers import certificate

    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", compiled_from)
    monkeypatch.setattr(certificate, "ABS_CHUNK_ROWS", chunk)
    A = _signed_random(300, 4)
    y = np.random.default_rng(3).standard_normal(300)
    got = certificate.abs_product(A, y)
    assert got.tobytes() == (abs(A) @ y).tobytes() and got[7] == 0.0


@pytest.mark.parametrize("seed", [4, 9])
def test_the_compiled_checks_give_numpys_values(monkeypatch, seed):
    """The symmetry and dominance checks in one compiled pass (no ``Aᵀ``, no ``|A|``) give numpy's
    values: entries stored on one side only, entries on both sides with different values, a
    symmetric matrix (0), a diagonally dominant one and one that is not."""
    from signorini.solvers import certificate

    A = _signed_random(300, seed)
    S = sp.csr_matrix(A + A.T)
    S.sort_indices()
    T = S.tolil()
    T[3, 5] = T[3, 5] + 1e-3  # one entry off its mirror
    T = sp.csr_matrix(T)
    D = sp.csr_matrix(S + sp.diags(np.asarray(abs(S).sum(axis=1)).ravel() + 1.0))
    matrices = (A, S, T, D)
    numpy_values = [certificate.symmetry_and_dominance(M) for M in matrices]
    monkeypatch.setattr(certificate, "COMPILED_MIN_UNKNOWNS", 0)
    assert [certificate.symmetry_and_dominance(M) for M in matrices] == numpy_values
    assert [v[1] > 0.0 for v in numpy_values] == [True, False, True, False]
    assert numpy_values[2][1] == pytest.approx(1e-3, rel=1e-9)
    assert [v[2] for v in numpy_values] == [False, False, False, True]
