"""PETSc's SNES VI and TAO solvers as peers of the work-precision study (``signorini.peers`` has its
own tests in ``tests/test_peers.py``): the statuses the study gives their answers, the skip when
petsc4py is missing, and (marker ``peers``) a smoke run of every configured peer at N = 21 and 41.

The smoke tests need petsc4py under the peer interpreter (``/usr/bin/python3``; Debian:
``make setup-peers``) and skip without it -- unless ``SIGNORINI_REQUIRE_PEERS=1`` (set by
``.ci/run`` where ``.ci/peers`` installed them), where its absence fails them.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from helpers import FAKE_INTERPRETERS, PROBLEM, ROOT, TEST_PEER_PYTHON, fake_interpreter
from helpers import PEER_DRIVER_FILE as DRIVER

from signorini.fem.discrete import DiscreteProblem
from signorini.peers import PEER_SOLVERS, PeerRoute, driver_environment, probe
from signorini.pipeline.config import load_config
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.norm import norm_stage
from signorini.studies.scene.solve import solve_stage
from signorini.studies.scene.store import SceneMesh, load_system
from signorini.studies.work_precision import measure as wp
from signorini.studies.work_precision import peers
from signorini.studies.work_precision.study import SolverConfig, study_configs

NORMS = ["L4", "W14", "Linf"]
REQUIRED = os.environ.get("SIGNORINI_REQUIRE_PEERS") == "1"
FAST = {"wait_s": 0.0, "retries": 0, "min_repeats": 1, "budget_s": 1.0}  # no waiting for a quiet machine


@pytest.fixture(scope="module")
def petsc_probe() -> dict:
    """The driver's probe under the peer interpreter; skips (or fails in CI) without petsc4py."""
    found = probe(TEST_PEER_PYTHON, DRIVER)
    if not found.get("petsc4py"):
        if REQUIRED:
            pytest.fail(f"SIGNORINI_REQUIRE_PEERS=1 but {found.get('error')}")
        pytest.skip(f"PETSc peers unavailable: {found.get('error')}")
    return found


def shipped_peers() -> dict[str, SolverConfig]:
    """The peer configurations of the shipped work-precision study."""
    config = load_config(ROOT / "workflow/config.yaml")
    configs = study_configs(config["scenes"]["work_precision"]["study"])
    return {k: c for k, c in configs.items() if c.peer and c.initial == "cold"}  # the _ws variants: same methods


def test_peer_configurations_are_recognised():
    configs = shipped_peers()
    assert {c.solver for c in configs.values()} == {"petsc_snes", "petsc_tao"}
    assert not any(c.exact for c in configs.values())
    kinds = {str(c.options.get("snes_type", c.options.get("tao_type"))) for c in configs.values()}
    assert kinds == {"vinewtonrsls", "vinewtonssls", "tron", "gpcg", "bnls", "bqpip", "blmvm"}


def _answer(u_status: str = "done", converged: bool = True, reason: str = "CONVERGED_GTTOL") -> dict:
    return {
        "status": u_status,
        "converged": converged,
        "converged_reason": reason,
        "iterations": 7,
        "solve_s": 0.01,
        "setup_s": 0.002,
        "solve_times": [0.01, 0.012],
        "petsc_version": "3.18.5",
        "effective": {"type": "tron", "ksp_type": "stcg", "pc_type": "cholesky", "factor_solver_type": "cholmod"},
    }


