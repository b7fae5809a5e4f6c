"""The built repository copy of a test run (``conftest.built_repo``): built once per run, in the
background from the start of the run, while the tests that do not need it go on.

A run's workers share one directory (``shared``).  ``start`` launches ``python built_copy.py``, which
takes the lock ``built.lock``, builds ``built/`` and marks it ``built.done``; ``ensure`` (the
fixture) takes the same lock, so it waits for a build under way, and builds the copy itself when no
build is done (none was started, or it failed: its log is ``built.log``).
"""

from __future__ import annotations

import atexit
import fcntl
import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import yaml
from helpers import MESHES_STUDY, SHIPPED_SCENES, TEST_SCENES, copy_repo, snakemake


def build(dest: Path, targets: list[str]) -> Path:
    """A repository copy in ``dest`` with the test scenes, every target of ``targets`` built."""
    repo = copy_repo(dest)
    path = repo / "workflow/config.yaml"
    config = yaml.safe_load(path.read_text(encoding="utf-8"))
    config["scenes"] = {name: config["scenes"][name] for name in SHIPPED_SCENES} | TEST_SCENES
    config["meshes_study"] = MESHES_STUDY
    # the second case's EOC test reads its three finest EOCs: its four finest meshes give them
    # unchanged (each mesh is solved on its own), at two thirds of the jobs
    config["scenes"]["case2"]["N"] = config["scenes"]["case2"]["N"][-4:]
    # and its convention norms in a job per mesh (the smoke scene keeps a job per norm, which the
    # fault tests damage one at a time): a quarter of its jobs, the same values
    config["scenes"]["case2"]["norm_jobs"] = "per_mesh"
    config["figures_scene"] = "smoke"
    path.write_text(yaml.safe_dump(config, sort_keys=False), encoding="utf-8")
    t0 = time.perf_counter()
    snakemake(repo, "-c2", *targets, timeout=3600)  # a loaded 2-core machine needs more than 10 min
    if "all" in targets and len(targets) > 1:
        # the summary (in `all`) reads the other studies' outputs, which this run wrote after it:
        # rendered again from them, as the next `snakemake all` of a user would
        snakemake(repo, "-c2", "all")
    print(f"built repository copy: {time.perf_counter() - t0:.1f} s", flush=True)
    return repo


def ensure(shared: Path, targets: list[str]) -> Path:
    """The run's built copy ``shared/built``: waited for while another process builds it, built here
    when no build is done."""
    with open(shared / "built.lock", "w", encoding="utf-8") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        repo, done = shared / "built", shared / "built.done"
        if not done.exists():
            shutil.rmtree(repo, ignore_errors=True)  # a build that failed
            repo.mkdir()
            build(repo, targets)
            done.touch()
    return repo


def start(shared: Path, targets: list[str]) -> None:
    """Build the run's copy in the background, unless a process of the run has started it already
    (stopped when the process that started it ends)."""
    try:
        os.close(os.open(shared / "built.started", os.O_CREAT | os.O_EXCL | os.O_WRONLY))
    except FileExistsError:
        return
    with open(shared / "built.log", "w", encoding="utf-8") as log:
        proc = subprocess.Popen(
            [sys.executable, __file__, str(shared), *targets],
            cwd=Path(__file__).parent,
            stdout=log,
            stderr=subprocess.STDOUT,
            start_new_session=True,
        )

    def stop() -> None:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)

    atexit.register(stop)


if __name__ == "__main__":
    sys.path.insert(0, str(Path(__file__).parent))
    ensure(Path(sys.argv[1]), sys.argv[2:])
