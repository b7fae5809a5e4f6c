"""rule work_precision_report: paper_figures/work_precision.md (the findings in numbers)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.work_precision.report import report_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    params = snakemake.params
    report_stage(i.csv, i.paper_table1, i.paper_table2, snakemake.output.md, source=params.source, timing=params.timing)
