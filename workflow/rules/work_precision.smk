# Work-precision study (issue 4): every solver configuration of a scene's `study` block at a
# sweep of tolerances, on the meshes of the source scene (whose exact solutions and norm
# artifacts are reused).  `snakemake -c2 work_precision` builds paper_figures/work_precision.*
# and cost_of_accuracy.*; not part of `all`.
include: "work_precision_common.smk"


rule work_precision_system:
    input:
        code=code("work_precision_system"),
        script="workflow/scripts/work_precision_system.py",
    output:
        npz=WP_PATHS["system_npz"],
        json=WP_PATHS["system_json"],
    log:
        "results/{scene}/logs/N{N}/work_precision_system.log",
    benchmark:
        "results/{scene}/benchmarks/N{N}/work_precision_system.tsv"
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: 500 + int(wc.N) ** 2 // 250,
        runtime=lambda wc: 5 + int(wc.N) ** 2 // 10000,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        diagonal=lambda wc: scene_of(wc).get("diagonal", "sw_ne"),
    script:
        "../scripts/work_precision_system.py"


rule work_precision_measure:
    input:
        system=WP_PATHS["system_npz"],
        system_json=WP_PATHS["system_json"],
        exact=lambda wc: wp_source(wc, PATHS["solution_npz"]),
        disc=lambda wc: list(wp_disc_norms(wc).values()),
        prev=wp_previous,
        code=code("work_precision_measure"),
        script="workflow/scripts/work_precision_measure.py",
    output:
        WP_PATHS["measure_json"],
    log:
        "results/{scene}/logs/N{N}/work_precision_{solver}.log",
    benchmark:
        "results/{scene}/benchmarks/N{N}/work_precision_{solver}.tsv"
    wildcard_constraints:
        solver=r"[a-z0-9_]+",
    # the finest meshes first: their jobs are the longest
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        # measured max RSS: 0.6-1.0 GB up to N = 501 (HiGHS at N = 101: 0.9 GB)
        mem_mb=lambda wc: 1500 + int(wc.N) ** 2 // 250,
        runtime=lambda wc: 5
        + (len(study_of(wc)["tolerances"]) + 1)
        * int(study_of(wc).get("time_limit_s", 600))
        // 60,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        config=lambda wc: wp_configs(wc)[wc.solver].as_dict(),
        tolerances=lambda wc: study_of(wc)["tolerances"],
        time_limit_s=lambda wc: study_of(wc).get("time_limit_s"),
        growth_exponent=lambda wc: study_of(wc).get(
            "growth_exponent", wp.GROWTH_EXPONENT
        ),
        disc_norm_jsons=wp_disc_norms,
        diagonal=lambda wc: scene_of(wc).get("diagonal", "sw_ne"),
        conventions=lambda wc: scene_of(wc).get("conventions", {}),
    script:
        "../scripts/work_precision_measure.py"


rule work_precision_table:
    input:
        jsons=lambda wc: wp_measure_jsons(WP),
        code=code("work_precision_table"),
        script="workflow/scripts/work_precision_table.py",
    output:
        f"{FIGDIR}/work_precision.csv",
    log:
        f"results/{WP}/logs/work_precision_table.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    script:
        "../scripts/work_precision_table.py"


rule work_precision_figures:
    input:
        csv=f"{FIGDIR}/work_precision.csv",
        code=code("work_precision_figures"),
        script="workflow/scripts/work_precision_figures.py",
    output:
        pdf=f"{FIGDIR}/work_precision.pdf",
        png=f"{FIGDIR}/work_precision.png",
        cost_pdf=f"{FIGDIR}/cost_of_accuracy.pdf",
        cost_png=f"{FIGDIR}/cost_of_accuracy.png",
    log:
        f"results/{WP}/logs/work_precision_figures.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    params:
        figure_N=lambda wc: study_of(WP).get("figure_N", []),
    script:
        "../scripts/work_precision_figures.py"


rule work_precision_report:
    input:
        csv=f"{FIGDIR}/work_precision.csv",
        paper_table1="workflow/reference/paper_table1.csv",
        paper_table2="workflow/reference/paper_table2.csv",
        code=code("work_precision_report"),
        script="workflow/scripts/work_precision_report.py",
    output:
        f"{FIGDIR}/work_precision.md",
    log:
        f"results/{WP}/logs/work_precision_report.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        source=lambda wc: study_of(WP)["source"],
    script:
        "../scripts/work_precision_report.py"


rule work_precision:
    input:
        WP_OUTPUTS,
    localrule: True
