# The chain every scene runs, per scene and N: (mesh ->) discretise -> solve -> norm (one job per norm,
# so a target computes only the norms it needs; or one per mesh, norm_jobs: per_mesh) ->
# errors.csv -> eoc.csv. The tables errors and eoc are local rules (seconds): on a cluster they
# run on the submitting node.
# A scene that names a mesh family has a mesh job per N, whose artifact the later stages read;
# the paper's Friedrichs-Keller mesh (the default) is built where it is needed.


rule mesh:
    """The triangulation of one scene and N, with what it is (sizes, edges, angles) and a .vtu."""
    input:
        code=code("mesh"),
    output:
        npz=PATHS["mesh_npz"],
        json=PATHS["mesh_json"],
        vtu=PATHS["mesh_vtu"],
    log:
        paths.log("mesh", "mesh"),
    benchmark:
        paths.benchmark("mesh", "mesh")
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    resources:
        # building a graded mesh refines it level by level: as much as assembling it
        mem_mb=lambda wc: resources.mem_mb("discretise", sized_N(wc)),
        runtime=lambda wc: resources.runtime_min("discretise", sized_N(wc)),
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
    script:
        "../scripts/mesh.py"


rule discretise:
    """Mesh and assemble (S_h) of one scene and N: A, b and the constrained nodes."""
    input:
        mesh=family_mesh(),
        code=code("discretise"),
    output:
        npz=PATHS["system_npz"],
        json=PATHS["system_json"],
    log:
        paths.log("mesh", "discretise"),
    benchmark:
        paths.benchmark("mesh", "discretise")
    # the largest meshes first: they are the critical path
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=lambda wc: resources.mem_mb("discretise", sized_N(wc)),
        runtime=lambda wc: resources.runtime_min("discretise", sized_N(wc)),
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
    script:
        "../scripts/discretise.py"


rule solve:
    """Solve (S_h) of one scene and N with the scene's solver, certified by its KKT residuals."""
    input:
        system=rules.discretise.output.npz,
        mesh=family_mesh(),
        code=code("solve"),
    output:
        npz=PATHS["solution_npz"],
        json=PATHS["solution_json"],
    log:
        paths.log("mesh", "solve"),
    benchmark:
        paths.benchmark("mesh", "solve")
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=lambda wc: resources.mem_mb(
            resources.solve_rule(
                scene_of(wc)["solver"], sized_N(wc), paper_mesh(scene_of(wc)["mesh"])
            ),
            sized_N(wc),
        ),
        runtime=lambda wc: resources.runtime_min("solve", sized_N(wc)),
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
        solver=scene_param("solver"),
        solver_options=scene_param("solver_options"),
    script:
        "../scripts/solve.py"


rule norm:
    """One norm of the error u - u_h of one scene and N."""
    input:
        solution=rules.solve.output.npz,
        mesh=family_mesh(),
        code=code("norm"),
    output:
        json=PATHS["norm_json"],
    log:
        paths.log("mesh", "norm_{norm}"),
    benchmark:
        paths.benchmark("mesh", "norm_{norm}")
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=lambda wc: resources.mem_mb("norm", sized_N(wc)),
        runtime=lambda wc: resources.norms_runtime_min(sized_N(wc), [wc.norm]),
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
        conventions=scene_param("conventions"),
    script:
        "../scripts/norm.py"


# norm_jobs: per_mesh (the slurm profile, or a scene's own setting): one job per mesh computes
# all of its scene's norms under the conventions from one error field, since on a cluster every
# job pays a scheduling round trip and a Snakemake start, and anywhere the evaluation is shared.
# Same script, inputs and parameters as `norm`, so artifacts of either mode are interchangeable:
# switching reruns nothing. True norms (nothing to share) and norms outside the scene's list (a
# target's extra norms) stay one job each.
for _scene in config["scenes"]:
    _norms = batched_norms(_scene)
    if _norms:

        rule:
            """A scene's norms of the error u - u_h under the conventions on one mesh, together."""
            name:
                NORMS_RULE.format(_scene)
            input:
                solution=rules.solve.output.npz.format(scene=_scene, N="{N}"),
                mesh=family_mesh(_scene),
                code=code("norm"),
            output:
                expand(
                    rules.norm.output.json,
                    scene=_scene,
                    norm=_norms,
                    allow_missing=True,
                ),
            log:
                paths.log("mesh", "norms", scene=_scene),
            benchmark:
                paths.benchmark("mesh", "norms", scene=_scene)
            # the group the slurm profile gives the mesh's other jobs (clusters only)
            group:
                MESH_GROUP
            conda:
                "../envs/signorini.yaml"
            resources:
                mem_mb=lambda wc, scene=_scene: resources.mem_mb(
                    "norm", sized_N(wc, scene)
                ),
                runtime=lambda wc, norms=_norms, scene=_scene: resources.norms_runtime_min(
                    sized_N(wc, scene), norms
                ),
            params:
                problem=scene_of(_scene)["problem"],
                diagonal=scene_of(_scene)["diagonal"],
                mesh=scene_of(_scene)["mesh"],
                conventions=scene_of(_scene)["conventions"],
            script:
                "../scripts/norm.py"

        workflow.ruleorder(NORMS_RULE.format(_scene), "norm")
        # Snakemake's code trigger compares a rule's source text, here the script line, which
        # differs from norm's only by its indentation: the same script, so the same code
        patches.share_code_source(
            workflow.get_rule(NORMS_RULE.format(_scene)), workflow.get_rule("norm")
        )


rule errors:
    """The scene's errors.csv: one row per N, one column per norm."""
    input:
        norms=lambda wc: flat(norm_jsons(wc.scene, scene_of(wc)["norms"])),
        code=code("errors"),
    output:
        # in the report as the scene's page (report.smk): a flagged output must exist
        # whenever a job of it is in the DAG, which would bar the committed findings of a study
        # whose scene was never computed here
        csv=PATHS["errors_csv"],
    log:
        paths.log("scene", "errors"),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_param("N"),
        norm_jsons=lambda wc: norm_jsons(wc.scene, scene_of(wc)["norms"]),
    script:
        "../scripts/errors.py"


rule eoc:
    """The scene's eoc.csv: EOCs of consecutive meshes and the regression slope."""
    input:
        errors=rules.errors.output.csv,
        code=code("eoc"),
    output:
        csv=PATHS["eoc_csv"],  # in the report as the scene's page, as errors.csv
    log:
        paths.log("scene", "eoc"),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    script:
        "../scripts/eoc.py"


rule vtk:
    """One solution as results/<scene>/N<N>/solution.vtu for ParaView (opt-in, not part of all)."""
    input:
        solution=rules.solve.output.npz,
        mesh=family_mesh(),
        code=code("vtk"),
    output:
        vtu=PATHS["solution_vtu"],
    log:
        paths.log("mesh", "vtk"),
    conda:
        "../envs/signorini.yaml"
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
    script:
        "../scripts/vtk.py"
