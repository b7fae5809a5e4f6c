"""Every change this workflow makes to Snakemake's internals, in one place.  FRAGILE: each patch
replaces or wraps a private name of Snakemake; each says why, and the Snakemake versions it was
checked against (``CHECKED``).  When a patched name is missing, the workflow refuses to start with
one line (``SnakemakeShapeError``) instead of silently running without the patch;
``tests/pipeline/test_patches.py`` fails when the patched names change shape.

1. ``coalesce_reevaluations``: Snakemake's scheduler keeps one re-evaluation timer pending.
2. ``check_before_running``: the cache check runs on the DAG of this run, between building it and
   running its jobs, and the DAG is built again when the check moved files or forces jobs.
3. ``share_code_source``: two rules that run one script count as the same code for Snakemake's
   ``code`` rerun trigger.
4. ``bound_scheduler_memory``: without a ``mem_mb`` of the user's, the scheduler holds the jobs'
   ``mem_mb`` against the memory of this machine.
"""

from __future__ import annotations

import functools
import threading
from collections.abc import Callable, Iterable
from typing import Any

CHECKED = ("9.27.1",)  # the Snakemake versions these patches were checked against


class SnakemakeShapeError(SystemExit):
    """A name this workflow patches is missing from the installed Snakemake (one line, no traceback)."""


def _require(owner: Any, name: str, why: str) -> Any:
    """``owner.name``, or a one-line refusal naming the version checked against."""
    found = getattr(owner, name, None)
    if not callable(found):
        from snakemake import __version__

        raise SnakemakeShapeError(
            f"signorini: Snakemake {__version__} has no {getattr(owner, '__name__', owner)}.{name}, which this "
            f"workflow patches ({why}; checked against Snakemake {', '.join(CHECKED)}): install the versions of "
            "environment.lock (make setup)"
        )
    return found


# --- 1. one re-evaluation timer ----------------------------------------------------------------
# Snakemake 9's scheduler (JobScheduler.schedule) ends every scheduling round by starting a timer
# that starts another round one rate-limit timespan later; a round started by a finished job starts
# a timer of its own, so after n finished jobs n timer chains run (snakemake/snakemake#3744, #2967).
# Each round resets the params and resources of every ready job and stats its inputs (code inputs
# included): late in a long run the main process took a sizeable share of a core
# (docs/evidence/design-measurements.md#one-reevaluation-timer).

_LOCK = threading.Lock()
_PENDING = "_signorini_reevaluation_pending"


def _schedule_reevaluation_once(self, delay: float) -> None:
    """``JobScheduler._schedule_reevalutation`` without a second timer while one is pending."""
    with _LOCK:
        if getattr(self, _PENDING, False):
            return
        setattr(self, _PENDING, True)

    def fire() -> None:
        with _LOCK:
            setattr(self, _PENDING, False)
        self._open_jobs.release()

    timer = threading.Timer(delay, fire)
    timer.daemon = True  # Snakemake's exit does not wait for it
    timer.start()


def coalesce_reevaluations() -> None:
    """Patch Snakemake's scheduler class in this process (the Snakefile calls it)."""
    from snakemake.scheduling.job_scheduler import JobScheduler

    _require(JobScheduler, "_schedule_reevalutation", "one re-evaluation timer at a time")  # Snakemake's spelling
    JobScheduler._schedule_reevalutation = _schedule_reevaluation_once


# --- 2. the cache check on this run's DAG -------------------------------------------------------
# Workflow.execute sets the executor plugin, calls _prepare_dag(**settings) (a new DAG object) and
# then _build_dag() (jobs, needrun); the jobs run after that.  The calls that run no jobs (--report,
# --summary, --dag, ...) build a DAG too, without an executor plugin: the check leaves them alone.
# Wrapping _build_dag lets the check see exactly the jobs the requested targets need; when it moved
# a file aside or forces a job, _prepare_dag is called again with the same arguments (recorded by
# the wrapper around it) and the DAG rebuilt from the disk.

MAX_ROUNDS = 4  # a check that still changes something after this many rebuilds is a bug: stop


def check_before_running(workflow: Any, check: Callable[[Any], Iterable[str] | None]) -> None:
    """Run ``check(dag)`` on every DAG this ``workflow`` builds to execute; ``check`` returns the
    files whose jobs must run (or None when it changed nothing), and the DAG is built again."""
    from snakemake.workflow import Workflow

    prepare = _require(Workflow, "_prepare_dag", "the cache check sees the DAG of the run")
    build = _require(Workflow, "_build_dag", "the cache check sees the DAG of the run")
    settings: dict = {}

    @functools.wraps(prepare)
    def prepare_recorded(self, *args, **kwargs):
        settings.update(args=args, kwargs=kwargs)
        return prepare(self, *args, **kwargs)

    @functools.wraps(build)
    def build_checked(self):
        build(self)
        if self.executor_plugin is None:  # --report, --summary, --dag, ...: no jobs run, nothing is checked
            return
        for _ in range(MAX_ROUNDS):
            forced = check(self.dag)
            if forced is None:
                return
            self.dag_settings.forcerun = frozenset({*self.dag_settings.forcerun, *forced})
            self.iocache.clear()  # the check moved files: what Snakemake saw is gone
            prepare(self, *settings["args"], **settings["kwargs"])
            build(self)
        raise RuntimeError(f"the cache check still changed the plan after {MAX_ROUNDS} rounds")

    workflow._prepare_dag = prepare_recorded.__get__(workflow)
    workflow._build_dag = build_checked.__get__(workflow)


# --- 3. one script, one code ------------------------------------------------------------------
# Snakemake's code rerun trigger compares a rule's source text (Rule.run_func_src); a rule made in
# a loop runs the same script as another rule and differs only by indentation.


def share_code_source(rule: Any, source: Any) -> None:
    """Give ``rule`` the source text ``source`` records for the code rerun trigger."""
    if not hasattr(source, "run_func_src"):
        _require(source, "run_func_src", "the code rerun trigger of rules that share a script")
    rule.run_func_src = source.run_func_src


# --- 4. the scheduler knows this machine's memory ----------------------------------------------
# Snakemake bounds the sum of the running jobs' mem_mb only by a global mem_mb resource the user
# gives; without one, two large solves start side by side and one dies of a MemoryError.


def bound_scheduler_memory(workflow: Any, limit_mb: int) -> int | None:
    """Set ``workflow.global_resources["mem_mb"]`` to ``limit_mb`` while the Snakefile is parsed
    (``JobScheduler`` copies ``workflow.global_resources`` when ``Workflow.execute`` starts it, and
    holds every job's ``mem_mb`` against it, as for ``--resources mem_mb=…``); the value set, or
    None when left alone: the user gave ``mem_mb``, or the jobs go to other machines (``--jobs``
    with a cluster executor: Snakemake's ``_nodes`` resource is set)."""
    from signorini.pipeline.resources import given_mem_mb

    resources = getattr(workflow, "global_resources", None)
    if resources is None or given_mem_mb(workflow) is not None:
        return None
    if getattr(resources.get("_nodes"), "value", None) is not None:
        return None
    resources["mem_mb"] = limit_mb
    return limit_mb
