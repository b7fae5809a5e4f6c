"""Semantic checks of the workflow configuration beyond its JSON schema.

The Snakefile fills in each scene's fields from the config's ``scene_defaults``, validates the
config against ``workflow/schemas/config.schema.yaml`` (which also fills in the schema's defaults,
e.g. ``diagonal: sw_ne``) and then calls ``check_config``; every error
names the offending field, e.g. ``scenes.paper.N[1]: 201.0 is not an integer``.
"""

from __future__ import annotations

import copy
import os
import sys
from collections.abc import Mapping, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from signorini.pipeline.resources import NodeLimits

SCHEMA = "workflow/schemas/config.schema.yaml"
DEFAULT_CONFIG = "workflow/config.yaml"


class ConfigError(ValueError):
    """The workflow configuration is invalid; the message names the offending field."""


@contextmanager
def one_line_errors(*kinds: type[Exception]):
    """In the Snakefile: a config error (``ConfigError`` and ``kinds``) ends the run with its one
    line, ``config error: <field>: …``, instead of Snakemake's report with a traceback."""
    try:
        yield
    except (ConfigError, *kinds) as err:
        raise SystemExit(f"config error: {err}") from None


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


SCENE_NAME_CHARS = "letters, digits, _ and -"

# --- the schema, with one-line messages ------------------------------------------------------

_TYPES = {"integer": "an integer", "number": "a number", "string": "a text", "array": "a list",
          "object": "a mapping of keys", "boolean": "true or false"}
# the schema's name patterns in words
_CHARACTERS = {
    "^[A-Za-z0-9_-]+$": SCENE_NAME_CHARS,
    "^[a-z0-9_]+$": "lower-case letters, digits and _",
    "^[A-Za-z0-9_.+-]+$": "letters, digits and _ . + -",
}


def field_name(path: Sequence) -> str:
    """``scenes.mine.norms[1]`` from a JSON path (keys and list indices)."""
    out = ""
    for part in path:
        out += f"[{part}]" if isinstance(part, int) else (f".{part}" if out else str(part))
    return out or "(top level)"


def _short(value: object, limit: int = 60) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def schema_message(error) -> str:
    """A jsonschema ``ValidationError`` in one line: the field, the value and what is allowed."""
    from signorini.fem.norms.names import GRAMMAR

    field, value, kind, arg = field_name(error.absolute_path), error.instance, error.validator, error.validator_value
    if kind == "pattern" and "L2boundary" in str(arg):  # the norm names: the grammar in words
        return f"{field}: unknown norm {_short(value)}; {GRAMMAR}"
    if kind == "pattern":
        allowed = _CHARACTERS.get(str(arg), f"the form {arg}")
        return f"{field}: {_short(value)} is not allowed; use {allowed} only"
    if kind == "type":
        return f"{field}: {_short(value)} is not {_TYPES.get(str(arg), arg)}"
    if kind == "enum":
        return f"{field}: {_short(value)} is not allowed; one of {', '.join(map(str, arg))}"
    if kind == "additionalProperties":
        known = sorted(error.schema.get("properties", {}))
        extra = sorted(set(value) - set(known)) if isinstance(value, dict) else []
        return f"{field}: unknown field {', '.join(map(repr, extra))}; allowed: {', '.join(known)}"
    if kind == "required":
        missing = [k for k in arg if k not in value]
        return f"{field}: {', '.join(map(repr, missing))} missing (required: {', '.join(arg)})"
    bounds = {"minimum": "≥", "exclusiveMinimum": ">", "maximum": "≤", "exclusiveMaximum": "<"}
    if kind in bounds:
        return f"{field}: {_short(value)} is not allowed; the value must be {bounds[kind]} {arg}"
    if kind in ("minItems", "minProperties"):
        return f"{field}: needs at least {arg} entr{'y' if arg == 1 else 'ies'}"
    return f"{field}: {' '.join(error.message.split())[:200]}"


