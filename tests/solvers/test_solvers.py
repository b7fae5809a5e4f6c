"""The dispatcher over the solver routes (``signorini.solvers.solve``, the package's ``__init__``)."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import rel_max_diff

from signorini.fem.discrete import build
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.solvers import SOLVERS, solve


def test_dispatcher_routes(cache):
    disc, exact = cache.discrete({}, 11), cache.solution({}, 11)
    assert {"direct", "multigrid", "cvxpy", "auto"} <= set(SOLVERS)
    assert solve("multigrid", disc.A, disc.b, disc.boundary, max_coarse=20).solver == "multigrid"
    # the direct route's results keep the name the artifacts record: active_set
    assert solve("auto", disc.A, disc.b, disc.boundary).solver == "active_set"  # 144 unknowns: direct
    r0 = solve("direct", disc.A, disc.b, disc.boundary)
    r1 = solve("active_set", disc.A, disc.b, disc.boundary)  # the direct route's earlier name
    assert r0.solver == "active_set" and np.array_equal(r0.u, r1.u)
    r2 = solve("cvxpy", disc.A, disc.b, disc.boundary, qp_solver="OSQP", tol=1e-12, warm_start=exact.u)
    r3 = solve("cvxpy_osqp", disc.A, disc.b, disc.boundary, tol=1e-12, warm_start=exact.u)
    r4 = solve_discrete(disc, "cvxpy", qp_solver="OSQP", tol=1e-12)
    assert r1.solver == "active_set" and r2.solver == r3.solver == r4.solver == "cvxpy_osqp"
    for r in (r1, r2, r3, r4):
        assert rel_max_diff(r.u, exact.u) <= 1e-8


def test_auto_route_takes_multigrid_from_the_crossover_on(monkeypatch, caplog):
    """``auto`` resolves by each mesh's size: with the crossover between the cascade's coarse
    mesh (N = 25: 676 unknowns) and the fine one (N = 101: 10 201), the coarse level is solved
    by the direct route and the fine one by multigrid, to the direct route's solution."""
    import logging

    import signorini.solvers as solvers
    from signorini.solvers import routes

    monkeypatch.setattr(routes, "MULTIGRID_FROM_UNKNOWNS", 5000)
    assert solvers.exact_route("auto", 4999) == "direct" and solvers.exact_route("auto", 5000) == "multigrid"
    assert solvers.exact_route("multigrid", 10) == "multigrid" and solvers.exact_route("active_set", 10) == "direct"
    disc = build(Problem(), 101)
    with caplog.at_level(logging.INFO, logger="signorini.solvers"):
        result = solve_discrete(disc, "auto")
    loggers = {record.name for record in caplog.records}
    assert {"signorini.solvers.active_set", "signorini.solvers.multigrid"} <= loggers
    direct = solve_discrete(disc, "direct")
    assert result.solver == "multigrid" and rel_max_diff(result.u, direct.u) <= 1e-12
    np.testing.assert_array_equal(np.sort(result.active), np.sort(direct.active))


def test_unknown_solver_name_raises_value_error_naming_it(cache):
    disc = cache.discrete({}, 11)
    with pytest.raises(ValueError, match="quadprog"):
        solve("quadprog", disc.A, disc.b, disc.boundary)
    with pytest.raises(ValueError, match="quadprog"):
        solve_discrete(disc, "quadprog")
