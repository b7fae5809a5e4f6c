# Stage 3: scene-level tables (errors.csv, eoc.csv) and the paper's tables and figures.


rule errors:
    input:
        norms=lambda wc: flat(norm_jsons(wc.scene, scene_of(wc)["norms"])),
        code=code("errors"),
        script="workflow/scripts/errors.py",
    output:
        PATHS["errors_csv"],
    log:
        "results/{scene}/logs/errors.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        N=lambda wc: scene_of(wc)["N"],
        norm_jsons=lambda wc: norm_jsons(wc.scene, scene_of(wc)["norms"]),
    script:
        "../scripts/errors.py"


rule eoc:
    input:
        errors=PATHS["errors_csv"],
        code=code("eoc"),
        script="workflow/scripts/eoc.py",
    output:
        PATHS["eoc_csv"],
    log:
        "results/{scene}/logs/eoc.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    script:
        "../scripts/eoc.py"


rule table1:
    input:
        norms=flat(norm_jsons(FIG, TABLE1_NORMS)),
        code=code("tables"),
        script="workflow/scripts/table1.py",
    output:
        csv=f"{FIGDIR}/table1.csv",
        md=f"{FIGDIR}/table1.md",
        tex=f"{FIGDIR}/table1.tex",
    log:
        f"results/{FIG}/logs/table1.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=norm_jsons(FIG, TABLE1_NORMS),
    script:
        "../scripts/table1.py"


rule table2:
    input:
        eoc=PATHS["eoc_csv"].format(scene=FIG),
        code=code("tables"),
        script="workflow/scripts/table2.py",
    output:
        csv=f"{FIGDIR}/table2.csv",
        md=f"{FIGDIR}/table2.md",
        tex=f"{FIGDIR}/table2.tex",
    log:
        f"results/{FIG}/logs/table2.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        N=scene_of(FIG)["N"],
    script:
        "../scripts/table2.py"


rule figure2:
    input:
        fields=PATHS["fields_npz"].format(scene=FIG),
        code=code("figures"),
        script="workflow/scripts/figure2.py",
    output:
        pdf=f"{FIGDIR}/figure2.pdf",
        png=f"{FIGDIR}/figure2.png",
    log:
        f"results/{FIG}/logs/figure2.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/figure2.py"


rule figure3:
    input:
        norms=flat(norm_jsons(FIG, FIGURE3_NORMS)),
        code=code("figures"),
        script="workflow/scripts/figure3.py",
    output:
        pdf=f"{FIGDIR}/figure3.pdf",
        png=f"{FIGDIR}/figure3.png",
    log:
        f"results/{FIG}/logs/figure3.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=norm_jsons(FIG, FIGURE3_NORMS),
    script:
        "../scripts/figure3.py"


rule reproduction:
    input:
        table1=f"{FIGDIR}/table1.csv",
        table2=f"{FIGDIR}/table2.csv",
        paper_table1="workflow/reference/paper_table1.csv",
        paper_table2="workflow/reference/paper_table2.csv",
        remarks="workflow/reference/deviation_remarks.md",
        code=code("reproduction"),
        script="workflow/scripts/reproduction.py",
    output:
        f"{FIGDIR}/reproduction.md",
    log:
        f"results/{FIG}/logs/reproduction.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    script:
        "../scripts/reproduction.py"


RUNTIME_NORMS = list(
    dict.fromkeys([*scene_of(FIG)["norms"], *TABLE1_NORMS, *FIGURE3_NORMS])
)
RUNTIME_JOBS = [
    {
        "rule": "solve",
        "scene": FIG,
        "N": N,
        "norm": "",
        "benchmark": f"results/{FIG}/benchmarks/N{N}/solve.tsv",
        "artifact": PATHS["solution_json"].format(scene=FIG, N=N),
    }
    for N in scene_of(FIG)["N"]
] + [
    {
        "rule": "norm",
        "scene": FIG,
        "N": N,
        "norm": n,
        "benchmark": f"results/{FIG}/benchmarks/N{N}/norm_{n}.tsv",
        "artifact": PATHS["norm_json"].format(scene=FIG, N=N, norm=n),
    }
    for N in scene_of(FIG)["N"]
    for n in RUNTIME_NORMS
]


rule runtime:
    input:
        benchmarks=[job["benchmark"] for job in RUNTIME_JOBS],
        artifacts=[job["artifact"] for job in RUNTIME_JOBS],
        code=code("runtime"),
        script="workflow/scripts/runtime.py",
    output:
        f"{FIGDIR}/runtime.csv",
    log:
        f"results/{FIG}/logs/runtime.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        jobs=RUNTIME_JOBS,
    script:
        "../scripts/runtime.py"
