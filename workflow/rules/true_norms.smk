# The norms of Tables 1-2 evaluated to a stated accuracy (<norm>_true, signorini.fem.norms.true)
# on the rendered scene's meshes, beside the paper's conventions and printed values, and the same
# on the finer meshes of the scene `fine`. Not part of `all`: the true norm jobs take seconds to
# half a minute each on the paper's meshes (snakemake -c2 true_norms), minutes at h = 1/4001
# (snakemake -c2 fine).


rule true_tables:
    """table1_true and table2_true: convention, true and published errors, EOCs of the true norms."""
    input:
        norms=flat(true_table_norms()),
        paper_table1=REFERENCES["paper_table1"],
        code=code("true_tables"),
    output:
        **reported(FIGURES["true_tables"], "true_tables", "Paper", "True norms"),
    log:
        paths.log("scene", "true_tables", scene=FIG),
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"],
        norm_jsons=true_table_norms(),
    script:
        "../scripts/true_tables.py"


rule true_norms:
    """The true norms beside the paper's conventions: paper_figures/table{1,2}_true.{csv,md}."""
    input:
        target_outputs("true_norms"),
    localrule: True


rule fine_tables:
    """Table 2 continued on the scene fine's meshes: conventions, true norms and their EOCs."""
    input:
        norms=flat(true_table_norms(FINE)),
        paper_table1=REFERENCES["paper_table1"],
        code=code("fine_tables"),
    output:
        **reported(FIGURES["fine_tables"], "fine_tables", "Theory", "Finer meshes"),
    log:
        paths.log("scene", "fine_tables", scene=FINE),
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FINE)["N"],
        norm_jsons=true_table_norms(FINE),
    script:
        "../scripts/fine_tables.py"


rule fine:
    """Table 2 continued to h = 1/4001: paper_figures/table{1,2}_fine.{csv,md}."""
    input:
        target_outputs("fine"),
    localrule: True
