"""The PETSc peers in the built repository copy's work-precision study: certified rows with petsc4py,
skipped rows with the probe's reason without it, and an edit of the peers' driver."""

from __future__ import annotations

import pandas as pd
from helpers import PEER_DRIVER_FILE as DRIVER
from helpers import TEST_PEER_PYTHON, clone_built, planned, snakemake

from signorini import peers
from signorini.pipeline.paths import PEER_DRIVER


def test_peers_in_the_small_study(built_repo):
    """The built copy's study has one peer: certified rows when petsc4py is there; otherwise,
    whatever kept the peer from starting, skipped rows that give the probe's reason."""
    df = pd.read_csv(built_repo / "paper_figures/work_precision.csv")
    rows = df[df["config"] == "petsc_tron"]
    assert len(rows) == 2 * 3  # N = 11, 21: default and two tolerances
    warm = df[df["config"] == "petsc_tron_ws"]  # below the cascade's first coarse level: no start to give
    assert len(warm) == 2 * 3 and set(warm["status"]) == {"skipped"} and set(warm["start"]) == {"cascade"}
    found = peers.probe(TEST_PEER_PYTHON, DRIVER)
    if found.get("petsc4py"):
        tight = rows[rows["tol_label"] == "1e-08"]
        assert set(tight["status"]) == {"ok"} and (tight["kkt_worst"] <= 1e-8).all()
        assert tight["converged_reason"].str.startswith("CONVERGED").all() and (tight["setup_s"] > 0).all()
        assert "## PETSc peers" in (built_repo / "paper_figures/work_precision.md").read_text(encoding="utf-8")
    else:
        assert set(rows["status"]) == {"skipped"}
        # N = 11 gives the probe's reason; N = 21 the same, "at N=11" (skipped on the previous mesh)
        assert found["error"] and all(str(r).startswith(found["error"]) for r in rows["reason"]), rows["reason"]


def test_a_driver_edit_reruns_only_the_peer_jobs(built_repo, tmp_path):
    repo = clone_built(built_repo, tmp_path / "repo")
    driver = repo / PEER_DRIVER
    driver.write_text(driver.read_text() + "\n# edited\n")
    jobs = planned(snakemake(repo, "-n", "work_precision"))
    measured = {(wc["N"], wc["solver"]) for rule, wc in jobs if rule == "work_precision_measure"}
    assert measured == {(N, name) for N in ("11", "21") for name in ("petsc_tron", "petsc_tron_ws")}
