"""The short console (``src/snakemake_logger_plugin_signorini``, set by the default profile
``profiles/default/config.yaml``): one line per finished job with the count and the time left,
Snakemake's own output for dry runs, one line for Ctrl-C."""

from __future__ import annotations

import io
import logging
from types import SimpleNamespace

import yaml
from helpers import ROOT, planned_jobs
from snakemake_interface_logger_plugins.common import LogEvent

import snakemake_logger_plugin_signorini as console


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


def test_ctrl_c_ends_with_one_line():
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
    assert profile == {"logger": ["signorini"]}
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
