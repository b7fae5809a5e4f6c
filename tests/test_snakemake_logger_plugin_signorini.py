"""The short console (``src/snakemake_logger_plugin_signorini``, set by the default profile
``profiles/default/config.yaml``): one line per finished job with the count and the time left,
Snakemake's own output for dry runs, one line for Ctrl-C."""

from __future__ import annotations

import io
import logging
import os
import signal
import subprocess
import sys
import threading
from types import SimpleNamespace

import pytest
import yaml
from helpers import ROOT, planned_jobs
from snakemake_interface_logger_plugins.common import LogEvent

import snakemake_logger_plugin_signorini as console

BLOCK_INTERRUPTS_IN_THREADS = console.block_interrupts_in_threads  # the fixture below replaces it in the module

# Snakemake's block for an unknown scene in a target (as printed by Snakemake 9.27)
UNKNOWN_SCENE = """InputFunctionException in file "/x/workflow/rules/integrity.smk", line 73:
Error:
  ConfigError: unknown scene 'nosuch'; configured: paper, smoke
Wildcards:
  scene=nosuch
Traceback:
  File "/x/workflow/rules/scene.smk", line 141, in <lambda>
  File "/x/workflow/rules/common.smk", line 120, in scene_of (rule errors, line 266, /x/workflow/rules/scene.smk)"""


@pytest.fixture(autouse=True)
def process_hooks(monkeypatch):
    """A handler installs the excepthook and the thread hook of its run's process: undone after
    each test, and the thread hook not installed here (``test_jobs_start_with_sigint_blocked...``
    tests it)."""
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    monkeypatch.setattr(console, "block_interrupts_in_threads", lambda: None)


def handler(dryrun: bool = False, quiet=None) -> tuple[console.LogHandler, io.StringIO]:
    settings = SimpleNamespace(
        printshellcmds=True, nocolor=True, quiet=quiet, debug_dag=False, verbose=False,
        show_failed_logs=False, stdout=False, dryrun=dryrun,
    )
    h = console.LogHandler(settings, None)
    h.stream = io.StringIO()
    return h, h.stream


def record(msg: str | None = None, level: int = logging.INFO, **extra) -> logging.LogRecord:
    r = logging.LogRecord("snakemake", level, __file__, 0, msg, None, None)
    r.__dict__.update(extra)
    return r


def job_info(jobid: int, rule: str, **wildcards) -> logging.LogRecord:
    return record(
        f" Rule: {rule}, Jobid: {jobid}", event=LogEvent.JOB_INFO, jobid=jobid, rule_msg=None, rule_name=rule,
        local=False, input=["in.npz"], output=[f"out{jobid}.json"], log=[], benchmark=None, wildcards=wildcards,
        reason="Missing output files", resources={}, priority=0, threads=1, indent=False, is_checkpoint=False,
        printshellcmd=True, is_handover=False, shellcmd=None,
    )


def finished(jobid: int, done: int, total: int) -> list[logging.LogRecord]:
    return [
        record(f"Finished jobid: {jobid} (Rule: x)", event=LogEvent.JOB_FINISHED, job_id=jobid),
        record(None, event=LogEvent.PROGRESS, done=done, total=total),
    ]


def test_one_line_per_finished_job_with_count_and_time_left():
    h, out = handler()
    records = [
        record("Building DAG of jobs..."),
        record("Select jobs to execute..."),
        job_info(3, "solve", scene="paper", N="101"),
        job_info(4, "norm", scene="paper", N="101", norm="L4"),
        record("Execute 2 jobs..."),
        record("python script", event=LogEvent.SHELLCMD, cmd="python script"),
        *finished(3, 1, 2),
        *finished(4, 2, 2),
        record("Complete log(s): .snakemake/log/x.log"),
    ]
    for r in records:
        h.emit(r)
    lines = out.getvalue().splitlines()
    assert lines[0] == "Building DAG of jobs..." and lines[-1].startswith("Complete log(s)")
    assert lines[1].startswith("[1/2] solve scene=paper N=101   0:00 elapsed, about 0:00 left"), lines
    assert lines[2].startswith("[2/2] norm scene=paper N=101 norm=L4   0:00 elapsed") and "left" not in lines[2]
    assert len(lines) == 4  # no scheduling chatter, no job blocks, no shell commands


