"""Finite element replication of Christof & Haubner's scalar Signorini experiments (Section 7).

Subpackages: ``fem`` (the mathematics), ``solvers`` (the discrete variational inequality),
``pipeline`` (workflow infrastructure: paths, config checks, artifacts, job logs, code
dependencies) and ``studies`` (one folder per study: its stages, reports and figures).
This ``__init__`` imports nothing of the package, so that a job runs only the modules it uses.
"""

import os as _os

__version__ = "0.2.0"

# In a workflow job (the Snakefile sets this for its jobs only): Ctrl-C ends the job with exit
# status 130 and no traceback (SystemExit runs the clean-ups, as KeyboardInterrupt would), so that
# the console shows Snakemake's one line, not a traceback per running job.  Under the short console
# the job starts with SIGINT blocked (snakemake_logger_plugin_signorini.block_interrupts_in_threads),
# so that a Ctrl-C during Snakemake's script preamble waits for this handler: unblocking delivers it
# now, and the job ends here, before it has written anything.
if _os.environ.get("SIGNORINI_JOB_INTERRUPT") == "quiet":
    import signal as _signal

    def _interrupted(signum: int, frame: object) -> None:
        raise SystemExit(128 + signum)

    _signal.signal(_signal.SIGINT, _interrupted)
    _signal.pthread_sigmask(_signal.SIG_UNBLOCK, {_signal.SIGINT})
