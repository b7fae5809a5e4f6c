"""The config check (``signorini.pipeline.config``): what the mathematics cannot use is refused
before any job, in one line that names the field, the value and what is allowed."""

from __future__ import annotations

import copy

import numpy as np
import pytest
import yaml
from helpers import NORMS, PROBLEM, ROOT, SMOKE_N, copy_repo, snakemake

from signorini.fem.discrete import build
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.config import (
    SCENE_NAME_MAX,
    SUPPORT_CELLS,
    ConfigError,
    amplitude_ceiling,
    amplitude_floor,
    apply_scene_defaults,
    check_config,
    energy_ceiling,
    load_yaml,
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


def refused_with(path: tuple, value: object) -> str:
    """The one line refusing the shipped config with ``value`` at ``scenes.<path>``."""
    config = shipped()
    target = config["scenes"]
    for key in path[:-1]:
        target = target[key]
    target[path[-1]] = value
    return refused(config)


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


def test_an_amplitude_whose_load_vector_overflows_is_refused():
    """``problem: {A: 1e308}`` gave inf in b; the bound follows R and c."""
    message = refused(with_smoke(problem={"A": 1e308}))
    assert message.startswith("scenes.smoke.problem.A: 1e+308 is too large: the right-hand side f"), message
    assert "overflow" in message and f"need A ≤ {amplitude_ceiling(0.45, 1):.4e}" in message
    assert amplitude_ceiling(0.1, 1) < amplitude_ceiling(0.45, 1)  # f ~ A R^{-1/2}: a smaller support peaks higher
    assert amplitude_ceiling(0.45, 1e4) < amplitude_ceiling(0.45, 0)


@pytest.mark.parametrize(("R", "c", "N"), [(0.45, 1.0, 11), (0.1, 1.0, 31), (0.45, 1e4, 11)])
def test_the_amplitude_ceiling_is_where_the_load_vector_overflows(R, c, N):
    """Computed: just below the ceiling b is finite, the solve is certified and every norm (the
    paper's, one-sided, a true norm) is a finite number; a tenth above it b holds inf, and the
    config check refuses it."""
    from signorini.fem.norms.evaluate import evaluate_named_norms

    ceiling = amplitude_ceiling(R, c)
    problem = Problem(x0=0.5, R=R, A=ceiling * (1 - 1e-6), c=c)
    disc = build(problem, N, "sw_ne")
    assert np.isfinite(disc.b).all() and np.abs(disc.b).max() > 1e300
    # the true norms' bound of D²u overflows near the free point there: fewer triangles excluded, same value
    with np.errstate(over="ignore"):
        errors = evaluate_named_norms(problem, disc.mesh, solve_discrete(disc).u, [*NORMS, "L4plus", "L4_true"])
    assert all(np.isfinite(value) and value > 0 for value in errors.values()), errors
    with np.errstate(over="ignore", invalid="ignore"):
        assert not np.isfinite(build(Problem(x0=0.5, R=R, A=1.1 * ceiling, c=c), N, "sw_ne").b).all()
    with pytest.raises(ConfigError, match=r"problem\.A: .* is too large"):
        check_config(with_smoke(N=[N, 2 * N], problem={"x0": 0.5, "R": R, "A": 1.1 * ceiling, "c": c}))


def test_conjugate_gradients_bound_the_amplitude_by_the_energy():
    """The multigrid route (and the theory scene's Ritz projection) computes the energy A²·a(u₁, u₁)
    as a plain sum: below its ceiling the route solves, a tenth above it CG breaks down; the scene
    is refused, the direct route keeps the larger bound of the load vector."""
    from signorini.solvers import NotConvergedError

    ceiling = energy_ceiling(0.45, 1.0)
    disc = build(Problem(A=0.99 * ceiling), 41, "sw_ne")
    assert solve_discrete(disc, solver="multigrid").certificate is not None
    with np.errstate(over="ignore", invalid="ignore"), pytest.raises((NotConvergedError, ValueError)):
        solve_discrete(build(Problem(A=1.1 * ceiling), 41, "sw_ne"), solver="multigrid")
    message = refused(with_smoke(solver="multigrid", problem={"A": 1.1 * ceiling}))
    assert "too large for conjugate gradients" in message and f"need A ≤ {ceiling:.4e}" in message, message
    check_config(with_smoke(solver="active_set", problem={"A": 1.1 * ceiling}))


@pytest.mark.parametrize(
    ("changes", "fragments"),
    [
        ({"problem": {"x0": 0.999, "R": 0.0005}}, ["scenes.smoke.N[0]:", "0.0055 cells", "meshes at N = 6000"]),
        ({"problem": {"R": 0.1}}, ["scenes.smoke.problem.R:", "1.1 cells", "need R ≥ 0.273 or meshes from N = 30"]),
        ({"N": [1, 2], "norms": ["L4plus", "L4minus"]}, ["scenes.smoke.N[0]:", "0.45 cells", "N = 7 (R ≥ 3h)"]),
    ],
)
def test_a_support_the_coarsest_mesh_does_not_resolve_is_refused(changes, fragments):
    """A support smaller than a cell gave L4 = W1inf = 0 for a nonzero u and a crashing eoc job;
    N = [1, 2] gave L4plus = 0 (no node in the support): R ≥ 3h on the coarsest mesh."""
    message = refused(with_smoke(**changes))
    assert all(f in message for f in fragments), message


def test_the_support_rule_is_where_the_errors_and_their_one_sided_parts_behave():
    """Computed: on N = 1 the plus part of the error vanishes (so would its EOC); with the support
    at the rule's bound, R = 3/N, every error and one-sided part is nonzero and decreases."""
    from signorini.fem.norms.conventional import evaluate_norms

    names = ["L4", "W1inf", "L4plus", "L4minus"]

    def errors(R: float, N: int) -> dict:
        problem = Problem(R=R)
        disc = build(problem, N, "sw_ne")
        return evaluate_norms(problem, disc.mesh, solve_discrete(disc).u, names)

    assert errors(0.45, 1)["L4plus"] == 0.0
    coarse, fine = errors(SUPPORT_CELLS / 11, 11), errors(SUPPORT_CELLS / 11, 21)
    assert all(0 < fine[n] < coarse[n] for n in names), (coarse, fine)
    check_config(with_smoke(problem={"R": SUPPORT_CELLS / 11}))  # the bound itself passes


def test_every_shipped_scene_resolves_its_support():
    config = shipped()
    for name, scene in config["scenes"].items():
        assert scene["problem"]["R"] * min(scene["N"]) >= SUPPORT_CELLS, name
    validate(config)


@pytest.mark.parametrize(
    ("where", "value", "fragments"),
    [
        (("study", "tolerances", 1), float("inf"), ["scenes.work_precision.study.tolerances[1]: inf", "finite"]),
        (("study", "timing", "spread"), float("nan"), ["scenes.work_precision.study.timing.spread: .nan is not"]),
        (("problem", "c"), float("nan"), ["scenes.work_precision.problem"]),
    ],
)
def test_nan_and_infinite_tolerances_are_refused_wherever_they_are(where, value, fragments):
    """NaN passes every bound of the schema (each comparison is false): refused anywhere; a
    study's tolerances are finite and positive like a solver's."""
    message = refused_with(("work_precision", *where), value)
    assert all(f in message for f in fragments), message


def test_an_atlas_columns_certificate_tolerance_is_finite_and_positive():
    config = shipped()
    config["scenes"]["stability"]["atlas"]["solvers"]["osqp"]["kkt_tol"] = float("nan")
    message = refused(config)
    assert message.startswith("scenes.stability.atlas.solvers.osqp.kkt_tol: nan is not allowed; a tolerance"), message


def test_cores_zero_is_refused():
    from signorini.pipeline.config import check_cores

    with pytest.raises(ConfigError, match=r"^--cores 0: no job could ever run; give at least 1$"):
        check_cores(0)
    check_cores(1)
    check_cores(None)  # --lint, --summary, ...: no cores given
    check_cores(0, nodes=50)  # --jobs on a cluster: the local cores bound nothing


@pytest.mark.parametrize("args", [["-c0"], ["-j0"]])  # make all CORES=0; -j is --cores on this machine
def test_snakemake_refuses_cores_zero_before_planning(tmp_path, args):
    """``snakemake -c0`` planned the jobs and then waited for a free core for ever."""
    copy_repo(tmp_path)
    proc = snakemake(tmp_path, *args, "--workflow-profile", "none", "results/smoke/N11/system.npz", check=False,
                     timeout=120)
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.strip()]
    assert proc.returncode != 0, lines
    assert lines[-1] == "config error: --cores 0: no job could ever run; give at least 1", lines
    assert not (tmp_path / "results").exists()


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
        (("solver",), "gurobi", ["scenes.smoke.solver: 'gurobi' is not allowed; one of direct, multigrid,"]),
        (("N", 1), 201.5, ["scenes.smoke.N[1]: 201.5 is not an integer"]),
        (("N", 0), 0, ["scenes.smoke.N[0]: 0 is not allowed; the value must be ≥ 1"]),
        (("problem", "c"), -1, ["scenes.smoke.problem.c: reaction coefficient c=-1.0 must be non-negative"]),
        (("problem", "x0"), "half", ["scenes.smoke.problem.x0: 'half' is not a number"]),
        (("nroms",), ["L4"], ["scenes.smoke: unknown field 'nroms'; allowed: N, atlas,"]),
        (("norms",), [], ["scenes.smoke.norms: needs at least 1 entry"]),
    ],
)
def test_schema_errors_are_one_line_naming_field_value_and_what_is_allowed(path, value, fragments):
    message = refused_with(("smoke", *path), value)
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
        (30_000, None, r"N\[1\]: N = 30000 needs about {need} GB"),
        (1001, 1000, r"N\[1\]: N = 1001 needs about {need} GB .* more than the 1.0 GB available"),
    ],
)
def test_a_mesh_that_cannot_fit_is_refused_before_any_job(N, limit, message):
    from signorini.pipeline.resources import largest_job

    need = f"{largest_job(N)[1] / 1024:.1f}"
    message = message.replace("{need}", need.replace(".", r"\."))
    config = load_config(ROOT / "workflow/config.yaml")
    config = {"figures_scene": "smoke", "scenes": {"smoke": {**config["scenes"]["smoke"], "N": [11, N]}}}
    with pytest.raises(ConfigError, match=message):
        check_config(config, limit)


