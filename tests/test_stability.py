"""The stability atlas (issue 5): the exact solver's behaviour on small versions of every case,
the problems with closed-form solutions, the bad-input errors, the isolation of a solve, the
atlas configuration, and the scene end to end (Snakemake, in a temporary copy)."""

from __future__ import annotations

import csv
import json
import os
import time
from pathlib import Path

import numpy as np
import pytest
import scipy.sparse as sp

from signorini.fem.discrete import build
from signorini.fem.norms import evaluate_norms
from signorini.fem.problem import (
    ConstantProblem,
    FullContactProblem,
    Problem,
    ProblemParameterError,
    make_problem,
)
from signorini.fem.solve import solve_discrete
from signorini.pipeline.config import load_config
from signorini.solvers import BadInputError, NotConvergedError, active_set_solve, cvxpy_solve, kkt_certificate
from signorini.solvers.certificate import Certificate
from signorini.solvers.linalg import is_positive_definite
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

ROOT = Path(__file__).resolve().parents[1]
AMPLITUDES = [1e-12, 1e-6, 1.0, 1e6, 1e12]
NORMS = ["L4", "Linf", "W14", "W1inf", "H12"]


def rel(u, v) -> float:
    return float(np.abs(u - v).max() / np.abs(v).max())


# ---------------------------------------------------------------------------------
# 1. data scaling
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


def test_normalized_cvxpy_is_scale_invariant_and_raw_is_not():
    """With ``normalize=True`` OSQP's answer scales with the data; as shipped (absolute
    tolerances) it does not converge for A = 1e12 (or returns a non-KKT point)."""
    N = 11
    ref = cvxpy_solve(*_qp(build(Problem(A=1.0), N)), solver="OSQP", tol=1e-8, normalize=True)
    for A in (1e-12, 1e12):
        res = cvxpy_solve(*_qp(build(Problem(A=A), N)), solver="OSQP", tol=1e-8, normalize=True)
        assert res.certificate.ok and rel(res.u / A, ref.u) <= 1e-8
        np.testing.assert_array_equal(res.active, ref.active)
    try:
        raw = cvxpy_solve(*_qp(build(Problem(A=1e12), N)), solver="OSQP", tol=1e-8, check=False)
    except NotConvergedError:
        return
    assert not raw.certificate.ok


def _qp(disc):
    return disc.A, disc.b, disc.boundary


# ---------------------------------------------------------------------------------
# 2. stiff reaction
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("c", [0.0, 1e-8, 1e8])
def test_exact_solver_on_extreme_reaction(c):
    """Nearly semicoercive (c → 0, κ₂(A) → ∞) and mass-dominated (c h² ≫ 1) systems are solved
    and certified; the free block stays well conditioned."""
    disc = build(Problem(c=c), 11)
    res = solve_discrete(disc)
    assert res.certificate.ok and np.all(np.isfinite(res.u))
    cond = stab_cases.condition_estimates(disc, res.active)
    if c <= 1e-8:
        assert cond["cond_A"] > 1e8 and cond["cond_free"] < 1e4
    else:
        assert cond["cond_A"] < 100


def test_extreme_eigenvalues_agree_with_dense():
    A = build(Problem(c=1e-4), 15).A  # 256 unknowns: the ARPACK branch
    lmin, lmax = stab_cases.extreme_eigenvalues(A)
    w = np.linalg.eigvalsh(A.toarray())
    assert lmax == pytest.approx(w[-1], rel=1e-6)
    assert lmin == pytest.approx(w[0], rel=1e-4)


# ---------------------------------------------------------------------------------
# 3. mesh extremes
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
# 4. degenerate contact: problems with closed-form solutions
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


def test_no_contact_is_certified_on_a_fine_mesh():
    """u ≡ 1 at N = 201: the load-relative stationarity of the exact solution is 5e-10 before
    iterative refinement (K 1 cancels, σ = ‖b‖∞ = h²); refinement and the rounding floor of the
    certificate (16 ε ‖|A||u|‖∞/σ) certify it."""
    disc = build(ConstantProblem(1.0, 1.0), 201)
    res = solve_discrete(disc)
    assert res.certificate.ok and res.certificate.floor > res.certificate.tol
    assert np.abs(res.u - 1.0).max() <= 1e-10


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


