# Beyond the paper: supercloseness, the discrete H^{1/2}(boundary) norm and contact-set metrics
# per mesh, then the findings, table and figures of the `theory` scene.
# `snakemake -c2 theory` builds them; not part of `all`.


rule theory_quantities:
    """Supercloseness, discrete H^{1/2}(boundary) norm and contact set of one solution."""
    input:
        system=rules.discretise.output.npz,
        solution=rules.solve.output.npz,
        mesh=family_mesh(),
        code=code("theory_quantities"),
    output:
        json=PATHS["theory_json"],
    log:
        paths.log("mesh", "theory"),
    benchmark:
        paths.benchmark("mesh", "theory")
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=lambda wc: resources.mem_mb("theory_quantities", sized_N(wc)),
        runtime=lambda wc: resources.runtime_min("theory_quantities", sized_N(wc)),
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        mesh=scene_param("mesh"),
    script:
        "../scripts/theory_quantities.py"


rule contact_set:
    """The discrete contact sets of the theory scene against the exact one; condition (A_h) per mesh."""
    input:
        solutions=lambda wc: expand(
            rules.solve.output.npz, scene=THEORY, N=scene_of(THEORY)["N"]
        ),
        code=code("contact_set"),
    output:
        **reported(FIGURES["contact_set"], "contact_set", "Theory", "Contact set"),
    log:
        paths.log("scene", "contact_set", scene=THEORY),
    conda:
        "../envs/signorini.yaml"
    params:
        N=lambda wc: scene_of(THEORY)["N"],
        problem=lambda wc: scene_of(THEORY)["problem"],
        diagonal=lambda wc: scene_of(THEORY)["diagonal"],
    script:
        "../scripts/contact_set.py"


rule theory_report:
    """The theory scene's findings, per-mesh table, rates data and figures (rates against p,
    supercloseness, the ends of the contact sets)."""
    input:
        errors=expand(rules.errors.output.csv, scene=THEORY),
        theory=lambda wc: expand(
            rules.theory_quantities.output.json, scene=THEORY, N=scene_of(THEORY)["N"]
        ),
        true_norms=lambda wc: flat(theory_true_norms()),
        contact_set=rules.contact_set.output.csv,
        code=code("theory_report"),
    output:
        **reported(FIGURES["theory_report"], "theory", "Theory"),
    log:
        paths.log("scene", "theory_report", scene=THEORY),
    conda:
        "../envs/signorini.yaml"
    params:
        true_norm_jsons=lambda wc: theory_true_norms(),
    script:
        "../scripts/theory_report.py"


rule theory:
    """The theory scene: paper_figures/theory.{md,csv}, theory_rates.*, theory_extra.*, contact_set.*."""
    input:
        target_outputs("theory"),
    localrule: True