def test_peer_answers_get_the_study_statuses(cache):
    """Certified like every answer: exact u → ok; a perturbed u → inaccurate; PETSc's divergence
    → failed with its reason (answer kept); driver errors → failed; missing inner solver → skipped."""
    disc, exact = cache.discrete({}, 11), cache.solution({}, 11)
    config = SolverConfig("p", "petsc_tao", "p", {"tao_type": "tron"})
    ok = peers.outcome(config, disc, 1e-10, _answer(), exact.u)
    assert ok.status == "ok" and ok.result.certificate.worst <= 1e-10 and ok.times == [0.01, 0.012]
    assert ok.extra["peer_info"] == "PETSc 3.18.5: tron ksp=stcg pc=cholesky/cholmod"
    assert ok.extra["setup_s"] == 0.002 and ok.extra["converged_reason"] == "CONVERGED_GTTOL"
    bad = peers.outcome(config, disc, 1e-10, _answer(), exact.u * 1.01)
    assert bad.status == "inaccurate" and bad.reason.startswith("KKT residual")
    diverged = peers.outcome(config, disc, None, _answer(converged=False, reason="DIVERGED_MAXITS"), exact.u)
    assert diverged.status == "failed" and diverged.reason == "PETSc DIVERGED_MAXITS" and diverged.result is not None
    error = peers.outcome(config, disc, None, {"status": "error", "reason": "PETSc error 60: sizes"}, None)
    assert (error.status, error.reason, error.result) == ("failed", "PETSc error 60: sizes", None)
    missing = peers.outcome(config, disc, None, {"status": "unavailable", "reason": "no mumps"}, None)
    assert (missing.status, missing.reason) == ("skipped", "no mumps")


def _system(tmp: Path, N: int) -> dict:
    """The inputs of a measurement job at N (system, exact solution, discretisation errors)."""
    at = SceneMesh(PROBLEM, N, "sw_ne")
    discretise_stage(at, tmp / "system.npz", tmp / "system.json")
    solve_stage(at, tmp / "system.npz", "active_set", tmp / "solution.npz", tmp / "solution.json")
    for n in NORMS:
        norm_stage(at, tmp / "solution.npz", n, tmp / f"{n}.json", {})
    return {
        "system": tmp / "system.npz",
        "system_json": tmp / "system.json",
        "exact": tmp / "solution.npz",
        "disc": {n: tmp / f"{n}.json" for n in NORMS},
        "prev": None,
        "peer_driver": DRIVER,
    }


@pytest.mark.parametrize("kind", ["missing", "project", "no_numpy"])
def test_without_petsc4py_the_peers_are_skipped(tmp_path, kind):
    """No interpreter, or one without (a compatible) petsc4py or numpy: every run ``skipped`` with the reason."""
    python = fake_interpreter(tmp_path, kind)
    inputs = _system(tmp_path, 11)
    spec = SolverConfig("p", "petsc_snes", "p", {"snes_type": "vinewtonrsls"}).as_dict()
    at = SceneMesh(PROBLEM, 11, "sw_ne")
    info = wp.measure_stage(at, spec, [1e-6], 30.0, inputs, tmp_path / "out.json", peer_python=python, timing=FAST)
    records = info["records"]
    assert [r["status"] for r in records] == ["skipped", "skipped"]
    assert all(FAKE_INTERPRETERS[kind] in r["reason"] for r in records) and not info["peer"]["petsc4py"]


# the status at tolerance 1e-10 of each shipped peer on N = 21 and 41 (PETSc 3.18, Debian 12)
EXPECTED = {
    "petsc_rsls_cholmod": "ok",
    "petsc_rsls_mumps": "ok",
    "petsc_rsls_boomeramg": "ok",
    "petsc_rsls_boomeramg_ew": "ok",
    "petsc_rsls_gamg": "ok",  # GAMG rebuilt before each step (the reduced space changes size)
    "petsc_ssls": "failed",  # DIVERGED_LINE_SEARCH
    "petsc_tron_boomeramg": "ok",
    "petsc_tron_cholmod": "ok",
    "petsc_gpcg_boomeramg": "ok",
    "petsc_gpcg_cholmod": "ok",
    "petsc_bnls": "ok",
    "petsc_bqpip": "inaccurate",  # stops on its gradient test far from the solution; the certificate says so
    "petsc_blmvm": "failed",  # DIVERGED_MAXITS
}