def apply_scene_defaults(config: dict) -> dict:
    """Fill in every scene's fields from the config's ``scene_defaults`` (in place; the config is
    returned): a field a scene does not give is a copy of the default, and a mapping such as
    ``problem`` is merged field by field (a scene's ``problem: {A: 5}`` changes only ``A``)."""
    defaults = config.get("scene_defaults") or {}
    for block in (config.get("scenes") or {}).values():
        if not isinstance(block, dict):
            continue  # the schema check names it
        for key, value in defaults.items():
            given = block.get(key)
            if isinstance(value, dict) and isinstance(given, dict):
                block[key] = copy.deepcopy(value) | given
            elif key not in block:
                block[key] = copy.deepcopy(value)
    return config


def load_config(path: str | os.PathLike = DEFAULT_CONFIG) -> dict:
    """A workflow config file as a run sees its scenes (``apply_scene_defaults``), unchecked."""
    return apply_scene_defaults(load_yaml(path))


def validate_config(config: dict, schema: str | Path = SCHEMA) -> None:
    """The scene defaults (``apply_scene_defaults``), the schema check (one line per error,
    ``schema_message``), then Snakemake's ``validate``, which fills in the schema's defaults."""
    import jsonschema
    from snakemake.utils import validate

    apply_scene_defaults(config)
    validator = jsonschema.Draft202012Validator(load_yaml(schema))
    error = jsonschema.exceptions.best_match(validator.iter_errors(config))
    if error is not None:
        raise ConfigError(schema_message(error))
    validate(config, str(schema))


# --- the checks of single fields: the config check and the command line share them -------------

# the smallest positive normal double: below it a number keeps fewer than 53 significant bits
SMALLEST_NORMAL = 2.0**-1022
# a scene name is a directory of results/ and part of rule and file names: a short file-name part
SCENE_NAME_MAX = 100


def check_mesh_size(field: str, N: object) -> int:
    """``N`` (cells per side) as an int; ConfigError naming ``field`` unless a positive integer."""
    if isinstance(N, bool) or not isinstance(N, int):
        raise ConfigError(f"{field}: {N!r} is not an integer (cells per side, h = 1/N)")
    if N < 1:
        raise ConfigError(f"{field}: {N} is not allowed; a mesh has at least 1 cell per side (N ≥ 1)")
    return N


def check_mesh_sizes(field: str, Ns: Sequence) -> None:
    """Mesh sizes from coarse to fine: positive integers, strictly increasing (each EOC compares a
    mesh with the previous, coarser one; a repeated or unsorted N would pair the wrong meshes)."""
    for i, N in enumerate(Ns):
        check_mesh_size(f"{field}[{i}]", N)
    for i in range(1, len(Ns)):
        if Ns[i] == Ns[i - 1] or Ns[i] in Ns[:i]:
            raise ConfigError(f"{field}[{i}]: N = {Ns[i]} is listed twice; each mesh once, coarse to fine")
        if Ns[i] < Ns[i - 1]:
            raise ConfigError(
                f"{field}: {list(Ns)} is not increasing (N = {Ns[i - 1]} before {Ns[i]}); list the meshes "
                f"coarse to fine: {sorted(Ns)}"
            )


def check_norm_name(field: str, name: object) -> str:
    """The canonical spelling of a norm name; ConfigError naming ``field`` for a name outside the
    grammar (``fem.norms.names``, in words) or a second spelling of a norm (``L1.0``, ``L01``: ``L1``)."""
    from signorini.fem.norms.names import UnknownNormError, canonical_norm_name

    try:
        canonical = canonical_norm_name(str(name))
    except UnknownNormError as err:
        raise ConfigError(f"{field}: {err}") from None
    if canonical != name:
        raise ConfigError(
            f"{field}: {name!r} is the norm {canonical}; write it {canonical} (one spelling per norm: "
            "the exponent without leading zeros or a trailing .0)"
        )
    return canonical


