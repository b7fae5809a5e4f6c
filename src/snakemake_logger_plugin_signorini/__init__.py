"""A short console for Snakemake (``--logger signorini``; the workflow's default profile
``profiles/default/config.yaml`` sets it): one line per finished job with the count and an
estimate of the time left, Snakemake's own messages otherwise, one line for Ctrl-C (the jobs end
quietly too) and one line for a target with an unknown scene or norm (Snakemake's block with its
traceback goes to its log file, ``.snakemake/log/``).

    [ 12/57] solve scene=paper N=301   1:05 elapsed, about 2:10 left

Dry runs, ``--verbose`` and ``--quiet`` are printed as Snakemake prints them (the job blocks
``rule X:`` with their wildcards, inputs and reasons); each job's own messages stay in its log
file (``results/<scene>/logs/...``), and ``--workflow-profile none`` gives Snakemake's console.
"""

from __future__ import annotations

import logging
import os
import re
import signal
import sys
import threading
import time
import traceback
from collections.abc import Sequence
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
# how Snakemake reports a job that ended by Ctrl-C: 128 + SIGINT, the status the package's jobs exit
# with (signorini.pipeline.joblog.INTERRUPTED)
JOB_INTERRUPTED = f"non-zero exit status {128 + signal.SIGINT}."
# Snakemake's block for an exception raised in an input, params or resources function: its cause,
# message and the job's wildcards
INPUT_FUNCTION_ERROR = re.compile(r"^Error:\n  (\w+): (.*)\nWildcards:\n((?:  \w+=.*\n?)*)", re.MULTILINE)
# causes that are a mistake in what the user asked for (a scene, a norm name, a config field), not a
# fault of the workflow: one line, the block goes to Snakemake's log file
USER_ERRORS = ("ConfigError", "UnknownNormError")


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


def interrupt_line(done: int, total: int, reruns_incomplete: bool = True) -> str:
    """The one line of Ctrl-C.  The jobs Ctrl-C cut off leave their outputs marked incomplete in
    ``.snakemake``; Snakemake reruns them only with ``--rerun-incomplete`` (the default profile sets
    it) and otherwise refuses the next run, so without it the advice names the option."""
    again = "the same command" if reruns_incomplete else "the same command with --rerun-incomplete"
    if not done:
        return f"interrupted: no job had finished; {again} starts again"
    return f"interrupted: {done} of {total} jobs finished and kept; {again} continues from them"


def command_line(argv: Sequence[str]) -> tuple[list[str], bool] | None:
    """The targets of a Snakemake command line and whether it reruns incomplete jobs, as Snakemake
    reads them (its own parser, with the profiles it applies: ``--workflow-profile none``, a
    user's ``--profile``); None if the line cannot be read so (then the advice names the option)."""
    import contextlib
    import io

    try:
        from snakemake.cli import parse_args

        with contextlib.redirect_stderr(io.StringIO()):  # its "Using profile ..." line, printed once already
            _, args = parse_args(list(argv))
    except (Exception, SystemExit):
        return None
    return [str(t) for t in args.targets or []], bool(args.rerun_incomplete)


def input_error_line(text: str, targets: Sequence[str]) -> str | None:
    """``error: <target>: <message>`` for Snakemake's block of an input function whose cause is a
    user's mistake (``USER_ERRORS``), naming the requested target whose path holds the job's
    wildcards (else the rule and the wildcards); None for any other message."""
    m = INPUT_FUNCTION_ERROR.search(text)
    if m is None or m[1] not in USER_ERRORS:
        return None
    wildcards = [line.strip() for line in m[3].splitlines() if line.strip()]
    values = [w.split("=", 1)[1] for w in wildcards]
    target = next((t for t in targets if all(v in t for v in values)), None)
    if target is None:
        rule = re.search(r"\(rule (\w+), line", text)
        target = " ".join([f"rule {rule[1]}" if rule else "a job", *wildcards])
    return f"error: {target}: {m[2]}"


def block_interrupts_in_threads() -> None:
    """Start every later thread of this process with SIGINT blocked.  Ctrl-C reaches every process
    of the terminal's group, the jobs too, and a job's interpreter spends its first half second in
    Snakemake's script preamble, before the package's quiet handler (``signorini/__init__.py``)
    exists: a SIGINT there printed a traceback with the 20 KB pickled preamble line.  Snakemake
    starts the jobs from its worker threads, whose signal mask they inherit (through bash): the
    signal then waits, blocked, until the job imports the package, which installs its handler and
    unblocks it, so the job ends at once and quietly.  Python runs signal handlers in the main
    thread only, which keeps SIGINT, so this process still stops on Ctrl-C.  An existing thread
    profile hook (a profiler) is left alone."""
    if threading.getprofile() is not None:
        return

    def block(*_: object) -> None:
        signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        sys.setprofile(None)

    threading.setprofile(block)


