"""The stability atlas's cases (``signorini.studies.stability.cases``): condition estimates and
extreme eigenvalues, the bad-input cases and their clear errors, the isolation of a solve, and the
classification of a case's rows."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest
from helpers import ROOT

from signorini.fem.discrete import build
from signorini.fem.problem import Problem, ProblemParameterError
from signorini.fem.solve import solve_discrete
from signorini.pipeline.config import load_config
from signorini.solvers import BadInputError, cvxpy_solve
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

# ---------------------------------------------------------------------------------
# stiff reaction
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
# bad input
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


def test_the_multigrid_column_is_measured_like_the_direct_one():
    """The multigrid route is an exact column: the certificate's 1e-10, no cvxpy options, and on
    a case the same contact set and u as the direct route's column."""
    from signorini.fem.norms.conventional import evaluate_norms

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
