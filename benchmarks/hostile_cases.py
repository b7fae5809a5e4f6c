"""The cache checks tried as a hostile but realistic user would: each case on its own copy of a
built repository, the command a user runs, its exit code and what happened to the data.

A temporary copy of the checkout (Snakefile, workflow/, src/, profiles/, environment.lock, the
committed paper_figures/) gets a config whose rendered scene ``s1`` (and a second scene ``s2``,
A = 20) has the meshes N = 11, 21, 41; ``all`` is built once.  Every case then works on a copy of
that build and records: the commands with their exit codes, the files lost (present before, gone
and not moved aside after), the files moved aside, and whether the result is right (Tables 1-2
equal to the ones an undamaged run renders).  Written to ``docs/evidence/reliability_round3.json``:

    python benchmarks/hostile_cases.py
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = str(Path(sys.executable).with_name("snakemake"))
PYTHON = sys.executable
CONFIG = """figures_scene: s1
scenes:
  s1:
    N: [11, 21, 41]
  s2:
    N: [11, 21, 41]
    problem: {A: 20}
"""
RENDERED = [f"paper_figures/table{k}.{ext}" for k in (1, 2) for ext in ("csv", "md", "tex")]


def run(repo: Path, *args: str, tool: str = SNAKEMAKE) -> dict:
    started = time.monotonic()
    proc = subprocess.run(
        [tool, *args], cwd=repo, capture_output=True, text=True, encoding="utf-8", timeout=1800,
        env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"},
    )
    lines = [line for line in (proc.stdout + proc.stderr).splitlines() if line.startswith("signorini:")]
    return {
        "command": " ".join(["snakemake" if tool == SNAKEMAKE else Path(tool).name, *args]),
        "exit_code": proc.returncode,
        "seconds": round(time.monotonic() - started, 1),
        "check_lines": lines,
        "traceback": "Traceback" in proc.stdout + proc.stderr,
    }


def files(repo: Path) -> dict[str, bytes]:
    return {
        str(p.relative_to(repo)): p.read_bytes()
        for top in ("results", "paper_figures")
        for p in sorted((repo / top).rglob("*"))
        if p.is_file() and "logs" not in p.parts and "benchmarks" not in p.parts and ".seals" not in p.parts
    }


def build(base: Path) -> Path:
    repo = base / "built"
    repo.mkdir()
    shutil.copy2(ROOT / "Snakefile", repo)
    shutil.copy2(ROOT / "environment.lock", repo)
    ignore = shutil.ignore_patterns("__pycache__", "*.egg-info", "*.pyc")
    for name in ("workflow", "src", "profiles", "paper_figures"):
        shutil.copytree(ROOT / name, repo / name, ignore=ignore)
    (repo / "s1.yaml").write_text(CONFIG, encoding="utf-8")
    step = run(repo, "-c2", "all", "--configfile", "s1.yaml")
    assert step["exit_code"] == 0, step
    return repo


def flip(path: Path, old: str, new: str) -> None:
    text = path.read_text(encoding="utf-8")
    assert old in text, (path, old)
    path.write_text(text.replace(old, new, 1), encoding="utf-8")


def case_user_scene_defaults(repo: Path) -> list[dict]:
    user = "scene_defaults: {problem: {c: 2}}\nscenes:\n  mine: {N: [11, 21]}\n"
    (repo / "user.yaml").write_text(user, encoding="utf-8")
    return [run(repo, "-c2", "results/mine/errors.csv", "--configfile", "s1.yaml", "user.yaml")]


def case_other_scene_other_meshes(repo: Path) -> list[dict]:
    (repo / "s3.yaml").write_text(CONFIG.replace("N: [11, 21, 41]\n  s2", "N: [11, 21, 31]\n  s2"), encoding="utf-8")
    return [run(repo, "-c2", "results/s2/errors.csv", "--configfile", "s3.yaml")]


def case_swapped_system(repo: Path) -> list[dict]:
    for name in ("system.npz", "system.json"):
        shutil.copy2(repo / f"results/s1/N11/{name}", repo / f"results/s1/N21/{name}")
    return [run(repo, "-c2", "all", "--configfile", "s1.yaml") for _ in range(2)]


def case_norm_copied(repo: Path) -> list[dict]:
    shutil.copy2(repo / "results/s1/N11/norms/L4.json", repo / "results/s1/N41/norms/L4.json")
    return [run(repo, "-c2", "all", "--configfile", "s1.yaml") for _ in range(2)]


def case_scene_switched_back(repo: Path) -> list[dict]:
    steps = []
    for scene in ("s2", "s1"):
        (repo / "s1.yaml").write_text(CONFIG.replace("figures_scene: s1", f"figures_scene: {scene}"), encoding="utf-8")
        shutil.rmtree(repo / ".snakemake", ignore_errors=True)
        steps.append(run(repo, "-c2", "all", "--configfile", "s1.yaml"))
    return steps


def case_errors_bit_flip(repo: Path) -> list[dict]:
    path = repo / "results/s1/errors.csv"
    data = bytearray(path.read_bytes())
    at = data.index(b"41,") + 30  # a digit of an error on the finest mesh
    data[at] ^= 0x01
    path.write_bytes(bytes(data))
    return [run(repo, "-c2", "all", "--configfile", "s1.yaml")]


def case_spreadsheet_round_trip(repo: Path) -> list[dict]:
    path = repo / "results/s1/errors.csv"
    rows = [line.split(",") for line in path.read_text(encoding="utf-8").splitlines()]
    cells = [[c if c[:1].isalpha() else f"{float(c):.6g}" for c in row] for row in rows]
    path.write_bytes("\r\n".join(",".join(row) for row in cells).encode())
    return [run(repo, "-c2", "all", "--configfile", "s1.yaml")]


def case_h12_bit_flip(repo: Path) -> list[dict]:
    path = repo / "results/s1/h12_boundary.csv"
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0x01
    path.write_bytes(bytes(data))
    return [run(repo, "-c2", "all", "--configfile", "s1.yaml")]


def case_check_without_all(repo: Path) -> list[dict]:
    fresh = repo.parent / "fresh"
    shutil.copytree(ROOT / "paper_figures", fresh / "paper_figures")
    shutil.copytree(repo / "results/s1", fresh / "results/coarse_h1")  # any scene table, no rendering
    return [run(fresh, "-m", "signorini.pipeline.check", "--reference-dir", str(ROOT / "paper_figures"), tool=PYTHON)]


def case_clean_corrupt_through_symlink(repo: Path) -> list[dict]:
    elsewhere = repo.parent / "results-elsewhere"
    shutil.move(repo / "results", elsewhere)
    (repo / "results").symlink_to(elsewhere)
    (elsewhere / "s1/errors.csv.corrupt").write_text("x", encoding="utf-8")
    (elsewhere / "s1/N11/system.npz.stale").write_text("x", encoding="utf-8")
    shutil.copy2(ROOT / "Makefile", repo / "Makefile")
    step = run(repo, "clean-corrupt", tool=shutil.which("make") or "make")
    step["left"] = sorted(str(p) for p in elsewhere.rglob("*") if p.suffix in (".corrupt", ".stale"))
    return [step]


CASES: dict[str, Callable[[Path], list[dict]]] = {
    "a user's scene_defaults and a target of their own scene": case_user_scene_defaults,
    "a run for another scene while the rendered scene's meshes differ from the rendered tables": (
        case_other_scene_other_meshes
    ),
    "system.npz/.json of N = 11 copied over N = 21": case_swapped_system,
    "a norm JSON copied from N = 11 to N = 41": case_norm_copied,
    "figures_scene switched to s2 and back, .snakemake deleted each time": case_scene_switched_back,
    "one flipped bit in errors.csv": case_errors_bit_flip,
    "errors.csv through a spreadsheet (6 digits, CRLF)": case_spreadsheet_round_trip,
    "one flipped bit in h12_boundary.csv": case_h12_bit_flip,
    "make check where all never ran (a scene table of another scene present)": case_check_without_all,
    "make clean-corrupt with results/ a symbolic link": case_clean_corrupt_through_symlink,
}


def outcome(built: Path, repo: Path, before: dict[str, bytes]) -> dict:
    after = files(repo)
    aside = {p for p in after if p.endswith((".stale", ".corrupt"))}
    moved = {p.rsplit(".", 1)[0] for p in aside}
    lost = sorted(p for p in before if p not in after and p not in moved)
    reference = {p: (built / p).read_bytes() for p in RENDERED}
    wrong = sorted(p for p in RENDERED if (repo / p).is_file() and (repo / p).read_bytes() != reference[p])
    return {"lost": lost, "moved_aside": sorted(aside), "rendered_tables_differ_from_an_undamaged_run": wrong}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/reliability_round3.json")
    parser.add_argument("cases", nargs="*", help="names of cases to run (default: all)")
    args = parser.parse_args()
    results = []
    with tempfile.TemporaryDirectory() as tmp:
        built = build(Path(tmp))
        for name, case in CASES.items():
            if args.cases and not any(c in name for c in args.cases):
                continue
            repo = Path(tmp) / f"case{len(results)}"
            shutil.copytree(built, repo, symlinks=True)
            before = files(repo)
            steps = case(repo)
            result = {"case": name, "steps": steps, **outcome(built, repo, before)}
            print(json.dumps(result)[:400], flush=True)
            results.append(result)
    args.out.write_text(json.dumps({"config": CONFIG, "cases": results}, indent=1) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