CONFIGFILE_OPTIONS = ("--configfile", "--configfiles")
CONFIG_SUFFIXES = (".yaml", ".yml", ".json")  # what a config file is called; an output is not
RULE = re.compile(r"^(?:rule|checkpoint)\s+(\w+)\s*:", re.MULTILINE)


def configfile_hint(argv: list[str]) -> str | None:
    """What is wrong with the words after ``--configfile`` (which takes every word up to the next
    option) that Snakemake cannot read as config files, one line each: a word that looks like a
    target (``looks_like_target``) as such, with a last line saying to write the targets first;
    any other with the reason (``signorini.pipeline.config.load_yaml``'s message: a syntax error
    with file, line and column, not UTF-8, empty, not a mapping, no such file).  None when
    Snakemake reads every file."""
    words = _configfile_words(argv)
    lines, targets = [], []
    for word in words:
        problem = config_problem(Path(word))
        if problem is None:
            continue
        if looks_like_target(word):
            targets.append(word)
            lines.append(
                f"--configfile: {word!r} is not a config file (YAML or JSON with keys at top level) but, as it "
                "seems, a target: --configfile reads every word up to the next option."
            )
        else:
            lines.append(f"--configfile: {problem}")
    if targets:
        configs = " ".join(w for w in words if w not in targets) or "my.yaml"
        lines.append(
            f"Write the targets first: snakemake {' '.join(targets)} --configfile {configs}  (or end the list with --)"
        )
    return "\n".join(lines) or None


def config_problem(path: Path) -> str | None:
    """Why Snakemake cannot read ``path`` as a config file (JSON, else YAML, a mapping at top level),
    in one line, or None when it can (a key given twice it reads too: the workflow names that)."""
    import json

    import yaml

    from signorini.pipeline.config import ConfigError, load_yaml

    try:
        text = path.read_text(encoding="utf-8")
        try:
            data = json.loads(text)
        except ValueError:
            data = yaml.safe_load(text)
        if isinstance(data, dict):
            return None
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        pass
    try:
        load_yaml(path)
    except ConfigError as err:
        return f"{err}{_similar(path)}"
    return f"{path}: not a mapping of keys at top level"


def looks_like_target(word: str) -> bool:
    """A word after ``--configfile`` that is most likely a target: a rule of the workflow here, or
    not named like a config file and either no file at all (``all``) or an existing file, an
    output such as ``paper_figures/table1.csv``."""
    path = Path(word)
    if word in _rule_names():
        return True
    named_as_config = path.suffix.lower() in CONFIG_SUFFIXES
    return not named_as_config and (not path.exists() or (path.is_file() and path.suffix != ""))


def _similar(path: Path) -> str:
    """`` (did you mean my.yaml?)`` for a missing file with a config file of a similar name beside it."""
    import difflib

    if path.exists() or not path.parent.is_dir():
        return ""
    names = [p.name for p in path.parent.iterdir() if p.suffix.lower() in CONFIG_SUFFIXES]
    close = difflib.get_close_matches(path.name, names, n=1)
    return f" (did you mean {path.parent / close[0]}?)" if close else ""


def _rule_names() -> set[str]:
    """The rules of the workflow in the working directory (its Snakefile and workflow/rules/)."""
    files = [Path("Snakefile"), Path("workflow/Snakefile"), *sorted(Path("workflow/rules").glob("*.smk"))]
    names: set[str] = set()
    for file in files:
        try:
            names.update(RULE.findall(file.read_text(encoding="utf-8")))
        except (OSError, UnicodeDecodeError):
            continue
    return names


def _configfile_words(argv: list[str]) -> list[str]:
    """The words Snakemake reads as config files: each after ``--configfile`` up to the next option,
    and the value of ``--configfile=FILE``."""
    words: list[str] = []
    for i, arg in enumerate(argv):
        if arg in CONFIGFILE_OPTIONS:
            words += _until_option(argv[i + 1:])
        elif arg.startswith(tuple(f"{option}=" for option in CONFIGFILE_OPTIONS)):
            words.append(arg.partition("=")[2])
    return words


