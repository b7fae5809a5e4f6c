"""rule free_point_error: paper_figures/free_point_error.{pdf,png} (|u − u_h| near the free point)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.free_point import free_point_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    at = SceneMesh(dict(p.problem), int(p.N), str(p.diagonal))
    free_point_stage(at, snakemake.input.solution[0], p.conventions, snakemake.output)