def check_norm_names(field: str, names: Sequence) -> None:
    """At least one norm, each of the grammar in its canonical spelling, none twice."""
    if not names:
        raise ConfigError(f"{field}: no norm given; name at least one, e.g. L4 or W14")
    seen: dict[str, int] = {}
    for i, name in enumerate(names):
        canonical = check_norm_name(f"{field}[{i}]", name)
        if canonical in seen:
            raise ConfigError(f"{field}[{i}]: {canonical} is listed twice (also {field}[{seen[canonical]}])")
        seen[canonical] = i


def amplitude_floor(R: float, N_max: int) -> float:
    """The smallest amplitude ``A`` whose errors on meshes up to ``N_max`` are normal doubles.

    The error scales linearly with ``A`` (``u`` and the data do), and the norms scale their
    integrands by powers of two (``fem.norms.conventional.power_scale``), which is exact: what is lost below
    this bound is the error itself, a difference of values of size ``A·|u₁|`` that becomes a
    subnormal number with fewer significant bits (relative spacing ``2^-1074 / |e|``).  The
    smallest error reported, the ``L^p`` error on the finest mesh, is about ``A R^{3/2} h²``
    (``|u₁| ≤ ψ r^{3/2} ≤ R^{3/2}``; second order); it must be at least ``2^-1022``."""
    return SMALLEST_NORMAL * float(N_max) ** 2 / float(R) ** 1.5


def check_amplitude(field: str, A: float, R: float, Ns: Sequence[int]) -> None:
    """``A`` > 0 and large enough that the errors on the finest mesh do not underflow (``amplitude_floor``)."""
    if A == 0.0:
        raise ConfigError(
            f"{field}: 0 makes u ≡ 0 and every error vanish, so no order of convergence exists"
            " (the stability atlas covers f ≡ 0 as a case)"
        )
    floor = amplitude_floor(R, max(Ns, default=1))
    if abs(A) < floor:
        raise ConfigError(
            f"{field}: {A!r} is too small: at N = {max(Ns, default=1)} the errors (about A·R^1.5/N²) would be "
            f"subnormal numbers and lose their digits; need A ≥ {floor:.1e}"
        )


def check_memory(field: str, N: int, limit_mb: int, available: str = "available", solver: str = "active_set") -> None:
    """The largest job on mesh ``N`` with solves by ``solver`` (``resources.largest_job``) fits
    into ``limit_mb``."""
    from signorini.pipeline.resources import largest_job

    rule, need = largest_job(N, solver)
    if need > limit_mb:
        raise ConfigError(
            f"{field}: N = {N} needs about {_gb(need)} for its {rule} job (estimate from the "
            f"peaks measured at N = 2001), more than the {limit_mb / 1024:.1f} GB {available}"
        )


def _gb(mb: float) -> str:
    return f"{mb / 1024:.1f} GB" if mb < 1024 * 10**5 else f"{mb / 1024:.1e} GB"


def check_scene_name(field: str, name: object) -> None:
    """A scene name that can be a directory name, a wildcard value and part of a rule name."""
    import re

    text = str(name)
    if not re.fullmatch(r"[A-Za-z0-9_-]+", text):
        bad = sorted({c for c in text if not re.fullmatch(r"[A-Za-z0-9_-]", c)})
        shown = text if len(text) <= 40 else text[:37] + "..."
        raise ConfigError(
            f"{field}: scene name {shown!r} has the characters {''.join(bad)!r}; use {SCENE_NAME_CHARS} only"
            if bad else f"{field}: a scene name must not be empty"
        )
    if len(text) > SCENE_NAME_MAX:
        raise ConfigError(
            f"{field}: scene name {text[:20]}... has {len(text)} characters; at most {SCENE_NAME_MAX} (it names "
            "a directory under results/ and the files of its jobs)"
        )