def test_closed_form_problems_satisfy_their_pde():
    """-Δu + c u = f by finite differences, u ≥ 0 / ∂_ν u ≥ 0 on the boundary."""
    x = np.random.default_rng(0).uniform(0.1, 0.9, size=(2, 50))
    d = 1e-4
    for p in (FullContactProblem(2.0, 3.0), ConstantProblem(2.0, 4.0), ConstantProblem(0.0, 0.0)):
        lap = sum((p.u(x + d * e[:, None]) - 2 * p.u(x) + p.u(x - d * e[:, None])) / d**2 for e in np.eye(2))
        np.testing.assert_allclose(-lap + p.c * p.u(x), p.f(x), atol=1e-5 * (1 + np.abs(p.f(x)).max()))
        g = p.grad_u(x)
        fd = np.stack([(p.u(x + d * e[:, None]) - p.u(x - d * e[:, None])) / (2 * d) for e in np.eye(2)])
        np.testing.assert_allclose(g, fd, atol=1e-6)
    s = np.linspace(0, 1, 11)
    fc = FullContactProblem(1.0, 1.0)
    bottom = np.stack([s, 0 * s])
    assert np.all(np.abs(fc.u(bottom)) < 1e-15) and np.all(-fc.grad_u(bottom)[1] >= 0)  # ∂_ν = -∂_y


def test_problem_factory_and_validation():
    assert make_problem({"x0": 0.5, "R": 0.45, "A": 10, "c": 1}) == Problem()
    assert make_problem({"kind": "constant", "value": 2.0, "c": 4.0}).exact == 0.5
    assert make_problem({"kind": "full_contact"}).as_dict() == {"kind": "full_contact", "A": 1.0, "c": 1.0}
    bad = [
        {"kind": "constant", "value": -1.0},  # Dirichlet solution: no closed form (and u ≡ 0 is wrong)
        {"kind": "constant", "value": 1.0, "c": 0.0},
        {"kind": "constant", "value": float("nan")},
        {"kind": "full_contact", "A": -1.0},
        {"kind": "nosuch"},
        {"kind": "constant", "wrong": 1.0},
    ]
    for params in bad:
        with pytest.raises(ProblemParameterError):
            make_problem(params)


# ---------------------------------------------------------------------------------
# 5. bad input
# ---------------------------------------------------------------------------------

EXPECTED_ERRORS = {
    "nan_b": (BadInputError, "NaN/Inf"),
    "inf_A": (BadInputError, "NaN/Inf"),
    "non_spd": (BadInputError, "not positive semidefinite"),
    "nonsymmetric": (BadInputError, "not symmetric"),
    "empty_constraints": (BadInputError, "empty constraint set"),
}


@pytest.mark.parametrize("corrupt", sorted(EXPECTED_ERRORS))
def test_bad_input_raises_a_clear_error(corrupt):
    case = stab_atlas.Case("bad", "bad_input", Problem().as_dict(), 11, corrupt=corrupt)
    disc = stab_cases.build_case(case)
    error, text = EXPECTED_ERRORS[corrupt]
    t0 = time.perf_counter()
    with pytest.raises(error, match=text):
        solve_discrete(disc)
    with pytest.raises(error, match=text):
        cvxpy_solve(disc.A, disc.b, disc.boundary, solver="CLARABEL")
    assert time.perf_counter() - t0 < 10.0  # not a hang


def test_nan_parameter_is_rejected_when_building():
    case = stab_atlas.Case("bad", "bad_input", Problem().as_dict(), 11, corrupt="nan_parameter")
    with pytest.raises(ProblemParameterError, match="finite"):
        stab_cases.build_case(case)


