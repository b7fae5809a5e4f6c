"""rule h12_boundary: results/<scene>/h12_boundary.csv (H^{1/2} with whole-edge and split boundary rules)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.boundary_rule import h12_boundary_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    meshes = [SceneMesh(dict(p.problem), int(N), str(p.diagonal)) for N in p.N]
    h12_boundary_stage(meshes, list(snakemake.input.solutions), p.conventions, snakemake.output.csv)
