"""Every patch of Snakemake's internals (``signorini.pipeline.patches``): what each does, and that
the names it patches still have the shape it was written for (these tests fail when a Snakemake
update changes them)."""

from __future__ import annotations

import subprocess
import threading
import time

import pytest
from helpers import SNAKEMAKE

from signorini.pipeline import patches


class _Scheduler:
    """What the patched method touches of Snakemake's ``JobScheduler``: the semaphore that starts
    a scheduling round."""

    def __init__(self) -> None:
        self._open_jobs = threading.Semaphore(0)


def _rounds(scheduler: _Scheduler) -> int:
    n = 0
    while scheduler._open_jobs.acquire(blocking=False):
        n += 1
    return n


def test_requests_while_a_timer_is_pending_start_one_round():
    """Five rounds asking for a re-evaluation (a job finished in each) start one round, not five
    timer chains; once it has fired, the next request starts a timer again; the timer is a daemon
    thread, so the process exits without waiting for it."""
    scheduler = _Scheduler()
    before = {t.ident for t in threading.enumerate()}
    for _ in range(5):
        patches._schedule_reevaluation_once(scheduler, 0.05)
    timers = [t for t in threading.enumerate() if t.ident not in before]
    assert len(timers) == 1 and timers[0].daemon
    time.sleep(0.3)
    assert _rounds(scheduler) == 1
    patches._schedule_reevaluation_once(scheduler, 0.05)
    time.sleep(0.3)
    assert _rounds(scheduler) == 1


def test_the_snakefile_patches_snakemakes_scheduler():
    """The Snakefile calls the patch, and this Snakemake has the method it replaces."""
    from helpers import ROOT
    from snakemake.scheduling.job_scheduler import JobScheduler

    assert "patches.coalesce_reevaluations()" in (ROOT / "Snakefile").read_text()
    patches.coalesce_reevaluations()
    assert JobScheduler._schedule_reevalutation is patches._schedule_reevaluation_once


# Snakemake's internals, inspected in a subprocess: importing snakemake.api loads PuLP, after which
# OSQP's set-up crashes the interpreter (a clash of their native libraries), and a test of the
# cvxpy routes may share this worker process
SHAPE_CHECK = """
import inspect, json
import snakemake.api  # first, as Snakemake itself loads its modules
from snakemake.dag import DAG
from snakemake.rules import Rule
from snakemake.scheduling.job_scheduler import JobScheduler
from snakemake.settings.types import DAGSettings
from snakemake.workflow import Workflow

source = inspect.getsource(Workflow.execute)
order = ("self._executor_plugin = executor_plugin", "self._prepare_dag(", "self._build_dag()", "scheduler(")
print(json.dumps({
    "reevaluation_parameters": list(inspect.signature(JobScheduler._schedule_reevalutation).parameters)[:2],
    "execute_in_order": [source.index(step) for step in order] == sorted(source.index(step) for step in order),
    "no_plugin_without_execute": "self._executor_plugin = None" in inspect.getsource(Workflow.__post_init__),
    "build_dag_parameters": list(inspect.signature(Workflow._build_dag).parameters),
    "rule_run_func_src": "run_func_src" in inspect.getsource(Rule),
    "dag_jobs": callable(DAG.needrun_jobs) and isinstance(DAG.jobs, property),
    "dag_targetjobs": "self.targetjobs" in inspect.getsource(DAG.__init__),
    "dag_settings_forcerun": "forcerun" in DAGSettings.__dataclass_fields__,
}))
"""


