"""The config check (``signorini.pipeline.config``): what the mathematics cannot use is refused
before any job, in one line that names the field, the value and what is allowed."""

from __future__ import annotations

import copy

import pytest
import yaml
from helpers import NORMS, PROBLEM, ROOT, SMOKE_N, copy_repo, snakemake

from signorini.fem.discrete import build
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.config import (
    SCENE_NAME_MAX,
    ConfigError,
    amplitude_floor,
    check_config,
    validate_config,
)
from signorini.pipeline.config import load_config as read_config

SCHEMA = ROOT / "workflow/schemas/config.schema.yaml"


def shipped() -> dict:
    """The shipped config with its scene defaults filled in, as a run sees it."""
    return load_config(ROOT / "workflow/config.yaml")


def refused(config: dict) -> str:
    """The one message the schema or the semantic check gives for ``config``."""
    with pytest.raises(ConfigError) as info:
        validate_config(config, SCHEMA)
        check_config(config)
    message = str(info.value)
    assert "\n" not in message and len(message) <= 320, message  # one line, readable
    return message


def with_smoke(**changes) -> dict:
    config = shipped()
    config["scenes"]["smoke"].update(copy.deepcopy(changes))
    return config


@pytest.mark.parametrize(
    ("N", "fragments"),
    [
        ([41, 11, 21], ["scenes.smoke.N:", "not increasing", "[11, 21, 41]"]),
        ([11, 21, 21], ["scenes.smoke.N[2]", "N = 21 is listed twice"]),
        ([11, 21, 11], ["scenes.smoke.N[2]", "N = 11 is listed twice"]),
    ],
)
def test_mesh_sizes_must_increase_strictly(N, fragments):
    message = refused(with_smoke(N=N))
    assert all(f in message for f in fragments), message


@pytest.mark.parametrize(
    ("norms", "fragments"),
    [
        (["L4", "L1", "L1.0"], ["scenes.smoke.norms[2]", "'L1.0' is the norm L1", "write it L1"]),
        (["L01"], ["scenes.smoke.norms[0]", "'L01' is the norm L1"]),
        (["W12.50"], ["norms[0]", "write it W12.5"]),
        (["Linf_true", "L4", "Linf_true"], ["scenes.smoke.norms[2]", "Linf_true is listed twice", "norms[0]"]),
    ],
)
def test_a_norm_has_one_spelling_and_appears_once(norms, fragments):
    message = refused(with_smoke(norms=norms))
    assert all(f in message for f in fragments), message


def test_a_norm_typo_is_one_line_with_the_grammar_in_words():
    message = refused(with_smoke(norms=["L4", "W1_4"]))
    assert message.startswith("scenes.smoke.norms[1]: unknown norm 'W1_4'"), message
    assert "exponent p ≥ 1" in message and "H12" in message and "_true" in message
    assert "^(" not in message and "[0-9]" not in message  # no regular expression


@pytest.mark.parametrize("A", [1e-320, 5e-324, 1e-310, 1e-305])
def test_an_amplitude_whose_errors_underflow_is_refused(A):
    message = refused(with_smoke(problem={"x0": 0.5, "R": 0.45, "A": A, "c": 1}))
    assert message.startswith("scenes.smoke.problem.A:") and "subnormal" in message and "need A ≥" in message


def test_the_amplitude_floor_follows_the_finest_mesh():
    """The floor grows with N² (the errors shrink like h²); the paper's A = 10 is far above it,
    and amplitudes just above the floor at N = 41 are accepted."""
    assert amplitude_floor(0.45, 82) == pytest.approx(4 * amplitude_floor(0.45, 41))
    assert amplitude_floor(0.45, 2001) < 1e-298
    check_config(with_smoke(problem={"x0": 0.5, "R": 0.45, "A": 2 * amplitude_floor(0.45, 41), "c": 1}))


def test_the_floor_is_where_the_errors_lose_digits():
    """Computed: the errors are A times those at A = 1 to round-off above the floor; well below
    it (A = 1e-320, subnormal data) they are wrong by factors."""
    names = ["L4", "Linf", "W14", "H12"]

    def errors(A: float) -> dict:
        problem = Problem(A=A)
        disc = build(problem, 21, "sw_ne")
        return evaluate_norms(problem, disc.mesh, solve_discrete(disc).u, names)

    unit = errors(1.0)
    A = 4 * amplitude_floor(0.45, 21)
    above = errors(A)
    assert all(abs(above[n] / A / unit[n] - 1) < 1e-12 for n in names), above
    below = errors(1e-320)
    assert any(abs(below[n] / 1e-320 / unit[n] - 1) > 0.1 for n in names), below


