# Beyond the paper: every solver configuration of a scene's `study` block at a sweep of
# tolerances, on the meshes of the source scene (whose assembled systems, exact solutions and
# norm artifacts are reused).  `snakemake -c2 work_precision` builds paper_figures/
# work_precision.* and cost_of_accuracy.*; not part of `all`.


rule work_precision_measure:
    """One solver configuration of the study at all its tolerances on one mesh."""
    input:
        system=wp_source(rules.discretise.output.npz),
        system_json=wp_source(rules.discretise.output.json),
        exact=wp_source(rules.solve.output.npz),
        disc=lambda wc: list(wp_disc_norms(wc).values()),
        prev=wp_previous,
        code=code("work_precision_measure"),
        # a PETSc peer's driver runs outside the package: an edit reruns the peers' jobs only
        peer_driver=wp_peer_driver,
    output:
        json=PATHS["wp_measure_json"],
    log:
        paths.log("mesh", "work_precision_{solver}"),
    benchmark:
        paths.benchmark("mesh", "work_precision_{solver}")
    wildcard_constraints:
        solver=r"[a-z0-9_]+",
    # the finest meshes first: their jobs are the longest
    priority: lambda wc: int(wc.N)
    conda:
        "../envs/signorini.yaml"
    resources:
        # measured max RSS: 0.6-1.0 GB up to N = 501 (HiGHS at N = 101: 0.9 GB)
        mem_mb=lambda wc: resources.mem_mb("work_precision_measure", wc.N),
        runtime=lambda wc: 5
        + (len(study_of(wc)["tolerances"]) + 1)
        * int(study_of(wc).get("time_limit_s", 600))
        // 60,
    params:
        problem=scene_param("problem"),
        diagonal=scene_param("diagonal"),
        conventions=scene_param("conventions"),
        config=lambda wc: wp_configs(wc)[wc.solver].as_dict(),
        tolerances=lambda wc: study_of(wc)["tolerances"],
        time_limit_s=lambda wc: study_of(wc).get("time_limit_s"),
        growth_exponent=lambda wc: study_of(wc).get(
            "growth_exponent", wp_study.GROWTH_EXPONENT
        ),
        disc_norm_jsons=wp_disc_norms,
        peer_python=lambda wc: study_of(wc).get("peer_python", PEER_PYTHON),
        timing=lambda wc: study_of(wc).get("timing", {}),
    script:
        "../scripts/work_precision_measure.py"


rule work_precision_table:
    """Every measurement of the study in one table."""
    input:
        jsons=lambda wc: wp_measure_jsons(WP),
        code=code("work_precision_table"),
    output:
        **reported(FIGURES["work_precision_table"], "work_precision", "Work precision"),
    log:
        paths.log("scene", "work_precision_table", scene=WP),
    conda:
        "../envs/signorini.yaml"
    script:
        "../scripts/work_precision_table.py"


rule work_precision_figures:
    """Algebraic error against solve time per solver, and the cost of accuracy."""
    input:
        csv=rules.work_precision_table.output.csv,
        code=code("work_precision_figures"),
    output:
        **reported(
            FIGURES["work_precision_figures"], "work_precision", "Work precision"
        ),
    log:
        paths.log("scene", "work_precision_figures", scene=WP),
    conda:
        "../envs/signorini.yaml"
    params:
        figure_N=lambda wc: study_of(WP).get("figure_N", []),
    script:
        "../scripts/work_precision_figures.py"


rule work_precision_report:
    """The study's findings in numbers, against the published Tables 1-2."""
    input:
        csv=rules.work_precision_table.output.csv,
        paper_table1=REFERENCES["paper_table1"],
        paper_table2=REFERENCES["paper_table2"],
        # and the report's prose, a file of the package that no import names (study.REPORT_TEMPLATE)
        code=[*code("work_precision_report"), os.path.relpath(wp_study.REPORT_TEMPLATE)],
    output:
        **reported(FIGURES["work_precision_report"], "work_precision", "Work precision"),
    log:
        paths.log("scene", "work_precision_report", scene=WP),
    conda:
        "../envs/signorini.yaml"
    params:
        source=lambda wc: study_of(WP)["source"],
        timing=lambda wc: study_of(WP).get("timing", {}),
    script:
        "../scripts/work_precision_report.py"


rule work_precision:
    """The work-precision study: paper_figures/work_precision.* and cost_of_accuracy.*."""
    input:
        target_outputs("work_precision"),
    localrule: True
