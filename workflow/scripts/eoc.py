"""rule eoc: results/<scene>/eoc.csv (EOCs and regression slope) from errors.csv."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.eoc import eoc_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    eoc_stage(snakemake.input.errors, snakemake.output.csv)