@pytest.mark.parametrize(
    ("norms", "missing"),
    [(["L2", "H1"], "L4, L16, Linf, W14, W116, W1inf, H12"), (["L4", "L16", "Linf", "W14", "W1inf", "H12"], "W116")],
)
def test_figures_scene_needs_the_papers_norms(norms, missing):
    config = with_smoke(norms=norms)
    config["figures_scene"] = "smoke"
    message = refused(config)
    assert message.startswith("figures_scene: scene 'smoke' lacks the norms " + missing), message
    assert "scenes.smoke.norms" in message


def test_figures_scene_needs_two_meshes():
    config = with_smoke(N=[21])
    config["figures_scene"] = "smoke"
    assert "Table 2's EOCs need two" in refused(config)


@pytest.mark.parametrize(
    ("name", "fragments"),
    [
        ("s" * 300, ["scenes: scene name", "300 characters", f"at most {SCENE_NAME_MAX}"]),
        ("my scene", ["scenes: 'my scene' is not allowed", "letters, digits, _ and -"]),
        ("a/b", ["scenes: 'a/b'", "letters, digits, _ and -"]),
        ("ü", ["scenes: 'ü'"]),
    ],
)
def test_scene_names_that_cannot_be_paths_are_refused(name, fragments):
    config = shipped()
    config["scenes"][name] = copy.deepcopy(config["scenes"]["smoke"])
    message = refused(config)
    assert all(f in message for f in fragments), message


@pytest.mark.parametrize(
    ("path", "value", "fragments"),
    [
        (("solver",), "gurobi", ["scenes.smoke.solver: 'gurobi' is not allowed; one of active_set,"]),
        (("N", 1), 201.5, ["scenes.smoke.N[1]: 201.5 is not an integer"]),
        (("N", 0), 0, ["scenes.smoke.N[0]: 0 is not allowed; the value must be ≥ 1"]),
        (("problem", "c"), -1, ["scenes.smoke.problem.c: -1 is not allowed; the value must be ≥ 0"]),
        (("problem", "x0"), "half", ["scenes.smoke.problem.x0: 'half' is not a number"]),
        (("nroms",), ["L4"], ["scenes.smoke: unknown field 'nroms'; allowed: N, atlas,"]),
        (("norms",), [], ["scenes.smoke.norms: needs at least 1 entry"]),
    ],
)
def test_schema_errors_are_one_line_naming_field_value_and_what_is_allowed(path, value, fragments):
    config = shipped()
    target = config["scenes"]["smoke"]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    message = refused(config)
    assert all(f in message for f in fragments), message


def test_a_missing_field_is_named():
    config = shipped()
    del config["scenes"]["smoke"]["solver"], config["scene_defaults"]["solver"]
    assert refused(config) == "scenes.smoke: 'solver' missing (required: N, norms, solver, problem)"


def test_snakemake_prints_a_config_error_in_one_line(tmp_path):
    """What a user sees: Snakemake's note on the extra config file, then one line; no traceback,
    nothing built."""
    copy_repo(tmp_path)
    bad = {"scenes": {"mine": {"N": [8, 16], "norms": ["L2", "W1_4"], "solver": "active_set",
                               "problem": {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}}}}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(bad), encoding="utf-8")
    proc = snakemake(tmp_path, "-n", "--configfile", "bad.yaml", check=False)
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.strip()]
    assert proc.returncode != 0
    assert lines[-1].startswith("config error: scenes.mine.norms[1]: unknown norm 'W1_4'; a norm is"), lines
    assert len(lines) <= 2 and "Traceback" not in proc.stderr and "File " not in proc.stderr, lines
    assert not (tmp_path / "results").exists()


def test_scene_defaults_fill_what_a_scene_leaves_out_and_merge_the_problem():
    from signorini.pipeline.config import apply_scene_defaults

    config = {
        "scene_defaults": {"norms": ["L2"], "solver": "active_set", "problem": {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}},
        "scenes": {"a": {"N": [8]}, "b": {"N": [8], "norms": ["H1"], "problem": {"A": 5}}},
    }
    apply_scene_defaults(config)
    a, b = config["scenes"]["a"], config["scenes"]["b"]
    assert a["norms"] == ["L2"] and b["norms"] == ["H1"] and b["solver"] == "active_set"
    assert b["problem"] == {"x0": 0.5, "R": 0.45, "A": 5, "c": 1}
    a["problem"]["A"] = 7  # each scene holds its own copy: editing one changes no other
    assert config["scene_defaults"]["problem"]["A"] == 10 and b["problem"]["A"] == 5


def test_the_shipped_scenes_state_the_shared_problem_and_norms_once():
    raw = yaml.safe_load((ROOT / "workflow/config.yaml").read_text(encoding="utf-8"))
    shared = raw["scene_defaults"]
    for name, block in raw["scenes"].items():
        assert block.get("problem") != shared["problem"] and block.get("norms") != shared["norms"], name


