"""The study's configurations (``signorini.studies.work_precision.study``)."""

from __future__ import annotations

import pytest
from helpers import ROOT

from signorini.pipeline.config import load_config
from signorini.studies.work_precision.routes import Kind
from signorini.studies.work_precision.study import SolverConfig, StudyConfigError, study_configs


def test_mistyped_options_of_a_study_or_atlas_column_are_refused():
    from signorini.studies.stability.atlas import AtlasConfigError, check_atlases

    study = {"configs": {"osqp": {"solver": "cvxpy_osqp", "options": {"polishing": "no"}}}}
    with pytest.raises(StudyConfigError, match="study.configs.osqp.options.polishing: 'no' is not of type int"):
        study_configs(study)
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["stability"]["atlas"]["solvers"]["scs"]["options"]["time_limit"] = 60
    with pytest.raises(AtlasConfigError, match="atlas.solvers.scs.options.time_limit: not an option of cvxpy_solve"):
        check_atlases(config)


def test_same_warm_start_variants():
    """``same_warm_start``: every peer gets a ``_ws`` variant started from the cascade; the
    others do not (cvxpy's QP interfaces take no initial guess); below the cascade's first
    coarse level the variant's runs are skipped with the reason."""
    study = {
        "configs": {
            "as": {"solver": "active_set"},
            "tron": {"solver": "petsc_tao", "label": "TRON", "options": {"tao_type": "tron"}},
        },
        "qp_solvers": ["cvxpy_osqp"],
        "same_warm_start": True,
    }
    configs = study_configs(study)
    assert list(configs) == ["as", "tron", "osqp", "tron_ws"]
    assert configs["tron_ws"].initial == "cascade" and configs["tron_ws"].label == "TRON (cascade start)"
    assert configs["tron"].initial == "cold" and configs["as"].initial == "cascade"
    assert SolverConfig(**configs["tron_ws"].as_dict()) == configs["tron_ws"]  # the rule's params round trip


def test_every_solver_is_named_as_the_scenes_and_the_atlas_name_it():
    """One spelling across scenes, atlas and study: an exact route, ``cvxpy_<solver>`` or a peer; the
    table names a cvxpy solver as cvxpy does.  Any other name is refused, not taken for a QP solver."""
    from signorini.studies.work_precision.study import (
        UnknownSolverError,
        kind_of,
        table_route,
        table_solver,
    )

    assert [kind_of(s) for s in ("active_set", "auto", "cvxpy_osqp", "petsc_tao")] == [
        Kind.EXACT,
        Kind.EXACT,
        Kind.QP,
        Kind.PEER,
    ]
    assert table_solver("cvxpy_clarabel") == "CLARABEL" and table_solver("multigrid") == "multigrid"
    assert table_route("CLARABEL") == "cvxpy_clarabel" and table_route("petsc_snes") == "petsc_snes"
    for name in ("osqp", "cvxpy_", "gurobi"):
        with pytest.raises(UnknownSolverError, match=f"unknown solver '{name}'; choose one of the routes .*multigrid"):
            kind_of(name)
    # cvxpy's own spelling of a QP solver: the route that runs it is named
    with pytest.raises(UnknownSolverError, match=r"unknown solver 'OSQP' \(cvxpy_osqp for cvxpy's OSQP\); choose"):
        kind_of("OSQP")
    with pytest.raises(UnknownSolverError, match="study.configs.osqp.solver: unknown solver 'OSQP'.*cvxpy_osqp"):
        study_configs({"configs": {"osqp": {"solver": "OSQP"}}})
    with pytest.raises(StudyConfigError, match="study.qp_solvers: 'active_set' is not a QP solver"):
        study_configs({"qp_solvers": ["active_set"]})
    assert SolverConfig("x", "cvxpy_scs", "SCS").kind is Kind.QP


def test_the_shipped_study_names_its_solvers_as_the_scenes_do():
    config = load_config(ROOT / "workflow/config.yaml")
    configs = study_configs(config["scenes"]["work_precision"]["study"], installed=["OSQP", "SCS"])
    assert configs["osqp"].solver == configs["osqp_nopolish"].solver == "cvxpy_osqp"
    assert configs["scs"].solver == "cvxpy_scs" and configs["scs"].label == "SCS"
