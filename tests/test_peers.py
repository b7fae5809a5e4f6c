"""PETSc's solvers as peers (``signorini.peers``): the driver (``workflow/peers/petsc_peer.py``)
reads its inner solvers and tolerances, any failure to start it is an unavailable peer with its
reason, and an answer is certified like every other solver's."""

from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from helpers import FAKE_INTERPRETERS, fake_interpreter
from helpers import PEER_DRIVER_FILE as DRIVER

from signorini import peers


def _driver():
    spec = importlib.util.spec_from_file_location("petsc_peer", DRIVER)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_driver_reads_inner_solvers_and_tolerances():
    driver = _driver()
    options = {"pc_type": "hypre", "tao_bnk_pc_type": "gamg", "pc_factor_mat_solver_type": "mumps", "ksp_type": "cg"}
    assert driver.required_inner(options) == ["hypre", "gamg", "mumps"]
    assert driver.tolerance_options("snes", None) == {}
    assert driver.tolerance_options("snes", 1e-6) == {"snes_rtol": 1e-6, "snes_stol": 1e-6, "ksp_rtol": 1e-6}
    assert driver.tolerance_options("tao", 1e-6)["tao_gttol"] == 1e-6
    # from an initial guess: absolute tests against the cold start's residual ‖b‖ = 2
    assert driver.tolerance_options("snes", 1e-6, 2.0) == {
        "snes_rtol": 0.0,
        "snes_atol": 2e-6,
        "snes_stol": 1e-6,
        "ksp_rtol": 1e-6,
    }
    warm = driver.tolerance_options("tao", 1e-6, 2.0)
    assert (warm["tao_gatol"], warm["tao_gttol"], warm["tao_grtol"]) == (2e-6, 0.0, 0.0)


def test_geometric_multigrid_levels_follow_the_grids_halvings():
    """PCMG on the grid's DMDA (``dm_type da``): one level more than the cells per side halve down
    to the coarsest grid kept; none where they do not halve (the study's odd N) or the unknowns
    are not a square grid."""
    driver = _driver()
    assert driver.dmda_levels(33**2) == (4, "")  # 32 → 16 → 8 → 4 cells
    assert driver.dmda_levels(513**2) == (8, "")  # 512 → ... → 4
    assert driver.dmda_levels(25**2) == (3, "")  # 24 → 12 → 6 cells: 3 would be below the coarsest kept
    for n in (502**2, 12**2):  # 501 and 11 cells per side
        levels, why = driver.dmda_levels(n)
        assert levels == 0 and "cannot be coarsened" in why
    assert driver.dmda_levels(500)[0] == 0 and "square" in driver.dmda_levels(500)[1]


@pytest.mark.parametrize("kind", sorted(FAKE_INTERPRETERS))
def test_any_failure_to_start_the_peer_is_unavailable_with_its_reason(tmp_path, kind):
    found = peers.probe(fake_interpreter(tmp_path, kind), DRIVER)
    assert found["petsc4py"] is False and FAKE_INTERPRETERS[kind] in found["error"], found




def test_an_answer_is_certified_against_the_system(cache):
    """The multiplier is ``(Au − b)_B``, the contact set where ``u_B ≤ 0``; without a tolerance the
    certificate asks for PETSc's default, and a perturbed ``u`` fails it."""
    disc, exact = cache.discrete({}, 11), cache.solution({}, 11)
    answer = {"solve_s": 0.01, "setup_s": 0.002, "iterations": 7}
    result = peers.certified(answer, exact.u, disc.A, disc.b, disc.boundary, 1e-10, "tron")
    np.testing.assert_array_equal(result.lam, (disc.A @ exact.u - disc.b)[disc.boundary])
    np.testing.assert_array_equal(result.active, disc.boundary[exact.u[disc.boundary] <= 0.0])
    assert result.certificate.ok and result.iterations == 7 and result.info["setup_s"] == 0.002
    default = peers.certified(answer, exact.u * 1.01, disc.A, disc.b, disc.boundary, None, "tron")
    assert default.certificate.tol == peers.DEFAULT_TOL and not default.certificate.ok


def test_what_the_table_shows_of_an_answer():
    answer = {"petsc_version": "3.18.5", "effective": {"type": "vinewtonrsls", "ksp_type": "cg", "pc_type": "hypre",
                                                      "hypre_type": "boomeramg"}}
    assert peers.peer_info(answer) == "PETSc 3.18.5: vinewtonrsls ksp=cg pc=hypre/boomeramg"
    assert peers.peer_info({}) == ""