def test_indefinite_matrix_that_the_active_set_would_accept_is_rejected():
    """A = K − M: every clamped block is definite, so before the PSD check the active-set method
    returned a "certified" KKT point of an unbounded QP (the constant direction lowers the energy)."""
    disc = stab_cases.build_case(stab_atlas.Case("bad", "bad_input", Problem().as_dict(), 21, corrupt="non_spd"))
    ones = np.ones(disc.b.size)
    assert ones @ (disc.A @ ones) < 0  # a feasible direction of negative curvature
    with pytest.raises(BadInputError):
        active_set_solve(disc.A, disc.b, disc.boundary)


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


def test_semicoercive_matrix_passes_the_psd_check():
    """c = 0 (A = K singular, still convex) is a valid Signorini QP, also on a jittered mesh."""
    disc = stab_cases.build_case(stab_atlas.Case("j", "mesh", Problem(c=0.0).as_dict(), 21, jitter=0.2))
    res = solve_discrete(disc)
    assert res.certificate.ok


def test_certificate_never_certifies_nan():
    assert not Certificate(0.0, 0.0, 0.0, float("nan"), 1e-10).ok
    assert not Certificate(float("nan"), 0.0, 0.0, 0.0, 1e-10).ok
    assert Certificate(0.0, 0.0, 0.0, 0.0, 1e-10).ok


# ---------------------------------------------------------------------------------
# isolation of a solve, atlas rows
# ---------------------------------------------------------------------------------


def test_run_isolated_reports_every_outcome():
    assert stab_cases.run_isolated(lambda: 41 + 1, 30) == ("ok", 42)
    outcome, reason = stab_cases.run_isolated(lambda: 1 / 0, 30)
    assert outcome == "error" and reason.startswith("ZeroDivisionError")
    t0 = time.perf_counter()
    outcome, reason = stab_cases.run_isolated(lambda: time.sleep(60), 1.0)
    assert outcome == "timeout" and time.perf_counter() - t0 < 10
    outcome, reason = stab_cases.run_isolated(lambda: os._exit(3), 30)
    assert outcome == "crash" and "3" in reason


def test_run_case_classifies_and_never_raises():
    scene = load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]
    atlas = stab_atlas.parse_atlas(scene)
    atlas = stab_atlas.Atlas(
        (
            stab_atlas.Case("ok", "scaling", Problem().as_dict(), 6, solvers=("active_set", "osqp")),
            stab_atlas.Case("bad", "bad_input", Problem().as_dict(), 6, corrupt="nan_parameter", solvers=("osqp",)),
        ),
        atlas.solvers,
        ("L4", "H12"),
        timeout_s=60,
    )
    info, arrays = stab_cases.run_case(atlas, atlas.cases[0])
    rows = {r["solver"]: r for r in info["rows"]}
    assert rows["active_set"]["status"] == "ok" and rows["active_set"]["as_expected"]
    assert rows["active_set"]["kkt_worst"] <= 1e-10 and not rows["active_set"]["nan_inf"]
    assert rows["osqp"]["diff_to_active_set"] <= 1e-6
    assert set(arrays) == {"u_active_set", "active_active_set", "u_osqp", "active_osqp"}
    assert info["cond"]["cond_A"] > 1
    info, arrays = stab_cases.run_case(atlas, atlas.cases[1])
    (row,) = info["rows"]
    assert row["status"] == "failed" and row["as_expected"] and row["reason"].startswith("ProblemParameterError")
    assert arrays == {}


# ---------------------------------------------------------------------------------
# configuration
# ---------------------------------------------------------------------------------


def test_shipped_atlas_parses_and_every_case_builds():
    config = load_config(ROOT / "workflow/config.yaml")
    atlas = stab_atlas.scene_atlas(config, "stability")
    assert {c.group for c in atlas.cases} == set(stab_atlas.GROUPS)
    for case in atlas.cases:
        if case.N <= 201 and case.corrupt != "nan_parameter":
            disc = stab_cases.build_case(case)
            assert disc.b.size == (case.N + 1) ** 2
        job = atlas.job(case.name)
        json.dumps(job)
        assert stab_atlas.Atlas.from_job(job).cases[0] == case


