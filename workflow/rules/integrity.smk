# The cache check, on the DAG of this run: between building the plan and running its jobs
# (signorini.pipeline.patches.check_before_running). It looks at the outputs of the jobs the
# requested targets need, and at nothing else:
#
# a damaged output is moved to <name>.corrupt, one not vouched for (out of date, misplaced,
# written outside this workflow) to <name>.stale, and a rendered output of paper_figures/ that
# is not what its job would render from the current cache has its job forced (the file stays
# until the job replaces it). Temporary files of atomic writes left by a killed job (kill -9)
# are deleted. A dry run or --touch only names what it finds (signorini.pipeline.integrity).
#
# First, every job the plan starts must fit the memory a job can use here (through Slurm: the
# largest node), so a scene nobody asked for may need more than this machine has.
from signorini.pipeline.integrity import (
    apply_verdicts,
    judge,
    planned_outputs,
    remove_leftover_temporaries,
    runs_jobs,
)
from signorini.pipeline.config import check_planned_memory, memory_limit
from signorini.pipeline.joblog import LOCK_VARIABLE, environment

# the artifacts record the environment lock's digest (signorini.pipeline.joblog.environment)
os.environ[LOCK_VARIABLE] = str(Path(workflow.basedir) / "environment.lock")


def check_plan(dag):
    """The cache check of one DAG: the files whose jobs must run now, or None when nothing changed
    (rendered outputs already forced in an earlier round count as unchanged)."""
    with one_line_errors():
        limit = memory_limit(_mem_limit, slurm_node(workflow))
        check_planned_memory(dag.needrun_jobs(), config, *limit)
    execute = runs_jobs(workflow.executor_plugin)
    verdicts = judge(planned_outputs(dag, code_digest), environment())
    forced = set(workflow.dag_settings.forcerun)
    verdicts.rerender = {p: r for p, r in verdicts.rerender.items() if p not in forced}
    apply_verdicts(verdicts, execute)
    if not execute or not verdicts:
        remove_leftover_temporaries([paths.RESULTS, paths.FIGDIR], execute=execute)
        return None
    return list(verdicts.rerender)


if workflow.is_main_process:
    patches.check_before_running(workflow, check_plan)
