# Shared helpers: the package import, config checks, scenes and code inputs.
import functools
import shlex
import sys
from pathlib import Path

from snakemake.exceptions import WorkflowError

# Snakemake runs every script job as `<sys.executable> <script>` through bash and quotes only the
# script (snakemake/script/__init__.py, PythonScript.execute_script), so an interpreter path with
# a space or another shell character breaks every job ("bash: .../sp: No such file or directory").
# That cannot be quoted from here: refuse before the first job (with --sdm conda the jobs run
# `python` of the rules' conda environment instead).
_deploy = {m.name.lower() for m in workflow.deployment_settings.deployment_method}
if shlex.quote(sys.executable) != sys.executable and "conda" not in _deploy:
    raise WorkflowError(
        f"the Python interpreter {sys.executable!r} lies in a path the shell splits (a space or "
        "a shell character): Snakemake starts every script job as `<interpreter> <script>` without "
        "quoting the interpreter, so each job would fail. Put the environment in a plain path, e.g. "
        "`make setup VENV=$HOME/.venvs/signorini` (the checkout itself may have spaces)."
    )

# the jobs end quietly on Ctrl-C (signorini/__init__.py); this process imported the package
# already (the Snakefile, which also puts src/ on the jobs' PYTHONPATH), so Snakemake's own
# handling of Ctrl-C stays as it is
os.environ.update(SIGNORINI_JOB_INTERRUPT="quiet")

from signorini.fem.mesh_families import paper_mesh
from signorini.fem.norms.names import true_name
from signorini.published import FIGURE3_NORMS, TABLE1_NORMS, TABLE2_NORMS
from signorini.pipeline import paths, resources
from signorini.pipeline.artifacts import code_digest
from signorini.pipeline.codedeps import ImportCache, code_inputs
from signorini.pipeline.config import (
    ConfigError,
    check_config,
    check_cores,
    check_norm_name,
    one_line_errors,
)
from signorini.peers import PEER_PYTHON
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.work_precision import study as wp_study


def slurm_node(workflow):
    """The largest node of the Slurm partition the jobs go to when this run submits them through
    the slurm executor (None otherwise); known once the run starts, not while parsing.
    """
    if getattr(workflow.executor_plugin, "name", None) != "slurm":
        return None
    defaults = workflow.resource_settings.default_resources or {}
    # --default-resources slurm_partition=...: an expression Snakemake evaluates per job; its text
    partition = defaults.get("slurm_partition")
    partition = getattr(partition, "raw", partition)
    node = resources.slurm_node_limits(
        str(partition).strip("\"'") if partition else None
    )
    cores = workflow.resource_settings.cores
    if cores and cores > node.cpus:
        raise ConfigError(
            f"--cores {cores}: a group job would request --cpus-per-task={cores}, more than the "
            f"{node.cpus} CPUs of the largest node of Slurm partition {node.partition}"
        )
    return node


# integer N, norm names of the grammar, admissible problem parameters; atlas blocks (case names,
# groups, problems, solver columns); study blocks (reuse of the source scene's artifacts): one line
_mem_limit = resources.given_mem_mb(workflow)  # --resources / profile, else None
with one_line_errors(stab_atlas.AtlasConfigError, wp_study.StudyConfigError):
    # --cores 0 on this machine: Snakemake would plan, then wait for a free core for ever
    check_cores(
        workflow.resource_settings.cores, workflow.global_resources["_nodes"].value
    )
    # the meshes' memory: on the plan of the requested targets (integrity.smk)
    check_config(config, memory=False)
    stab_atlas.check_atlases(config)
    for _name, _scene in config["scenes"].items():
        if "study" in _scene:
            wp_study.check_study(config["scenes"], _name)
# without a mem_mb of the user's, the scheduler holds the jobs' mem_mb requests against the
# memory of this machine (or its cgroup): two large jobs never run side by side
patches.bound_scheduler_memory(workflow, resources.usable_memory(per_process=False).mb)


# Through Slurm, every scene job's run-time request must fit the time limit of the partition, and
# a group job's CPUs (--cores) its largest node: refused before the first submission, not left
# pending for ever (the memory of the jobs this run needs: check_plan, integrity.smk).
onstart:
    if (node := slurm_node(workflow)) is not None:
        check_config(config, _mem_limit, node=node, memory=False)


wildcard_constraints:
    scene=r"[A-Za-z0-9_-]+",
    N=r"[1-9][0-9]*",
    norm=r"[A-Za-z0-9._]+",


PATHS = paths.PATHS


def in_checkout(path):
    """A file of this checkout (next to the Snakefile, e.g. workflow/reference/...): relative as it
    is when the working directory is the checkout (the paths the outputs name stay the same), else
    absolute (snakemake -d elsewhere, or -s from another directory)."""
    base = Path(workflow.basedir)
    return path if base.resolve() == Path.cwd().resolve() else str(base / path)


