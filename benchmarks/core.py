"""Speed and memory benchmark of the numerical core, measured side by side in one process.

    python benchmarks/core.py                      # N = 501 -> results/benchmarks/core_N501.json
    python benchmarks/core.py --N 101              # quick check
    python benchmarks/core.py --N 2001 --memory-only   # build + solve + norms, peak RSS only

Keys (seconds unless noted):

- ``factorization_s``     one sparse Cholesky factorisation of A (``solvers.linalg.factorize``), best of 2
- ``active_set_solve_s``  ``solve_discrete`` with the default cascade warm start (coarse levels included),
  median of 3 runs (``active_set_runs_s``),
  with ``active_set_iterations`` and the factorisation / triangular-solve / correction-column counts of the fine level
- ``active_set_cold_s``   the same solve from a cold start (run in a child process with a time limit)
- ``cvxpy_clarabel_s``    ``cvxpy_solve(..., solver="CLARABEL")`` on the same A, b, boundary, median of
  ``--clarabel-runs`` (3) runs like the active set's, with its max-norm difference to the
  active-set solution
- ``rhs_assembly_s``      ``load_vector(mesh, ...)`` (16-point rule, over chunks of triangles as in the
  pipeline), ``norms_s`` ``evaluate_norms`` (chunked)
  for L4, L16, Linf, W14, W116, W1inf, H12
- ``peak_rss_mib``        ``getrusage(RUSAGE_SELF).ru_maxrss`` at the end (and after each stage)

plus the ratios the project sets targets for (active set ≤ 3× one factorisation, ≥ 20× faster than
CLARABEL, b + norms ≤ 10 s), the machine and the package versions.  The JSON is written atomically.
"""

from __future__ import annotations

import argparse
import functools
import importlib.metadata
import logging
import multiprocessing as mp
import os
import platform
import resource
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from signorini.fem.assembly import load_vector, p1_basis, system_matrix
from signorini.fem.discrete import DiscreteProblem, build
from signorini.fem.mesh import boundary_nodes, friedrichs_keller
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import save_json
from signorini.pipeline.jobenv import THREAD_VARIABLES
from signorini.solvers import cvxpy_solve
from signorini.solvers.linalg import backend_name, factorize

ROOT = Path(__file__).resolve().parents[1]
NORMS = ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12"]
PACKAGES = ["signorini", "numpy", "scipy", "scikit-fem", "sksparse-minimal"]
PACKAGES += ["cvxpy", "clarabel", "osqp", "scs", "highspy"]
TARGETS = {"active_set_over_factorization_max": 3.0, "clarabel_over_active_set_min": 20.0, "rhs_plus_norms_max_s": 10.0}

log = logging.getLogger("benchmarks.core")


