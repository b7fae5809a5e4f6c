# Helpers of the work-precision study rules (work_precision.smk): the scene's paths, its
# solver configurations, the source scene's artifacts a job reuses.
from signorini import work_precision as wp

WP = "work_precision"  # the scene rendered into paper_figures/
WP_PATHS = {
    "system_npz": "results/{scene}/N{N}/work_precision/system.npz",
    "system_json": "results/{scene}/N{N}/work_precision/system.json",
    "measure_json": "results/{scene}/N{N}/work_precision/{solver}.json",
}
WP_OUTPUTS = [
    *expand(
        f"{FIGDIR}/{{name}}.{{ext}}",
        name=["work_precision", "cost_of_accuracy"],
        ext=["pdf", "png"],
    ),
    f"{FIGDIR}/work_precision.csv",
    f"{FIGDIR}/work_precision.md",
]

for _name, _scene in config["scenes"].items():
    if "study" in _scene:
        wp.check_study(config["scenes"], _name)


def study_of(wildcards):
    """The `study` block of the job's scene."""
    study = scene_of(wildcards).get("study")
    if study is None:
        raise ValueError(f"scene {wildcards.scene!r} has no study block")
    return study


def wp_configs(scene):
    """{name: SolverConfig} of a scene's study (imports cvxpy: call only when planning jobs)."""
    return wp.study_configs(study_of(scene))


def wp_source(wildcards, path, **fields):
    """A path of the study's source scene for the job's N."""
    return path.format(scene=study_of(wildcards)["source"], N=wildcards.N, **fields)


def wp_previous(wildcards):
    """This configuration's artifact on the previous mesh of the scene (none for the first)."""
    Ns = scene_of(wildcards)["N"]
    k = Ns.index(int(wildcards.N))
    if k == 0:
        return []
    return WP_PATHS["measure_json"].format(
        scene=wildcards.scene, N=Ns[k - 1], solver=wildcards.solver
    )


def wp_disc_norms(wildcards):
    """{norm: the source scene's norm artifact of this N}: the discretisation errors."""
    return {
        n: wp_source(wildcards, PATHS["norm_json"], norm=n)
        for n in scene_of(wildcards)["norms"]
    }


def wp_measure_jsons(scene):
    """Every measurement artifact of a scene: one per (N, solver configuration)."""
    return [
        WP_PATHS["measure_json"].format(scene=scene, N=N, solver=name)
        for N in scene_of(scene)["N"]
        for name in wp_configs(scene)
    ]
