"""Semantic checks of the workflow configuration beyond its JSON schema.

The Snakefile validates the config against ``workflow/schemas/config.schema.yaml`` (which also
fills in the defaults, e.g. ``diagonal: sw_ne``) and then calls ``check_config``; every error
names the offending field, e.g. ``scenes.paper.N[1]: 201.0 is not an integer``.
"""

from __future__ import annotations

import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from signorini.pipeline.resources import NodeLimits

SCHEMA = "workflow/schemas/config.schema.yaml"
DEFAULT_CONFIG = "workflow/config.yaml"


class ConfigError(ValueError):
    """The workflow configuration is invalid; the message names the offending field."""


def load_yaml(path: str | Path) -> dict:
    """A config file's content; a syntax error is named with file, line and column (Snakemake
    itself only says that a config file is not valid YAML)."""
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    except yaml.MarkedYAMLError as err:
        mark = err.problem_mark or err.context_mark
        where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
        raise ConfigError(f"{where}: {err.problem or err.context}") from None
    except (OSError, yaml.YAMLError) as err:
        raise ConfigError(f"{path}: {err}") from None
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: a config file holds a mapping of keys (scenes, figures_scene)")
    return data


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


def _check_runtime(where: str, Ns: list, norms: list, node: NodeLimits) -> None:
    """Each mesh's Slurm job (its discretise, solve and norm jobs, one after another) within the
    partition's time limit: Slurm would leave a longer job pending for ever."""
    from signorini.pipeline.resources import mesh_group_runtime_min

    if node.time_limit_min is None:
        return
    for i, N in enumerate(Ns):
        need = mesh_group_runtime_min(N, norms)
        if need > node.time_limit_min:
            raise ConfigError(
                f"{where}.N[{i}]: N = {N} requests {need} min for its mesh job (discretise, solve and {len(norms)} "
                f"norms one after another), more than the time limit of {node.time_limit_min} min of Slurm "
                f"partition {node.partition}"
            )


def check_config(config: Mapping, mem_limit_mb: int | None = None, node: NodeLimits | None = None) -> None:
    """Semantic checks of a schema-valid config: integer ``N`` (not ``101.0``), unique ``N``,
    norm names of the grammar (``fem.norm_names``), admissible problem parameters and conventions,
    meshes whose jobs fit into ``mem_limit_mb`` (default: this machine's memory; with ``node``, the
    largest node of a Slurm partition: its memory and time limit), the solver's options (names and
    types, ``signorini.pipeline.solver_options``)."""
    from signorini.pipeline.resources import machine_mem_mb
    from signorini.pipeline.solver_options import check_options

    limit = int(mem_limit_mb) if mem_limit_mb else machine_mem_mb()
    available = "available"
    if node is not None:
        limit = min(limit, node.mem_mb) if mem_limit_mb else node.mem_mb
        available = f"of the largest node of Slurm partition {node.partition}"
    from signorini.fem.conventions import Conventions
    from signorini.fem.problem import Problem, ProblemParameterError

    scenes = config.get("scenes") or {}
    if not scenes:
        raise ConfigError("scenes: at least one scene is required")
    for name, scene in scenes.items():
        where = f"scenes.{name}"
        _check_N(where, scene.get("N", []))
        _check_memory(where, scene.get("N", []), limit, available)
        problem = check_options(f"{where}.solver_options", scene.get("solver", ""), scene.get("solver_options") or {})
        if problem:
            raise ConfigError(problem)
        _check_norms(where, scene.get("norms", []))
        if node is not None:
            _check_runtime(where, scene.get("N", []), scene.get("norms", []), node)
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


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m signorini.pipeline.config [FILE ...]``: check the workflow config with the given
    ``--configfile`` files merged in, as a run would (syntax with file and line, schema, semantics)."""
    from snakemake.utils import update_config, validate

    files = [DEFAULT_CONFIG, *(sys.argv[1:] if argv is None else argv)]
    try:
        config: dict = {}
        for path in files:
            update_config(config, load_yaml(path))
        validate(config, SCHEMA)
        check_config(config)
    except Exception as err:  # schema errors come as snakemake's WorkflowError
        print(f"config check failed: {err}", file=sys.stderr)
        return 1
    print(f"config ok: {', '.join(files)} ({len(config['scenes'])} scenes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