def test_the_patched_names_have_the_shape_the_patches_expect():
    """JobScheduler._schedule_reevalutation(self, delay); Workflow.execute sets the executor plugin,
    calls _prepare_dag and then _build_dag (the check runs between them and the jobs), and without
    execute there is no plugin; _build_dag takes no argument; Rule.run_func_src exists; DAG exposes
    jobs, needrun_jobs and targetjobs; DAGSettings.forcerun."""
    import json
    import sys

    proc = subprocess.run([sys.executable, "-c", SHAPE_CHECK], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    shape = json.loads(proc.stdout.strip().splitlines()[-1])
    assert shape.pop("reevaluation_parameters") == ["self", "delay"]
    assert shape.pop("build_dag_parameters") == ["self"]
    assert all(shape.values()), shape


def test_a_missing_patched_name_refuses_to_start_in_one_line():
    class Shapeless:
        pass

    with pytest.raises(patches.SnakemakeShapeError) as err:
        patches._require(Shapeless, "_build_dag", "the cache check sees the DAG of the run")
    message = str(err.value)
    assert "\n" not in message and "_build_dag" in message and patches.CHECKED[0] in message


def test_the_installed_snakemake_is_a_checked_version():
    """A new Snakemake in environment.lock: re-check every patch, then add its version to CHECKED."""
    from snakemake import __version__

    assert __version__ in patches.CHECKED


# --- the scheduler's memory -------------------------------------------------------------------


def fake_workflow(resources: list[str] = (), nodes: int | None = None):
    """What ``bound_scheduler_memory`` reads of Snakemake's workflow: its global resources, as
    Snakemake 9 builds them from --resources (``Workflow.__post_init__``)."""
    from types import SimpleNamespace

    from snakemake.resources import Resources

    global_resources = Resources.parse(list(resources), allow_expressions=False)
    global_resources["_cores"], global_resources["_nodes"] = 2, nodes
    return SimpleNamespace(global_resources=global_resources)


def test_without_a_mem_mb_of_the_users_the_scheduler_gets_this_machines_memory():
    from signorini.pipeline.patches import bound_scheduler_memory
    from signorini.pipeline.resources import given_mem_mb, usable_memory

    workflow = fake_workflow()
    assert given_mem_mb(workflow) is None
    assert bound_scheduler_memory(workflow, usable_memory(False).mb) == usable_memory(False).mb
    assert workflow.global_resources["mem_mb"].value == usable_memory(False).mb
    for given, mb in ((["mem_mb=5000"], 5000), (["mem=8GB"], 8000)):  # the user's limit stays
        workflow = fake_workflow(given)
        assert given_mem_mb(workflow) == mb and bound_scheduler_memory(workflow, 1000) is None
        assert workflow.global_resources["mem_mb"].value == mb
    workflow = fake_workflow(nodes=50)  # jobs on a cluster's nodes: not this machine's memory
    assert bound_scheduler_memory(workflow, 1000) is None and "mem_mb" not in workflow.global_resources


def test_two_jobs_whose_memory_exceeds_the_machines_do_not_run_side_by_side(tmp_path):
    """Through Snakemake's scheduler (-c2, no --resources): two jobs that each request just over
    half of the memory run one after the other (without the bound they started together)."""
    from signorini.pipeline.resources import usable_memory

    half = usable_memory(False).mb // 2 + 1
    (tmp_path / "Snakefile").write_text(f"""\
from signorini.pipeline import patches, resources

patches.bound_scheduler_memory(workflow, resources.usable_memory(per_process=False).mb)

rule all:
    input: "big1", "big2"

rule job:
    output: "big{{i}}"
    resources: mem_mb={half}
    shell: "date +%s.%N > {{output}}; sleep 0.5; date +%s.%N >> {{output}}"
""", encoding="utf-8")
    subprocess.run([SNAKEMAKE, "-c2", "--workflow-profile", "none", "-q"], cwd=tmp_path, check=True,
                   capture_output=True, timeout=120)

    def span(name: str) -> tuple[float, float]:
        start, end = map(float, (tmp_path / name).read_text(encoding="utf-8").split())
        return start, end

    (s1, e1), (s2, e2) = span("big1"), span("big2")
    assert e1 <= s2 or e2 <= s1, "two large jobs ran side by side"
