"""rule reproduction: paper_figures/reproduction.md (ours | paper | relative deviation)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.reproduction import reproduction_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    reproduction_stage(
        i.table1,
        i.table2,
        i.paper_table1,
        i.paper_table2,
        i.remarks,
        snakemake.output.md,
        i.h12_boundary,
        conventions=i.conventions,
        load_rule=i.load_rule,
    )
