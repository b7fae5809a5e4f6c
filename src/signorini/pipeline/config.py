"""Semantic checks of the workflow configuration beyond its JSON schema.

The Snakefile fills in each scene's fields from the config's ``scene_defaults``, validates the
config against ``workflow/schemas/config.schema.yaml`` (which also fills in the schema's defaults,
e.g. ``diagonal: sw_ne``) and then calls ``check_config``; every error
names the offending field, e.g. ``scenes.paper.N[1]: 201.0 is not an integer``.
"""

from __future__ import annotations

import copy
import json
import math
import os
import sys
from collections.abc import Iterable, Mapping, Sequence
from contextlib import contextmanager
from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

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
    itself only says that a config file is not valid YAML), and so is a key given twice in one
    mapping (yaml and Snakemake keep the last block silently).  JSON that is no YAML for PyYAML
    (tabs) is read as JSON.  A missing file, one that is not UTF-8, empty, or not a mapping: one
    line each."""
    import yaml

    try:
        raw = Path(path).read_bytes()
    except FileNotFoundError:
        raise ConfigError(f"{path}: no such file; give the path of a YAML or JSON config file") from None
    except IsADirectoryError:
        raise ConfigError(f"{path}: a directory, not a config file; give a YAML or JSON file") from None
    except OSError as err:
        raise ConfigError(f"{path}: cannot be read ({err.strerror or err}); give a readable config file") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        utf16 = raw[:2] in (b"\xff\xfe", b"\xfe\xff")  # a byte-order mark: what editors on Windows write
        kind = "UTF-16 text" if utf16 else "not UTF-8 text"
        raise ConfigError(f"{path}: {kind}; a config file is UTF-8 text: save it as UTF-8") from None
    try:
        data = yaml.load(text, Loader=_unique_key_loader())
    except yaml.MarkedYAMLError as err:
        data = _json_or_raise(path, text, err)
    except yaml.YAMLError as err:
        raise ConfigError(f"{path}: {err}") from None
    if not isinstance(data, dict):
        held = {type(None): "empty (or only comments)", list: "holds a list", str: "holds a text"}
        what = held.get(type(data), f"holds {data!r}")
        raise ConfigError(f"{path}: {what}; a config file holds a mapping of keys (scenes, figures_scene)")
    return data


@cache
def _unique_key_loader():
    """yaml's SafeLoader refusing a key given twice in one mapping, with the line of each (on
    libyaml's parser where PyYAML has it: a fraction of the pure-Python parser's time, which a
    workflow start pays for every config and schema file; docs/evidence/design-measurements.md#yaml-parser)."""
    import yaml

    class UniqueKeyLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):
        def construct_mapping(self, node, deep=False):
            if isinstance(node, yaml.MappingNode):
                seen: dict = {}
                for key_node, _ in node.value:
                    if key_node.tag == "tag:yaml.org,2002:merge":
                        continue  # `<<: *anchor` merges keys on purpose
                    key = self.construct_object(key_node, deep=True)
                    try:
                        first = seen.setdefault(key, key_node.start_mark)
                    except TypeError:
                        continue  # an unhashable key: yaml's own error follows
                    if first is not key_node.start_mark:
                        error = yaml.constructor.ConstructorError(
                            None, None,
                            f"the key {key!r} is given twice in one mapping (also at line {first.line + 1}, column "
                            f"{first.column + 1}), and only the last would count; give each key once (merge the "
                            "two blocks)",
                            key_node.start_mark,
                        )
                        error.duplicate = True
                        raise error
            return super().construct_mapping(node, deep)

    return UniqueKeyLoader


