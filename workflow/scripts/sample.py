"""rule sample: u and f on a grid of the unit square (data of Figure 2)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.sample import GRID, sample_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    sample_stage(snakemake.params.problem, GRID, snakemake.output.npz)
