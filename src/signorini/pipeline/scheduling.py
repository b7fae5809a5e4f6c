"""Snakemake's scheduler with one re-evaluation timer at a time.

Snakemake 9's scheduler (``JobScheduler.schedule``) ends every scheduling round by starting a
timer that starts another round one rate-limit timespan later (``--max-jobs-per-timespan``,
default 100/1s). A round started by anything else, such as a job that finishes, starts a timer
of its own. So after n finished jobs, n timer chains run the round n times a second
(snakemake/snakemake#3744, #2967). Each round resets the params and resources of every ready
job and stats its inputs, and a rule's inputs here include its code (``pipeline.codedeps``).
In a 219-job work-precision run, after 150 jobs, the main process took a third of a core: 46 000
``stat`` calls and about 30 new threads a second. That is load the timing protocol sees and
waits for (``max_load``).

``coalesce_reevaluations`` keeps at most one timer pending: one round per timespan when
nothing happens, a round after every job as before, and the rate limit still re-checked within
a timespan. The timer thread is a daemon, so Snakemake's exit does not wait for it."""

from __future__ import annotations

import threading

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
    timer.daemon = True
    timer.start()


def coalesce_reevaluations() -> bool:
    """Patch Snakemake's scheduler class in this process (the Snakefile calls it); False if
    this Snakemake has no such method (then nothing is changed)."""
    try:
        from snakemake.scheduling.job_scheduler import JobScheduler
    except ImportError:
        return False
    if not callable(getattr(JobScheduler, "_schedule_reevalutation", None)):  # Snakemake's spelling
        return False
    JobScheduler._schedule_reevalutation = _schedule_reevaluation_once
    return True
