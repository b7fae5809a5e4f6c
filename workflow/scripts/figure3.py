"""rule figure3: paper_figures/figure3.{pdf,png} (L4 and W14 errors against h)."""

from signorini.figures import figure3
from signorini.pipeline import job_log, read_errors

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    figure3(read_errors(snakemake.params.N, snakemake.params.norm_jsons), snakemake.output.pdf, snakemake.output.png)
