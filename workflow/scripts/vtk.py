"""rule vtk: results/<scene>/N<N>/solution.vtu (u_h, u, error, λ, contact set) for ParaView."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.store import SceneMesh
from signorini.studies.scene.vtk import vtk_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    vtk_stage(SceneMesh.of_job(snakemake), snakemake.input.solution, snakemake.output.vtu)
