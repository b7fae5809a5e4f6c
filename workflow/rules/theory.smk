# Beyond the paper (issue 7): supercloseness, discrete H^{1/2}(boundary) norm and contact-set
# metrics per mesh, then the findings, table and figures of the `theory` scene.
# `snakemake -c2 theory` builds them; not part of `all`.

THEORY = "theory"
THEORY_OUTPUTS = [
    f"{FIGDIR}/theory.md",
    f"{FIGDIR}/theory.csv",
    *expand(
        f"{FIGDIR}/{{name}}.{{ext}}",
        name=["theory_rates", "theory_extra"],
        ext=["pdf", "png"],
    ),
]


rule theory_quantities:
    input:
        solution=PATHS["solution_npz"],
        code=code("theory"),
        script="workflow/scripts/theory_quantities.py",
    output:
        PATHS["theory_json"],
    log:
        "results/{scene}/logs/N{N}/theory.log",
    benchmark:
        "results/{scene}/benchmarks/N{N}/theory.tsv"
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=lambda wc: 1000 + int(wc.N) ** 2 // 500,  # 4.7 GB at N = 1001 before chunking
        runtime=lambda wc: 5 + int(wc.N) ** 2 // 50000,
    params:
        problem=lambda wc: scene_of(wc)["problem"],
        diagonal=lambda wc: scene_of(wc).get("diagonal", "sw_ne"),
    script:
        "../scripts/theory_quantities.py"


rule theory_report:
    input:
        errors=PATHS["errors_csv"].format(scene=THEORY),
        theory=lambda wc: expand(
            PATHS["theory_json"], scene=THEORY, N=scene_of(THEORY)["N"]
        ),
        code=code("theory_report"),
        script="workflow/scripts/theory_report.py",
    output:
        md=f"{FIGDIR}/theory.md",
        csv=f"{FIGDIR}/theory.csv",
        rates_pdf=f"{FIGDIR}/theory_rates.pdf",
        rates_png=f"{FIGDIR}/theory_rates.png",
        extra_pdf=f"{FIGDIR}/theory_extra.pdf",
        extra_png=f"{FIGDIR}/theory_extra.png",
    log:
        f"results/{THEORY}/logs/theory_report.log",
    conda:
        "../envs/signorini.yaml"
    threads: 1
    resources:
        mem_mb=1000,
        runtime=5,
    script:
        "../scripts/theory_report.py"


rule theory:
    input:
        THEORY_OUTPUTS,
    localrule: True