def test_the_estimate_is_linear_in_the_jobs_left():
    assert console.progress_line(10, 40, "solve", 65.0) == "[10/40] solve   1:05 elapsed, about 3:15 left"
    assert console.progress_line(40, 40, "all", 3725.0) == "[40/40] all   1:02:05 elapsed"


def test_ctrl_c_ends_with_one_line(monkeypatch):
    monkeypatch.setattr(console, "command_line", lambda argv: (["all"], True))
    h, out = handler()
    for r in [job_info(1, "discretise", scene="s", N="11"), *finished(1, 1, 5), job_info(2, "solve", N="11")]:
        h.emit(r)
    h.emit(record("Terminating processes on user request, this might take some time."))
    for _ in range(3):  # each running job's error, then Snakemake's exception
        h.emit(record("Error in rule solve", level=logging.ERROR, event=LogEvent.JOB_ERROR))
        h.emit(record("CalledProcessError ... died with <Signals.SIGINT: 2>", level=logging.ERROR))
    h.emit(record("Cancelling snakemake on user request.", level=logging.ERROR))
    lines = out.getvalue().splitlines()
    assert lines[-1] == "interrupted: 1 of 5 jobs finished and kept; the same command continues from them"
    assert len(lines) == 2 and "CalledProcessError" not in out.getvalue()


def test_a_dry_run_prints_snakemakes_job_blocks():
    """What the dry-run parsers of the tests and a user read: ``rule X:`` with its wildcards."""
    h, out = handler(dryrun=True)
    h.emit(job_info(3, "solve", scene="paper", N="101"))
    h.emit(job_info(4, "norm", scene="paper", N="101", norm="L4"))
    assert planned_jobs(out.getvalue()) == [
        ("solve", {"scene": "paper", "N": "101"}), ("norm", {"scene": "paper", "N": "101", "norm": "L4"})
    ]


def test_the_default_profile_selects_the_plugin():
    from snakemake_interface_logger_plugins.registry import LoggerPluginRegistry

    profile = yaml.safe_load((ROOT / "profiles/default/config.yaml").read_text(encoding="utf-8"))
    assert profile == {"logger": ["signorini"], "rerun-incomplete": True}
    assert LoggerPluginRegistry().get_plugin("signorini").log_handler is console.LogHandler


def test_a_target_after_configfile_is_recognised(tmp_path, monkeypatch):
    """``snakemake --configfile my.yaml all``: Snakemake reads ``all`` as a second config file."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my.yaml").write_text("scenes: {}\n", encoding="utf-8")
    (tmp_path / "table1.csv").write_text("N,L4\n101,1e-5\n", encoding="utf-8")
    for target in ("all", "table1.csv"):
        hint = console.configfile_hint(["-c2", "--configfile", "my.yaml", target])
        assert hint.count("\n") == 1 and f"--configfile: '{target}' is not a config file" in hint, hint
        assert f"snakemake {target} --configfile my.yaml" in hint
    assert console.configfile_hint(["all", "--configfile", "my.yaml", "-n"]) is None
    h, out = handler()
    monkeypatch.setattr("sys.argv", ["snakemake", "--configfile", "my.yaml", "all"])
    h.emit(record("FileNotFoundError: [Errno 2] No such file or directory: 'all'", level=logging.ERROR))
    assert out.getvalue().startswith("--configfile: 'all' is not a config file")


# what Snakemake cannot read as a config file: (file, content, the one line the console prints)
UNREADABLE = [
    ("syntax.yaml", b"scenes:\n  mine:\n    N: [11, 21\n", "--configfile: syntax.yaml:4:1: did not find expected ','"),
    ("utf16.yaml", "scenes: {}\n".encode("utf-16"), "--configfile: utf16.yaml: UTF-16 text; a config file is UTF-8"),
    ("empty.yaml", b"# nothing yet\n", "--configfile: empty.yaml: empty (or only comments); a config file holds"),
    ("list.yaml", b"- scenes\n", "--configfile: list.yaml: holds a list; a config file holds a mapping of keys"),
    ("mine.yml", None, "--configfile: mine.yml: no such file; give the path of a YAML or JSON config file (did you "
                       "mean my.yaml?)"),
]


def test_a_configfile_snakemake_cannot_read_is_named_with_the_reason(tmp_path, monkeypatch):
    """A syntax error, UTF-16, an empty file, a list, a misspelled path: each was called "as it seems,
    a target" with the advice to write the targets first; now one line with the reason each."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "my.yaml").write_text("scenes: {}\n", encoding="utf-8")
    for name, content, line in UNREADABLE:
        if content is not None:
            (tmp_path / name).write_bytes(content)
        hint = console.configfile_hint(["-n", "--configfile", name])
        assert hint.startswith(line) and "\n" not in hint and "target" not in hint, hint
        assert console.configfile_hint([f"--configfile={name}"]).startswith(line)
        lines = console.configfile_hint(["--configfile", "my.yaml", name, "all"]).splitlines()  # a line per file
        assert lines[0].startswith(line) and lines[1].startswith("--configfile: 'all' is not a config file"), lines
        assert lines[2].startswith(f"Write the targets first: snakemake all --configfile my.yaml {name}  (or end")


