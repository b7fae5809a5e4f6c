"""Ctrl-C of a real run as a terminal sends it: SIGINT to the whole process group, Snakemake and
its jobs alike.  The console shows one ``interrupted:`` line and no traceback, and the same command
then completes.  The decisions behind it (the advice, the blocked SIGINT of the jobs, the uncaught
interrupt) are tested in ``tests/test_snakemake_logger_plugin_signorini.py``."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import time
from pathlib import Path

import pytest
from helpers import ROOT, SNAKEMAKE, copy_repo, snakemake

from signorini.pipeline.integrity import table_defect

# a scene of two meshes and two norms: nine jobs
SCENE = "scenes:\n  tiny:\n    N: [11, 21]\n    norms: [L2, H1]\n"
TARGET = "results/tiny/errors.csv"


def in_preamble(group: int) -> bool:
    """Whether a job's interpreter in process group ``group`` (a process running a script of
    ``.snakemake/scripts/``) has Python's SIGINT handler (``SigCgt`` in ``/proc``): it is then in
    Snakemake's script preamble, where a Ctrl-C used to print a traceback, and stays there for
    about half a second (the import of Snakemake)."""
    for cmdline in Path("/proc").glob("[0-9]*/cmdline"):
        try:
            argv = cmdline.read_bytes().split(b"\0")
            if len(argv) < 2 or b"/.snakemake/scripts/" not in argv[1] or os.getpgid(int(cmdline.parent.name)) != group:
                continue
            status = (cmdline.parent / "status").read_text(encoding="utf-8")
        except (OSError, ProcessLookupError):
            continue  # gone meanwhile
        caught = next(line.split()[1] for line in status.splitlines() if line.startswith("SigCgt:"))
        if int(caught, 16) & 1 << (signal.SIGINT - 1):
            return True
    return False


@pytest.mark.slow
@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux's /proc to see a job start")
def test_ctrl_c_of_a_run_is_one_line_and_the_same_command_continues(tmp_path):
    """SIGINT to the process group while the first job is in Snakemake's script preamble, before
    the package's quiet handler exists, where a traceback with the 20 KB pickled preamble line used
    to reach the console."""
    repo = copy_repo(tmp_path)
    shutil.copytree(ROOT / "profiles", repo / "profiles")  # the short console, as in a checkout
    (repo / "tiny.yaml").write_text(SCENE, encoding="utf-8")
    command = ["-c2", TARGET, "--configfile", "tiny.yaml"]
    run = subprocess.Popen(
        [SNAKEMAKE, *command],
        cwd=repo,
        start_new_session=True,  # its own process group, as a terminal's foreground job
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        encoding="utf-8",
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )
    deadline = time.monotonic() + 300
    while run.poll() is None and not in_preamble(run.pid) and time.monotonic() < deadline:
        time.sleep(0.002)
    assert run.poll() is None, "the run ended before its first job started"
    os.killpg(run.pid, signal.SIGINT)
    out, _ = run.communicate(timeout=120)
    lines = out.splitlines()
    assert "Traceback" not in out and "Error in rule" not in out and len(out) < 2000, out
    assert [line for line in lines if line.startswith("interrupted:")] == [lines[-1]], out
    assert lines[-1] == "interrupted: no job had finished; the same command starts again", out
    assert len(lines) <= 16, out  # the profile line, the config line, the job stats, the one line
    snakemake(repo, *command)  # the same command completes
    assert table_defect(repo / TARGET) is None
