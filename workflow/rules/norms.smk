# Stage 2: one norm of u - u_h per job (scene, N, norm), so a target computes only the
# norms it needs (figure3 asks for L4 and W14 only).


rule norm:
    input:
        solution=PATHS["solution_npz"],
        code=code("norm"),
        script="workflow/scripts/norm.py",
    output:
        PATHS["norm_json"],
    log:
        "results/{scene}/logs/N{N}/norm_{norm}.log",
    benchmark:
        "results/{scene}/benchmarks/N{N}/norm_{norm}.tsv"
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: 500 + int(wc.N) ** 2 // 2000,  # measured: 0.4 GB at N = 1001
        runtime=lambda wc: 5 + int(wc.N) ** 2 // 50000,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        diagonal=lambda wc: scene_of(wc).get("diagonal", "sw_ne"),
        conventions=lambda wc: scene_of(wc).get("conventions", {}),
    script:
        "../scripts/norm.py"
