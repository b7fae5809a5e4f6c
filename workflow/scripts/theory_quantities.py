"""rule theory_quantities: supercloseness, discrete H^{1/2} norm, contact set for one scene and N."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.store import SceneMesh
from signorini.studies.theory.quantities import quantities_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    i = snakemake.input
    quantities_stage(SceneMesh.of_job(snakemake), i.system, i.solution, snakemake.output.json)
