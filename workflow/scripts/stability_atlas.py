"""rule stability_atlas: paper_figures/stability.{csv,md,pdf,png} from the case artifacts."""

from signorini.pipeline import job_log
from signorini.stability_report import atlas_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    atlas_stage(
        snakemake.params.norms,
        snakemake.params.solvers,
        snakemake.input.jsons,
        snakemake.input.npzs,
        snakemake.output.csv,
        snakemake.output.md,
        snakemake.output.pdf,
        snakemake.output.png,
    )
