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


NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize(
    ("solver", "options", "message"),
    [
        ("active_set", {"max_iter": -1}, "max_iter: -1 is not allowed; an iteration cap is at least 1"),
        ("active_set", {"max_iter": 0}, "max_iter: 0 is not allowed; an iteration cap is at least 1"),
        ("active_set", {"kkt_tol": NAN}, "kkt_tol: nan is not allowed; a tolerance is a finite number > 0"),
        ("active_set", {"kkt_tol": INF}, "kkt_tol: inf is not allowed; a tolerance"),
        ("active_set", {"kkt_tol": 0.0}, "kkt_tol: 0.0 is not allowed; a tolerance"),
        ("auto", {"kkt_tol": -1e-10}, "kkt_tol: -1e-10 is not allowed; a tolerance"),
        ("multigrid", {"max_cg_iter": 0}, "max_cg_iter: 0 is not allowed; an iteration cap"),
        ("multigrid", {"inner_rtol": NAN}, "inner_rtol: nan is not allowed; a tolerance"),
        ("multigrid", {"tol": 1e-6}, "tol: tol = 1e-06 is larger than inner_rtol = 1e-08"),
        ("cvxpy", {"qp_solver": "OSQP", "tol": NAN}, "tol: nan is not allowed; a tolerance"),
        ("cvxpy_osqp", {"max_iter": 0}, "max_iter: 0 is not allowed; an iteration cap"),
        ("cvxpy_osqp", {"cg_max_iter": 0}, "cg_max_iter: 0 is not allowed; an iteration cap"),
        ("cvxpy_osqp", {"eps_abs": INF}, "eps_abs: inf is not allowed; a tolerance"),
        ("cvxpy_osqp", {"polish_refine_iter": -1}, "polish_refine_iter: -1 is not allowed; a number of refinement"),
        ("cvxpy_osqp", {"time_limit": 0.0}, "time_limit: 0.0 is not allowed; a time limit is a number of seconds > 0"),
        ("cvxpy_osqp", {"rho": NAN}, "rho: nan is not a number"),
        ("cvxpy_scs", {"max_iters": 0}, "max_iters: 0 is not allowed; an iteration cap"),
        ("cvxpy_scs", {"time_limit_secs": INF}, "time_limit_secs: inf is not allowed; a time limit is a finite"),
        ("cvxpy_clarabel", {"max_iter": -1}, "max_iter: -1 is not allowed; an iteration cap"),
        ("cvxpy_clarabel", {"equilibrate_max_iter": -1}, "equilibrate_max_iter: -1 is not allowed; a number of"),
        ("cvxpy_clarabel", {"tol_gap_rel": NAN}, "tol_gap_rel: nan is not allowed; a tolerance"),
    ],
)
def test_caps_and_tolerances_a_solver_cannot_use_are_refused(solver, options, message):
    """``max_iter: -1`` failed in the solve job ("did not repeat within max_iter=-1 iterations"),
    ``kkt_tol: .nan`` failed its KKT certificate with every residual 0, ``kkt_tol: .inf`` certified
    anything: every route's iteration caps are ≥ 1, its tolerances finite and > 0."""
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"].update(solver=solver, solver_options=options)
    with pytest.raises(ConfigError) as info:
        check_config(config)
    assert str(info.value).startswith(f"scenes.smoke.solver_options.{message}"), info.value


@pytest.mark.parametrize(
    ("solver", "options"),
    [
        ("active_set", {"max_iter": 1, "kkt_tol": 1e-300}),
        ("multigrid", {"tol": 1e-9, "inner_rtol": 1e-9, "max_cg_iter": 1}),
        ("cvxpy_osqp", {"polish_refine_iter": 0, "time_limit": INF}),  # 0 switches refinement off; no time limit
        ("cvxpy_clarabel", {"equilibrate_max_iter": 0, "iterative_refinement_max_iter": 0, "time_limit": 60.0}),
    ],
)
def test_caps_and_tolerances_at_their_bounds_pass(solver, options):
    """What the solvers accept: a cap of 1, a tiny tolerance, 0 refinement steps; the solve of N = 11
    runs with them (a certificate, or a named failure to converge: not a refused option)."""
    from signorini.fem.discrete import build
    from signorini.fem.problem import Problem
    from signorini.fem.solve import solve_discrete
    from signorini.solvers import KKTError, NotConvergedError

    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"].update(solver=solver, solver_options=options)
    check_config(config)
    try:
        solve_discrete(build(Problem(), 11, "sw_ne"), solver=solver, **options)
    except (NotConvergedError, KKTError) as err:  # e.g. one Newton step is not enough: a result, not a usage error
        assert "not allowed" not in str(err) and "must be" not in str(err)


def test_study_configurations_and_atlas_columns_pass_the_same_checks():
    """A work-precision configuration's and an atlas column's options go through the same checks."""
    from signorini.studies.stability.atlas import AtlasConfigError, check_atlases
    from signorini.studies.work_precision.study import StudyConfigError, study_configs

    config = load_config(ROOT / "workflow/config.yaml")
    study = config["scenes"]["work_precision"]["study"]
    study["configs"]["osqp"]["options"] = {"max_iter": 0}
    with pytest.raises(StudyConfigError, match=r"study\.configs\.osqp\.options\.max_iter: 0 is not allowed"):
        study_configs(study, installed=("OSQP",))
    atlas = config["scenes"]["stability"]["atlas"]
    atlas["solvers"]["multigrid"]["options"] = {"kkt_tol": NAN}
    with pytest.raises(AtlasConfigError, match=r"atlas\.solvers\.multigrid\.options\.kkt_tol: nan is not allowed"):
        check_atlases(config)


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


def test_the_direct_route_and_its_earlier_name_accept_the_same_options():
    """``direct`` and ``active_set`` name one route (``signorini.solvers.routes.ALIASES``)."""
    from signorini.pipeline.solver_options import check_options, exact_routes, route_options

    assert route_options("direct") == route_options("active_set")
    assert {"direct", "active_set"} <= set(exact_routes())
    assert check_options("x", "direct", {"max_iter": 5, "backend": "superlu"}) is None
    assert check_options("x", "direct", {"amg": "geometric"}).startswith("x.amg: not an option of active_set_solve")
