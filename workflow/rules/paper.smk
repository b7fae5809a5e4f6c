# The paper's study, rendered from the scene `figures_scene` (default: paper): Tables 1-2,
# Figures 2-3, the reproduction report and the run times in paper_figures/.
# Every rule here is a local rule: seconds of reading and rendering, which on a cluster run on
# the submitting node instead of paying a queue round trip each.


rule sample:
    """u and f on a grid of the unit square: the data of Figure 2."""
    input:
        code=code("sample"),
    output:
        npz=PATHS["fields_npz"],
    log:
        paths.log("scene", "sample"),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        problem=scene_param("problem"),
    script:
        "../scripts/sample.py"


rule table1:
    """Table 1: the absolute errors (CSV, Markdown, LaTeX)."""
    input:
        norms=flat(norm_jsons(FIG, TABLE1_NORMS)),
        code=code("table1"),
    output:
        **reported(FIGURES["table1"], "table1", "Paper", "Tables"),
    log:
        paths.log("scene", "table1", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=norm_jsons(FIG, TABLE1_NORMS),
    script:
        "../scripts/table1.py"


rule table2:
    """Table 2: the EOCs, the regression slope and the expected orders."""
    input:
        eoc=expand(rules.eoc.output.csv, scene=FIG),
        norms=flat(norm_jsons(FIG, TABLE2_NORMS)),
        code=code("table2"),
    output:
        **reported(FIGURES["table2"], "table2", "Paper", "Tables"),
    log:
        paths.log("scene", "table2", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=norm_jsons(FIG, TABLE2_NORMS),
    script:
        "../scripts/table2.py"


rule figure2:
    """Figure 2: the solution u and the right-hand side f."""
    input:
        fields=expand(rules.sample.output.npz, scene=FIG),
        code=code("figure2"),
    output:
        **reported(FIGURES["figure2"], "figure2", "Paper", "Figures"),
    log:
        paths.log("scene", "figure2", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    script:
        "../scripts/figure2.py"


rule figure3:
    """Figure 3: the L4 and W14 errors against h with their expected slopes."""
    input:
        norms=flat(norm_jsons(FIG, FIGURE3_NORMS)),
        code=code("figure3"),
    output:
        **reported(FIGURES["figure3"], "figure3", "Paper", "Figures"),
    log:
        paths.log("scene", "figure3", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=norm_jsons(FIG, FIGURE3_NORMS),
    script:
        "../scripts/figure3.py"


rule h12_boundary:
    """The H^{1/2} error of the rendered scene's meshes with whole-edge and split boundary rules."""
    input:
        solutions=expand(rules.solve.output.npz, scene=FIG, N=scene_of(FIG)["N"]),
        code=code("h12_boundary"),
    output:
        csv=PATHS["h12_boundary_csv"].format(scene=FIG),
    log:
        paths.log("scene", "h12_boundary", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        problem=scene_of(FIG)["problem"],
        diagonal=scene_of(FIG)["diagonal"],
        conventions=scene_of(FIG)["conventions"],
    script:
        "../scripts/h12_boundary.py"


rule load_rule:
    """Table 1's norms with the load vector integrated by the norms' 16-point rule, as the paper states."""
    input:
        systems=expand(rules.discretise.output.npz, scene=FIG, N=scene_of(FIG)["N"]),
        norms=flat(norm_jsons(FIG, TABLE1_NORMS)),
        code=code("load_rule"),
    output:
        csv=PATHS["load_rule_csv"].format(scene=FIG),
    log:
        paths.log("scene", "load_rule", scene=FIG),
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        problem=scene_of(FIG)["problem"],
        diagonal=scene_of(FIG)["diagonal"],
        conventions=scene_of(FIG)["conventions"],
        norm_jsons=norm_jsons(FIG, TABLE1_NORMS),
    script:
        "../scripts/load_rule.py"


rule reproduction:
    """Every published cell of Tables 1-2: ours, the paper's, the relative deviation."""
    input:
        **REFERENCES,
        table1=rules.table1.output.csv,
        table2=rules.table2.output.csv,
        h12_boundary=rules.h12_boundary.output.csv,
        load_rule=rules.load_rule.output.csv,
        code=code("reproduction"),
    output:
        **reported(FIGURES["reproduction"], "reproduction", "Paper", "Reproduction"),
    log:
        paths.log("scene", "reproduction", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    script:
        "../scripts/reproduction.py"


rule runtime:
    """Run times of the rendered scene's discretise, solve and norm jobs."""
    input:
        benchmarks=[job["benchmark"] for job in runtime_jobs(FIG)],
        artifacts=[path for job in runtime_jobs(FIG) for path in job["artifacts"]],
        code=code("runtime"),
    output:
        **reported(FIGURES["runtime"], "runtime", "Paper", "Run times"),
    log:
        paths.log("scene", "runtime", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        jobs=runtime_jobs(FIG),
    script:
        "../scripts/runtime.py"


# the findings of the other studies, read from their committed outputs: parameters with their
# digest (an edited source reruns the summary), not inputs, so that `all` never recomputes a study.
# A run that renders another study anew may render it after the summary; the digest has changed
# then, and the next `snakemake all` renders the summary from it.
from signorini.studies import report as report_lib

# the figures' captions, relative to the working directory as every path of a parameter (an
# absolute one would change with the checkout's location and rerun the summary in a copy)
CAPTIONS = os.path.relpath(os.path.join(workflow.basedir, "workflow", "report"))
SUMMARY_SOURCES = {
    "table1_true": FIGURES["true_tables"]["table1_csv"],
    "table2_true": FIGURES["true_tables"]["table2_csv"],
    "table1_fine": FIGURES["fine_tables"]["table1_csv"],
    "table2_fine": FIGURES["fine_tables"]["table2_csv"],
    "table1_finest": FIGURES["finest_tables"]["table1_csv"],
    "theory": FIGURES["theory_report"]["csv"],
    "theory_rates": FIGURES["theory_report"]["rates_csv"],
    "contact_set": FIGURES["contact_set"]["csv"],
    "work_precision": FIGURES["work_precision_table"]["csv"],
    "stability": FIGURES["stability_atlas"]["csv"],
    "meshes": FIGURES["meshes_report"]["csv"],
}


rule summary:
    """The findings of every study in one page, each with its strength: paper_figures/summary.md."""
    input:
        **REFERENCES,
        table1=rules.table1.output.csv,
        table2=rules.table2.output.csv,
        h12_boundary=rules.h12_boundary.output.csv,
        load_rule=rules.load_rule.output.csv,
        code=code("summary"),
    output:
        **reported(FIGURES["summary"], "summary", "Findings"),
    log:
        paths.log("scene", "summary", scene=FIG),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    params:
        sources=SUMMARY_SOURCES,
        captions=CAPTIONS,
        digest=lambda wc: report_lib.digest(
            *SUMMARY_SOURCES.values(), *sorted(Path(CAPTIONS).glob("*.rst"))
        ),
    script:
        "../scripts/summary.py"


# what `all` builds: every output of the paper's rules, and the rendered scene's tables
PAPER_OUTPUTS = [
    *target_outputs("all"),
    *expand(rules.errors.output.csv, scene=FIG),
    *expand(rules.eoc.output.csv, scene=FIG),
]
