"""How every stage of the theory scene's chain grows with the mesh: time and peak memory per stage.

    python benchmarks/scale.py                              # N = 501 1001 2001 4001 -> docs/evidence/scale.json
    python benchmarks/scale.py --N 101 201 --out /tmp/s.json   # a quick check
    python benchmarks/scale.py --N 4001 --stages discretise solve_multigrid Linf_true --resume   # add to it

Each stage is the function the pipeline's job runs (``discretise_stage``, ``solve_stage`` with
the direct and the multigrid route, ``norms_stage`` with all of the scene's convention norms of
a mesh, as one per-mesh job computes them, ``norms_stage`` with each true norm of Table 2, and
``quantities_stage``), run in a fresh child process so that its wall time and its peak resident
memory (``ru_maxrss``) are its own; one BLAS thread.  The stages of a mesh read the artifacts
the previous ones wrote (the multigrid route's solution feeds the norms), in a working directory
kept between runs (``--workdir``).  The direct route is skipped where its predicted memory
(``pipeline.resources``) exceeds this machine's.

Keys: ``stages[<stage>][<N>] = {seconds, cpu_s, peak_rss_gib, load1}``, for a solve also its work
(``SOLVE_WORK``) and ``solve_s``, the seconds of the certified solve alone (``solve_discrete`` with
its cascade: the job also reads the system, estimates the algebraic error and writes the archive);
``memory_touched_gib`` (``touch_memory``); ``exponents[<stage>]``, the p of
time ∝ unknowns^p between successive N; ``solve_speedup_over_direct_N2001``; ``peak_rss_gib_N4001``,
the largest job at N = 4001; the load average before and after every stage, its range over the
run (``load1``) and the stages measured under a load above the cores (``loaded_stages``).
"""

from __future__ import annotations

import argparse
import inspect
import json
import math
import os
import resource
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TRUE_NORMS = ("L4_true", "L16_true", "Linf_true", "W14_true", "W116_true", "W1inf_true", "H12_true")
ROUTES = {"solve_direct": "active_set", "solve_multigrid": "multigrid"}
# what a solve record keeps of the route's work: Newton steps, CG iterations and V-cycles of the
# final mesh, and the fine-grid work units of the whole solve (the cascade's coarser meshes included)
SOLVE_WORK = ("iterations", "cg_iterations", "v_cycles", "work_units", "work_units_total")


def _scene() -> dict:
    from signorini.pipeline.config import load_config

    return load_config(ROOT / "workflow/config.yaml")["scenes"]["theory"]


def run_stage(stage: str, N: int, workdir: Path) -> None:
    """In the child: run one stage on mesh N and print its wall time and peak RSS as JSON."""
    from signorini.fem.norms.names import parse_norm_name
    from signorini.studies.scene.discretise import discretise_stage
    from signorini.studies.scene.norm import norms_stage
    from signorini.studies.scene.solve import solve_stage
    from signorini.studies.scene.store import SceneMesh
    from signorini.studies.theory.quantities import quantities_stage

    scene = _scene()
    at = SceneMesh(scene["problem"], N, scene.get("diagonal", "sw_ne"))
    d = workdir / f"N{N}"
    d.mkdir(parents=True, exist_ok=True)
    conventions = scene.get("conventions", {})
    solution = d / "solution_multigrid.npz"
    t0, c0, work = time.perf_counter(), time.process_time(), {}
    if stage == "discretise":
        discretise_stage(at, d / "system.npz", d / "system.json")
    elif stage in ROUTES:
        name = stage.removeprefix("solve_")
        info = solve_stage(at, d / "system.npz", ROUTES[stage], d / f"solution_{name}.npz", d / f"solution_{name}.json")
        work = {key: info["summary"][key] for key in SOLVE_WORK if key in info["summary"]}
        # the certified solve alone (``solve_discrete`` with its cascade), without reading the system,
        # the algebraic-error estimate and the archive the job adds
        work["solve_s"] = info["timings"]["solve_s"]
    elif stage == "convention_norms":
        names = [n for n in scene["norms"] if not parse_norm_name(n).true]
        norms_stage(at, solution, {n: d / f"{n}.json" for n in names}, conventions)
    elif stage in TRUE_NORMS or stage in scene["norms"]:  # one norm, as a job of the norm rule computes it
        norms_stage(at, solution, {stage: d / f"{stage}.json"}, conventions)
    elif stage == "theory_quantities":
        # the stage of a tree before the Ritz projection read the system archive took no system_npz
        takes_system = "system_npz" in inspect.signature(quantities_stage).parameters
        quantities_stage(at, *([d / "system.npz"] if takes_system else []), solution, d / "theory.json")
    else:
        raise ValueError(f"unknown stage {stage}")
    seconds, cpu_s = time.perf_counter() - t0, time.process_time() - c0
    rss_gib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # kB on Linux
    print(json.dumps({"seconds": seconds, "cpu_s": cpu_s, "peak_rss_gib": rss_gib} | work))


