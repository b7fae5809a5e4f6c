"""rule runtime: paper_figures/runtime.csv from the benchmark: files and in-job timers."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.runtime import runtime_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    runtime_stage(snakemake.params.jobs, snakemake.output.csv)
