"""Snakemake's scheduler with one re-evaluation timer at a time (``signorini.pipeline.scheduling``)."""

from __future__ import annotations

import threading
import time

from signorini.pipeline import scheduling


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
        scheduling._schedule_reevaluation_once(scheduler, 0.05)
    timers = [t for t in threading.enumerate() if t.ident not in before]
    assert len(timers) == 1 and timers[0].daemon
    time.sleep(0.3)
    assert _rounds(scheduler) == 1
    scheduling._schedule_reevaluation_once(scheduler, 0.05)
    time.sleep(0.3)
    assert _rounds(scheduler) == 1


def test_the_snakefile_patches_snakemakes_scheduler():
    """The Snakefile calls the patch, and this Snakemake has the method it replaces."""
    from helpers import ROOT
    from snakemake.scheduling.job_scheduler import JobScheduler

    assert "coalesce_reevaluations()" in (ROOT / "Snakefile").read_text()
    assert scheduling.coalesce_reevaluations()
    assert JobScheduler._schedule_reevalutation is scheduling._schedule_reevaluation_once
