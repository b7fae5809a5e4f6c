"""rule figure3: paper_figures/figure3.{pdf,png} (L4 and W14 errors against h)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.figures import figure3_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p, o = snakemake.params, snakemake.output
    figure3_stage(p.N, p.norm_jsons, o.pdf, o.png)
