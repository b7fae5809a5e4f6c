"""rule stability_atlas: paper_figures/stability.{csv,md,pdf,png} from the case artifacts."""

from signorini.pipeline.joblog import job_log
from signorini.studies.stability.report import atlas_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p, i = snakemake.params, snakemake.input
    atlas_stage(p.norms, p.solvers, i.jsons, i.npzs, snakemake.output, p.solver_specs)
