"""How the work-precision study runs its routes (``signorini.studies.work_precision.routes``): the
options of a call and the residual its answer must reach, the call itself, and how the table names
the solver."""

from __future__ import annotations

import math

import pytest

from signorini.studies.work_precision import routes
from signorini.studies.work_precision.study import SolverConfig


def test_an_exact_route_is_certified_to_its_kkt_tolerance_whatever_the_tolerance(cache):
    config = SolverConfig("cold", "active_set", "active set (cold)", {"warm_start": None})
    assert config.runner is routes.EXACT and config.kind is routes.Kind.EXACT
    options, required = routes.EXACT.settings(config, 1e-2, 30.0)
    assert options == {"warm_start": None} and required == 1e-10  # no time limit, no tolerance
    assert routes.EXACT.settings(SolverConfig("a", "multigrid", "mg", {"kkt_tol": 1e-12}), None, None)[1] == 1e-12
    result, own = routes.EXACT.call(config, cache.discrete({}, 11), None, options)()
    assert own is None and result.certificate.ok and result.solver == "active_set"


def test_a_cvxpy_route_gets_the_solvers_time_limit_and_default_tolerance():
    osqp = SolverConfig("osqp", "cvxpy_osqp", "OSQP", {"polishing": False})
    assert osqp.runner is routes.CVXPY and routes.Cvxpy.qp_solver("cvxpy_osqp") == "OSQP"
    assert routes.CVXPY.settings(osqp, None, 30.0) == ({"polishing": False, "time_limit": 30.0}, 1e-3)
    assert routes.CVXPY.settings(osqp, 1e-6, None) == ({"polishing": False}, 1e-6)
    scs = SolverConfig("scs", "cvxpy_scs", "SCS", {"time_limit_secs": 5.0})
    assert routes.CVXPY.settings(scs, None, 30.0)[0] == {"time_limit_secs": 5.0}  # the configuration's own kept
    unknown = SolverConfig("x", "cvxpy_nosuch", "NOSUCH")
    assert math.isnan(routes.CVXPY.settings(unknown, None, 30.0)[1])  # no default known: nothing certified
    assert routes.CVXPY.log_option(SolverConfig("h", "cvxpy_highs", "HIGHS")) == "log_file"
    assert routes.CVXPY.log_option(osqp) is None and routes.EXACT.log_option(osqp) is None
    assert routes.CVXPY.table_name("cvxpy_clarabel") == "CLARABEL" and routes.EXACT.table_name("auto") == "auto"


def test_a_peer_is_not_run_in_process():
    peer = SolverConfig("tron", "petsc_tao", "TRON")
    assert peer.runner is routes.PEER and peer.peer and not peer.exact
    peer.runner.warm_up(peer)  # nothing to load: the driver starts a fresh process per run
    with pytest.raises(NotImplementedError):
        peer.runner.settings(peer, None, None)
