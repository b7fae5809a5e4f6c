"""The study's configurations (``signorini.studies.work_precision.study``)."""

from __future__ import annotations

import pytest
from helpers import ROOT

from signorini.pipeline.config import load_config
from signorini.studies.work_precision.study import SolverConfig, study_configs


def test_mistyped_options_of_a_study_or_atlas_column_are_refused():
    from signorini.studies.stability.atlas import AtlasConfigError, check_atlases
    from signorini.studies.work_precision.study import StudyConfigError, study_configs

    study = {"configs": {"osqp": {"solver": "OSQP", "options": {"polishing": "no"}}}}
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
        "qp_solvers": ["OSQP"],
        "same_warm_start": True,
    }
    configs = study_configs(study)
    assert list(configs) == ["as", "tron", "osqp", "tron_ws"]
    assert configs["tron_ws"].initial == "cascade" and configs["tron_ws"].label == "TRON (cascade start)"
    assert configs["tron"].initial == "cold" and configs["as"].initial == "cascade"
    assert SolverConfig(**configs["tron_ws"].as_dict()) == configs["tron_ws"]  # the rule's params round trip
