"""rule work_precision_measure: one solver configuration at all its tolerances on one mesh."""

# one BLAS/OpenMP thread (signorini.pipeline.jobenv), inherited from the workflow process

from signorini.pipeline.joblog import job_log
from signorini.studies.scene.store import SceneMesh
from signorini.studies.work_precision.measure import measure_stage

snakemake = globals()["snakemake"]  # injected by the script: directive

with job_log(snakemake):
    p, i = snakemake.params, snakemake.input
    inputs = {
        "system": i.system,
        "system_json": i.system_json,
        "exact": i.exact,
        "disc": p.disc_norm_jsons,
        "prev": i.prev or None,
        "peer_driver": i.peer_driver[0] if i.peer_driver else None,
    }
    measure_stage(
        SceneMesh.of_job(snakemake),
        p.config,
        p.tolerances,
        p.time_limit_s,
        inputs,
        snakemake.output.json,
        conventions=p.conventions,
        growth_exponent=p.growth_exponent,
        peer_python=p.peer_python,
        timing=p.timing,
    )
