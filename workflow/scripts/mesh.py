"""rule mesh: the triangulation of one scene and N of a scene that names a mesh family."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.mesh import mesh_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    mesh_stage(SceneMesh.of_job(snakemake), snakemake.output.npz, snakemake.output.json, snakemake.output.vtu)