def test_a_scene_whose_errors_vanish_is_rejected():
    config = load_config(ROOT / "workflow/config.yaml")
    config["scenes"]["smoke"]["problem"] = {**PROBLEM, "A": 0}
    with pytest.raises(ConfigError, match=r"scenes\.smoke\.problem\.A: 0 makes u ≡ 0"):
        check_config(config)


@pytest.mark.parametrize(
    ("N", "limit", "message"),
    [
        (10_000_000, None, r"N\[1\]: N = 10000000 needs about .* GB for its solve job"),
        (30_000, None, r"N\[1\]: N = 30000 needs about 1758.3 GB"),
        (1001, 1000, r"N\[1\]: N = 1001 needs about 2.4 GB .* more than the 1.0 GB available"),
    ],
)
def test_a_mesh_that_cannot_fit_is_refused_before_any_job(N, limit, message):
    config = load_config(ROOT / "workflow/config.yaml")
    config = {"figures_scene": "smoke", "scenes": {"smoke": {**config["scenes"]["smoke"], "N": [11, N]}}}
    with pytest.raises(ConfigError, match=message):
        check_config(config, limit)


def test_a_yaml_syntax_error_is_named_with_file_and_line(tmp_path, monkeypatch, capsys):
    """Snakemake says only that a config file is not valid YAML; the Snakefile checks the shipped
    config first, and ``python -m signorini.pipeline.config`` a file given with ``--configfile``."""
    from signorini.pipeline.config import load_yaml, main

    bad = tmp_path / "mine.yaml"
    bad.write_text("scenes:\n  mine:\n    N: [11, 21\n    norms: [L4]\n")
    with pytest.raises(ConfigError, match=r"mine\.yaml:4:10: expected ',' or '\]'"):
        load_yaml(bad)
    monkeypatch.chdir(ROOT)
    assert main([str(bad)]) == 1 and "mine.yaml:4:10" in capsys.readouterr().err
    good = tmp_path / "good.yaml"
    problem = "    problem: {x0: 0.5, R: 0.45, A: 10, c: 1}\n"
    good.write_text(bad.read_text().replace("21\n", "21]\n") + "    solver: active_set\n" + problem)
    scenes = len(load_yaml("workflow/config.yaml")["scenes"]) + 1
    assert main([str(good)]) == 0 and f"({scenes} scenes)" in capsys.readouterr().out


def load_config(path=ROOT / "workflow/config.yaml") -> dict:
    """The config at ``path`` (the shipped one by default) with its scene defaults filled in."""
    return read_config(path)


# --- config and schema ---------------------------------------------------------------------


def validate(config: dict) -> None:
    """What the Snakefile does: schema validation, then the semantic checks."""
    from signorini.pipeline.config import validate_config

    validate_config(config, ROOT / "workflow/schemas/config.schema.yaml")
    check_config(config)


def test_shipped_config_is_valid():
    config = load_config()
    validate(config)
    assert config["scenes"]["paper"]["N"] == [101, 201, 301, 401, 501]
    assert config["scenes"]["paper"]["norms"] == NORMS
    assert config["scenes"]["paper"]["problem"] == {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}
    assert config["scenes"]["smoke"]["N"] == SMOKE_N


@pytest.mark.parametrize(
    ("path", "value", "expected"),
    [
        (("norms", 0), "L4x", ["norms", "L4x"]),  # unknown norm: schema pattern
        (("norms", 0), "L0.5", ["norms[0]", "p ≥ 1"]),  # passes the pattern, parse_norm rejects it
        (("solver",), "gurobi", ["solver", "gurobi"]),
        (("N", 0), 0, ["N[0]", "0", "≥ 1"]),
        (("N", 0), -3, ["N"]),
        (("N", 1), 201.5, ["N", "integer"]),
        (("N", 1), 201.0, ["N[1]", "not an integer"]),  # JSON schema counts 201.0 as integer
        (("N", 1), "201", ["N", "integer"]),
        (("N",), 101, ["N", "a list"]),
        (("norms",), "L4", ["norms", "a list"]),
        (("problem", "x0"), "half", ["x0", "number"]),
        (("problem", "R"), 0.6, ["problem", "R"]),  # support leaves the square: Problem rejects it
        (("nroms",), ["L4"], ["nroms"]),  # a typo in a key
    ],
)
def test_invalid_config_names_the_field(path, value, expected):
    config = copy.deepcopy(load_config())
    target = config["scenes"]["smoke"]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    with pytest.raises(Exception) as info:  # WorkflowError (schema) or ConfigError (semantics)
        validate(config)
    message = str(info.value)
    for fragment in expected:
        assert fragment in message, message


def test_unknown_figures_scene_is_rejected():
    config = load_config()
    config["figures_scene"] = "nope"
    with pytest.raises(ConfigError, match="figures_scene"):
        validate(config)