def peak_rss_mib() -> float:
    """Peak resident set size of this process so far (Linux reports KiB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def timed(fn, *args, **kwargs):
    t0 = time.perf_counter()
    out = fn(*args, **kwargs)
    return out, time.perf_counter() - t0


def machine_info() -> dict:
    info = {
        "cpu_count": os.cpu_count(),
        "cpus_available": len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else None,
        "platform": platform.platform(),
        "processor": platform.processor() or platform.machine(),
        "python": sys.version.split()[0],
        "load_average_at_start": list(os.getloadavg()),
        "threads_env": {k: os.environ.get(k) for k in THREAD_VARIABLES},
    }
    try:
        with open("/proc/meminfo", encoding="utf-8") as fh:
            total_kib = int(next(line for line in fh if line.startswith("MemTotal")).split()[1])
        info["memory_total_gib"] = round(total_kib / 2**20, 2)
    except (OSError, StopIteration, ValueError):
        pass
    try:
        with open("/proc/cpuinfo", encoding="utf-8") as fh:
            info["cpu_model"] = next(line.split(":", 1)[1].strip() for line in fh if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return info


def package_versions() -> dict:
    versions = {}
    for name in PACKAGES:
        try:
            versions[name] = importlib.metadata.version(name)
        except importlib.metadata.PackageNotFoundError:
            versions[name] = None
    try:  # read-only
        versions["git_commit"] = subprocess.run(
            ["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, encoding="utf-8", check=True, timeout=10
        ).stdout.strip()
    except (OSError, subprocess.SubprocessError):
        versions["git_commit"] = None
    return versions


def _cold_solve_child(N: int, diagonal: str, queue) -> None:
    disc = build(Problem(), N, diagonal)
    res, seconds = timed(solve_discrete, disc, "active_set", None)
    queue.put({"seconds": seconds, "iterations": res.iterations, "info": res.info, "u": res.u})


def cold_solve(N: int, diagonal: str, timeout: float) -> dict | None:
    """Time a cold-start active-set solve in a child process; None when it exceeds ``timeout``."""
    ctx = mp.get_context("fork")
    queue = ctx.Queue()
    proc = ctx.Process(target=_cold_solve_child, args=(N, diagonal, queue))
    proc.start()
    try:
        return queue.get(timeout=timeout)
    except Exception:  # queue.Empty: the limit was reached
        return None
    finally:
        if proc.is_alive():
            proc.terminate()
        proc.join()


def _assemble(out: dict, N: int, diagonal: str, problem: Problem) -> DiscreteProblem:
    """Mesh and assembly, timed as the pipeline assembles (discrete.build): A with a degree-2
    basis, b over chunks of triangles with the 16-point rule (a whole-mesh degree-8 basis alone is
    ~11 GB at N = 2001)."""
    mesh, out["mesh_s"] = timed(friedrichs_keller, N, diagonal)
    basis, out["basis_s"] = timed(p1_basis, mesh, 2)
    A, out["matrix_assembly_s"] = timed(system_matrix, basis, problem.c)
    del basis
    b, out["rhs_assembly_s"] = timed(load_vector, mesh, problem)
    out["rss_after_mib"]["assembly"] = peak_rss_mib()
    log.info("N=%d: assembly done (b in %.2f s)", N, out["rhs_assembly_s"])
    # the object the solver route takes, from the very arrays timed above (no second copy)
    return DiscreteProblem(problem, N, diagonal, mesh, A, b, boundary_nodes(mesh))


def _factorize(out: dict, A) -> None:
    """One sparse Cholesky factorisation of A, best of 2."""
    times = [timed(factorize, A)[1] for _ in range(2)]
    out["factorization_s"] = min(times)
    out["factorization_runs_s"] = times
    out["rss_after_mib"]["factorization"] = peak_rss_mib()
    log.info("factorization: %.2f s (%s)", out["factorization_s"], out["factorization_backend"])


def _cascade_solve(out: dict, disc: DiscreteProblem, repeats: int):
    """The exact solve with the cascade warm start, median of ``repeats``."""
    runs = [timed(solve_discrete, disc) for _ in range(repeats)]
    res = runs[0][0]
    out["active_set_runs_s"] = [seconds for _, seconds in runs]
    out["active_set_solve_s"] = float(np.median(out["active_set_runs_s"]))
    out["active_set_iterations"] = int(res.iterations)
    out["active_set_fine_level_s"] = float(res.wall_time_s)
    out["active_set_info"] = dict(res.info)  # Python ints and the backend name
    out["active_set_factorizations"] = int(res.info.get("factorizations", -1))
    out["active_set_triangular_solves"] = int(res.info.get("triangular_solves", -1))
    out["active_set_certificate"] = res.certificate.as_dict()
    out["n_active"] = int(res.active.size)
    out["rss_after_mib"]["active_set"] = peak_rss_mib()
    log.info("active set (cascade): %.2f s, %d iterations, %s", out["active_set_solve_s"], res.iterations, res.info)
    return res


def _norms(out: dict, disc: DiscreteProblem, u: np.ndarray) -> None:
    t0 = time.perf_counter()
    out["norms"] = evaluate_norms(disc.problem, disc.mesh, u, NORMS)  # what the pipeline's norm jobs run
    out["norms_s"] = time.perf_counter() - t0
    out["rss_after_mib"]["norms"] = peak_rss_mib()
    log.info("norms: %.2f s", out["norms_s"])


def _cold_start(out: dict, N: int, diagonal: str, timeout: float, u: np.ndarray) -> None:
    """The cold start, in a child process with a time limit."""
    cold = cold_solve(N, diagonal, timeout)
    if cold is None:
        out["active_set_cold_s"] = None
        out["active_set_cold_timed_out_after_s"] = timeout
        log.info("cold start: exceeded %.0f s", timeout)
        return
    out["active_set_cold_s"] = cold["seconds"]
    out["active_set_cold_iterations"] = int(cold["iterations"])
    out["active_set_cold_info"] = dict(cold["info"])
    out["active_set_cold_max_diff"] = float(np.abs(cold["u"] - u).max() / np.abs(u).max())
    log.info("cold start: %.2f s, %s", cold["seconds"], cold["info"])


def _clarabel(out: dict, disc: DiscreteProblem, runs: int, u: np.ndarray) -> None:
    """The same QP through cvxpy / CLARABEL, median of ``runs``; a failure is recorded."""
    try:
        clarabel = functools.partial(cvxpy_solve, disc.A, disc.b, disc.boundary, solver="CLARABEL", check=False)
        clar_runs = [timed(clarabel) for _ in range(runs)]
        clar = clar_runs[-1][0]
        out["cvxpy_clarabel_runs_s"] = [seconds for _, seconds in clar_runs]
        out["cvxpy_clarabel_s"] = float(np.median(out["cvxpy_clarabel_runs_s"]))
        del clar_runs
        out["cvxpy_clarabel_solver_time_s"] = clar.info.get("solve_time_s")
        out["cvxpy_clarabel_iterations"] = int(clar.iterations)
        out["cvxpy_clarabel_certificate"] = clar.certificate.as_dict()
        diff = np.abs(clar.u - u)
        out["cvxpy_clarabel_max_diff_abs"] = float(diff.max())
        out["cvxpy_clarabel_max_diff_rel"] = float(diff.max() / np.abs(u).max())
        log.info("CLARABEL: %.2f s, rel. max diff %.2e", out["cvxpy_clarabel_s"], out["cvxpy_clarabel_max_diff_rel"])
    except Exception as err:  # record, do not lose the other numbers
        out["cvxpy_clarabel_s"] = None
        out["cvxpy_clarabel_error"] = f"{type(err).__name__}: {err}"
        log.error("CLARABEL failed: %s", out["cvxpy_clarabel_error"])
    out["rss_after_mib"]["cvxpy_clarabel"] = peak_rss_mib()


def _ratios(out: dict) -> None:
    """The ratios against the project's targets."""
    fact, solve_s, clar_s = out["factorization_s"], out["active_set_solve_s"], out.get("cvxpy_clarabel_s")
    out["active_set_over_factorization"] = solve_s / fact
    out["clarabel_over_active_set"] = clar_s / solve_s if clar_s else None
    out["rhs_plus_norms_s"] = out["rhs_assembly_s"] + out.get("norms_s", np.nan)
    out["meets_targets"] = {
        "active_set_le_3x_factorization": out["active_set_over_factorization"] <= 3.0,
        "clarabel_ge_20x_active_set": None if clar_s is None else out["clarabel_over_active_set"] >= 20.0,
        "rhs_plus_norms_le_10s": bool(out["rhs_plus_norms_s"] <= 10.0),
    }


