"""The solver options of each route (``signorini.pipeline.solver_options``): unknown or mistyped
options are refused before any job, and the option tables are what the installed QP solvers accept."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp
from helpers import ROOT

from signorini.pipeline.config import ConfigError, check_config, load_config


@pytest.mark.parametrize(
    ("solver", "options", "message"),
    [
        ("active_set", {"max_iters": 5}, "solver_options.max_iters: not an option of active_set_solve"),
        ("active_set", {"max_iter": "5"}, "solver_options.max_iter: '5' is not of type int"),
        ("cvxpy_osqp", {"max_iters": 5}, "solver_options.max_iters: not an option of cvxpy_solve/OSQP"),
        ("cvxpy_scs", {"max_iter": 5}, "solver_options.max_iter: not an option of cvxpy_solve/SCS"),
        ("cvxpy_clarabel", {"max_iter": "5"}, "solver_options.max_iter: '5' is not of type int"),
        ("cvxpy", {"qp_solver": "OSQP", "tol": "1e-8"}, "solver_options.tol: '1e-8' is not of type float"),
        ("cvxpy_osqp", {"normalize": "yes"}, "solver_options.normalize: 'yes' is not of type bool"),
        ("multigrid", {"backend": "cholmod"}, "solver_options.backend: not an option of multigrid_solve"),
        ("multigrid", {"inner_rtol": "1e-8"}, "solver_options.inner_rtol: '1e-8' is not of type float"),
        ("auto", {"amg": "classical"}, "solver_options.amg: not an option of active_set_solve and multigrid_solve"),
    ],
)
def test_unknown_or_mistyped_solver_options_are_refused(solver, options, message):
    """Named before any job runs (they used to fail inside the solve job, after assembly, with an
    unnamed TypeError); valid options of the same route pass."""
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"].update(solver=solver, solver_options=options)
    with pytest.raises(ConfigError, match=f"scenes.smoke.{message}"):
        check_config(config)
    valid = {
        "active_set": {"max_iter": 50, "kkt_tol": 1e-11},
        "cvxpy": {"qp_solver": "OSQP", "tol": 1e-8},
        "multigrid": {"amg": "smoothed_aggregation", "inner_rtol": 1e-9, "max_coarse": 100},
        "auto": {"max_iter": 50, "kkt_tol": 1e-11, "frontier_growth": True},
    }
    config["scenes"]["smoke"]["solver_options"] = valid.get(solver, {"tol": 1e-8, "normalize": True, "verbose": False})
    check_config(config)


def test_the_option_tables_match_the_installed_qp_solvers():
    """The config check knows OSQP's and SCS's settings without importing them: the tables must be
    what the installed packages accept (a new release with other settings fails here)."""
    import osqp.ext_builtin
    import scs

    from signorini.pipeline.solver_options import OSQP_SETTINGS, SCS_SETTINGS, route_options

    settings = osqp.ext_builtin.OSQPSettings()
    installed = {name for name in dir(settings) if not name.startswith("_")}
    assert set(OSQP_SETTINGS) == installed
    for name, kind in OSQP_SETTINGS.items():
        assert kind is object or isinstance(getattr(settings, name), kind), name
    data = {"P": sp.csc_matrix(np.eye(1)), "A": sp.csc_matrix(-np.eye(1)), "b": np.zeros(1), "c": np.ones(1)}
    values = {bool: False, int: 100, float: 1e-6, str: ""}
    scs.SCS(data, {"l": 1}, **{name: values[kind] for name, kind in SCS_SETTINGS.items() if kind is not str})
    scs.SCS(data, {"l": 1}, linear_solver="qdldl", write_data_filename=None, log_csv_filename=None)
    with pytest.raises(TypeError):
        scs.SCS(data, {"l": 1}, not_a_setting=1)
    assert "polishing" in route_options("cvxpy_osqp")[1] and "tol" in route_options("OSQP")[1]