def _check_figures_scene(config: Mapping, scenes: Mapping) -> None:
    """The scene paper_figures/ is rendered from has the paper's norms and two meshes at least."""
    from signorini.published import FIGURE3_NORMS, TABLE1_NORMS, TABLE2_NORMS

    fig = config.get("figures_scene")
    if fig is None:
        return
    if fig not in scenes:
        raise ConfigError(f"figures_scene: {fig!r} is not one of the scenes {sorted(scenes)}")
    needed = list(dict.fromkeys([*TABLE2_NORMS, *TABLE1_NORMS, *FIGURE3_NORMS]))
    missing = [n for n in needed if n not in scenes[fig].get("norms", [])]
    if missing:
        raise ConfigError(
            f"figures_scene: scene {fig!r} lacks the norms {', '.join(missing)} of Tables 1-2 and Figure 3; "
            f"add them to scenes.{fig}.norms or render another scene"
        )
    if len(scenes[fig].get("N", [])) < 2:
        raise ConfigError(f"figures_scene: scene {fig!r} has one mesh; Table 2's EOCs need two at least")


def _check_scene(where: str, scene: Mapping, limit: int, available: str, node: NodeLimits | None) -> None:
    from signorini.fem.norms.conventions import Conventions
    from signorini.fem.problem import Problem, ProblemParameterError
    from signorini.pipeline.solver_options import check_options

    Ns = scene.get("N", [])
    check_mesh_sizes(f"{where}.N", Ns)
    for i, N in enumerate(Ns):
        check_memory(f"{where}.N[{i}]", N, limit, available, scene["solver"])  # filled by the scene defaults
    problem = check_options(f"{where}.solver_options", scene.get("solver", ""), scene.get("solver_options") or {})
    if problem:
        raise ConfigError(problem)
    check_norm_names(f"{where}.norms", scene.get("norms", []))
    if node is not None:
        _check_runtime(where, Ns, scene.get("norms", []), node)
    try:
        problem = Problem(**scene.get("problem", {}))
    except (ProblemParameterError, TypeError) as err:
        raise ConfigError(f"{where}.problem: {err}") from None
    check_amplitude(f"{where}.problem.A", problem.A, problem.R, Ns)
    try:
        Conventions(**scene.get("conventions", {}))
    except (ValueError, TypeError) as err:
        raise ConfigError(f"{where}.conventions: {err}") from None


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


def check_config(config: dict, mem_limit_mb: int | None = None, node: NodeLimits | None = None) -> None:
    """Semantic checks of a schema-valid config: scene names that can be paths, integer ``N``
    strictly increasing, norm names of the grammar (``fem.norms.names``) in their one spelling and
    each once, admissible problem parameters with an amplitude whose errors do not underflow,
    conventions, meshes whose jobs fit into ``mem_limit_mb`` (default: this machine's memory; with
    ``node``, the largest node of a Slurm partition: its memory and time limit), the solver's
    options (``signorini.pipeline.solver_options``), and a ``figures_scene`` with the paper's norms.
    The scene defaults are filled in first (``apply_scene_defaults``: a no-op on a validated config)."""
    from signorini.pipeline.resources import machine_mem_mb

    apply_scene_defaults(config)

    limit = int(mem_limit_mb) if mem_limit_mb else machine_mem_mb()
    available = "available"
    if node is not None:
        limit = min(limit, node.mem_mb) if mem_limit_mb else node.mem_mb
        available = f"of the largest node of Slurm partition {node.partition}"
    scenes = config.get("scenes") or {}
    if not scenes:
        raise ConfigError("scenes: at least one scene is required")
    for name, scene in scenes.items():
        check_scene_name("scenes", name)
        _check_scene(f"scenes.{name}", scene, limit, available, node)
    _check_figures_scene(config, scenes)


def main(argv: Sequence[str] | None = None) -> int:
    """``python -m signorini.pipeline.config [FILE ...]``: check the workflow config with the given
    ``--configfile`` files merged in, as a run would (syntax with file and line, schema, semantics)."""
    from snakemake.utils import update_config

    files = [DEFAULT_CONFIG, *(sys.argv[1:] if argv is None else argv)]
    try:
        config: dict = {}
        for path in files:
            update_config(config, load_yaml(path))
        validate_config(config, SCHEMA)
        check_config(config)
    except Exception as err:  # schema errors come as snakemake's WorkflowError
        print(f"config check failed: {err}", file=sys.stderr)
        return 1
    print(f"config ok: {', '.join(files)} ({len(config['scenes'])} scenes)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
