"""rule figure2: paper_figures/figure2.{pdf,png} (u and f)."""

from signorini.artifacts import load_npz
from signorini.figures import figure2
from signorini.pipeline import job_log

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    figure2(load_npz(snakemake.input.fields), snakemake.output.pdf, snakemake.output.png)