def _until_option(words: list[str]) -> list[str]:
    out = []
    for word in words:
        if word.startswith("-"):
            break
        out.append(word)
    return out


def snakemake_log_files() -> list[str]:
    """The log files Snakemake writes this run to (``.snakemake/log/...``; none in a dry run)."""
    handlers = logging.getLogger("snakemake.logging").handlers
    return [h.baseFilename for h in handlers if isinstance(h, logging.FileHandler)]


def append_to_logs(paths: Sequence[str], text: str) -> None:
    """``text`` appended to each log file of ``paths`` (one that cannot be written is passed over)."""
    for path in paths:
        try:
            with open(path, "a", encoding="utf-8") as log:
                log.write(text.rstrip("\n") + "\n")
        except OSError:
            pass


class AfterInterrupt(logging.Handler):
    """The handler of last resort after Ctrl-C (``LogHandler.close``): each record appended to
    Snakemake's log files, none on the console."""

    def __init__(self, paths: Sequence[str]) -> None:
        super().__init__(logging.DEBUG)
        self.paths = list(paths)

    def emit(self, record: logging.LogRecord) -> None:
        append_to_logs(self.paths, record.getMessage())


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
        self.log_files: list[str] = []
        self.hinted = False
        # Ctrl-C: the jobs end quietly (block_interrupts_in_threads); Snakemake itself does not catch
        # it while it reads the workflow or plans the jobs: then excepthook says the one line
        self.cwd = os.getcwd()
        self.command: tuple[list[str], bool] | None = None
        self.previous_excepthook = sys.excepthook
        sys.excepthook = self.excepthook
        block_interrupts_in_threads()

    def write(self, text: str) -> None:
        if text:
            self.stream.write(text.rstrip("\n") + "\n")
            self.stream.flush()

    def command_line(self) -> tuple[list[str], bool] | None:
        """``command_line`` of this run, read once, in the directory Snakemake was started in (its
        profiles are found from there; after ``--directory`` moved elsewhere: None)."""
        if self.command is None and os.getcwd() == self.cwd:
            self.command = command_line(sys.argv[1:])
        return self.command

    def interrupt(self) -> None:
        """Print the one line of Ctrl-C (once)."""
        if not self.interrupted:
            self.interrupted = True
            self.log_files = snakemake_log_files()
            command = self.command_line()
            self.write(interrupt_line(self.done, self.total, command is not None and command[1]))

    def excepthook(self, kind: type[BaseException], value: BaseException, tb: object) -> None:
        """A Ctrl-C that Snakemake did not catch: the one line; its traceback into Snakemake's log
        file, if it opened one (a dry run writes none)."""
        if not issubclass(kind, KeyboardInterrupt):
            self.previous_excepthook(kind, value, tb)
            return
        append_to_logs(snakemake_log_files(), "".join(traceback.format_exception(kind, value, tb)))
        self.interrupt()

    def close(self) -> None:
        """Snakemake closes its console, then tears the workflow down; after Ctrl-C that tear-down
        can fail (it closes the event loop of a worker thread that is still running one,
        ``RuntimeError: Cannot close a running event loop``), and Snakemake logs the traceback to a
        logger with no handler left, which Python prints on the console (``logging.lastResort``).
        After the one line of Ctrl-C, what is logged so goes to Snakemake's log file instead."""
        if self.interrupted:
            logging.lastResort = AfterInterrupt(self.log_files)
        super().close()

    def input_error(self, record: logging.LogRecord) -> str | None:
        """The one line of an input function's exception that is the user's mistake (``input_error_line``)."""
        if getattr(record, "exception", None) != "InputFunctionException":
            return None
        command = self.command_line()
        words = [w for w in sys.argv[1:] if not w.startswith("-")]
        return input_error_line(str(record.msg or ""), command[0] if command else words)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            if record.levelno >= logging.ERROR and not self.hinted and (hint := configfile_hint(sys.argv[1:])):
                self.hinted = True  # Snakemake read a target as a config file: say so instead
                self.write(hint)
                return
            if record.levelno >= logging.ERROR and (line := self.input_error(record)):
                self.write(line)  # an unknown scene or norm in a target: Snakemake's block is in its log file
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
            self.interrupt()
            return
        if record.levelno >= logging.ERROR and JOB_INTERRUPTED in text:
            # a job ended by Ctrl-C (the package's quiet exit status) before Snakemake's own
            # process saw the signal (seen under load): the same one line, not its error block
            self.interrupt()
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