class _Job:
    """What ``check_planned_memory`` reads of a Snakemake job: its wildcards."""

    def __init__(self, **wildcards):
        self.wildcards = wildcards


def test_a_run_checks_the_memory_of_the_meshes_it_needs_and_of_no_others():
    """A scene that needs more memory than this machine has (``finest``) keeps no other target from
    running: the workflow leaves the meshes' memory out of the config check and checks the plan."""
    from signorini.pipeline.config import check_planned_memory

    config = load_config(ROOT / "workflow/config.yaml")
    config = {"figures_scene": "smoke", "scenes": {"smoke": config["scenes"]["smoke"],
                                                    "big": {**config["scenes"]["smoke"], "N": [11, 30_000]}}}
    with pytest.raises(ConfigError, match=r"scenes\.big\.N\[1\]: N = 30000 needs about"):
        check_config(copy.deepcopy(config), 4000)
    check_config(config, 4000, memory=False)
    small = [_Job(scene="smoke", N="11"), _Job(scene="smoke", N="21"), _Job(scene="big", N="11"), _Job(case="c")]
    check_planned_memory(small, config, 4000)
    # not a mesh of the scene (a target's file under another N): no estimate, Snakemake's own request
    check_planned_memory([*small, _Job(scene="big", N="29999")], config, 4000)
    with pytest.raises(ConfigError, match=r"^scenes\.big\.N\[1\]: N = 30000 needs about .* more than the 3\.9 GB "
                       r"available$"):
        check_planned_memory([*small, _Job(scene="big", N="30000", norm="L4")], config, 4000)


