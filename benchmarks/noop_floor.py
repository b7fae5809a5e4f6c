"""What a no-op costs against Snakemake's own floor, measured side by side in one run.

In a copy of the checkout with ``all`` built (``--repo`` reuses one), three commands are run in
turn, ``--repeats`` rounds (A B C A B C ...), each's wall and CPU seconds recorded with the
1-minute load average before it:

- ``floor``: ``snakemake --version`` (Python and Snakemake's imports: what any call pays);
- ``trivial``: a no-op of a one-rule workflow (Snakemake's parsing, DAG and scheduler set-up);
- ``noop``: ``snakemake -c2 all`` on the built cache ("Nothing to be done"): this workflow's
  parse, config checks, DAG and cache check.

With ``--compare DIR`` (a built copy of another revision) its no-op runs in the same rounds
(``noop_compared``).  The ratios are taken round by round (the commands of one round ran back
to back), reported as median with min and max.  Written to ``docs/evidence/noop_floor.json``:

    python benchmarks/noop_floor.py [--repo DIR] [--repeats 9]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
TRIVIAL = 'rule all:\n    input: "done"\n\nrule make:\n    output: "done"\n    shell: "touch {output}"\n'


def timed(cwd: Path, *args: str) -> dict:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    load = os.getloadavg()[0]
    t0 = time.perf_counter()
    proc = subprocess.run([SNAKEMAKE, *args], cwd=cwd, capture_output=True, encoding="utf-8")
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"snakemake {' '.join(args)} failed:\n{proc.stdout[-2000:]}{proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return {"wall_s": round(wall, 3), "cpu_s": round(cpu, 3), "load1_before": load, "out": proc.stdout + proc.stderr}


def built(tmp: Path) -> Path:
    repo = tmp / "repo"
    repo.mkdir()
    shutil.copy2(ROOT / "Snakefile", repo)
    shutil.copy2(ROOT / "environment.lock", repo)
    for name in ("workflow", "src", "profiles", "paper_figures"):
        shutil.copytree(ROOT / name, repo / name, ignore=shutil.ignore_patterns("__pycache__"))
    timed(repo, "-c2", "all")
    return repo


def summary(values: list[float]) -> dict:
    return {"median": round(statistics.median(values), 3), "min": round(min(values), 3), "max": round(max(values), 3)}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repo", type=Path, help="a copy of the checkout with `all` built (default: build one)")
    parser.add_argument("--compare", type=Path, help="a built copy of another revision: its no-op, in the same rounds")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/noop_floor.json")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="noop-floor-") as tmp:
        repo = args.repo or built(Path(tmp))
        trivial = Path(tmp) / "trivial"
        trivial.mkdir()
        (trivial / "Snakefile").write_text(TRIVIAL, encoding="utf-8")
        timed(trivial, "-c1")
        commands = {
            "floor": (repo, ["--version"]),
            "trivial": (trivial, ["-c1", "--workflow-profile", "none"]),
            "noop": (repo, ["-c2", "all"]),
        }
        if args.compare:
            commands["noop_compared"] = (args.compare, ["-c2", "all"])
            timed(args.compare, "-c2", "all")
        timed(repo, "-c2", "all")  # warm-up: the import cache of the code inputs, the page cache
        rounds = []
        for _ in range(args.repeats):
            run = {name: timed(cwd, *argv) for name, (cwd, argv) in commands.items()}
            for name in ("noop", "noop_compared"):
                if name in run and "Nothing to be done" not in run[name]["out"]:
                    raise RuntimeError(f"not a no-op:\n{run[name]['out'][-2000:]}")
            rounds.append({name: {k: v for k, v in r.items() if k != "out"} for name, r in run.items()})
    result = {
        "machine": {"cpus": os.cpu_count(), "processor": platform.processor() or platform.machine()},
        "commands": {name: " ".join(["snakemake", *argv]) for name, (_, argv) in commands.items()},
        "wall_s": {name: summary([r[name]["wall_s"] for r in rounds]) for name in commands},
        "cpu_s": {name: summary([r[name]["cpu_s"] for r in rounds]) for name in commands},
        "noop_over_floor_wall": summary([r["noop"]["wall_s"] / r["floor"]["wall_s"] for r in rounds]),
        "noop_over_trivial_wall": summary([r["noop"]["wall_s"] / r["trivial"]["wall_s"] for r in rounds]),
        **(
            {
                "compared": str(args.compare),
                "noop_compared_over_floor_wall": summary(
                    [r["noop_compared"]["wall_s"] / r["floor"]["wall_s"] for r in rounds]
                ),
                "noop_compared_over_noop_wall": summary(
                    [r["noop_compared"]["wall_s"] / r["noop"]["wall_s"] for r in rounds]
                ),
            }
            if args.compare
            else {}
        ),
        "load1_before": summary([r[name]["load1_before"] for r in rounds for name in commands]),
        "rounds": rounds,
    }
    args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    print(json.dumps({k: v for k, v in result.items() if k != "rounds"}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
