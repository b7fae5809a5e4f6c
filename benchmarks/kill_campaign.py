"""Kill campaign: random SIGINT / SIGTERM to a running scene, then recovery, then a comparison
with an uninterrupted build.

In a temporary copy of the repository (Snakefile, workflow/, src/, profiles/) the scene's chain
(``results/<scene>/eoc.csv``: discretise -> solve -> norms -> errors -> eoc) is built once without
interruption (the reference). In a second copy the same target is started again and again; each run
is sent SIGINT (Ctrl-C) or SIGTERM (a scheduler's stop), to its whole process group, after a random
delay, until ``--kills`` runs were interrupted, with a random artifact of the scene (and what was
computed from it) removed whenever a run got to the end first (so that there is always work to
interrupt). After every kill no file under its final name may fail its integrity check. A run that
stops with Snakemake's IncompleteFilesException (outputs of killed jobs still marked incomplete in
.snakemake) is followed by one with ``--rerun-incomplete``, as Snakemake tells the user; a run
still alive ``GRACE_S`` after its signal is killed with SIGKILL (and unlocked), and counted. Then
one run recovers, and every artifact must equal the reference: tables and archives byte for byte,
the JSON sidecars as data without what they record about the run (wall times, the machine's load:
``RUN_DEPENDENT``). Each run's console is kept and counted (lines, bytes, tracebacks,
``interrupted:`` lines): what a user sees after Ctrl-C.

    python benchmarks/kill_campaign.py --kills 15 --out docs/evidence/kill_campaign.json
"""

from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from signorini.pipeline.artifacts import load_json  # noqa: E402
from signorini.pipeline.integrity import artifact_ok  # noqa: E402

SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
SIGNALS = {"SIGINT": signal.SIGINT, "SIGTERM": signal.SIGTERM}
GRACE_S = 180  # how long a signalled run may take to stop its jobs and exit


def copy_repo(dest: Path) -> Path:
    """Snakefile, workflow/, src/ and the default profile (the console and rerun settings a user's
    `snakemake` call gets in a checkout)."""
    dest.mkdir(parents=True)
    shutil.copy2(ROOT / "Snakefile", dest / "Snakefile")
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    for name in ("workflow", "src", "profiles"):
        shutil.copytree(ROOT / name, dest / name, ignore=ignore)
    return dest


def start(repo: Path, target: str, console: Path, *extra: str) -> subprocess.Popen:
    with open(console, "wb") as out:
        return subprocess.Popen(
            [SNAKEMAKE, "-c2", *extra, target],
            cwd=repo,
            start_new_session=True,  # its own process group: the signal reaches the jobs too, as Ctrl-C does
            stdout=out,
            stderr=subprocess.STDOUT,
            env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
        )


def downstream(repo: Path, scene: str, removed: str) -> list[Path]:
    """``removed`` and everything of the chain computed from it (a mesh's solution and norms after
    its system, its norms after its solution; the scene's tables after anything), so that the next
    run has to recompute it: Snakemake rebuilds a missing file only when a job needs it."""
    base = repo / "results" / scene
    mesh = Path(removed).parent if "norms" not in removed else Path(removed).parent.parent
    later = {"system": ("system", "solution", "norms"), "solution": ("solution", "norms")}
    kind = Path(removed).stem
    found = [repo / removed]
    if kind in later:
        found += [p for p in (repo / mesh).rglob("*") if p.is_file() and p.relative_to(repo / mesh).parts[0]
                  .split(".")[0] in later[kind] and p != repo / removed]
    found += [base / name for name in ("errors.csv", "eoc.csv") if (base / name).exists()]
    return sorted({p for p in found if p.exists()})


def console_summary(console: Path) -> dict:
    """What the user saw of a run: lines, bytes, tracebacks, and the one-line interrupt notice."""
    text = console.read_text(encoding="utf-8", errors="replace")
    lines = text.splitlines()
    return {
        "console_lines": len(lines),
        "console_bytes": len(text.encode()),
        "tracebacks": text.count("Traceback"),
        "interrupted_lines": sum(line.startswith("interrupted:") for line in lines),
    }