def test_a_mesh_beyond_the_memory_is_refused_only_when_a_target_needs_it(tmp_path):
    """End to end: the shipped scene ``finest`` (N = 8001, about 21 GB per job) under a memory limit of
    8 GB: a dry run of another target passes, one of ``finest`` is refused in one line."""
    copy_repo(tmp_path)
    proc = snakemake(tmp_path, "-n", "results/smoke/N11/system.npz", "--resources", "mem_mb=8000", timeout=120)
    assert "config error" not in proc.stdout + proc.stderr
    proc = snakemake(tmp_path, "-n", "finest", "--resources", "mem_mb=8000", check=False, timeout=120)
    assert proc.returncode != 0
    assert "config error: scenes.finest.N[2]: N = 8001 needs about 21.3 GB for its solve_multigrid job" in proc.stderr


def test_a_yaml_syntax_error_is_named_with_file_and_line(tmp_path, monkeypatch, capsys):
    """Snakemake says only that a config file is not valid YAML; the Snakefile checks the shipped
    config first, and ``python -m signorini.pipeline.config`` a file given with ``--configfile``."""
    from signorini.pipeline.config import load_yaml, main

    bad = tmp_path / "mine.yaml"
    bad.write_text("scenes:\n  mine:\n    N: [11, 21\n    norms: [L4]\n")
    with pytest.raises(ConfigError, match=r"mine\.yaml:4:10: (did not find )?expected ',' or '\]'"):
        load_yaml(bad)
    monkeypatch.chdir(ROOT)
    assert main([str(bad)]) == 1 and "mine.yaml:4:10" in capsys.readouterr().err
    good = tmp_path / "good.yaml"
    problem = "    problem: {x0: 0.5, R: 0.45, A: 10, c: 1}\n"
    good.write_text(bad.read_text().replace("21\n", "21]\n") + "    solver: active_set\n" + problem)
    scenes = len(load_yaml("workflow/config.yaml")["scenes"]) + 1
    assert main([str(good)]) == 0 and f"({scenes} scenes)" in capsys.readouterr().out