@pytest.mark.peers
@pytest.mark.parametrize("N", [21])  # the statuses are the same from N = 21 on
def test_peer_smoke(tmp_path, petsc_probe, N, monkeypatch):
    """Every shipped peer at N: the converging ones agree with our certified solution to 1e-10
    (max norm, relative) and pass the KKT certificate at 1e-10; the statuses are as expected."""
    # the probe of this interpreter and driver is the fixture's: each configuration's measurement
    # would start the interpreter again to ask the same question (a job asks it once)
    real_probe = probe

    def known_probe(python, driver):
        same = (python, Path(driver).resolve()) == (TEST_PEER_PYTHON, DRIVER.resolve())
        return petsc_probe if same else real_probe(python, driver)

    monkeypatch.setattr("signorini.peers.probe", known_probe)
    configs = shipped_peers()
    assert set(configs) == set(EXPECTED)
    inputs = _system(tmp_path, N)
    exact_max = float(np.abs(np.load(inputs["exact"])["u"]).max())
    at = SceneMesh(PROBLEM, N, "sw_ne")
    got = {}
    for name, config in configs.items():
        out = tmp_path / f"{name}.json"
        spec = config.as_dict()
        info = wp.measure_stage(at, spec, [1e-10], 120.0, inputs, out, peer_python=TEST_PEER_PYTHON, timing=FAST)
        default, tight = info["records"]
        assert default["status"] in ("ok", "inaccurate", "failed"), (name, default)
        got[name] = tight["status"]
        if tight["status"] == "ok":
            assert tight["kkt_worst"] <= 1e-10, (name, tight)
            assert tight["alg_Linf"] <= 1e-10 * exact_max, (name, tight["alg_Linf"])
            assert tight["converged_reason"].startswith("CONVERGED") and tight["setup_s"] > 0
            assert tight["peer_info"].startswith(f"PETSc {petsc_probe['petsc_version']}")
        elif tight["status"] == "failed":
            assert tight["reason"].startswith("PETSc"), (name, tight["reason"])
    assert got == EXPECTED


def test_a_warm_started_peer_below_the_cascade_is_skipped(tmp_path):
    inputs = _system(tmp_path, 11)
    spec = SolverConfig("p_ws", "petsc_tao", "p", {"tao_type": "tron"}, "cascade").as_dict()
    at = SceneMesh(PROBLEM, 11, "sw_ne")
    out = tmp_path / "out.json"
    info = wp.measure_stage(at, spec, [1e-6], 30.0, inputs, out, peer_python=sys.executable, timing=FAST)
    assert {r["status"] for r in info["records"]} == {"skipped"}
    assert all(r["reason"].startswith("no cascade start below N = 96") for r in info["records"])
    assert {r["start"] for r in info["records"]} == {"cascade"}


@pytest.mark.peers
@pytest.mark.parametrize("name", ["petsc_rsls_cholmod", "petsc_tron_boomeramg"])
def test_peer_from_an_initial_guess(tmp_path, petsc_probe, name):
    """The driver starts from the initial guess it is given: from the exact solution a SNES VI
    Newton method and TAO TRON stop at once (≤ 1 iteration; the relative tests made absolute
    against the cold start's residual), from u = 0 they need more; the
    answer is certified like every other.  Timed under the protocol (CPU time of the solve)."""
    from signorini.timing import Protocol, ReferenceKernel, Timer

    inputs = _system(tmp_path, 41)
    config = shipped_peers()[name]
    exact = np.load(inputs["exact"])["u"]
    route = PeerRoute(TEST_PEER_PYTHON, str(DRIVER), str(inputs["system"]), petsc_probe)
    at = SceneMesh(PROBLEM, 41, "sw_ne")
    A, b, boundary = load_system(inputs["system"], 41)
    disc = DiscreteProblem(at.problem, 41, "sw_ne", at.mesh(), A, b, boundary)
    timer, kernel = Timer(Protocol.from_mapping(FAST)), ReferenceKernel(A)
    warm = peers.run_peer(config, route, disc, 1e-10, 120.0, timer, kernel, initial_guess=exact)
    cold = peers.run_peer(config, route, disc, 1e-10, 120.0, timer, kernel)
    assert warm.status == cold.status == "ok", (warm.reason, cold.reason)
    assert warm.result.iterations <= 1 < cold.result.iterations
    assert warm.extra["peer"]["start"] != "cold" and cold.extra["peer"]["start"] == "cold"
    assert warm.extra["timing"]["time_runs"] >= 1 and warm.extra["timing"]["cpu_share"] > 0


