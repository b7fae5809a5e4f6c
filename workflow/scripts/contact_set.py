"""rule contact_set: paper_figures/contact_set.{csv,pdf,png} (discrete contact sets, condition (A_h))."""

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.store import SceneMesh
from signorini.studies.theory.contact import contact_set_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    meshes = [SceneMesh(dict(p.problem), int(N), str(p.diagonal)) for N in p.N]
    contact_set_stage(meshes, list(snakemake.input.solutions), snakemake.output)