DUPLICATE = """\
scenes:
  mine:
    N: [11, 21]
    norms: [L4]
  other:
    N: [11, 21]
  mine:
    N: [21, 41]
"""


def test_a_key_given_twice_is_named_with_file_line_and_column(tmp_path, monkeypatch, capsys):
    """yaml (and Snakemake) kept the last ``mine:`` block silently; nested keys, JSON objects and
    ``python -m signorini.pipeline.config`` too.  Merge keys (``<<: *anchor``) are not a repeat."""
    from signorini.pipeline.config import main

    mine = tmp_path / "mine.yaml"
    mine.write_text(DUPLICATE, encoding="utf-8")
    twice = r"mine\.yaml:7:3: the key 'mine' is given twice in one mapping \(also at line 2, column 3\)"
    with pytest.raises(ConfigError, match=twice):
        load_yaml(mine)
    nested = tmp_path / "nested.yaml"
    nested.write_text("scenes:\n  mine:\n    N: [11, 21]\n    N: [21, 41]\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=r"nested\.yaml:4:5: the key 'N' is given twice"):
        load_yaml(nested)
    merged = tmp_path / "merged.yaml"
    merged.write_text("base: &b {N: [11, 21]}\nscenes:\n  mine:\n    <<: *b\n    N: [21, 41]\n", encoding="utf-8")
    assert load_yaml(merged)["scenes"]["mine"]["N"] == [21, 41]
    tabs = tmp_path / "tabs.json"  # JSON that PyYAML cannot read (tab indentation) is read as JSON
    tabs.write_text('{\n\t"scenes": {\n\t\t"mine": {"N": [11, 21]}\n\t}\n}\n', encoding="utf-8")
    assert load_yaml(tabs) == {"scenes": {"mine": {"N": [11, 21]}}}
    tabs.write_text('{\n\t"scenes": {},\n\t"scenes": {}\n}\n', encoding="utf-8")
    twice = r"tabs\.json(:3:2)?: the key 'scenes' is given twice in one (object|mapping)"
    with pytest.raises(ConfigError, match=twice):
        load_yaml(tabs)
    monkeypatch.chdir(ROOT)
    assert main([str(mine)]) == 1 and "mine.yaml:7:3: the key 'mine' is given twice" in capsys.readouterr().err


def test_snakemake_refuses_a_key_given_twice_in_a_configfile(tmp_path):
    copy_repo(tmp_path)
    (tmp_path / "mine.yaml").write_text(DUPLICATE, encoding="utf-8")
    proc = snakemake(tmp_path, "-n", "results/mine/errors.csv", "--configfile", "mine.yaml", check=False, timeout=120)
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.strip()]
    assert proc.returncode != 0 and lines[-1].startswith("config error: mine.yaml:7:3: the key 'mine' is given twice")


@pytest.mark.parametrize(
    ("content", "message"),
    [
        (b"", "empty.yaml: empty (or only comments); a config file holds a mapping of keys"),
        (b"- a\n- b\n", "empty.yaml: holds a list; a config file holds a mapping of keys"),
        ("scenes: {}\n".encode("utf-16"), "empty.yaml: UTF-16 text; a config file is UTF-8 text: save it as UTF-8"),
        (b"\xe9t\xe9: 1\n", "empty.yaml: not UTF-8 text"),
    ],
)
def test_a_config_file_that_is_no_mapping_of_utf8_text_is_one_line(tmp_path, content, message):
    (tmp_path / "empty.yaml").write_bytes(content)
    with pytest.raises(ConfigError) as info:
        load_yaml(tmp_path / "empty.yaml")
    assert str(info.value).endswith(message) or message in str(info.value), info.value
    with pytest.raises(ConfigError, match=r"missing\.yaml: no such file"):
        load_yaml(tmp_path / "missing.yaml")


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


