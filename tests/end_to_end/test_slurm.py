"""The cluster route: the slurm profile on a throw-away single-node Slurm (scripts/slurm/).

The cluster tests need Slurm's daemons (Debian: slurm-wlm, munge) and root; CI has both (its
Slurm step installs them), elsewhere they are skipped.  They start a cluster without accounting,
so the executor's job status comes from squeue, and always stop it again.
"""

from __future__ import annotations

import math
import os
import shutil
import subprocess

import pytest
import yaml
from helpers import ROOT, copy_repo, snakemake
from helpers import smoke_config as _smoke_config

from signorini.pipeline.resources import MEM_MB, largest_job, machine_mem_mb
from signorini.studies.scene.store import read_norm

START, STOP = ROOT / "scripts/slurm/start-cluster", ROOT / "scripts/slurm/stop-cluster"
HAS_SLURM = all(shutil.which(cmd) for cmd in ("slurmctld", "slurmd", "munged", "sbatch")) and os.geteuid() == 0
needs_slurm = pytest.mark.skipif(not HAS_SLURM, reason="needs Slurm's daemons (slurm-wlm, munge) and root")
SLURM = ("--profile", "workflow/profiles/slurm", "--slurm-status-command", "squeue")


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    """A single-node Slurm without accounting: the environment that points Slurm's commands at it."""
    state = tmp_path_factory.mktemp("slurm")
    try:
        # the node announces 1 GB less than the machine has: a mesh between the two fits here
        # but not on the node
        memory = str(machine_mem_mb() - 1024)
        proc = subprocess.run([START, "--real-memory", memory, state], capture_output=True, text=True, timeout=900)
        assert proc.returncode == 0, proc.stdout + proc.stderr
        env_file = (state / "env").read_text()
        conf = env_file.split("SLURM_CONF=")[1].split("\n")[0]
        yield {"SLURM_CONF": conf, "PATH": f"{state / 'bin'}{os.pathsep}{os.environ['PATH']}"}
    finally:
        subprocess.run([STOP, state], capture_output=True, timeout=120)


@needs_slurm
def test_the_smoke_scene_runs_through_slurm_without_accounting(cluster, tmp_path, monkeypatch):
    """Two mesh groups as Slurm jobs, their status from squeue (sacct fails without slurmdbd); the
    default config passes the node check (every request fits the node), and the norms equal a
    local run's."""
    for key, value in cluster.items():
        monkeypatch.setenv(key, value)
    targets = ["results/smoke/N11/norms/L4.json", "results/smoke/N21/norms/W1inf.json"]
    (tmp_path / "slurm").mkdir()
    (tmp_path / "local").mkdir()
    slurm, local = copy_repo(tmp_path / "slurm"), copy_repo(tmp_path / "local")
    proc = snakemake(slurm, *targets, *SLURM, timeout=900)
    out = proc.stdout + proc.stderr
    assert out.count("submitted with SLURM jobid") == 2, out[-3000:]
    assert "Falling back to 'sacct'" not in out
    snakemake(local, "-c2", *targets)
    for target in targets:
        *_, N, _, norm = target.replace(".json", "").split("/")
        N = int(N[1:])
        assert read_norm(slurm / target, norm, N) == read_norm(local / target, norm, N)


@needs_slurm
def test_a_request_larger_than_the_node_is_refused_before_submission(cluster, tmp_path, monkeypatch):
    for key, value in cluster.items():
        monkeypatch.setenv(key, value)
    repo = copy_repo(tmp_path)
    # a solve that needs 0.5 GB less than the machine has (this machine would run it) and 0.5 GB
    # more than the node
    base, per = MEM_MB["solve"]
    N = math.isqrt((machine_mem_mb() - 512 - base) * per)
    assert largest_job(N)[0] == "solve"
    scene = {**_smoke_config([])["scenes"]["smoke"], "N": [11, N]}
    (repo / "big.yaml").write_text(yaml.safe_dump({"scenes": {"big": scene}}))
    # the memory of the meshes a run needs is checked on its plan: the big mesh's solve
    proc = snakemake(repo, f"results/big/N{N}/solution.npz", *SLURM, "--configfile", "big.yaml", check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert f"scenes.big.N[1]: N = {N} needs about" in out
    assert "of the largest node of Slurm partition main" in out
    assert "submitted with SLURM jobid" not in out
    proc = snakemake(repo, "results/smoke/N11/system.npz", *SLURM, "--cores", "64", check=False)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0
    assert "a group job would request --cpus-per-task=64, more than the" in out
    assert "submitted with SLURM jobid" not in out
