"""rule figure2: paper_figures/figure2.{pdf,png} (u and f)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.figures import figure2_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    figure2_stage(snakemake.input.fields[0], snakemake.output.pdf, snakemake.output.png)