REFERENCES = {name: in_checkout(path) for name, path in paths.REFERENCES.items()}
FIGURES = paths.FIGURES
FIG = config["figures_scene"]  # the scene paper_figures/ is rendered from
# a mesh's jobs on a cluster (discretise, solve, its norms): one job group, named as in the
# slurm profile's `groups` (group names of the command line are not known while parsing)
MESH_GROUP = "mesh"
THEORY = paths.THEORY_SCENE  # the scene rendered into paper_figures/theory*
FINE = "fine"  # the scene rendered into paper_figures/table{1,2}_fine.*
FINEST = "finest"  # the scene rendered into paper_figures/table{1,2}_finest.*
WP = "work_precision"  # the scene rendered into paper_figures/work_precision*, cost_of_accuracy*
STAB = "stability"  # the scene rendered into paper_figures/stability.*


def scene_of(wildcards):
    """The config block of the job's scene (schema defaults filled in).  A job of one norm (a
    target's norm need not be in the scene's list) has its norm checked as the config check
    checks the scenes' norms (the grammar, one spelling), and refused when its exponent is so
    large that the evaluation would overflow: a ConfigError or UnknownNormError, one line on the
    console (snakemake_logger_plugin_signorini.input_error_line)."""
    name = wildcards if isinstance(wildcards, str) else wildcards.scene
    if name not in config["scenes"]:
        raise ConfigError(
            f"unknown scene {name!r}; configured: {', '.join(sorted(config['scenes']))} (a scene of "
            "your own goes into a config file passed with --configfile, docs/scenes.md)"
        )
    norm = getattr(wildcards, "norm", None)
    if norm is not None:  # the grammar, one spelling, an exponent a double can hold
        check_norm_name("norm", norm)
    return config["scenes"][name]


def scene_param(key):
    """A params function: the job's scene's ``key`` (problem, diagonal, conventions, ...)."""
    return lambda wc: scene_of(wc)[key]


def family_mesh(scene=None):
    """An input function: the mesh artifact of the job's mesh when its scene (``scene``, else the
    job's) names a mesh family, none for the paper's Friedrichs-Keller mesh."""

    def mesh_of(wildcards):
        name = scene or wildcards.scene
        if paper_mesh(scene_of(name)["mesh"]):
            return []
        return PATHS["mesh_npz"].format(scene=name, N=wildcards.N)

    return mesh_of


def sized_N(wildcards, scene=None):
    """The N the resource requests of a job's mesh are computed from: the job's N on the paper's
    mesh, the N of a Friedrichs-Keller mesh with as many vertices on a family mesh of its scene
    (``scene``, else the job's; signorini.pipeline.resources.sized_N)."""
    return resources.sized_N(
        int(wildcards.N), scene_of(scene or wildcards.scene)["mesh"]
    )


# every Snakemake process parses this file (a cluster: each job): the direct imports of unchanged
# files come from a cache in .snakemake/ (saved at the end of the Snakefile)
IMPORTS = ImportCache(paths.IMPORT_CACHE)


def code(script):
    """A rule's code inputs: its script and every package module the script imports, directly
    or indirectly (signorini.pipeline.codedeps), so that an edit reruns exactly its jobs.
    """
    return code_inputs(
        Path(workflow.basedir) / "workflow" / "scripts" / f"{script}.py",
        SRC,
        os.getcwd(),
        IMPORTS,
    )


def reported(outputs, caption, category, subcategory=None):
    """{name: path} marked for the Snakemake report, captioned by workflow/report/<caption>.rst.
    Flagged update: a rendered (committed) output is not removed before its job runs and is
    restored when the job fails, so a run never loses a committed file."""
    # Snakemake's parser would read `report(` opening a line as its keyword
    in_report = report
    return {
        name: update(
            in_report(
                path,
                caption=f"../report/{caption}.rst",
                category=category,
                subcategory=subcategory,
                labels={"file": Path(path).name},
            )
        )
        for name, path in outputs.items()
    }


# the rules of norm_jobs: per_mesh, one per scene: norms_<scene> (scene.smk); they run norm.py
NORMS_RULE = "norms_{}"


def batched_norms(scene):
    """The norms one per-mesh job of ``scene`` computes: with norm_jobs per_mesh (the scene's own
    setting, else the config's), its norms under the conventions, which share one error field;
    a true norm shares nothing and stays a job of its own.  Empty with norm_jobs per_norm.
    """
    mode = scene_of(scene).get("norm_jobs", config["norm_jobs"])
    if mode != "per_mesh":
        return []
    return [n for n in scene_of(scene)["norms"] if n != true_name(n)]


@functools.cache
def current_code_digest(rule):
    """The digest of a rule's code inputs now (what its jobs record at their start); a rule's
    script has the rule's name, the norms_<scene> rules run norm.py (in either mode)."""
    is_norms = any(rule == NORMS_RULE.format(scene) for scene in config["scenes"])
    return code_digest(code("norm" if is_norms else rule))


