"""rule discretise: mesh and assembly of (S_h) for one scene and N."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.discretise import discretise_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    discretise_stage(SceneMesh.of_job(snakemake), snakemake.output.npz, snakemake.output.json)
