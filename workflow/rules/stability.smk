# Beyond the paper: the numerical stability atlas.  Every case of the `stability` scene's `atlas`
# block solved by every solver column, one job per case (a failing solver is recorded, never
# fatal), then the table, report and figure.  `snakemake -c2 stability` builds
# paper_figures/stability.{csv,md,pdf,png}; not part of `all`.


rule stability_case:
    """One case of the stability atlas solved by every solver column."""
    input:
        code=code("stability_case"),
    output:
        json=PATHS["atlas_case_json"],
        npz=PATHS["atlas_case_npz"],
    log:
        paths.log("case", "atlas"),
    benchmark:
        paths.benchmark("case", "atlas")
    wildcard_constraints:
        case=r"[A-Za-z0-9_.+-]+",
    # the largest meshes first: they are the critical path
    priority: lambda wc: atlas_of(wc.scene).case(wc.case).N
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=lambda wc: 1500 + atlas_of(wc.scene).case(wc.case).N ** 2 // 150,
        runtime=lambda wc: atlas_of(wc.scene).runtime_min(wc.case),
    params:
        # the case, its solver columns, norms and limits: editing a case reruns its job only
        job=lambda wc: atlas_of(wc.scene).job(wc.case),
    script:
        "../scripts/stability_case.py"


rule stability_atlas:
    """The atlas's table, report and figure from every case."""
    input:
        jsons=lambda wc: stab_atlas.case_artifacts(
            config, STAB, rules.stability_case.output.json
        ),
        npzs=lambda wc: stab_atlas.case_artifacts(
            config, STAB, rules.stability_case.output.npz
        ),
        code=code("stability_atlas"),
    output:
        **reported(FIGURES["stability_atlas"], "stability", "Stability"),
    log:
        paths.log("scene", "atlas", scene=STAB),
    conda:
        "../envs/signorini.yaml"
    resources:
        mem_mb=2000,
        runtime=10,
    params:
        norms=lambda wc: list(atlas_of(STAB).norms),
        solvers=lambda wc: list(atlas_of(STAB).solvers),
        # each column's route, options and tolerance: what the report's explanations read
        solver_specs=lambda wc: {
            label: {
                "label": spec.label,
                "solver": spec.solver,
                "options": dict(spec.options),
                "kkt_tol": spec.kkt_tol,
            }
            for label, spec in atlas_of(STAB).solvers.items()
        },
    script:
        "../scripts/stability_atlas.py"


rule stability:
    """The stability atlas: paper_figures/stability.{csv,md,pdf,png}."""
    input:
        target_outputs("stability"),
    localrule: True
