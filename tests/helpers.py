"""Helpers of the workflow tests: repository copies, Snakemake runs and dry-run parsing.

Workflow runs happen in a temporary copy of the repository (Snakefile, workflow/, src/), so
the real tree and its results/ cache are never touched.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

from signorini.studies.work_precision.study import PEER_PYTHON

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
PROBLEM = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}
# the PETSc peers' interpreter of the tests (default: the study's, /usr/bin/python3); .ci/run sets
# one without numpy for a second pass, so that the "skipped, with the reason" route is tested too
TEST_PEER_PYTHON = os.environ.get("SIGNORINI_TEST_PEER_PYTHON") or PEER_PYTHON


def copy_repo(dest: Path) -> Path:
    """Snakefile, workflow/ and src/ (the rules' code inputs) into ``dest``; mtimes preserved."""
    shutil.copy2(ROOT / "Snakefile", dest / "Snakefile")
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    shutil.copytree(ROOT / "workflow", dest / "workflow", ignore=ignore)
    shutil.copytree(ROOT / "src", dest / "src", ignore=ignore)
    return dest


def clone_built(repo: Path, dest: Path) -> Path:
    """A copy of a built repository copy (results, outputs, Snakemake's metadata), mtimes kept,
    for a test that edits or damages it."""
    shutil.copytree(repo, dest, symlinks=True, dirs_exist_ok=True, ignore=shutil.ignore_patterns("__pycache__"))
    return dest


def snakemake(workdir: Path, *args: str, check: bool = True, timeout: float = 600) -> subprocess.CompletedProcess:
    proc = subprocess.run(
        [SNAKEMAKE, *args],
        cwd=workdir,
        capture_output=True,
        text=True,
        timeout=timeout,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )
    if check and proc.returncode != 0:
        raise AssertionError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-6000:]}")
    return proc


def planned_jobs(text: str) -> list[tuple[str, dict[str, str]]]:
    """(rule, wildcards) of every job in a dry run's output."""
    jobs: list[tuple[str, dict[str, str]]] = []
    for line in text.splitlines():
        if m := re.match(r"^(?:local)?rule (\w+):$", line):
            jobs.append((m.group(1), {}))
        elif (m := re.match(r"^\s+wildcards: (.*)$", line)) and jobs:
            jobs[-1][1].update(kv.split("=", 1) for kv in m.group(1).split(", "))
    return jobs


def planned(proc: subprocess.CompletedProcess) -> list[tuple[str, dict[str, str]]]:
    return planned_jobs(proc.stdout + proc.stderr)


def planned_rules(proc: subprocess.CompletedProcess) -> set[str]:
    return {rule for rule, _ in planned(proc)} - {"all"}


def dry_run_jobs(text: str) -> list[dict]:
    """Every job block of a dry run's output: ``rule``, ``wildcards``, ``input``, ``output``, ``log``."""
    jobs: list[dict] = []
    for line in text.splitlines():
        if m := re.match(r"^(?:local)?rule (\w+):$", line):
            jobs.append({"rule": m.group(1), "wildcards": {}, "input": [], "output": [], "log": []})
        elif jobs and (m := re.match(r"^\s+(input|output|log|wildcards): (.*)$", line)):
            key, value = m.groups()
            if key == "wildcards":
                jobs[-1]["wildcards"].update(kv.split("=", 1) for kv in value.split(", "))
            else:
                jobs[-1][key] = value.split(", ")
    return jobs


def job_key(job: dict) -> tuple[str, tuple]:
    return job["rule"], tuple(sorted(job["wildcards"].items()))