def artifacts(repo: Path, scene: str) -> dict[str, Path]:
    """{relative path: path} of the scene's artifacts (logs and benchmark files are per run)."""
    base = repo / "results" / scene
    found = {}
    for path in sorted(base.rglob("*")):
        rel = path.relative_to(repo)
        if path.is_file() and not {"logs", "benchmarks"} & set(rel.parts):
            found[str(rel)] = path
    return found


# what a JSON sidecar records about the run rather than the result: wall times (of the solve, and
# of each Newton step in its history) and the machine's load when the job started (system.json's load1)
RUN_DEPENDENT = ("timings", "load1", "summary.wall_time_s", "summary.history[].elapsed_s")


def comparable(path: Path) -> bytes | dict:
    """What must not depend on interruptions: the bytes, or a JSON sidecar without its records of
    the run (``RUN_DEPENDENT``; the checksum, which covers them, goes with them)."""
    if path.suffix != ".json" or path.name.startswith("."):
        return path.read_bytes()
    data = load_json(path)
    for key in RUN_DEPENDENT:
        *parents, leaf = key.split(".")
        nodes = [data]
        for parent in parents:  # "name[]": every row of the list under name
            rows = [node.get(parent.removesuffix("[]"), {}) for node in nodes]
            nodes = [row for rows_ in rows for row in rows_] if parent.endswith("[]") else rows
        for node in nodes:
            node.pop(leaf, None)
    return data


def _difference(a: Path, b: Path) -> list[str]:
    """What differs between two artifacts: ``["bytes"]``, the top-level JSON keys, or nothing."""
    x, y = comparable(a), comparable(b)
    if isinstance(x, bytes) or isinstance(y, bytes):
        return [] if x == y else ["bytes"]
    return sorted(k for k in set(x) | set(y) if x.get(k) != y.get(k))


def damaged(repo: Path) -> list[str]:
    """Files under a final name that fail their integrity check (none may, after any kill)."""
    return [str(p.relative_to(repo)) for p in (repo / "results").rglob("*") if p.is_file() and not artifact_ok(p)]