def norm_jsons(scene, norms):
    """{norm: [the norm job's artifact per N of the scene]}"""
    Ns = scene_of(scene)["N"]
    return {
        n: [rules.norm.output.json.format(scene=scene, N=N, norm=n) for N in Ns]
        for n in norms
    }


def true_table_norms(scene=FIG):
    """{norm: artifacts} of ``scene`` (the rendered one) for every Table 2 norm the scene lists
    (all seven on the paper's, the fine and the theory scenes) and its true variant."""
    bases = [base for base in TABLE2_NORMS if base in scene_of(scene)["norms"]]
    names = [n for base in bases for n in (base, true_name(base))]
    return norm_jsons(scene, names)


def theory_true_norms():
    """{norm: artifacts} of the theory scene's true norms (their accuracy goes into theory.md)."""
    names = [n for n in scene_of(THEORY)["norms"] if n == true_name(n)]
    return norm_jsons(THEORY, names)


def target_outputs(target):
    """Every output of the rules a target rule renders (``paths.TARGETS``, the one list of them);
    call after those rules are defined."""
    return [
        path for rule in paths.TARGETS[target] for path in getattr(rules, rule).output
    ]


def flat(mapping):
    return [p for values in mapping.values() for p in values]


# --- the paper's run times ---


def runtime_jobs(scene):
    """The discretise, solve and norm jobs of a scene whose run times runtime.csv reports (with
    norm_jobs: per_mesh, one job per mesh for the scene's convention norms: its row names them all).
    """
    norms = list(
        dict.fromkeys([*scene_of(scene)["norms"], *TABLE1_NORMS, *FIGURE3_NORMS])
    )
    batched = batched_norms(scene)
    jobs = []
    for N in scene_of(scene)["N"]:

        def norm_json(n):
            return rules.norm.output.json.format(scene=scene, N=N, norm=n)

        for step in ("discretise", "solve"):
            artifact = getattr(rules, step).output.json.format(scene=scene, N=N)
            jobs.append((step, N, "", step, [artifact]))
        if batched:
            jobs.append(
                ("norms", N, " ".join(batched), "norms", list(map(norm_json, batched)))
            )
        for n in (n for n in norms if n not in batched):
            jobs.append(("norm", N, n, f"norm_{n}", [norm_json(n)]))
    return [
        {
            "rule": rule,
            "scene": scene,
            "N": N,
            "norm": norm,
            "benchmark": paths.benchmark("mesh", name, scene=scene, N=str(N)),
            "artifacts": artifacts,
        }
        for rule, N, norm, name, artifacts in jobs
    ]


# --- the work-precision study ---


def study_of(wildcards):
    """The `study` block of the job's scene."""
    study = scene_of(wildcards).get("study")
    if study is None:
        raise ConfigError(f"scene {wildcards.scene!r} has no study block")
    return study


def wp_configs(scene):
    """{name: SolverConfig} of a scene's study (imports cvxpy: call only when planning jobs)."""
    from signorini.solvers import installed_qp_solvers

    return wp_study.study_configs(study_of(scene), installed_qp_solvers())


def wp_source(path):
    """An input function: ``path`` (a template) of the study's source scene for the job's N."""
    return lambda wc: path.format(scene=study_of(wc)["source"], N=wc.N)


def wp_previous(wildcards):
    """This configuration's artifact on the previous mesh of the scene (none for the first)."""
    Ns = scene_of(wildcards)["N"]
    k = Ns.index(int(wildcards.N))
    if k == 0:
        return []
    return rules.work_precision_measure.output.json.format(
        scene=wildcards.scene, N=Ns[k - 1], solver=wildcards.solver
    )


def wp_peer_driver(wildcards):
    """The PETSc peers' driver, for a peer configuration's jobs (none for the others)."""
    return (
        [in_checkout(paths.PEER_DRIVER)]
        if wp_configs(wildcards)[wildcards.solver].peer
        else []
    )


def wp_disc_norms(wildcards):
    """{norm: the source scene's norm artifact of this N}: the discretisation errors."""
    source, N = study_of(wildcards)["source"], wildcards.N
    return {
        n: rules.norm.output.json.format(scene=source, N=N, norm=n)
        for n in scene_of(wildcards)["norms"]
    }


def wp_measure_jsons(scene):
    """Every measurement artifact of a scene: one per (N, solver configuration)."""
    return [
        rules.work_precision_measure.output.json.format(scene=scene, N=N, solver=name)
        for N in scene_of(scene)["N"]
        for name in wp_configs(scene)
    ]


# --- the stability atlas ---


def atlas_of(scene):
    """The parsed atlas of a scene."""
    return stab_atlas.scene_atlas(config, scene)