@pytest.mark.peers
def test_a_peer_factorisation_runs_on_one_thread(tmp_path, petsc_probe):
    """CHOLMOD's supernodal factorisation asks for an OpenMP pool of its own whatever the BLAS
    thread variables say; in the study's environment (``signorini.peers.driver_environment``) the driver's process ends
    its solve with as many threads as one whose factorisation was never threaded (TRON with
    BoomerAMG), and without that environment's limits with more."""
    inputs = _system(tmp_path, 61)  # at N = 41 CHOLMOD's supernodes are too small to thread
    configs, answers = shipped_peers(), {}
    for name, env in [("petsc_rsls_cholmod", driver_environment()), ("petsc_tron_boomeramg", driver_environment()),
                      ("unlimited", {k: v for k, v in os.environ.items() if not k.startswith("OMP_")})]:
        config = configs["petsc_rsls_cholmod" if name == "unlimited" else name]
        request = {"kind": PEER_SOLVERS[config.solver], "options": dict(config.options), "tol": 1e-8}
        (tmp_path / "request.json").write_text(json.dumps(request), encoding="utf-8")
        out = tmp_path / name
        subprocess.run([TEST_PEER_PYTHON, str(DRIVER), "solve", str(inputs["system"]), str(tmp_path / "request.json"),
                        str(out)], env=env, check=True, capture_output=True)
        answers[name] = json.loads((out / "result.json").read_text(encoding="utf-8"))
    assert answers["petsc_rsls_cholmod"]["threads"] == answers["petsc_tron_boomeramg"]["threads"]
    assert answers["unlimited"]["threads"] > answers["petsc_rsls_cholmod"]["threads"]


@pytest.mark.peers
def test_geometric_multigrid_on_the_grids_dmda_runs_where_the_cells_halve(tmp_path, petsc_probe):
    """``dm_type da`` (the race's PCMG peer, ``benchmarks/peers.py``): on a grid of 32 cells per
    side PCMG coarsens the DMDA three times, and vinewtonrsls with CG/PCMG reaches our certified
    solution; on 33 cells the driver answers ``unavailable`` with PETSc's reason instead of a
    one-level "multigrid"."""
    from signorini.timing import Protocol, ReferenceKernel, Timer

    options = {"snes_type": "vinewtonrsls", "ksp_type": "cg", "pc_type": "mg", "dm_type": "da"}
    config = SolverConfig("petsc_rsls_pcmg", "petsc_snes", "vinewtonrsls + CG/PCMG", options)
    for N, status in [(32, "ok"), (33, "skipped")]:
        (tmp_path / str(N)).mkdir()
        inputs = _system(tmp_path / str(N), N)
        at = SceneMesh(PROBLEM, N, "sw_ne")
        A, b, boundary = load_system(inputs["system"], N)
        disc = DiscreteProblem(at.problem, N, "sw_ne", at.mesh(), A, b, boundary)
        route = PeerRoute(TEST_PEER_PYTHON, str(DRIVER), str(inputs["system"]), petsc_probe)
        out = peers.run_peer(config, route, disc, 1e-10, 120.0, Timer(Protocol.from_mapping(FAST)), ReferenceKernel(A))
        assert out.status == status, (N, out.reason)
        if status == "ok":
            exact = np.load(inputs["exact"])["u"]
            assert np.abs(out.result.u - exact).max() <= 1e-10 * np.abs(exact).max()
            assert out.extra["peer"]["options"]["pc_mg_levels"] == 4  # 32 → 16 → 8 → 4 cells
        else:
            assert "cannot be coarsened" in out.reason
    tron = SolverConfig("petsc_tron_pcmg", "petsc_tao", "TRON + PCMG", {"tao_type": "tron", "pc_type": "mg",
                                                                        "dm_type": "da"})
    out = peers.run_peer(tron, route, disc, 1e-10, 120.0, Timer(Protocol.from_mapping(FAST)), ReferenceKernel(A))
    assert out.status == "skipped" and "SNES only" in out.reason  # no DM under TAO's inner solver