def run(args: argparse.Namespace) -> dict:
    N, diagonal = args.N, args.diagonal
    problem = Problem()
    out: dict = {
        "N": N,
        "unknowns": (N + 1) ** 2,
        "diagonal": diagonal,
        "problem": problem.as_dict(),
        "mode": "memory_only" if args.memory_only else "full",
        "factorization_backend": backend_name(),
        "machine": machine_info(),
        "versions": package_versions(),
        "targets": TARGETS,
        "rss_after_mib": {},
    }
    disc = _assemble(out, N, diagonal, problem)
    if not args.memory_only:
        _factorize(out, disc.A)
    res = _cascade_solve(out, disc, 1 if args.memory_only else 3)
    if not args.no_norms:
        _norms(out, disc, res.u)
    if not args.memory_only:
        if args.skip_cold:
            out["active_set_cold_s"] = None
        else:
            _cold_start(out, N, diagonal, args.cold_timeout, res.u)
        if args.skip_cvxpy:
            out["cvxpy_clarabel_s"] = None
        else:
            _clarabel(out, disc, args.clarabel_runs, res.u)
        _ratios(out)
    out["machine"]["load_average_at_end"] = list(os.getloadavg())  # others' jobs inflate the timings
    out["peak_rss_mib"] = peak_rss_mib()
    out["peak_rss_gib"] = out["peak_rss_mib"] / 1024.0
    out["fits_24_gib"] = out["peak_rss_gib"] < 24.0
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--N", type=int, default=501, help="cells per side (default 501)")
    parser.add_argument("--diagonal", default="sw_ne", choices=("sw_ne", "nw_se"))
    parser.add_argument("--out", type=Path, default=None, help="default results/benchmarks/core_N{N}.json")
    parser.add_argument("--memory-only", action="store_true", help="only assemble, solve (cascade) and norms; peak RSS")
    parser.add_argument("--no-norms", action="store_true", help="skip the norms")
    parser.add_argument("--skip-cvxpy", action="store_true", help="skip the CLARABEL comparison")
    parser.add_argument("--clarabel-runs", type=int, default=3, help="CLARABEL solves timed (median reported)")
    parser.add_argument("--skip-cold", action="store_true", help="skip the cold-start solve")
    parser.add_argument("--cold-timeout", type=float, default=900.0, help="limit for the cold-start solve (s)")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s: %(message)s")
    logging.getLogger("skfem").setLevel(logging.WARNING)
    if args.out is None:
        suffix = "_memory" if args.memory_only else ""
        args.out = ROOT / "results" / "benchmarks" / f"core_N{args.N}{suffix}.json"
    result = run(args)
    save_json(args.out, result)
    log.info("wrote %s (peak RSS %.0f MiB)", args.out, result["peak_rss_mib"])
    return 0


if __name__ == "__main__":
    sys.exit(main())