def test_the_multigrid_column_is_measured_like_the_direct_one():
    """The multigrid route is an exact column: the certificate's 1e-10, no cvxpy options, and on
    a case the same contact set and u as the direct route's column."""
    from signorini.fem.norms import evaluate_norms

    config = load_config(ROOT / "workflow/config.yaml")
    atlas = stab_atlas.scene_atlas(config, "stability")
    spec = atlas.solvers["multigrid"]
    assert spec.solver == "multigrid" and spec.kkt_tol == 1e-10
    disc = stab_cases.build_case(atlas.case("A_1"))
    norms = list(atlas.norms)
    u_norms = evaluate_norms(disc.problem, disc.mesh, np.zeros(disc.b.size), norms)
    mg = stab_cases._solve_and_measure(disc, spec, norms, u_norms)
    direct = stab_cases._solve_and_measure(disc, atlas.solvers["active_set"], norms, u_norms)
    assert mg["row"]["cert"]["ok"] and np.array_equal(mg["active"], direct["active"])
    assert np.abs(mg["u"] - direct["u"]).max() <= 1e-12 * np.abs(direct["u"]).max()


@pytest.mark.parametrize(
    "change, field",
    [
        ({"group": "nosuch"}, "cases[0].group"),
        ({"name": "a b"}, "cases[0].name"),
        ({"solvers": ["nosuch"]}, "cases[0].solvers"),
        ({"problem": {"R": 0.9}}, "cases[0].problem"),
        ({"problem": {"kind": "constant", "value": -1.0}}, "cases[0].problem"),
        ({"reference": "nosuch"}, "cases[0].reference"),
        ({"corrupt": "nosuch"}, "cases[0].corrupt"),
        ({"N": 0}, "cases[0].N"),
        ({"jitter": 0.5}, "cases[0].jitter"),
    ],
)
def test_atlas_config_errors_name_the_field(change, field):
    scene = {
        "N": [11],
        "norms": ["L4"],
        "problem": Problem().as_dict(),
        "atlas": {"solvers": {"active_set": {"solver": "active_set"}}, "cases": [{"name": "a", "group": "mesh"}]},
    }
    scene["atlas"]["cases"][0].update(change)
    with pytest.raises(stab_atlas.AtlasConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
        stab_atlas.parse_atlas(scene)


# ---------------------------------------------------------------------------------
# the scene end to end
# ---------------------------------------------------------------------------------

def test_small_atlas_end_to_end(built_repo):
    from conftest import TEST_SCENES
    from helpers import snakemake

    out = built_repo / "paper_figures"
    rows = list(csv.DictReader((out / "stability.csv").open()))
    cases = TEST_SCENES["stability"]["atlas"]["cases"]
    expected = sum(len(c.get("solvers", ["active_set", "osqp", "osqp_raw"])) for c in cases)
    assert len(rows) == expected
    assert {r["status"] for r in rows} <= set(stab_atlas.STATUSES)
    assert not any(r["nan_inf"] == "True" for r in rows)
    exact = {r["case"]: r for r in rows if r["solver"] == "active_set"}
    assert all(r["as_expected"] == "True" for r in exact.values())
    assert exact["bad_spd"]["status"] == "failed" and exact["bad_spd"]["reason"].startswith("BadInputError")
    assert float(exact["A_1e-9"]["ref_diff_u"]) <= 1e-10 and exact["A_1e-9"]["ref_same_contact"] == "True"
    assert float(exact["f_zero"]["err_L4"]) == 0.0
    normalized = next(r for r in rows if r["case"] == "A_1e-9" and r["solver"] == "osqp")
    assert normalized["status"] == "ok" and float(normalized["ref_diff_u"]) <= 1e-8
    md = (out / "stability.md").read_text()
    assert all(f"**{c['name']}**" in md for c in cases)
    assert sum(line.startswith("- **") for line in md.splitlines()) == len(cases)  # one line per case
    for ext in ("pdf", "png"):
        assert (out / f"stability.{ext}").stat().st_size > 10_000
    # a rerun is a no-op; the scene is not part of `all`
    proc = snakemake(built_repo, "-n", "stability")
    assert "Nothing to be done" in proc.stdout + proc.stderr
    proc = snakemake(built_repo, "-n", "--forceall", "all")
    assert "stability_case" not in proc.stdout + proc.stderr
