"""rule norm (one norm) and the norms_<scene> rules (all of a scene's norms): norms of u - u_h
for one scene and N.  Each output is results/<scene>/N<N>/norms/<norm>.json: its stem names the norm."""

from pathlib import Path

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.norm import norms_stage
from signorini.studies.scene.store import SceneMesh

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    outputs = {Path(path).stem: path for path in snakemake.output}
    norms_stage(SceneMesh.of_job(snakemake), snakemake.input.solution, outputs, snakemake.params.conventions)
