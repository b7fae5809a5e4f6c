"""A short console for Snakemake (``--logger signorini``; the workflow's default profile
``profiles/default/config.yaml`` sets it): one line per finished job with the count and an
estimate of the time left, Snakemake's own messages otherwise, and one line for Ctrl-C.

    [ 12/57] solve scene=paper N=301   1:05 elapsed, about 2:10 left

Dry runs, ``--verbose`` and ``--quiet`` are printed as Snakemake prints them (the job blocks
``rule X:`` with their wildcards, inputs and reasons); each job's own messages stay in its log
file (``results/<scene>/logs/...``), and ``--workflow-profile none`` gives Snakemake's console.
"""

from __future__ import annotations

import logging
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from snakemake_interface_logger_plugins.base import LogHandlerBase
from snakemake_interface_logger_plugins.common import LogEvent
from snakemake_interface_logger_plugins.settings import LogHandlerSettingsBase

# Snakemake's scheduling chatter, one or more lines per job: left out of the short console
CHATTER = re.compile(
    r"^(Select jobs to execute|Execute \d+ jobs|Assuming unrestricted shared filesystem|Using shell:|"
    r"Provided cores:|Rules claiming more threads|Conda environments: ignored|Finished jobid:|"
    r"Removing temporary output|Touching output file|Waiting at most)"
)
INTERRUPT = ("Terminating processes on user request", "Cancelling snakemake on user request")


@dataclass
class LogHandlerSettings(LogHandlerSettingsBase):
    """No settings of its own."""


def clock(seconds: float) -> str:
    """``1:05`` or ``1:02:05``."""
    minutes, s = divmod(int(round(seconds)), 60)
    hours, m = divmod(minutes, 60)
    return f"{hours}:{m:02d}:{s:02d}" if hours else f"{m}:{s:02d}"


def job_label(rule: str, wildcards: dict | None) -> str:
    """``solve scene=paper N=301``."""
    return " ".join([rule, *(f"{k}={v}" for k, v in (wildcards or {}).items())])


def progress_line(done: int, total: int, label: str, elapsed: float) -> str:
    """The line of a finished job: count, job, time so far and a linear estimate of the rest."""
    width = len(str(total))
    left = elapsed / done * (total - done) if done else float("nan")
    estimate = f", about {clock(left)} left" if 0 < done < total else ""
    return f"[{done:>{width}}/{total}] {label}   {clock(elapsed)} elapsed{estimate}"


def interrupt_line(done: int, total: int) -> str:
    """The one line of Ctrl-C."""
    if not done:
        return "interrupted: no job had finished; the same command starts again"
    return f"interrupted: {done} of {total} jobs finished and kept; the same command continues from them"


CONFIGFILE_OPTIONS = ("--configfile", "--configfiles")


def configfile_hint(argv: list[str]) -> str | None:
    """Two lines when a word after ``--configfile`` (which takes every word up to the next option)
    is no config file but, most likely, a target; None otherwise."""
    import yaml

    words: list[str] = []
    for i, arg in enumerate(argv):
        if arg in CONFIGFILE_OPTIONS:
            words += [w for w in _until_option(argv[i + 1:])]
    for word in words:
        path = Path(word)
        try:
            data = yaml.safe_load(path.read_text(encoding="utf-8")) if path.is_file() else None
        except (OSError, UnicodeDecodeError, yaml.YAMLError):
            data = None
        if not isinstance(data, dict):
            configs = " ".join(w for w in words if w != word) or "my.yaml"
            return (
                f"--configfile: {word!r} is not a config file (YAML or JSON with keys at top level) but, as it "
                f"seems, a target: --configfile reads every word up to the next option.\n"
                f"Write the targets first: snakemake {word} --configfile {configs}  (or end the list with --)"
            )
    return None


def _until_option(words: list[str]) -> list[str]:
    out = []
    for word in words:
        if word.startswith("-"):
            break
        out.append(word)
    return out


class LogHandler(LogHandlerBase):
    """The short console (see the module docstring)."""

    def __post_init__(self) -> None:
        from snakemake.logging import DefaultFilter, DefaultFormatter

        s = self.common_settings
        self.snakemake_formatter = DefaultFormatter(s.quiet, s.show_failed_logs)
        self.snakemake_filter = DefaultFilter(s.quiet, s.debug_dag, s.verbose, s.dryrun, s.printshellcmds)
        # dry runs, --verbose and --quiet: Snakemake's own console
        self.passthrough = bool(s.dryrun or s.verbose or s.quiet)
        self.stream = sys.stdout if s.stdout else sys.stderr
        self.labels: dict[int, str] = {}
        self.finished: list[int] = []
        self.started: float | None = None
        self.done, self.total = 0, 0
        self.interrupted = False
        self.hinted = False

    def write(self, text: str) -> None:
        if text:
            self.stream.write(text.rstrip("\n") + "\n")
            self.stream.flush()

    def emit(self, record: logging.LogRecord) -> None:
        try:
            if record.levelno >= logging.ERROR and not self.hinted and (hint := configfile_hint(sys.argv[1:])):
                self.hinted = True  # Snakemake read a target as a config file: say so instead
                self.write(hint)
                return
            if self.passthrough:
                if self.snakemake_filter.filter(record):
                    self.write(self.snakemake_formatter.format(record))
                return
            self.short(record)
        except Exception:  # a console must never end the run
            self.handleError(record)

    def short(self, record: logging.LogRecord) -> None:
        event = getattr(record, "event", None)
        text = str(record.msg or "")
        if self.interrupted:
            return  # after Ctrl-C: the one line is printed, the jobs' SIGINT errors are not
        if any(text.startswith(m) for m in INTERRUPT) or event == LogEvent.ERROR and "KeyboardInterrupt" in text:
            self.interrupted = True
            self.write(interrupt_line(self.done, self.total))
            return
        if event == LogEvent.JOB_INFO:
            self.labels[record.jobid] = job_label(record.rule_name, record.wildcards)
            self.started = self.started or time.monotonic()
        elif event == LogEvent.JOB_FINISHED:
            self.finished.append(record.job_id)
        elif event == LogEvent.PROGRESS:
            self.done, self.total = record.done, record.total
            label = self.labels.get(self.finished[-1], "job") if self.finished else "job"
            self.write(progress_line(self.done, self.total, label, time.monotonic() - (self.started or 0.0)))
        elif event in (LogEvent.SHELLCMD, LogEvent.RESOURCES_INFO, LogEvent.JOB_STARTED, LogEvent.RULEGRAPH,
                       LogEvent.WORKFLOW_STARTED):
            return
        elif event is None and record.levelno <= logging.INFO and CHATTER.match(text):
            return
        elif self.snakemake_filter.filter(record):
            self.write(self.snakemake_formatter.format(record))

    @property
    def writes_to_stream(self) -> bool:
        return True

    @property
    def writes_to_file(self) -> bool:
        return False

    @property
    def has_filter(self) -> bool:
        return True

    @property
    def has_formatter(self) -> bool:
        return True

    @property
    def needs_rulegraph(self) -> bool:
        return False
