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


rule free_point_error:
    """|u - u_h| near the free point (x0, 0) on the rendered scene's coarsest mesh, with the point sets
    of the conventions' maxima."""
    input:
        solution=expand(rules.solve.output.npz, scene=FIG, N=scene_of(FIG)["N"][0]),
        code=code("free_point_error"),
    output:
        **reported(
            FIGURES["free_point_error"], "free_point_error", "Paper", "True norms"
        ),
    log:
        paths.log("scene", "free_point_error", scene=FIG),
    conda:
        "../envs/signorini.yaml"
    params:
        N=scene_of(FIG)["N"][0],
        problem=scene_of(FIG)["problem"],
        diagonal=scene_of(FIG)["diagonal"],
        conventions=scene_of(FIG)["conventions"],
    script:
        "../scripts/free_point_error.py"


rule true_norms:
    """The true norms beside the paper's conventions: paper_figures/table{1,2}_true.{csv,md}."""
    input:
        target_outputs("true_norms"),
    localrule: True


# Table 2 continued on a scene's finer meshes (fine_tables: to h = 1/4001; finest_tables: to 1/8001)
for _scene in (FINE, FINEST):

    rule:
        """Table 2 continued on a scene's meshes: conventions, true norms and their EOCs."""
        name:
            f"{_scene}_tables"
        input:
            norms=flat(true_table_norms(_scene)),
            paper_table1=REFERENCES["paper_table1"],
            code=code("fine_tables"),
        output:
            **reported(
                FIGURES[f"{_scene}_tables"],
                f"{_scene}_tables",
                "Theory",
                "Finer meshes",
            ),
        log:
            paths.log("scene", f"{_scene}_tables", scene=_scene),
        conda:
            "../envs/signorini.yaml"
        params:
            scene=_scene,
            N=scene_of(_scene)["N"],
            norm_jsons=true_table_norms(_scene),
        script:
            "../scripts/fine_tables.py"


rule eoc_against_h:
    """The EOCs of Table 2's seven norms against h, h = 1/101 ... 1/4001, with the expected orders."""
    input:
        true_table1=rules.true_tables.output.table1_csv,
        fine_table1=rules.fine_tables.output.table1_csv,
        code=code("eoc_against_h"),
    output:
        **reported(FIGURES["eoc_against_h"], "eoc_against_h", "Theory", "Finer meshes"),
    log:
        paths.log("scene", "eoc_against_h", scene=FINE),
    localrule: True
    conda:
        "../envs/signorini.yaml"
    script:
        "../scripts/eoc_against_h.py"


rule fine:
    """Table 2 continued to h = 1/4001: paper_figures/table{1,2}_fine.{csv,md}."""
    input:
        target_outputs("fine"),
    localrule: True


rule finest:
    """Table 2 one mesh further, to h = 1/8001 (L4, W14, H12): paper_figures/table{1,2}_finest.{csv,md}."""
    input:
        target_outputs("finest"),
    localrule: True
