"""rule load_rule: results/<scene>/load_rule.csv (Table 1's norms with the load vector by the norms' rule)."""

from signorini.pipeline.joblog import job_log
from signorini.studies.paper.load_rule import load_rule_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p = snakemake.params
    meshes = [SceneMesh(dict(p.problem), int(N), str(p.diagonal)) for N in p.N]
    load_rule_stage(meshes, list(snakemake.input.systems), p.norm_jsons, p.conventions, snakemake.output.csv)
