# The cache check, before Snakemake inspects any file (included last: it asks the rules for the
# parameters their jobs would get).
#
# A cached artifact damaged after it was written (truncated npz, incomplete JSON, a removed
# checksum) is moved to <name>.corrupt, so that it is rebuilt, not read. A valid artifact that
# is out of date -- its recorded code, inputs or parameters differ from what the current code
# and config give (also when .snakemake is gone), or a scene table holds other meshes or norms --
# is removed, so that it is rebuilt, not trusted. Temporary files of atomic writes left by a
# killed job (kill -9) are deleted. All of this happens only when Snakemake executes jobs: the
# check runs at the start of Workflow.execute, where the executor Snakemake chose says whether
# it is a dry run or --touch (however spelled: -n, --dry-r, -nc2, a profile's dryrun: true);
# the calls that plan nothing (--lint, -l, --summary, --report, --dag, ...) never get there.
from signorini.pipeline.integrity import (
    cached_artifacts,
    quarantine_corrupt,
    remove_leftover_temporaries,
    remove_rendered,
    remove_stale,
    rendered_mismatch,
    runs_jobs,
    warn_corrupt,
)
from signorini.pipeline.joblog import plain


def current_params(path, provenance):
    """The params a job writing ``path`` would get now, normalised as artifacts record them
    (signorini.pipeline.joblog.plain): Snakemake's own expansion of the producing rule's
    ``params:`` (the rule that wrote it if it still exists, as in either norm_jobs mode the
    norms of a mesh have two producers with the same params); None when no rule writes it.
    """
    producers = [r for r in workflow.rules if r.is_producer(path)]
    writer = next((r for r in producers if r.name == provenance.get("rule")), None)
    writer = writer or next(iter(producers), None)
    if writer is None:
        return None
    wildcards = writer.get_wildcards(path)
    job_input = writer.expand_input(wildcards)[0]
    job_output = writer.expand_output(wildcards)[0]
    params = writer.expand_params(wildcards, job_input, job_output, None)[0]
    return plain(params.items())


def check_cache(execute):
    """Move damaged artifacts aside, remove out-of-date ones and killed jobs' temporaries (a run
    that executes jobs), or only name them (a dry run, --touch)."""
    cached = list(cached_artifacts(paths.RESULTS, config["scenes"]))
    if execute:
        quarantine_corrupt(cached)
    else:
        warn_corrupt(cached)
    remove_stale(cached, current_code_digest, execute, current_params)
    tables = {name: FIGURES[name]["csv"] for name in ("table1", "table2")}
    if (reason := rendered_mismatch(tables, scene_of(FIG)["N"])) is not None:
        meshes = (
            "table1",
            "table2",
            "figure3",
            "reproduction",
        )  # what shows the meshes
        rendered = [p for rule in meshes for p in FIGURES[rule].values()]
        remove_rendered(rendered, reason, execute)
    remove_leftover_temporaries([paths.RESULTS, paths.FIGDIR], execute=execute)


def checked_first(execute):
    """Workflow.execute, preceded by the cache check (Snakemake passes the executor plugin by
    keyword; a version that does not makes this fail loudly, not skip the check)."""

    @functools.wraps(execute)
    def run(*args, executor_plugin, **kwargs):
        check_cache(runs_jobs(executor_plugin))
        return execute(*args, executor_plugin=executor_plugin, **kwargs)

    return run


if workflow.is_main_process:
    workflow.execute = checked_first(workflow.execute)