def test_a_memoised_validation_gives_the_same_config_and_never_hides_an_error(tmp_path, monkeypatch):
    """The second workflow start with an unchanged config takes the validated config (defaults
    filled in) from the memo without validating; a changed config, schema or check is validated
    again, so an error is never hidden by the memo."""
    import signorini.pipeline.config as cfg

    memo = tmp_path / "validated.json"
    first, second = shipped(), shipped()
    cfg.validate_config(first, SCHEMA, memo=memo)
    monkeypatch.setattr(cfg, "_defaults_validator", lambda: pytest.fail("validated again"))
    cfg.validate_config(second, SCHEMA, memo=memo)
    assert second == first and second["scenes"]["smoke"]["diagonal"] == "sw_ne"
    monkeypatch.undo()
    bad = shipped()
    bad["scenes"]["smoke"]["N"] = [11, 21.5]
    with pytest.raises(ConfigError, match=r"scenes\.smoke\.N\[1\]"):
        cfg.validate_config(bad, SCHEMA, memo=memo)


def test_a_scene_of_another_problem_kind_takes_only_its_own_parameters():
    """A scene's problem of another kind than the defaults' is not merged with them; each of its
    parameters is required and checked by its class, the field named."""
    check_config(with_smoke(problem={"kind": "full_contact", "A": 2.0, "c": 1.0}))
    config = shipped()
    config["scenes"]["smoke"]["problem"] = {"kind": "constant", "value": 1.0}
    apply_scene_defaults(config)
    assert config["scenes"]["smoke"]["problem"] == {"kind": "constant", "value": 1.0}
    assert refused(config) == "scenes.smoke.problem: 'c' missing (the constant problem's parameters: value, c)"
    message = refused(with_smoke(problem={"kind": "constant", "value": 1.0, "c": 0.0}))
    assert message.startswith("scenes.smoke.problem.c: value > 0 needs c > 0"), message
    message = refused(with_smoke(problem={"kind": "full_contact", "A": 1.0, "c": 1.0, "R": 0.3}))
    assert message.startswith("scenes.smoke.problem.R: full_contact problem: unknown parameter 'R'"), message


@pytest.mark.parametrize(
    ("mesh", "fragments"),
    [
        ({"family": "voronoi"}, ["scenes.smoke.mesh.family: 'voronoi' is not allowed", "delaunay"]),
        ({"family": "delaunay", "grading": 2}, ["scenes.smoke.mesh: mesh family 'delaunay' has no parameter"]),
        ({"family": "graded", "grading": "steep"}, ["scenes.smoke.mesh.grading: 'steep' is not a number"]),
        ({"family": "delaunay", "seed": 0.5}, ["scenes.smoke.mesh: mesh parameter seed=0.5 must be a int"]),
    ],
)
def test_a_mesh_block_names_a_family_and_its_parameters(mesh, fragments):
    message = refused_with(("smoke", "mesh"), mesh)
    assert all(f in message for f in fragments), message


def test_the_schemas_mesh_families_are_the_codes():
    from signorini.fem.mesh_families import MESH_FAMILIES

    schema = yaml.safe_load(SCHEMA.read_text(encoding="utf-8"))
    assert schema["$defs"]["scene"]["properties"]["mesh"]["properties"]["family"]["enum"] == list(MESH_FAMILIES)


def test_scene_defaults_merge_a_mesh_block_of_the_same_family_only():
    from signorini.pipeline.config import apply_scene_defaults

    config = {
        "scene_defaults": {"mesh": {"family": "delaunay", "seed": 2}},
        "scenes": {"a": {"N": [8]}, "b": {"N": [8], "mesh": {"family": "delaunay", "jitter": 0.1}},
                   "c": {"N": [8], "mesh": {"family": "graded"}}},
    }
    apply_scene_defaults(config)
    a, b, c = (config["scenes"][k]["mesh"] for k in "abc")
    assert a == {"family": "delaunay", "seed": 2} and b == {"family": "delaunay", "seed": 2, "jitter": 0.1}
    assert c == {"family": "graded"}
