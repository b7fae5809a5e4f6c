# Numerical stability atlas (issue 5): every case of the `stability` scene's `atlas` block
# solved by every solver column, one job per case (a failing solver is recorded, never
# fatal), then the table, report and figure.  `snakemake -c2 stability` builds
# paper_figures/stability.{csv,md,pdf,png}; not part of `all`.
from signorini import stability

STAB = "stability"  # the scene rendered into paper_figures/stability.*
STAB_PATHS = {
    "case_json": "results/{scene}/atlas/{case}.json",
    "case_npz": "results/{scene}/atlas/{case}.npz",
}
STAB_OUTPUTS = [f"{FIGDIR}/stability.{ext}" for ext in ("csv", "md", "pdf", "png")]

stability.check_atlases(config)  # case names, groups, problems, solver columns

# A damaged cached case artifact is moved aside (and rebuilt), as in common.smk.
if workflow.is_main_process:
    pipeline.quarantine_corrupt(
        p
        for name, scene in config["scenes"].items()
        if "atlas" in scene
        for ext in ("json", "npz")
        for p in Path("results", name, "atlas").glob(f"*.{ext}")
    )


rule stability_case:
    input:
        code=code("stability_case"),
        script="workflow/scripts/stability_case.py",
    output:
        json=STAB_PATHS["case_json"],
        npz=STAB_PATHS["case_npz"],
    log:
        "results/{scene}/logs/atlas/{case}.log",
    benchmark:
        "results/{scene}/benchmarks/atlas/{case}.tsv"
    wildcard_constraints:
        case=r"[A-Za-z0-9_.+-]+",
    # the largest meshes first: they are the critical path
    priority: lambda wc: stability.scene_atlas(config, wc.scene).case(wc.case).N
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: 1500
        + stability.scene_atlas(config, wc.scene).case(wc.case).N ** 2 // 150,
        runtime=lambda wc: stability.scene_atlas(config, wc.scene).runtime_min(wc.case),
    params:
        # the case, its solver columns, norms and limits: editing a case reruns its job only
        job=lambda wc: stability.scene_atlas(config, wc.scene).job(wc.case),
    script:
        "../scripts/stability_case.py"


rule stability_atlas:
    input:
        jsons=lambda wc: stability.case_artifacts(config, STAB, STAB_PATHS["case_json"]),
        npzs=lambda wc: stability.case_artifacts(config, STAB, STAB_PATHS["case_npz"]),
        code=code("stability_atlas"),
        script="workflow/scripts/stability_atlas.py",
    output:
        csv=f"{FIGDIR}/stability.csv",
        md=f"{FIGDIR}/stability.md",
        pdf=f"{FIGDIR}/stability.pdf",
        png=f"{FIGDIR}/stability.png",
    log:
        f"results/{STAB}/logs/atlas.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=2000,
        runtime=10,
    params:
        norms=lambda wc: list(stability.scene_atlas(config, STAB).norms),
        solvers=lambda wc: list(stability.scene_atlas(config, STAB).solvers),
    script:
        "../scripts/stability_atlas.py"


rule stability:
    input:
        STAB_OUTPUTS,
    localrule: True
