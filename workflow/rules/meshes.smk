# Beyond the paper: Theorem 6.1 on the mesh families (signorini.fem.mesh_families). The scenes of
# config's meshes_study run the scene chain (a mesh job per N for a family mesh); the report
# compares their rates. `snakemake -c2 meshes` builds paper_figures/meshes.{md,csv} and
# meshes_rates.{pdf,png}; not part of `all`.
MESHES = config.get("meshes_study") or []


def meshes_scene_inputs(name):
    """What the report reads of one scene of the study: its errors, meshes, solutions and true
    norms (paths), and its mesh block, diagonal and problem."""
    scene = scene_of(name)
    Ns = scene["N"]
    family = not paper_mesh(scene["mesh"])

    def each(key):
        return [PATHS[key].format(scene=name, N=N) for N in Ns] if family else []

    return {
        "errors": rules.errors.output.csv.format(scene=name),
        "N": Ns,
        "mesh": scene["mesh"],
        "diagonal": scene["diagonal"],
        "problem": scene["problem"],
        "mesh_jsons": each("mesh_json"),
        "mesh_npzs": each("mesh_npz"),
        "solutions": [rules.solve.output.npz.format(scene=name, N=N) for N in Ns],
        "true_norms": norm_jsons(
            name, [n for n in scene["norms"] if n == true_name(n)]
        ),
    }


def meshes_inputs(wildcards):
    """Every file the report reads, of every scene of the study."""
    paths_ = []
    for name in MESHES:
        spec = meshes_scene_inputs(name)
        paths_ += [
            spec["errors"],
            *spec["mesh_jsons"],
            *spec["mesh_npzs"],
            *spec["solutions"],
        ]
        paths_ += flat(spec["true_norms"])
    return paths_


rule meshes_report:
    """The mesh-family study's findings, rates and figure."""
    input:
        files=meshes_inputs,
        code=code("meshes_report"),
    output:
        **reported(FIGURES["meshes_report"], "meshes", "Theory", "Mesh families"),
    log:
        paths.log("scene", "meshes_report", scene="meshes"),
    conda:
        "../envs/signorini.yaml"
    params:
        scenes=lambda wc: {name: meshes_scene_inputs(name) for name in MESHES},
        reference=lambda wc: MESHES[0] if MESHES else None,
    script:
        "../scripts/meshes_report.py"


rule meshes:
    """The mesh-family study: paper_figures/meshes.{md,csv}, meshes_rates.{pdf,png}."""
    input:
        target_outputs("meshes"),
    localrule: True
