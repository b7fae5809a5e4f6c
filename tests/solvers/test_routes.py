"""The solver routes by name (``signorini.solvers.routes``): each route's declared options are its
function's keyword parameters, the names are the config schema's, and the module stays light."""

from __future__ import annotations

import inspect
import subprocess
import sys
import typing

import pytest
import yaml
from helpers import ROOT

from signorini.solvers import route_functions, routes


def test_the_dispatcher_has_a_function_for_every_route():
    functions = route_functions()
    assert set(functions) == set(routes.ROUTES)
    for name, route in routes.ROUTES.items():
        assert functions[name].__module__ == route.module and functions[name].__name__ == route.function


@pytest.mark.parametrize("name", sorted(routes.ROUTES))
def test_the_declared_options_are_the_signature_of_the_route(name):
    """Names in order, defaults, and types: the default's, or for a default of None one of the
    annotation's (``float | None``: float) or any (``np.ndarray | None``)."""
    route, function = routes.ROUTES[name], route_functions()[name]
    signature = list(inspect.signature(function).parameters.values())
    data = signature[:3]
    params = [p for p in signature[3:] if p.kind is p.POSITIONAL_OR_KEYWORD and p.name != route.qp_parameter]
    assert [p.name for p in data] == ["A", "b", "constrained"]
    assert [p.name for p in params] == list(route.options)
    hints = typing.get_type_hints(function)
    for p in params:
        option = route.options[p.name]
        assert option.default == p.default, p.name
        if p.default is None:
            assert option.nullable and (option.kind is None or option.kind in typing.get_args(hints[p.name])), p.name
        else:
            assert option.kind is type(p.default) and not option.nullable, p.name


def test_the_schema_lists_the_registry_names():
    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text(encoding="utf-8"))
    assert tuple(schema["$defs"]["scene"]["properties"]["solver"]["enum"]) == routes.config_names()


def test_names_resolve_to_routes():
    assert routes.resolve("direct", 10) == (routes.DIRECT, None)
    assert routes.resolve("active_set", 10) == (routes.DIRECT, None)  # the earlier name
    assert routes.resolve("auto", routes.MULTIGRID_FROM_UNKNOWNS - 1) == (routes.DIRECT, None)
    assert routes.resolve("auto", routes.MULTIGRID_FROM_UNKNOWNS) == (routes.MULTIGRID, None)
    assert routes.resolve("cvxpy_osqp", 10) == (routes.CVXPY, "osqp")
    assert routes.exact_route("active_set", 10) == "direct" and routes.exact_route("cvxpy_osqp", 10) == "cvxpy_osqp"
    assert {"direct", "active_set", "multigrid", "auto"} <= set(routes.EXACT_SOLVERS)
    assert "cvxpy" not in routes.EXACT_SOLVERS and routes.SOLVERS == (*routes.ROUTES, "auto")
    for name in ("quadprog", "cvxpy_", "Direct"):
        with pytest.raises(ValueError, match="unknown solver"):
            routes.resolve(name, 10)


def test_the_registry_imports_no_numerics():
    """The config checks read it on every Snakemake parse."""
    code = "import sys, signorini.solvers.routes; print(sorted({'numpy', 'scipy', 'cvxpy'} & set(sys.modules)))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
