"""Wall time of a cold ``all`` through Slurm against the local ``snakemake -c2 all``, on this machine:

    python benchmarks/slurm_walltime.py      # as root, Debian -> docs/evidence/slurm_walltime.json

Starts a single-node Slurm with accounting (``scripts/slurm/start-cluster --accounting``; CPUs
and memory of this machine), then in fresh copies of the repository (Snakefile, workflow/, src/)
runs ``snakemake -c2 all`` (local), ``snakemake all --profile workflow/profiles/slurm`` (Slurm),
the same with one job per norm (``--config norm_jobs=per_norm``), the local run once more and
once with the Slurm profile's ``norm_jobs: per_mesh``, each from an empty cache, and stops the
cluster.  Records each wall
time (whole Snakemake calls), the 1-minute load average before each run, the Slurm jobs
submitted, and the ratio of the Slurm time to the mean of the two local times.  The JSON is
written atomically.
"""

from __future__ import annotations

import argparse
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
LOCAL_PER_MESH = ("-c2", "all", "--config", "norm_jobs=per_mesh")
SLURM_ARGS = ("--profile", "workflow/profiles/slurm", "--default-resources", "slurm_account=signorini")
SLURM_PER_NORM = ("all", *SLURM_ARGS, "--config", "norm_jobs=per_norm")


def fresh_copy(dest: Path) -> Path:
    dest.mkdir()
    shutil.copy2(ROOT / "Snakefile", dest / "Snakefile")
    for name in ("workflow", "src"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__"))
    return dest


def timed_run(repo: Path, args: tuple[str, ...], env: dict) -> dict:
    """One cold Snakemake call in ``repo``: wall time, load before, Slurm jobs submitted."""
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.run([SNAKEMAKE, *args], cwd=repo, capture_output=True, encoding="utf-8", env=env)
    seconds = time.perf_counter() - t0
    out = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise RuntimeError(f"snakemake {' '.join(args)} failed:\n{out[-3000:]}")
    return {"wall_s": seconds, "load1_before": load, "slurm_jobs": out.count("submitted with SLURM jobid")}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/slurm_walltime.json")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT / "src"))
    from signorini.pipeline.artifacts import save_json

    with tempfile.TemporaryDirectory(prefix="signorini-slurm-bench-") as tmp:
        state = Path(tmp) / "cluster"
        env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
        try:
            t0 = time.perf_counter()
            subprocess.run([ROOT / "scripts/slurm/start-cluster", "--accounting", state], check=True)
            start_s = time.perf_counter() - t0
            conf = (state / "etc/slurm.conf").as_posix()
            env_slurm = {**env, "SLURM_CONF": conf, "PATH": f"{state / 'bin'}{os.pathsep}{env['PATH']}"}
            runs = {
                "local_1": timed_run(fresh_copy(Path(tmp) / "local_1"), ("-c2", "all"), env),
                "slurm": timed_run(fresh_copy(Path(tmp) / "slurm"), ("all", *SLURM_ARGS), env_slurm),
                # the same profile with one job per norm: what the per-mesh norms job saves
                "slurm_per_norm": timed_run(fresh_copy(Path(tmp) / "slurm_per_norm"), SLURM_PER_NORM, env_slurm),
                "local_2": timed_run(fresh_copy(Path(tmp) / "local_2"), ("-c2", "all"), env),
                # the Slurm route's job granularity, locally: what batching the norms alone changes
                "local_per_mesh": timed_run(fresh_copy(Path(tmp) / "local_per_mesh"), LOCAL_PER_MESH, env),
            }
        finally:
            subprocess.run([ROOT / "scripts/slurm/stop-cluster", state], check=False)
    local_s = (runs["local_1"]["wall_s"] + runs["local_2"]["wall_s"]) / 2
    result = {
        "runs": runs,
        "local_mean_s": local_s,
        "slurm_s": runs["slurm"]["wall_s"],
        "ratio_slurm_to_local": runs["slurm"]["wall_s"] / local_s,
        "cluster_start_s": start_s,
        "cluster": "single node (this machine), scripts/slurm/start-cluster --accounting",
        "machine": {"cpus": os.cpu_count(), "platform": platform.platform(), "python": platform.python_version()},
        "date": time.strftime("%Y-%m-%d %H:%M:%S"),
        "note": "cold runs of `all` (empty cache) in fresh copies of the repository; local = snakemake -c2 all",
    }
    save_json(args.out, result)
    print(
        f"cold all: local {runs['local_1']['wall_s']:.0f} s / {runs['local_2']['wall_s']:.0f} s, through Slurm "
        f"{result['slurm_s']:.0f} s ({runs['slurm']['slurm_jobs']} Slurm jobs): ratio "
        f"{result['ratio_slurm_to_local']:.2f}; through Slurm with norm_jobs=per_norm "
        f"{runs['slurm_per_norm']['wall_s']:.0f} s; local with norm_jobs=per_mesh "
        f"{runs['local_per_mesh']['wall_s']:.0f} s -> {args.out}"
    )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
