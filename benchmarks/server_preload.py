"""What the tests' Snakemake server saves per call by loading Snakemake's planning modules before it
forks (``tests/snakemake_server.py``, ``PRELOADED``), measured side by side in one run.

Two servers answer the same dry run (``snakemake -n results/smoke/errors.csv`` in a copy of the
checkout): one that loads only ``snakemake.cli`` before forking a call, one that also loads
``PRELOADED`` and collects the plugin registries.  They take turns, ``--calls`` calls each per round
(A B A B ...), ``--rounds`` rounds; each round's wall seconds per call and the 1-minute load before
it are recorded, and the ratio (preloaded / not) is taken round by round, its median given with a
bootstrap interval.  A dry run computes on
one thread, so on a quiet machine its wall time is its CPU time.  Written to
``docs/evidence/server_preload.json``:

    python benchmarks/server_preload.py [--rounds 5] [--calls 8]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # the tests' server

from snakemake_server import PRELOADED, Server  # noqa: E402

from signorini import intervals  # noqa: E402

SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
DRY_RUN = ["-n", "results/smoke/errors.csv"]


def checkout_copy(dest: Path) -> Path:
    """Snakefile, the lock, workflow/, src/ and the committed outputs: what a dry run reads."""
    shutil.copy2(ROOT / "Snakefile", dest)
    shutil.copy2(ROOT / "environment.lock", dest)
    for name in ("workflow", "src", "paper_figures", "docs/evidence"):
        shutil.copytree(ROOT / name, dest / name, ignore=shutil.ignore_patterns("__pycache__"))
    return dest


def per_call(server: Server, repo: Path, calls: int) -> dict:
    """Wall seconds per dry run over ``calls`` calls, with the 1-minute load before them."""
    env = {**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    for _ in range(calls):
        proc = server.run(SNAKEMAKE, DRY_RUN, repo, env, 300)
        if proc.returncode != 0:
            raise RuntimeError(f"snakemake {' '.join(DRY_RUN)} failed:\n{proc.stderr[-3000:]}")
    return {"wall_s": round((time.perf_counter() - t0) / calls, 4), "load1_before": load}


def summary(values: list[float]) -> dict:
    return {"median": round(statistics.median(values), 4), "min": round(min(values), 4), "max": round(max(values), 4)}


def compare(rounds: list[dict]) -> dict:
    """Per kind the wall seconds per call, and the ratio preloaded / not preloaded taken round by round
    (the two servers' calls of a round ran back to back, under the same load): its median with the
    bootstrap interval and verdict of ``signorini.intervals`` (``below``: the preload is faster)."""
    walls = {kind: [r[kind]["wall_s"] for r in rounds] for kind in ("cli_only", "preloaded")}
    per_round = [r["preloaded"]["wall_s"] / r["cli_only"]["wall_s"] for r in rounds]
    ratio = intervals.median(per_round, ("server_preload", "preloaded_over_cli_only"))
    return {
        "wall_s_per_call": {kind: summary(values) for kind, values in walls.items()},
        "preloaded_over_cli_only": summary(per_round)
        | {"interval": ratio.summary(), "verdict": intervals.verdict(ratio)},
        "load1_before": summary([r[kind]["load1_before"] for r in rounds for kind in ("cli_only", "preloaded")]),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--calls", type=int, default=8)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/server_preload.json")
    args = parser.parse_args(argv)
    servers = {"cli_only": Server(preload=False), "preloaded": Server(preload=True)}
    with tempfile.TemporaryDirectory(prefix="server-preload-") as tmp:
        repo = checkout_copy(Path(tmp))
        for server in servers.values():  # start each server; the first dry run fills the page cache
            per_call(server, repo, 1)
        rounds = [
            {kind: per_call(server, repo, args.calls) for kind, server in servers.items()} for _ in range(args.rounds)
        ]
    result = {
        "machine": {"cpus": os.cpu_count(), "processor": platform.processor() or platform.machine()},
        "command": " ".join(["snakemake", *DRY_RUN]),
        "preloaded_modules": list(PRELOADED),
        **compare(rounds),
        "rounds": rounds,
        "python": sys.version.split()[0],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    ratio = result["preloaded_over_cli_only"]
    print(f"wall per dry run: {result['wall_s_per_call']}; preloaded / cli only {ratio} -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
