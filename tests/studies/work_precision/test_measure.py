"""The work-precision study's measurements: norms of a P1 function, the measurement function
(statuses, algebraic error of the exact solver, the machine it ran on).  The findings, the report
and the figures have their own test modules."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import PROBLEM
from skfem import MeshTri

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms import p1 as p1norms
from signorini.fem.norms.conventional import Conventions, evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.quadrature import stroud_conical
from signorini.pipeline.jobenv import THREAD_VARIABLES
from signorini.published import PAPER_NORMS
from signorini.solvers import Certificate, NotConvergedError, SolveResult
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh, load_system
from signorini.studies.work_precision import measure as wp
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.study import study_configs

OMP, OPENBLAS = THREAD_VARIABLES[0], THREAD_VARIABLES[2]  # two of the variables jobenv names

NORMS = list(PAPER_NORMS)
FAST = {"wait_s": 0.0, "retries": 1, "budget_s": 2.0}  # the protocol without waiting for a quiet machine


# --- norms of a P1 function -----------------------------------------------------------------


def test_complete_homogeneous_polynomial(rng):
    x, y, z = rng.standard_normal((3, 7))
    for p in (0, 1, 2, 4, 16):
        brute = sum(x**a * y**b * z ** (p - a - b) for a in range(p + 1) for b in range(p + 1 - a))
        np.testing.assert_allclose(p1norms._complete_homogeneous(x, y, z, p), brute, rtol=1e-12)


@pytest.mark.parametrize("form", ["components", "gradient", "seminorm"])
def test_p1_norms_match_the_quadrature_norms(rng, form):
    """Where the pipeline's quadrature is exact for a P1 function (|v|⁴, |∇v|^p, boundary
    integrands; maxima at vertices), p1_norms agrees with evaluate_norms of u ≡ 0 (A = 0)."""
    mesh = friedrichs_keller(9)
    v = rng.standard_normal(mesh.p.shape[1])
    conv = Conventions(w1p_form=form)
    names = ["L2", "L4", "Linf", "W14", "W1inf", "H1", "H12", "L2boundary"]
    ours = p1norms.p1_norms(mesh, v, names, conv)
    ref = evaluate_norms(Problem(A=0.0), mesh, v, names, conv)
    for name in names:
        assert ours[name] == pytest.approx(ref[name], rel=1e-12), name


def test_p1_norms_high_powers_are_exact(rng):
    """L¹⁶ of a linear function on one triangle against a 400-point conical Gauss rule."""
    tri = MeshTri(np.array([[0.0, 0.7, 0.1], [0.0, 0.2, 0.9]]), np.array([[0], [1], [2]]))
    w = np.array([0.3, -1.0, 0.7])
    s, t, weights = stroud_conical(20)
    values = w @ np.vstack([1 - s, s * (1 - t), s * t])
    area = 0.5 * abs(0.7 * 0.9 - 0.1 * 0.2)
    for p in (4, 16):
        ref = (area * np.sum(np.abs(values) ** p * weights)) ** (1 / p)
        assert p1norms.p1_norms(tri, w, [f"L{p}"])[f"L{p}"] == pytest.approx(ref, rel=1e-12)
    assert p1norms.p1_norms(tri, 1e-150 * w, ["L16"])["L16"] == pytest.approx(1e-150 * ref, rel=1e-12)  # no underflow


def test_p1_norms_of_zero_and_unsupported_names():
    mesh = friedrichs_keller(4)
    assert p1norms.p1_norms(mesh, np.zeros(25), NORMS) == dict.fromkeys(NORMS, 0.0)
    with pytest.raises(ValueError, match="not supported"):
        p1norms.p1_norms(mesh, np.ones(25), ["L4plus"])


# --- configurations, skips and failure classification -----------------------------------------


def test_study_configs_add_installed_solvers():
    study = {"configs": {"osqp": {"solver": "cvxpy_osqp", "label": "OSQP (polish)"}}, "qp_solvers": "installed"}
    configs = study_configs(study, installed=["CLARABEL", "OSQP"])
    assert list(configs) == ["osqp", "clarabel"]
    assert configs["osqp"].solver == "cvxpy_osqp" and configs["osqp"].label == "OSQP (polish)"
    assert configs["clarabel"].solver == "cvxpy_clarabel" and configs["clarabel"].label == "CLARABEL"
    assert configs["clarabel"].kind is Kind.QP and not configs["clarabel"].exact


def test_every_exact_route_is_an_exact_configuration():
    """The direct and the multigrid route (and auto) run once, certified, labelled exact."""
    study = {"configs": {name: {"solver": name} for name in ("active_set", "multigrid", "auto")}}
    configs = study_configs(study)
    for config in configs.values():
        assert config.exact and config.solver in ("active_set", "multigrid", "auto")
        assert wp.planned_runs(config, [1e-2, 1e-8]) == [None] and wp.tolerance_label(None, config) == "exact"


def test_skip_reason_from_the_previous_mesh():
    ok = {"N": 101, "n_dofs": 10404, "status": "ok", "reason": "", "time_s": 10.0}
    assert wp.skip_reason(None, 40401, 120.0) is None
    assert wp.skip_reason(ok, 40401, 120.0) is None  # predicted 10 · 3.88^1.5 ≈ 77 s
    assert wp.skip_reason(ok, 40401, 60.0).startswith("time budget (predicted 77 s")
    failed = {**ok, "status": "failed", "reason": "solver status infeasible"}
    assert wp.skip_reason(failed, 40401, None) == "failed at N=101: solver status infeasible"
    limit = {**ok, "status": "failed", "reason": "time limit (120 s)"}
    assert wp.skip_reason(limit, 40401, 120.0).startswith("time budget")
    skipped = {"N": 201, "status": "skipped", "reason": "failed at N=101: x"}
    assert wp.skip_reason(skipped, 90601, 120.0) == "failed at N=101: x"


def test_classify_failure():
    limit = NotConvergedError("cvxpy/OSQP returned status 'user_limit'", status="user_limit")
    assert wp.classify_failure(limit, 119.0, 120.0) == ("failed", "time limit (120 s)")
    assert wp.classify_failure(limit, 1.0, 120.0)[1] == "iteration limit (status user_limit)"
    status, reason = wp.classify_failure(NotConvergedError("x", status="optimal_inaccurate"), 1, None)
    assert status == "inaccurate" and "optimal_inaccurate" in reason
    assert wp.classify_failure(ValueError("boom"), 0.1, None) == ("failed", "ValueError: boom")
    # the status is read from the error, not from its message
    unlabelled = NotConvergedError("returned status 'user_limit'")
    assert wp.classify_failure(unlabelled, 1.0, None)[1].startswith("NotConvergedError")
    assert wp.classify_failure(NotConvergedError("", status="infeasible"), 1.0, None)[1] == "solver status infeasible"


# --- the measurement ------------------------------------------------------------------------


@pytest.fixture(scope="module")
def small_study(tmp_path_factory):
    """N = 12: the cached system, the exact solution and the discretisation errors, as the
    workflow provides them to a measurement job."""
    d = tmp_path_factory.mktemp("wp")
    N = 12
    discretise_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / "system.npz", d / "system.json")
    solve_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / "system.npz", "active_set", d / "solution.npz", d / "solution.json")
    disc = {}
    for n in NORMS:
        norm_stage(SceneMesh(PROBLEM, N, "sw_ne"), d / "solution.npz", n, d / f"{n}.json", {})
        disc[n] = d / f"{n}.json"
    return {"dir": d, "N": N, "disc": disc}


def measure(small_study, config: dict, tolerances=(1e-2,), out="out.json", prev_json=None) -> list[dict]:
    d = small_study["dir"]
    spec = {"name": "x", "label": "x", "options": {}, **config}
    inputs = {
        "system": d / "system.npz",
        "system_json": d / "system.json",
        "exact": d / "solution.npz",
        "disc": small_study["disc"],
        "prev": prev_json,
    }
    at = SceneMesh(PROBLEM, small_study["N"], "sw_ne")
    info = wp.measure_stage(at, spec, tolerances, 30.0, inputs, d / out, timing=FAST)
    return info["records"]


def test_exact_solver_has_zero_algebraic_error(small_study):
    import json

    (rec,) = measure(small_study, {"solver": "active_set"})
    machine = json.loads(rec["machine"])  # the machine and software, recorded with every run
    assert machine["cores"] >= 1 and set(machine["threads"]) >= {OMP, OPENBLAS}
    assert "Python" in machine["software"] and "numpy" in machine["software"]
    assert rec["status"] == "ok" and rec["tol_label"] == "exact" and rec["kkt_worst"] <= 1e-10
    for n in NORMS:
        assert rec[f"alg_{n}"] == 0.0
        assert rec[f"total_{n}"] == rec[f"disc_{n}"]  # the source scene's discretisation error
    times = [float(t) for t in rec["times"].split()]
    assert rec["time_runs"] == len(times) >= 1 and rec["time_s"] == pytest.approx(float(np.median(times)), rel=1e-5)
    assert rec["time_ref"] == pytest.approx(rec["time_s"] / rec["ref_s"], rel=0.5) and rec["start"] == "cascade"
    assert rec["time_stop"] in ("spread", "max_repeats", "budget") and rec["cpu_share"] > 0
    (cold,) = measure(small_study, {"solver": "active_set", "options": {"warm_start": None, "backend": "superlu"}})
    assert cold["status"] == "ok" and cold["alg_L4"] < 1e-12 * cold["disc_L4"]


def test_qp_solver_runs_default_then_loose_to_tight(small_study):
    recs = measure(small_study, {"solver": "cvxpy_osqp", "options": {"polishing": False}}, tolerances=(1e-8, 1e-2))
    assert [r["tol_label"] for r in recs] == ["default", "1e-02", "1e-08"]
    assert {r["solver"] for r in recs} == {"OSQP"}  # the table names cvxpy's solver as cvxpy does
    assert recs[0]["is_default"] and not recs[1]["is_default"]
    assert all(r["status"] in ("ok", "inaccurate") for r in recs)
    assert recs[1]["alg_L4"] > recs[2]["alg_L4"] > 0.0  # a tighter tolerance, a smaller algebraic error
    # total error within the triangle inequality of discretisation and algebraic error
    for r in recs:
        assert r["total_W14"] <= r["disc_W14"] + r["alg_W14"] * (1 + 1e-9)


def test_failing_solver_is_recorded_not_raised(small_study, monkeypatch):
    import signorini.solvers

    recs = measure(small_study, {"solver": "cvxpy_nosuch"}, out="nosuch.json")
    assert {r["status"] for r in recs} == {"failed"}
    assert all("NOSUCH" in r["reason"] and "alg_L4" not in r for r in recs)
    assert np.isfinite(recs[0]["time_s"]) and recs[0]["disc_L4"] > 0

    # an answer whose KKT residual exceeds the requested tolerance is measured and marked
    exact = load_system(small_study["dir"] / "system.npz")[1] * 0.0

    def sloppy(A, b, B, solver, tol=None, **kwargs):
        cert = Certificate(1e-1, 0.0, 0.0, 0.0, 1e-6)
        return SolveResult(exact.copy(), np.zeros(B.size), B, 7, 0.01, cert, "cvxpy_fake")

    monkeypatch.setattr(signorini.solvers, "cvxpy_solve", sloppy)
    recs = measure(small_study, {"solver": "cvxpy_osqp"}, out="sloppy.json")
    assert [r["status"] for r in recs] == ["inaccurate", "inaccurate"]
    # the residual and the tolerance it missed are recorded as numbers, the reason names the kind
    assert [(r["reason"], r["kkt_worst"], r["kkt_required"]) for r in recs] == [
        ("KKT residual above the tolerance", 1e-1, 1e-3),  # OSQP's default
        ("KKT residual above the tolerance", 1e-1, 1e-2),
    ]
    assert recs[0]["alg_L4"] > 0 and recs[0]["iterations"] == 7

    def raising(*args, **kwargs):
        raise NotConvergedError("cvxpy/OSQP returned status 'infeasible'", status="infeasible")

    monkeypatch.setattr(signorini.solvers, "cvxpy_solve", raising)
    recs = measure(small_study, {"solver": "cvxpy_osqp"}, out="raising.json")
    assert [(r["status"], r["reason"]) for r in recs] == [("failed", "solver status infeasible")] * 2


def test_previous_failure_skips_the_run(small_study):
    measure(small_study, {"solver": "cvxpy_nosuch"}, out="prev.json")
    recs = measure(small_study, {"solver": "cvxpy_nosuch"}, out="next.json", prev_json=small_study["dir"] / "prev.json")
    assert {r["status"] for r in recs} == {"skipped"}
    assert all(r["reason"].startswith("failed at N=12") for r in recs)
