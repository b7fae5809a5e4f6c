"""rule summary: paper_figures/summary.md (the findings of every study, each with its strength)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.summary import summary_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    summary_stage(dict(snakemake.input), dict(p.sources), p.captions, snakemake.output.md)