def _json_or_raise(path: str | Path, text: str, err) -> dict:
    """The content of a JSON file PyYAML cannot read (tabs), or the YAML error ``err`` with file,
    line and column."""
    import json

    if not getattr(err, "duplicate", False):

        def unique(pairs: list) -> dict:
            keys = [key for key, _ in pairs]
            twice = next((key for i, key in enumerate(keys) if key in keys[:i]), None)
            if twice is not None:
                raise ConfigError(f"{path}: the key {twice!r} is given twice in one object; give each key once")
            return dict(pairs)

        try:
            return json.loads(text, object_pairs_hook=unique)
        except json.JSONDecodeError:
            pass  # not JSON either: the YAML error stands
    mark = err.problem_mark or err.context_mark
    where = f"{path}:{mark.line + 1}:{mark.column + 1}" if mark else str(path)
    raise ConfigError(f"{where}: {err.problem or err.context}") from None


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
    from signorini.fem.norms.names import GRAMMAR, NORM_PATTERN

    field, value, kind, arg = field_name(error.absolute_path), error.instance, error.validator, error.validator_value
    if kind == "pattern" and arg == NORM_PATTERN:  # the norm names: the grammar in words
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
    ``problem`` is merged field by field (a scene's ``problem: {A: 5}`` changes only ``A``; a
    problem of another ``kind`` than the default's is the scene's own)."""
    defaults = config.get("scene_defaults") or {}
    for block in (config.get("scenes") or {}).values():
        if not isinstance(block, dict):
            continue  # the schema check names it
        for key, value in defaults.items():
            given = block.get(key)
            if isinstance(value, dict) and isinstance(given, dict) and _same_kind(value, given):
                block[key] = copy.deepcopy(value) | given
            elif key not in block:
                block[key] = copy.deepcopy(value)
    return config


def _same_kind(default: Mapping, given: Mapping) -> bool:
    """Whether two problem blocks are of one kind (``fem.problem.make_problem``; without a ``kind``
    the default one), and two mesh blocks of one family (``fem.mesh_families``; without a
    ``family`` the paper's); other mappings have neither."""
    from signorini.fem.mesh_families import FRIEDRICHS_KELLER
    from signorini.fem.problem import DEFAULT_KIND

    same_kind = default.get("kind", DEFAULT_KIND) == given.get("kind", DEFAULT_KIND)
    return same_kind and default.get("family", FRIEDRICHS_KELLER) == given.get("family", FRIEDRICHS_KELLER)


def load_config(path: str | os.PathLike = DEFAULT_CONFIG) -> dict:
    """A workflow config file as a run sees its scenes (``apply_scene_defaults``), unchecked."""
    return apply_scene_defaults(load_yaml(path))


def validate_config(config: dict, schema: str | Path = SCHEMA, memo: str | Path | None = None) -> None:
    """The scene defaults (``apply_scene_defaults``), then one pass of the schema check that fills
    in the schema's defaults as it goes (as Snakemake's ``validate`` does, the recipe of
    jsonschema's FAQ) and reports the best-matching error in one line (``schema_message``).

    ``memo``: a file holding the last valid config with its defaults, keyed by the SHA-256 of the
    config as given, the schema and this module; the same key gives the same result, so a
    Snakemake call with an unchanged config takes it from there instead of importing jsonschema
    and validating again, a noticeable part of every workflow start
    (docs/evidence/design-measurements.md#config-memo)."""
    key = _memo_key(config, schema)
    if memo is not None and key is not None and (known := _recall(memo, key)) is not None:
        config.clear()
        config.update(known)
        return
    import jsonschema

    apply_scene_defaults(config)
    error = jsonschema.exceptions.best_match(_defaults_validator()(load_yaml(schema)).iter_errors(config))
    if error is not None:
        raise ConfigError(schema_message(error))
    if memo is not None and key is not None:
        from signorini.pipeline.artifacts import atomic_write_text

        atomic_write_text(memo, json.dumps({"key": key, "config": config}))


def _memo_key(config: dict, schema: str | Path) -> str | None:
    """SHA-256 of the config as given, the schema and this module; None for a config JSON cannot
    hold exactly (keys that are not text: not memoised)."""
    import hashlib

    try:
        text = json.dumps(config, sort_keys=True, allow_nan=True)
    except (TypeError, ValueError):
        return None
    if json.loads(text) != config:
        return None
    h = hashlib.sha256(text.encode())
    for path in (schema, __file__):
        h.update(Path(path).read_bytes())
    return h.hexdigest()


def _recall(memo: str | Path, key: str) -> dict | None:
    try:
        stored = json.loads(Path(memo).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return stored.get("config") if isinstance(stored, dict) and stored.get("key") == key else None


@cache
def _defaults_validator():
    """Draft 2020-12 validation that also sets every missing property that has a ``default``."""
    import jsonschema

    base = jsonschema.Draft202012Validator
    properties = base.VALIDATORS["properties"]

    def set_defaults(validator, props, instance, schema):
        if isinstance(instance, dict):
            for name, sub in props.items():
                if isinstance(sub, dict) and "default" in sub:
                    instance.setdefault(name, copy.deepcopy(sub["default"]))
        yield from properties(validator, props, instance, schema)

    return jsonschema.validators.extend(base, {"properties": set_defaults})


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
    _check_exponent(field, canonical)
    return canonical


LARGEST_EXPONENT = 1023  # |e/s|^p with the power of two s ≤ max|e| < 2s is below 2^p: a double up to p = 1023


def _check_exponent(field: str, name: str) -> None:
    """Refuse an Lp/W1p exponent whose evaluation overflows a double (``power_scale``)."""
    from signorini.fem.norms.names import lp_names, parse_norm_name

    spec = parse_norm_name(name)
    if spec.p is not None and LARGEST_EXPONENT < spec.p < float("inf"):
        limit = lp_names(float("inf"))[0 if spec.family == "L" else 1] + spec.part + ("_true" if spec.true else "")
        raise ConfigError(
            f"{field}: the exponent p = {spec.p:g} of {name} is too large: the norm sums |e/s|^p with s the power "
            f"of two at or below max |e|, which reaches 2^p and overflows a double for p > {LARGEST_EXPONENT}; "
            f"take p ≤ {LARGEST_EXPONENT}, or {limit} for the maximum (the limit p → ∞)"
        )


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


@cache
def rhs_peak(R: float, c: float) -> float:
    """``max |f| / A`` of the manufactured problem with support radius ``R`` and reaction ``c``.

    ``f = A ũ (-4 ψ'/r - ψ'' + c ψ)`` (``fem.problem.Problem.f``) with ``|ũ| = r^{3/2} |sin(3θ/2)|``,
    so at each ``r`` the largest ``|f|`` is on the ray ``θ = π/3`` (``sin(3θ/2) = 1``): ``Problem.f``
    itself is evaluated there at ``A = 1``, on a grid of ``[0, R]`` refined around its maximum
    (relative error of the maximum about 1e-13).  ``u`` and ``∇u`` are smaller: ``|u| ≤ A R^{3/2}``,
    ``|∇u| ≤ A (630 max s^{11/2} (1 − s)⁴ + 3/2) R^{1/2} ≤ 2.5 A R^{1/2}``, against a peak of about
    ``7.5 A R^{-1/2}`` here, for the admissible ``R < 1/2``."""
    import numpy as np

    from signorini.fem.problem import Problem

    problem = Problem(x0=0.5, R=float(R), A=1.0, c=float(c))

    def on_ray(r: np.ndarray) -> np.ndarray:
        return np.abs(problem.f(np.array([0.5 + r / 2, r * math.sqrt(3.0) / 2])))

    r = np.linspace(0.0, float(R), 2049)
    i = int(np.argmax(on_ray(r)))
    fine = np.linspace(r[max(i - 1, 0)], r[min(i + 1, r.size - 1)], 2049)
    return float(max(on_ray(r).max(), on_ray(fine).max()))


def amplitude_ceiling(R: float, c: float) -> float:
    """The largest amplitude ``A`` whose right-hand side ``f`` (``rhs_peak``), and so the load
    vector ``b_i = ∫ f φ_i`` (a sum of ``f`` times weights of total at most 1), is a finite double.
    The norms of the error are computed with power-of-two scaling (``fem.norms.conventional``) and
    measure values of the size of ``u`` and ``∇u``, several times smaller than ``f`` (``rhs_peak``),
    so ``f`` is the bound (``tests/pipeline/test_config.py`` computes b, the solve and the norms just
    below it).  The 16 rounding units allow for the dozen floating-point operations that compute ``f``."""
    return sys.float_info.max / (rhs_peak(R, c) * (1.0 + 16 * sys.float_info.epsilon))


@cache
def energy_of_u1(R: float, c: float) -> float:
    """``a(u₁, u₁) = ∫ |∇u₁|² + c u₁²`` of the manufactured solution at ``A = 1``.

    ``u₁ = −ψ(r) r^{3/2} sin(3θ/2)`` on the half-disc ``r < R``, ``0 ≤ θ ≤ π``; ``sin²`` and ``cos²``
    of ``3θ/2`` both integrate to ``π/2`` over ``[0, π]``, so ``a = (π/2) ∫₀^R ((ψ' r^{3/2} + (3/2) ψ
    r^{1/2})² + (9/4) ψ² r + c ψ² r³) r dr``, a polynomial of degree 22 in ``r`` (ψ has degree 9):
    16-point Gauss–Legendre integrates it exactly."""
    import numpy as np

    from signorini.fem.problem import Problem

    problem = Problem(x0=0.5, R=float(R), A=1.0, c=float(c))
    x, w = np.polynomial.legendre.leggauss(16)
    r, w = (x + 1.0) * R / 2, w * R / 2
    psi, dpsi = problem.psi(r), problem.dpsi(r)
    radial = (dpsi * r**1.5 + 1.5 * psi * np.sqrt(r)) ** 2 + 2.25 * psi**2 * r + c * psi**2 * r**3
    return float(math.pi / 2 * np.sum(w * radial * r))


def energy_ceiling(R: float, c: float) -> float:
    """The largest amplitude whose energy ``A² a(u₁, u₁)`` (``energy_of_u1``) is a finite double:
    conjugate gradients (the multigrid route, the theory scene's Ritz projection) and the H¹ norms
    of P1 functions compute such energies as plain sums, and break down beyond it: the multigrid
    route fails just above this bound, which the discrete energy approaches from below
    (docs/evidence/design-measurements.md#energy-ceiling)."""
    return math.sqrt(sys.float_info.max) / math.sqrt(energy_of_u1(R, c) * (1.0 + 16 * sys.float_info.epsilon))


def check_amplitude(field: str, A: float, R: float, Ns: Sequence[int], c: float = 1.0, energies: bool = False) -> None:
    """``A`` > 0, large enough that the errors on the finest mesh do not underflow
    (``amplitude_floor``) and small enough that the right-hand side does not overflow
    (``amplitude_ceiling``, which depends on the reaction coefficient ``c``); with ``energies``
    (jobs that run conjugate gradients), small enough that the energy does not (``energy_ceiling``)."""
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
    ceiling = amplitude_ceiling(R, c)
    if abs(A) > ceiling:
        raise ConfigError(
            f"{field}: {A!r} is too large: the right-hand side f = -Δu + cu reaches {rhs_peak(R, c):.3g}·A "
            f"(R = {R}, c = {c}) and the load vector would overflow to inf; need A ≤ {ceiling:.4e}"
        )
    ceiling = energy_ceiling(R, c)
    if energies and abs(A) > ceiling:
        raise ConfigError(
            f"{field}: {A!r} is too large for conjugate gradients (the multigrid route, the theory quantities): "
            f"the energy A²·a(u₁, u₁) = {energy_of_u1(R, c):.3g}·A² (R = {R}, c = {c}) would overflow to inf; need "
            f"A ≤ {ceiling:.4e}, or the direct route (solver: direct)"
        )


# The support of u must span this many cells of the coarsest mesh (R·N ≥ 3).  With the paper's
# norms and the one-sided L4plus/L4minus on coarse meshes: below one cell the error or a one-sided
# part of it vanishes (no node in the support: u_h does not see u) or grows on refinement; at one
# cell an EOC is still negative (L4plus); from about two cells every EOC is positive, and at three
# they approach the asymptotic orders.  Every shipped scene has a wider support
# (docs/evidence/design-measurements.md#support-cells).
SUPPORT_CELLS = 3


def check_support(where: str, problem, Ns: Sequence[int]) -> None:
    """The support of ``u`` (the half-disc of radius ``R`` around ``(x0, 0)``) spans at least
    ``SUPPORT_CELLS`` cells of the coarsest mesh: ``R ≥ 3 h``.  Named as ``problem.R`` when a
    larger admissible ``R`` (``R < min(x0, 1 − x0)``) would do, else as the coarsest mesh ``N[0]``."""
    if not Ns:
        return
    N, R = min(Ns), float(problem.R)
    if R * N * (1 + 1e-12) >= SUPPORT_CELLS:  # the product rounds: R = 3/N itself passes
        return
    need_N = math.ceil(SUPPORT_CELLS / R * (1 - 1e-12))
    r_max = min(problem.x0, 1.0 - problem.x0)
    what = (
        f"the support of u (radius R = {R:g} around x0 = {problem.x0:g}) spans {R * N:.3g} cells of the coarsest "
        f"mesh N = {N}; with fewer than {SUPPORT_CELLS} the errors (or their one-sided parts) vanish or grow on "
        "refinement: no order of convergence"
    )
    if SUPPORT_CELLS / N < r_max:
        raise ConfigError(f"{where}.problem.R: {what}; need R ≥ {SUPPORT_CELLS / N:.3g} or meshes from N = {need_N}")
    raise ConfigError(f"{where}.N[0]: {what}; start the meshes at N = {need_N} (R ≥ {SUPPORT_CELLS}h)")


def check_memory(field: str, N: int, limit_mb: int, available: str = "available", solver: str = "direct") -> None:
    """The largest job on mesh ``N`` with solves by ``solver`` (``resources.largest_job``) fits
    into ``limit_mb``."""
    from signorini.pipeline.resources import largest_job

    rule, need = largest_job(N, solver)
    if need > limit_mb:
        raise ConfigError(
            f"{field}: N = {N} needs about {_gb(need)} for its {rule} job (estimate from the "
            f"peaks measured at N = 2001 and 4001), more than the {limit_mb / 1024:.1f} GB {available}"
        )


def check_planned_memory(jobs: Iterable[Any], config: Mapping, limit_mb: int, available: str = "available") -> None:
    """The meshes of the jobs a run starts (Snakemake's, the plan of the requested targets) fit into
    ``limit_mb`` (``check_memory``, by their scene's solver): the memory check of the meshes this run
    needs and of no others, so that a scene that needs more than this machine has keeps no other
    target from running.  (Snakemake lowers a job's ``mem_mb`` request to the memory it was given, so
    the requests are computed here, not read from the jobs.)  The error names the largest mesh."""
    from signorini.pipeline.resources import largest_job

    scenes, meshes = config.get("scenes") or {}, set()
    for job in jobs:
        name, N = job.wildcards.get("scene"), job.wildcards.get("N")
        if name in scenes and N is not None and int(N) in scenes[name].get("N", []):
            meshes.add((name, int(N)))
    for name, N in sorted(meshes, key=lambda mesh: -largest_job(mesh[1], scenes[mesh[0]]["solver"])[1]):
        check_memory(f"scenes.{name}.N[{scenes[name]['N'].index(N)}]", N, limit_mb, available, scenes[name]["solver"])


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


def _check_problem(where: str, block: Mapping, Ns: Sequence[int], energies: bool) -> None:
    """The scene's problem (``fem.problem.make_problem``): a known kind with each of its parameters
    given and admitted by its class (the error names the parameter); for the paper's manufactured
    problem also its amplitude (``check_amplitude``) and support (``check_support``) on the meshes."""
    from signorini.fem.problem import DEFAULT_KIND, ProblemParameterError, make_problem, problem_class

    try:
        kind = problem_class(block)
        missing = [name for name in kind.parameters() if name not in block]
        if missing:
            raise ConfigError(
                f"{where}.problem: {', '.join(map(repr, missing))} missing (the {kind.kind} problem's parameters: "
                f"{', '.join(kind.parameters())})"
            )
        problem = make_problem(block)
    except ProblemParameterError as err:
        field = f"{where}.problem" + (f".{err.parameter}" if err.parameter else "")
        raise ConfigError(f"{field}: {err}") from None
    if problem.kind == DEFAULT_KIND:
        check_amplitude(f"{where}.problem.A", problem.A, problem.R, Ns, problem.c, energies)
        check_support(where, problem, Ns)


def _check_scene(where: str, scene: Mapping, limit: int | None, available: str, node: NodeLimits | None) -> None:
    from signorini.fem.norms.conventions import Conventions
    from signorini.pipeline.solver_options import check_options

    Ns = scene.get("N", [])
    check_mesh_sizes(f"{where}.N", Ns)
    for i, N in enumerate(Ns if limit is not None else ()):
        check_memory(f"{where}.N[{i}]", N, limit, available, scene["solver"])  # filled by the scene defaults
    problem = check_options(f"{where}.solver_options", scene.get("solver", ""), scene.get("solver_options") or {})
    if problem:
        raise ConfigError(problem)
    check_norm_names(f"{where}.norms", scene.get("norms", []))
    if node is not None:
        _check_runtime(where, Ns, scene.get("norms", []), node)
    _check_problem(where, scene.get("problem", {}), Ns, _runs_conjugate_gradients(where, scene, Ns))
    _check_study_and_atlas(where, scene)
    _check_mesh(where, scene.get("mesh") or {})
    try:
        Conventions(**scene.get("conventions", {}))
    except (ValueError, TypeError) as err:
        raise ConfigError(f"{where}.conventions: {err}") from None


def _check_meshes_study(names: Sequence[str], scenes: Mapping) -> None:
    """The mesh-family study's scenes: configured, each once, at least two meshes each."""
    for i, name in enumerate(names):
        if name not in scenes:
            raise ConfigError(f"meshes_study[{i}]: {name!r} is not a scene; configured: {', '.join(sorted(scenes))}")
        if name in names[:i]:
            raise ConfigError(f"meshes_study[{i}]: {name!r} is listed twice")
        if len(scenes[name].get("N", [])) < 2:
            raise ConfigError(f"meshes_study[{i}]: scene {name!r} needs two meshes or more for a rate")


def _check_mesh(where: str, spec: Mapping) -> None:
    """A scene's ``mesh`` block: a family of ``fem.mesh_families`` and parameters its function takes,
    of their defaults' types."""
    from signorini.fem.mesh_families import check_mesh_spec

    try:
        check_mesh_spec(spec)
    except ValueError as err:
        raise ConfigError(f"{where}.mesh: {err}") from None


def _runs_conjugate_gradients(where: str, scene: Mapping, Ns: Sequence[int]) -> bool:
    """Whether jobs of the scene compute energies by conjugate gradients: a solve by the multigrid
    route (the scene's solver or a study configuration's, ``auto`` by the mesh's size), or the
    theory quantities (a Ritz projection by multigrid CG and H¹ norms, energies both)."""
    from signorini.pipeline.paths import THEORY_SCENE
    from signorini.pipeline.resources import solve_rule

    study = scene.get("study") if isinstance(scene.get("study"), Mapping) else {}
    configs = study.get("configs") or {}
    solvers = [scene.get("solver", "")]
    solvers += [spec.get("solver", "") for spec in configs.values() if isinstance(spec, Mapping)]
    multigrid = any(solve_rule(str(solver), N) == "solve_multigrid" for solver in solvers for N in Ns)
    return multigrid or where == f"scenes.{THEORY_SCENE}"


def _check_study_and_atlas(where: str, scene: Mapping) -> None:
    """The tolerances a study or an atlas passes to its solvers besides their options (checked by
    ``solver_options.check_options``): a study's ``tolerances``, an atlas column's ``kkt_tol``."""
    from signorini.pipeline.solver_options import value_problem

    study, atlas = scene.get("study"), scene.get("atlas")
    tolerances = (study.get("tolerances") or []) if isinstance(study, Mapping) else []
    for i, tol in enumerate(tolerances):
        if (problem := value_problem("tol", tol, float)) is not None:
            raise ConfigError(f"{where}.study.tolerances[{i}]: {tol!r} {problem}")
    columns = (atlas.get("solvers") or {}) if isinstance(atlas, Mapping) else {}
    for label, spec in columns.items():
        tol = spec.get("kkt_tol") if isinstance(spec, Mapping) else None
        if tol is not None and (problem := value_problem("kkt_tol", tol, float)) is not None:
            raise ConfigError(f"{where}.atlas.solvers.{label}.kkt_tol: {tol!r} {problem}")


def check_numbers(value: object, path: tuple = ()) -> None:
    """No NaN anywhere in the config (YAML's ``.nan``): no field can use it, and it passes every
    bound of the schema (each comparison with NaN is false)."""
    if isinstance(value, float) and math.isnan(value):
        raise ConfigError(f"{field_name(path)}: .nan is not a number; give a number")
    if isinstance(value, Mapping):
        for key, item in value.items():
            check_numbers(item, (*path, key))
    elif isinstance(value, list):
        for i, item in enumerate(value):
            check_numbers(item, (*path, i))


def check_cores(cores: int | None, nodes: int | None = None) -> None:
    """``--cores`` of a run on this machine is at least 1: with 0 Snakemake plans the jobs and
    then waits for a free core for ever (with ``--jobs`` on a cluster the cores bound nothing)."""
    if cores is not None and cores < 1 and nodes is None:
        raise ConfigError(f"--cores {cores}: no job could ever run; give at least 1")


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


def memory_limit(mem_limit_mb: int | None = None, node: NodeLimits | None = None) -> tuple[int, str]:
    """The memory a job may use in MB and what sets it, as the messages say it: the limit the user
    gave (``available``), else this process's (the machine's, a cgroup's or a ulimit's:
    ``resources.usable_memory``); with ``node``, at most the largest node of a Slurm partition."""
    from signorini.pipeline.resources import usable_memory

    limit, available = (int(mem_limit_mb), "available") if mem_limit_mb else usable_memory()
    if node is not None:
        limit = min(limit, node.mem_mb) if mem_limit_mb else node.mem_mb
        available = f"of the largest node of Slurm partition {node.partition}"
    return limit, available


def check_config(
    config: dict, mem_limit_mb: int | None = None, node: NodeLimits | None = None, memory: bool = True
) -> None:
    """Semantic checks of a schema-valid config: scene names that can be paths, integer ``N``
    strictly increasing, norm names of the grammar (``fem.norms.names``) in their one spelling and
    each once, admissible problem parameters with an amplitude whose errors do not underflow,
    and a right-hand side that does not overflow, a support of ``u`` resolved by the coarsest mesh,
    conventions, meshes whose jobs fit into ``mem_limit_mb`` (``memory_limit``; with ``node``, the
    largest node of a Slurm partition: its memory and time limit), the solver's options
    (``signorini.pipeline.solver_options``) and tolerances, no NaN anywhere, and a ``figures_scene``
    with the paper's norms.  Without ``memory`` the meshes' memory is left to
    ``check_planned_memory`` (a run checks the meshes its targets need, not every scene's).
    The scene defaults are filled in first (``apply_scene_defaults``: a no-op on a validated config)."""
    apply_scene_defaults(config)
    limit, available = memory_limit(mem_limit_mb, node) if memory else (None, "")
    scenes = config.get("scenes") or {}
    if not scenes:
        raise ConfigError("scenes: at least one scene is required")
    for name, scene in scenes.items():
        check_scene_name("scenes", name)
        _check_scene(f"scenes.{name}", scene, limit, available, node)
    _check_figures_scene(config, scenes)
    _check_meshes_study(config.get("meshes_study") or [], scenes)
    check_numbers(config)  # last: the checks above say more where a NaN is a tolerance or a parameter


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
