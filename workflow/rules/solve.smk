# Stage 1: mesh + assembly + solve of (S_h), one job per scene and N.


rule solve:
    input:
        code=code("solve"),
        script="workflow/scripts/solve.py",
    output:
        npz=PATHS["solution_npz"],
        json=PATHS["solution_json"],
    log:
        "results/{scene}/logs/N{N}/solve.log",
    benchmark:
        "results/{scene}/benchmarks/N{N}/solve.tsv"
    # the largest solves first: they are the critical path (norm jobs default to 0)
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: 500 + int(wc.N) ** 2 // 250,
        runtime=lambda wc: 5 + int(wc.N) ** 2 // 10000,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        solver=lambda wc: scene_of(wc)["solver"],
        solver_options=lambda wc: scene_of(wc).get("solver_options", {}),
        diagonal=lambda wc: scene_of(wc).get("diagonal", "sw_ne"),
    script:
        "../scripts/solve.py"


rule sample:
    input:
        code=code("sample"),
        script="workflow/scripts/sample.py",
    output:
        PATHS["fields_npz"],
    log:
        "results/{scene}/logs/sample.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=500,
        runtime=5,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        n=161,
    script:
        "../scripts/sample.py"