def _direct_fits(N: int) -> str | None:
    """Why the direct route is not run at N (its predicted memory exceeds the machine's), or None."""
    from signorini.pipeline.resources import machine_mem_mb, mem_mb

    need, have = mem_mb("solve", N), machine_mem_mb()
    return None if need <= 0.9 * have else f"predicted {need / 1024:.1f} GiB > 90 % of {have / 1024:.1f} GiB"


def run_child(stage: str, N: int, workdir: Path, timeout_s: float, src: Path | None = None) -> dict:
    """One stage on mesh N in a child process (``run_stage``), with ``signorini`` imported from
    ``src`` if given (``benchmarks/stage_jobs.py``: another tree's): its record, and the load
    average before and after."""
    load0 = os.getloadavg()[0]
    cmd = [sys.executable, __file__, "--child", stage, "--N", str(N), "--workdir", str(workdir)]
    env = {**os.environ, "PYTHONPATH": str(src)} if src is not None else None
    try:
        proc = subprocess.run(
            cmd, capture_output=True, text=True, encoding="utf-8", timeout=timeout_s, cwd=ROOT, env=env
        )
    except subprocess.TimeoutExpired:
        return {"skipped": f"longer than {timeout_s:g} s", "load1": [load0, os.getloadavg()[0]]}
    if proc.returncode != 0:
        return {"failed": proc.stderr.strip().splitlines()[-1:], "load1": [load0, os.getloadavg()[0]]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    return out | {"load1": [load0, os.getloadavg()[0]]}


TOUCH_FRACTION = 0.8  # of the available memory, touched once before timing (``touch_memory``)


def touch_memory() -> float:
    """Fill ``TOUCH_FRACTION`` of the available memory once, in a child process, and free it: a
    virtual machine backs its memory on first use, which costs several times a later page fault
    (docs/evidence/design-measurements.md#reuse-freed-memory), and would be charged to whichever
    stage first reached that much.  The GiB touched."""
    available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    doubles = int(TOUCH_FRACTION * available) // 8
    subprocess.run([sys.executable, "-c", f"import numpy; numpy.ones({doubles})"], check=True)
    return doubles * 8 / 2**30


def exponents(stages: dict, unknowns: dict[int, int]) -> dict[str, dict[str, float]]:
    """p of time ∝ unknowns^p between successive measured N of every stage."""
    out: dict[str, dict[str, float]] = {}
    for stage, by_N in stages.items():
        Ns = sorted(int(N) for N, rec in by_N.items() if "seconds" in rec)
        seconds = {N: by_N[str(N)]["seconds"] for N in Ns}
        out[stage] = {
            f"{a}-{b}": math.log(seconds[b] / seconds[a]) / math.log(unknowns[b] / unknowns[a])
            for a, b in zip(Ns, Ns[1:], strict=False)
        }
    return out


def measure(
    Ns: list[int], stages: list[str], workdir: Path, timeout_s: float, save=None, done: dict | None = None
) -> dict:
    """Every stage at every N, coarse to fine; ``save(summary)`` after each stage (a run cut
    short leaves what it measured).  ``done``: records of an earlier run (``--resume``), kept;
    their stages are not measured again."""
    records: dict[str, dict[str, dict]] = {stage: {} for stage in stages}
    for stage, by_N in (done or {}).items():
        records.setdefault(stage, {}).update(by_N)
    Ns = sorted(set(Ns) | {int(N) for by_N in records.values() for N in by_N})
    for N in Ns:
        for stage in stages:
            if "seconds" in records[stage].get(str(N), {}):
                continue
            if stage == "solve_direct" and (why := _direct_fits(N)):
                records[stage][str(N)] = {"skipped": why}
            else:
                records[stage][str(N)] = run_child(stage, N, workdir, timeout_s)
            print(f"N={N} {stage}: {records[stage][str(N)]}", file=sys.stderr, flush=True)
            if save:
                save(summarise(Ns, records))
    return summarise(Ns, records)


def summarise(Ns: list[int], records: dict) -> dict:
    unknowns = {N: (N + 1) ** 2 for N in Ns}
    out = {"N": Ns, "unknowns": unknowns, "stages": records, "exponents": exponents(records, unknowns)}
    direct, multigrid = (records.get(s, {}).get("2001", {}).get("seconds") for s in ROUTES)
    out["solve_speedup_over_direct_N2001"] = direct / multigrid if direct and multigrid else None
    at_4001 = [rec["peak_rss_gib"] for rec in (r.get("4001", {}) for r in records.values()) if "peak_rss_gib" in rec]
    out["peak_rss_gib_N4001"] = max(at_4001) if at_4001 else None
    loads = [x for r in records.values() for rec in r.values() for x in rec.get("load1", [])]
    if loads:
        cores = os.cpu_count() or 1
        out["load1"] = {"min": min(loads), "median": statistics.median(loads), "max": max(loads), "cores": cores}
        # a stage measured under more runnable processes than cores did not run alone
        out["loaded_stages"] = sorted(
            f"{stage}/N{N}"
            for stage, r in records.items()
            for N, rec in r.items()
            if max(rec.get("load1", [0])) > cores
        )
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, nargs="+", default=[501, 1001, 2001, 4001])
    parser.add_argument(
        "--stages",
        nargs="+",
        default=["discretise", *ROUTES, "convention_norms", *TRUE_NORMS, "theory_quantities"],
    )
    parser.add_argument("--workdir", type=Path, default=ROOT / "results/benchmarks/scale")
    parser.add_argument("--timeout", type=float, default=3600.0, help="per stage, seconds")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/scale.json")
    parser.add_argument("--resume", action="store_true", help="keep the stages --out measured already")
    parser.add_argument("--child", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    from signorini.pipeline.jobenv import job_environment

    job_environment()  # before numpy loads its BLAS, in this process and its children
    if args.child:
        run_stage(args.child, args.N[0], args.workdir)
        return 0
    t0 = time.time()
    head = {"date": time.strftime("%Y-%m-%d %H:%M"), "cores": os.cpu_count(), "memory_touched_gib": touch_memory()}
    args.out.parent.mkdir(parents=True, exist_ok=True)

    def save(summary: dict, complete: bool = False) -> None:
        out = head | summary | {"wall_s": time.time() - t0, "complete": complete}
        args.out.write_text(json.dumps(out, indent=1) + "\n", encoding="utf-8")

    done = json.loads(args.out.read_text(encoding="utf-8"))["stages"] if args.resume and args.out.exists() else None
    save(measure(args.N, args.stages, args.workdir, args.timeout, save, done), complete=True)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
