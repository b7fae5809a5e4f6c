"""rule work_precision_figures: work_precision.{pdf,png} and cost_of_accuracy.{pdf,png}."""

from signorini.figures import cost_of_accuracy, work_precision_figure
from signorini.pipeline import job_log
from signorini.work_precision import read_measurements

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake.log[0]):
    o = snakemake.output
    df = read_measurements(snakemake.input.csv)
    work_precision_figure(df, snakemake.params.figure_N, o.pdf, o.png)
    cost_of_accuracy(df, o.cost_pdf, o.cost_png)
