"""The solve of a discrete problem (``signorini.fem.solve.solve_discrete``): the cascade warm start,
scale invariance, meshes of even and odd N, and problems with closed-form discrete solutions."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import check_kkt_independently, rel_max_diff
from helpers import rel_max_diff as rel

from signorini.fem.discrete import build
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import ConstantProblem, FullContactProblem, Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import kkt_certificate
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

# ---------------------------------------------------------------------------------
# warm starts
# ---------------------------------------------------------------------------------


@pytest.fixture(scope="module", params=["sw_ne", "nw_se"])
def cascade_pair(request):
    """N = 101: large enough that the cascade really warm-starts (from N = 25)."""
    disc = build(Problem(), 101, request.param)
    return disc, solve_discrete(disc, warm_start="cascade"), solve_discrete(disc, warm_start=None)


def test_cascade_warm_start_gives_the_cold_solution(cascade_pair):
    disc, warm, cold = cascade_pair
    assert rel_max_diff(warm.u, cold.u) <= 1e-12
    np.testing.assert_array_equal(np.sort(warm.active), np.sort(cold.active))
    assert warm.certificate.ok and cold.certificate.ok
    check_kkt_independently(disc.A, disc.b, disc.boundary, warm.u, warm.lam)


def test_cascade_warm_start_saves_factorisations(cascade_pair):
    _, warm, cold = cascade_pair
    assert warm.info["factorizations"] <= cold.info["factorizations"]
    assert warm.iterations <= cold.iterations
    assert warm.info["factorizations"] >= 1 and warm.info["triangular_solves"] >= warm.info["factorizations"]


def test_fine_solve_costs_one_factorisation_and_few_solves():
    """The cascade's point at N = 101: one factorisation, and the changes of the active set
    after it cost a handful of triangular solves (not one Krylov solve per Newton step)."""
    disc = build(Problem(), 101)
    res = solve_discrete(disc)
    assert res.info["factorizations"] == 1
    assert res.info["triangular_solves"] <= 2 + res.info["correction_columns"] <= 12


def test_a_cascade_start_that_does_not_settle_falls_back_to_the_cold_start(caplog, monkeypatch):
    """From the coarse interpolant of this problem the contact set must grow by about a hundred
    nodes.  With frontier growth of one node per end and step (no doubling reach) that exceeds
    max_iter, and the solve is repeated from the cold start, which settles; with the doubling
    reach the cascade start settles by itself."""
    import logging

    from signorini.solvers import pdas

    disc = build(Problem(x0=0.4142, R=0.3, A=10.0, c=1.0), 121, "sw_ne")
    cold = solve_discrete(disc, warm_start=None)
    with caplog.at_level(logging.WARNING, logger="signorini.fem.solve"):
        doubling = solve_discrete(disc)
    assert "did not settle" not in caplog.text and doubling.iterations < 30
    np.testing.assert_array_equal(np.sort(doubling.active), np.sort(cold.active))
    monkeypatch.setattr(pdas, "CREEP_STEPS", 10**6)
    with caplog.at_level(logging.WARNING, logger="signorini.fem.solve"):
        result = solve_discrete(disc)
    assert "cascade start did not settle" in caplog.text
    assert np.array_equal(result.u, cold.u) and result.certificate.ok


AMPLITUDES = [1e-12, 1e-6, 1.0, 1e6, 1e12]
NORMS = ["L4", "Linf", "W14", "W1inf", "H12"]


# ---------------------------------------------------------------------------------
# data scaling
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("N", [11, 21])
def test_exact_solver_is_scale_invariant(N):
    """u_h(sA) = s u_h(A) with the same contact set, iterations and relative errors (to 1e-10)."""
    ref_disc = build(Problem(A=1.0), N)
    ref = solve_discrete(ref_disc)
    ref_err = evaluate_norms(ref_disc.problem, ref_disc.mesh, ref.u, NORMS)
    for A in AMPLITUDES:
        disc = build(Problem(A=A), N)
        res = solve_discrete(disc)
        assert res.certificate.ok and res.certificate.worst <= 1e-12
        np.testing.assert_array_equal(res.active, ref.active)
        assert res.iterations == ref.iterations
        assert rel(res.u / A, ref.u) <= 1e-10
        err = evaluate_norms(disc.problem, disc.mesh, res.u, NORMS)
        for n in NORMS:  # relative errors: the exact u scales by A too
            assert err[n] / A == pytest.approx(ref_err[n], rel=1e-10)


# ---------------------------------------------------------------------------------
# mesh extremes
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("N", [2, 3, 4, 5, 10, 11])
def test_even_and_odd_N(N):
    """Even N: the free point (x0, 0) is a node, and it is in contact (u_h = 0 exactly).
    The free segment (x0 − R, x0) holds N//2 − 1 (even) or (N − 1)//2 (odd) nodes, none for
    N = 2, one for N = 3; every one of them is lifted (u_h > 0)."""
    disc = build(Problem(), N)
    res = solve_discrete(disc)
    assert res.certificate.ok and np.all(np.isfinite(res.u))
    x, y = disc.mesh.p
    bottom = disc.boundary[np.isclose(y[disc.boundary], 0.0)]
    segment = bottom[(x[bottom] > 0.05) & (x[bottom] < 0.5)]
    assert segment.size == {2: 0, 3: 1}.get(N, segment.size)
    assert np.all(res.u[segment] > 0.0)
    node = bottom[np.isclose(x[bottom], 0.5)]
    assert node.size == (1 if N % 2 == 0 else 0)
    assert np.all(res.u[node] == 0.0) and np.all(np.isin(node, res.active))
    err = evaluate_norms(disc.problem, disc.mesh, res.u, NORMS)
    assert all(np.isfinite(v) for v in err.values())


def test_jittered_mesh_warm_start_gives_the_cold_solution():
    """solve_discrete's cascade (coarse unjittered mesh, interpolated at the jittered nodes)
    stays a valid warm start: same solution as a cold start, fewer iterations."""
    case = stab_atlas.Case("j", "mesh", Problem().as_dict(), 101, jitter=0.2, seed=1)
    disc = stab_cases.build_case(case)
    assert not np.allclose(disc.mesh.p, build(Problem(), 101).mesh.p)
    warm, cold = solve_discrete(disc), solve_discrete(disc, warm_start=None)
    assert warm.certificate.ok and cold.certificate.ok
    assert rel(warm.u, cold.u) <= 1e-12
    np.testing.assert_array_equal(warm.active, cold.active)
    assert warm.iterations < cold.iterations


# ---------------------------------------------------------------------------------
# degenerate contact: problems with closed-form solutions
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("c", [0.0, 1.0])
@pytest.mark.parametrize("problem", ["manufactured", "constant"])
def test_zero_data_gives_exactly_zero(problem, c):
    """f ≡ 0: u_h = 0 exactly (every boundary node biactive), residuals 0, no NaN anywhere."""
    p = Problem(A=0.0, c=c) if problem == "manufactured" else ConstantProblem(0.0, c)
    disc = build(p, 12)
    with np.errstate(all="raise"):
        res = solve_discrete(disc)
        cert = kkt_certificate(disc.A, disc.b, disc.boundary, res.u, res.lam, 1e-10)
    assert np.all(res.u == 0.0) and np.all(res.lam == 0.0)
    assert cert.ok and cert.worst == 0.0
    assert all(v == 0.0 for v in evaluate_norms(p, disc.mesh, res.u, NORMS).values())


@pytest.mark.parametrize("N", [3, 11, 41])
def test_no_contact_constant_solution(N):
    """f ≡ 1, c = 1: u ≡ 1 is the exact and the discrete solution (K 1 = 0, b = M 1)."""
    p = ConstantProblem(1.0, 1.0)
    disc = build(p, N)
    res = solve_discrete(disc)
    assert res.active.size == 0 and res.certificate.ok
    assert np.abs(res.u - 1.0).max() <= 1e-11
    assert max(evaluate_norms(p, disc.mesh, res.u, NORMS).values()) <= 1e-11


@pytest.mark.parametrize("N", [11, 21])
def test_full_contact(N):
    """u = -sin(πx) sin(πy), f ≤ 0: every boundary node in contact; O(h²) in L⁴."""
    p = FullContactProblem(1.0, 1.0)
    disc = build(p, N)
    res = solve_discrete(disc)
    assert res.certificate.ok
    np.testing.assert_array_equal(np.sort(res.active), disc.boundary)
    assert np.all(res.u[disc.boundary] == 0.0) and np.all(res.lam >= 0.0)
    err = evaluate_norms(p, disc.mesh, res.u, ["L4"])["L4"]
    assert err <= 2.5 / N**2
