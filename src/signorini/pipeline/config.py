"""Semantic checks of the workflow configuration beyond its JSON schema.

The Snakefile validates the config against ``workflow/schemas/config.schema.yaml`` (which also
fills in the defaults, e.g. ``diagonal: sw_ne``) and then calls ``check_config``; every error
names the offending field, e.g. ``scenes.paper.N[1]: 201.0 is not an integer``.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from signorini.pipeline.resources import NodeLimits


class ConfigError(ValueError):
    """The workflow configuration is invalid; the message names the offending field."""


def _check_N(where: str, Ns: list) -> None:
    for i, N in enumerate(Ns):
        if isinstance(N, bool) or not isinstance(N, int):
            raise ConfigError(f"{where}.N[{i}]: {N!r} is not an integer (cells per side)")
        if N < 1:
            raise ConfigError(f"{where}.N[{i}]: {N} must be ≥ 1")
    if len(set(Ns)) != len(Ns):
        raise ConfigError(f"{where}.N: values must be unique, got {Ns}")


def _check_norms(where: str, norms: list) -> None:
    from signorini.fem.norm_names import UnknownNormError, parse_norm_name

    for i, norm in enumerate(norms):
        try:
            parse_norm_name(norm)
        except UnknownNormError as err:
            raise ConfigError(f"{where}.norms[{i}]: {err}") from None
    if len(set(norms)) != len(norms):
        raise ConfigError(f"{where}.norms: names must be unique, got {norms}")


def _check_memory(where: str, Ns: list, limit_mb: int, available: str = "available") -> None:
    from signorini.pipeline.resources import largest_job

    for i, N in enumerate(Ns):
        rule, need = largest_job(N)
        if need > limit_mb:
            raise ConfigError(
                f"{where}.N[{i}]: N = {N} needs about {need / 1024:.1f} GB for its {rule} job (estimate from the "
                f"peaks measured at N = 2001), more than the {limit_mb / 1024:.1f} GB {available}"
            )


def _check_runtime(where: str, Ns: list, n_norms: int, node: NodeLimits) -> None:
    """Each mesh's Slurm job (its discretise, solve and norm jobs, one after another) within the
    partition's time limit: Slurm would leave a longer job pending for ever."""
    from signorini.pipeline.resources import mesh_group_runtime_min

    if node.time_limit_min is None:
        return
    for i, N in enumerate(Ns):
        need = mesh_group_runtime_min(N, n_norms)
        if need > node.time_limit_min:
            raise ConfigError(
                f"{where}.N[{i}]: N = {N} requests {need} min for its mesh job (discretise, solve and {n_norms} "
                f"norms one after another), more than the time limit of {node.time_limit_min} min of Slurm "
                f"partition {node.partition}"
            )


def _check_solver_options(where: str, solver: str, options: Mapping) -> None:
    """Unknown or mistyped options of the active-set solver, named before any job runs (the cvxpy
    routes pass unknown keywords on to the QP solver, which names them itself)."""
    import inspect

    from signorini.solvers import active_set_solve

    if solver != "active_set":
        return
    params = inspect.signature(active_set_solve).parameters
    allowed = {name: p.default for name, p in params.items() if name not in ("A", "b", "constrained")}
    for key, value in options.items():
        if key not in allowed:
            raise ConfigError(
                f"{where}.solver_options.{key}: not an option of active_set_solve; choose from {sorted(allowed)}"
            )
        default = allowed[key]
        kind = float if isinstance(default, float) else type(default)
        if default is not None and not isinstance(value, kind if kind is not float else (int, float)):
            raise ConfigError(f"{where}.solver_options.{key}: {value!r} is not of type {kind.__name__}")


def check_config(config: Mapping, mem_limit_mb: int | None = None, node: NodeLimits | None = None) -> None:
    """Semantic checks of a schema-valid config: integer ``N`` (not ``101.0``), unique ``N``,
    norm names of the grammar (``fem.norm_names``), admissible problem parameters and conventions,
    meshes whose jobs fit into ``mem_limit_mb`` (default: this machine's memory; with ``node``, the
    largest node of a Slurm partition: its memory and time limit), the active-set solver's options."""
    from signorini.pipeline.resources import machine_mem_mb

    limit = int(mem_limit_mb) if mem_limit_mb else machine_mem_mb()
    available = "available"
    if node is not None:
        limit = min(limit, node.mem_mb) if mem_limit_mb else node.mem_mb
        available = f"of the largest node of Slurm partition {node.partition}"
    from signorini.fem.norms import Conventions
    from signorini.fem.problem import Problem, ProblemParameterError

    scenes = config.get("scenes") or {}
    if not scenes:
        raise ConfigError("scenes: at least one scene is required")
    for name, scene in scenes.items():
        where = f"scenes.{name}"
        _check_N(where, scene.get("N", []))
        _check_memory(where, scene.get("N", []), limit, available)
        if node is not None:
            _check_runtime(where, scene.get("N", []), len(scene.get("norms", [])), node)
        if scene.get("solver_options"):
            _check_solver_options(where, scene.get("solver", ""), scene["solver_options"])
        _check_norms(where, scene.get("norms", []))
        try:
            problem = Problem(**scene.get("problem", {}))
        except (ProblemParameterError, TypeError) as err:
            raise ConfigError(f"{where}.problem: {err}") from None
        if problem.A == 0.0:
            raise ConfigError(
                f"{where}.problem.A: 0 makes u ≡ 0 and every error vanish, so no order of convergence exists"
                " (the stability atlas covers f ≡ 0 as a case)"
            )
        try:
            Conventions(**scene.get("conventions", {}))
        except (ValueError, TypeError) as err:
            raise ConfigError(f"{where}.conventions: {err}") from None
    fig = config.get("figures_scene")
    if fig is not None and fig not in scenes:
        raise ConfigError(f"figures_scene: {fig!r} is not one of the scenes {sorted(scenes)}")