def campaign(repo: Path, scene: str, kills: int, rng: random.Random, delay: tuple[float, float]) -> list[dict]:
    target = f"results/{scene}/eoc.csv"
    rounds: list[dict] = []
    while sum(r["killed"] for r in rounds) < kills and len(rounds) < 4 * kills:
        # a run that failed without a signal: Snakemake found outputs of killed jobs marked
        # incomplete and asks for --rerun-incomplete, which the next run passes (as a user would)
        incomplete = bool(rounds) and not rounds[-1]["killed"] and rounds[-1]["exit_code"] != 0
        removed = None
        if (repo / target).exists():  # the last run finished: give the next one work to interrupt
            removed = rng.choice(sorted(p for p in artifacts(repo, scene) if p.endswith((".npz", ".json", ".csv"))))
            for path in downstream(repo, scene, removed):  # what was computed from it: work to redo
                path.unlink()
        name = rng.choice(sorted(SIGNALS))
        after = round(rng.uniform(*delay), 1)
        console = repo.parent / f"console-{len(rounds)}.txt"
        run = start(repo, target, console, *(["--rerun-incomplete"] if incomplete else []))
        try:
            run.wait(timeout=after)
            killed = False
        except subprocess.TimeoutExpired:
            os.killpg(run.pid, SIGNALS[name])
            killed, hung = True, False
            try:
                run.wait(timeout=GRACE_S)
            except subprocess.TimeoutExpired:  # not gone after the grace period: kill -9, as a user would
                hung = True
                os.killpg(run.pid, signal.SIGKILL)
                run.wait(timeout=60)
        rounds.append(
            {
                "signal": name if killed else None,
                "rerun_incomplete": incomplete,
                "sigkill_after_grace": killed and hung,
                "after_s": after,
                "killed": killed,
                "exit_code": run.returncode,
                "removed_before": removed,
                "damaged_after": damaged(repo),
                "lock_left": any((repo / ".snakemake/locks").glob("*")),
                "temporaries_left": sorted(str(p.relative_to(repo)) for p in (repo / "results").rglob(".*.tmp")),
                **console_summary(console),
            }
        )
        if rounds[-1]["lock_left"]:  # only after kill -9: Snakemake released it on SIGINT/SIGTERM
            subprocess.run([SNAKEMAKE, "--unlock"], cwd=repo, capture_output=True, check=True)
        print(json.dumps(rounds[-1]), flush=True)
    return rounds


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="smoke")
    parser.add_argument("--kills", type=int, default=15)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--min-delay", type=float, default=3.0, help="seconds after the start, at least")
    parser.add_argument("--max-delay", type=float, default=40.0, help="seconds after the start, at most")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/kill_campaign.json")
    args = parser.parse_args(argv)
    rng = random.Random(args.seed)
    target = f"results/{args.scene}/eoc.csv"
    with tempfile.TemporaryDirectory(prefix="kill-campaign-") as tmp:
        reference = copy_repo(Path(tmp) / "reference")
        subprocess.run([SNAKEMAKE, "-c2", target], cwd=reference, check=True, capture_output=True)
        repo = copy_repo(Path(tmp) / "campaign")
        rounds = campaign(repo, args.scene, args.kills, rng, (args.min_delay, args.max_delay))
        # recovery: leftovers of killed jobs count as old from here on (the next run removes them)
        for leftover in (repo / "results").rglob(".*.tmp"):
            os.utime(leftover, (1e9, 1e9))
        # recovery: every artifact of the reference is requested (a job's sidecar that no target
        # needs, say a solution.json removed above, is rebuilt only when asked for)
        want = artifacts(reference, args.scene)
        recovery = subprocess.run(
            [SNAKEMAKE, "-c2", "--rerun-incomplete", *want], cwd=repo, capture_output=True, encoding="utf-8"
        )
        got = artifacts(repo, args.scene)
        differing = {p: _difference(want[p], got[p]) for p in sorted(set(want) & set(got))}
        differing = {p: keys for p, keys in differing.items() if keys}
        result = {
            "scene": args.scene,
            "target": target,
            "seed": args.seed,
            "kills": sum(r["killed"] for r in rounds),
            "signals": {name: sum(r["signal"] == name for r in rounds) for name in SIGNALS},
            "grace_s": GRACE_S,
            "sigkill_after_grace": sum(r.get("sigkill_after_grace", False) for r in rounds),
            "runs_needing_rerun_incomplete": sum(r["rerun_incomplete"] for r in rounds),
            "rounds": rounds,
            "damaged_after_any_kill": sorted({p for r in rounds for p in r["damaged_after"]}),
            "interrupts_console_lines": [r["console_lines"] for r in rounds if r["killed"]],
            "interrupts_with_a_traceback": sum(r["killed"] and r["tracebacks"] > 0 for r in rounds),
            "interrupts_without_one_interrupted_line": sum(
                r["killed"] and r["signal"] == "SIGINT" and r["interrupted_lines"] != 1 for r in rounds
            ),
            "recovery_exit_code": recovery.returncode,
            "files_compared": len(set(want) & set(got)),
            "missing_after_recovery": sorted(set(want) - set(got)),
            "extra_after_recovery": sorted(set(got) - set(want)),
            "differing": differing,
            "identical": not differing and set(want) == set(got) and recovery.returncode == 0,
            "compared_as": "tables and .npz byte for byte; JSON sidecars as data without " + ", ".join(RUN_DEPENDENT),
        }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    print(f"{result['kills']} kills, recovery exit {recovery.returncode}, {result['files_compared']} files compared, "
          f"identical: {result['identical']} -> {args.out}")
    return 0 if result["identical"] and not result["damaged_after_any_kill"] else 1


if __name__ == "__main__":
    sys.exit(main())