def test_a_word_is_a_target_only_when_it_looks_like_one(tmp_path, monkeypatch):
    """A target: no such file and not named like a config file (``all``), an existing output
    (``table1.csv``), or a rule of the workflow here even where a file of that name exists."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "Snakefile").write_text("rule theory:\n    input: []\n", encoding="utf-8")
    (tmp_path / "theory").write_text("not: [a config\n", encoding="utf-8")
    (tmp_path / "settings").write_text("not: [a config\n", encoding="utf-8")
    (tmp_path / "table1.csv").write_text("N,L4\n101,1e-5\n", encoding="utf-8")
    assert [console.looks_like_target(w) for w in ("all", "table1.csv", "theory")] == [True, True, True]
    assert [console.looks_like_target(w) for w in ("mine.yaml", "mine.JSON", "settings")] == [False, False, False]
    assert console.configfile_hint(["--configfile", "settings"]).startswith("--configfile: settings:2:1:")


def test_snakemake_names_a_utf16_configfile(tmp_path):
    """For real: Snakemake fails to read the file, the console says why in one line."""
    import subprocess

    from helpers import SNAKEMAKE

    (tmp_path / "Snakefile").write_text("rule all:\n    input: []\n", encoding="utf-8")
    (tmp_path / "mine.yaml").write_bytes("scenes: {}\n".encode("utf-16"))
    proc = subprocess.run([SNAKEMAKE, "-n", "--logger", "signorini", "--configfile", "mine.yaml"], cwd=tmp_path,
                          capture_output=True, text=True, timeout=120)
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.strip()]
    assert proc.returncode != 0
    assert lines == ["--configfile: mine.yaml: UTF-16 text; a config file is UTF-8 text: save it as UTF-8"], lines


def test_the_ctrl_c_advice_names_rerun_incomplete_unless_the_run_has_it(tmp_path, monkeypatch):
    """Ctrl-C leaves the outputs of the jobs it cut off marked incomplete: the same command goes on
    only with --rerun-incomplete, which the default profile sets; a run without it (no workflow
    profile, or one of the user's own) is told to add it."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "Snakefile").write_text("rule all:\n", encoding="utf-8")
    (tmp_path / "profiles/default").mkdir(parents=True)
    (tmp_path / "profiles/default/config.yaml").write_bytes((ROOT / "profiles/default/config.yaml").read_bytes())
    (tmp_path / "mine").mkdir()
    (tmp_path / "mine/config.yaml").write_text("cores: 1\n", encoding="utf-8")
    cases = {
        ("-c2", "results/a.csv"): True,
        ("-c2", "--profile", "mine", "results/a.csv"): True,  # the workflow profile still applies
        ("-c2", "--workflow-profile", "none", "results/a.csv"): False,
        ("-c2", "--workflow-profile", "mine", "results/a.csv"): False,
        ("-c2", "--workflow-profile", "none", "--rerun-incomplete", "results/a.csv"): True,
    }
    for argv, reruns in cases.items():
        assert console.command_line(list(argv)) == (["results/a.csv"], reruns), argv
    assert console.command_line(["--no-such-option"]) is None  # unreadable: the advice names the option
    assert console.interrupt_line(3, 9, False) == (
        "interrupted: 3 of 9 jobs finished and kept; the same command with --rerun-incomplete continues from them"
    )
    assert console.interrupt_line(0, 9, False).endswith("the same command with --rerun-incomplete starts again")
    monkeypatch.setattr("sys.argv", ["snakemake", "-c2", "--workflow-profile", "none", "all"])
    h, out = handler()
    h.emit(record("Terminating processes on user request, this might take some time."))
    assert out.getvalue() == "interrupted: no job had finished; the same command with --rerun-incomplete starts again\n"


def test_a_ctrl_c_snakemake_does_not_catch_is_one_line_its_traceback_in_the_log(tmp_path, monkeypatch):
    """Ctrl-C while Snakemake reads the workflow or plans the jobs ends the process with an uncaught
    KeyboardInterrupt: the one line on the console, the traceback in Snakemake's log file."""
    monkeypatch.setattr(console, "command_line", lambda argv: (["all"], True))
    log = logging.FileHandler(tmp_path / "snakemake.log", encoding="utf-8")
    logging.getLogger("snakemake.logging").addHandler(log)
    try:
        h, out = handler()
        assert sys.excepthook == h.excepthook
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as err:
            sys.excepthook(type(err), err, err.__traceback__)
            sys.excepthook(type(err), err, err.__traceback__)  # printed once
    finally:
        logging.getLogger("snakemake.logging").removeHandler(log)
        log.close()
    assert out.getvalue() == "interrupted: no job had finished; the same command starts again\n"
    text = (tmp_path / "snakemake.log").read_text(encoding="utf-8")
    assert "Traceback" in text and "KeyboardInterrupt" in text
    seen = []
    monkeypatch.setattr(h, "previous_excepthook", lambda *args: seen.append(args[0]))
    h.excepthook(ValueError, ValueError("x"), None)  # anything else: as before
    assert seen == [ValueError]


TEAR_DOWN_ERROR = "Traceback (most recent call last):\n  ...\nRuntimeError: Cannot close a running event loop"


@pytest.mark.parametrize("interrupted", [True, False])
def test_after_ctrl_c_what_snakemake_logs_past_its_console_goes_to_its_log_file(tmp_path, monkeypatch, capsys,
                                                                                 interrupted):
    """Snakemake closes its console and log file, then tears the workflow down; after Ctrl-C that
    can fail (the event loop of a worker thread still running), and its traceback, logged with no
    handler left, reached the console through Python's handler of last resort.  After Ctrl-C it
    goes to Snakemake's log file; without Ctrl-C the console shows it as before."""
    monkeypatch.setattr(console, "command_line", lambda argv: (["all"], True))
    monkeypatch.setattr(logging, "lastResort", logging.lastResort)
    snakemake_logger = logging.getLogger("snakemake.logging")
    monkeypatch.setattr(snakemake_logger, "propagate", False)  # not to pytest's capturing handler on the root
    path = tmp_path / "snakemake.log"
    log = logging.FileHandler(path, encoding="utf-8")
    snakemake_logger.addHandler(log)
    try:
        h, out = handler()
        if interrupted:
            h.emit(record("Terminating processes on user request, this might take some time."))
    finally:  # as Snakemake's logger manager stops: its handlers closed and removed
        h.close()
        snakemake_logger.removeHandler(log)
        log.close()
    snakemake_logger.error(TEAR_DOWN_ERROR)
    console_text = capsys.readouterr().err
    if interrupted:
        assert out.getvalue() == "interrupted: no job had finished; the same command starts again\n"
        assert console_text == ""
        assert path.read_text(encoding="utf-8").endswith(TEAR_DOWN_ERROR + "\n")
    else:
        assert out.getvalue() == ""
        assert "Cannot close a running event loop" in console_text
        assert "Cannot close" not in path.read_text(encoding="utf-8")


def test_jobs_start_with_sigint_blocked_and_the_package_delivers_it_quietly(monkeypatch):
    """Threads started after ``block_interrupts_in_threads`` block SIGINT, and so do the processes
    they start (through bash, as Snakemake starts a job); a Ctrl-C that reaches such a job before
    the package is imported waits, and ends the job at the import, with exit status 130 and
    nothing printed.  The main thread keeps SIGINT."""
    monkeypatch.setattr(threading, "_profile_hook", None)  # the hook is undone after the test
    BLOCK_INTERRUPTS_IN_THREADS()
    job = ("import os, signal, sys; masked = signal.SIGINT in signal.pthread_sigmask(signal.SIG_BLOCK, []); "
           "print(masked, flush=True); os.kill(os.getpid(), signal.SIGINT); import signorini; print('not reached')")
    result = {}

    def start() -> None:
        result["mask"] = signal.pthread_sigmask(signal.SIG_BLOCK, [])
        result["job"] = subprocess.run(
            ["bash", "-c", f"set -euo pipefail; {sys.executable} -c \"{job}\""], capture_output=True, encoding="utf-8",
            env={**os.environ, "SIGNORINI_JOB_INTERRUPT": "quiet", "PYTHONPATH": str(ROOT / "src")},
        )

    thread = threading.Thread(target=start)
    thread.start()
    thread.join()
    assert signal.SIGINT in result["mask"] and signal.SIGINT not in signal.pthread_sigmask(signal.SIG_BLOCK, [])
    job = result["job"]
    assert job.stdout == "True\n" and job.stderr == "" and job.returncode == 130, job


def test_an_unknown_scene_or_norm_in_a_target_is_one_line(monkeypatch):
    """Snakemake's block for an input function's exception whose cause is the user's mistake
    (ConfigError, UnknownNormError): ``error: <target>: <message>``, in a run and a dry run; the
    block itself stays in Snakemake's log file."""
    line = "error: results/nosuch/errors.csv: unknown scene 'nosuch'; configured: paper, smoke"
    assert console.input_error_line(UNKNOWN_SCENE, ["all", "results/nosuch/errors.csv"]) == line
    assert console.input_error_line(UNKNOWN_SCENE, ["all"]).startswith("error: rule errors scene=nosuch: unknown scene")
    assert console.input_error_line(UNKNOWN_SCENE.replace("ConfigError", "KeyError"), ["all"]) is None  # a fault
    norm = UNKNOWN_SCENE.replace("ConfigError: unknown scene 'nosuch'; configured: paper, smoke",
                                 "UnknownNormError: unknown norm 'W1_4'; a norm is L or W1 ...")
    norm = norm.replace("  scene=nosuch", "  scene=paper\n  N=101\n  norm=W1_4")
    target = "results/paper/N101/norms/W1_4.json"
    assert console.input_error_line(norm, [target]) == f"error: {target}: unknown norm 'W1_4'; a norm is L or W1 ..."
    monkeypatch.setattr(console, "command_line", lambda argv: (["results/nosuch/errors.csv"], True))
    for dryrun in (False, True):
        h, out = handler(dryrun=dryrun)
        h.emit(record(UNKNOWN_SCENE, level=logging.ERROR, event=LogEvent.ERROR, exception="InputFunctionException"))
        assert out.getvalue() == line + "\n"


def test_a_job_ended_by_ctrl_c_before_snakemake_saw_it_is_the_one_line(monkeypatch):
    """Under load a job's quiet exit (status 130) can reach Snakemake before its own process handles
    the signal: the one interrupt line, not the failed job's error block; any other failure is
    printed as Snakemake prints it."""
    monkeypatch.setattr(console, "command_line", lambda argv: (["all"], True))
    h, out = handler()
    failed = "CalledProcessError in file x: Command '...' returned non-zero exit status {}."
    h.emit(record(failed.format(1), level=logging.ERROR))
    assert "exit status 1." in out.getvalue() and not h.interrupted
    h.emit(record(failed.format(130), level=logging.ERROR))
    h.emit(record("Error in rule discretise", level=logging.ERROR, event=LogEvent.JOB_ERROR))
    lines = out.getvalue().splitlines()
    assert h.interrupted and lines[-1].startswith("interrupted: ") and "exit status 130" not in out.getvalue()
