"""Does the timing protocol keep its ratios on a loaded machine?  The same slice of the
work-precision study, timed once as the machine is and once with busy processes beside it.

    python benchmarks/timing_robustness.py                 # N = 201, 501 -> docs/evidence/timing_robustness.json
    python benchmarks/timing_robustness.py --N 11,21 --out /tmp/t.json   # a quick check

Solvers (configurations of the shipped study, ``workflow/config.yaml``): our active set from
the cascade (the reference of the ratios) and cold, OSQP, CLARABEL and SCS through cvxpy at
``--tol``, and, when petsc4py runs under ``--python``, the PETSc peers of ``--peers``.  Per mesh
they are timed round-robin under the protocol of ``signorini.timing``
(``race.race``, ``benchmarks/race.py``); then ``--busy`` processes (default 2; ``--busy-kind numpy``: streaming array
updates and small matrix products, memory traffic as well as arithmetic; ``spin``: a Python
loop) are started, the same slice is timed again, and they are stopped.

The protocol is the shipped study's (its ``timing:`` block in ``workflow/config.yaml``) with the
load limit of one process (``--max-load``, default: the cores).

Written (atomically): both runs with every solver's times (CPU, wall; reference units) and
status, the loads (1-minute load average, median and range per run), the change factor of the
absolute times (loaded / quiet, median over solvers), and ``worst_ratio_change``: the largest
relative change, between the two runs, of a solver's CPU-time ratio to the reference solver (the
study ranks by CPU time; ``worst_ratio_change_ref`` and ``_wall``: the same for the ratios of
reference units and of wall-clock times).  Goal: ≤ ``GOAL`` while the wall times change by
about 2×.  Solvers that failed in either run are left out of the change.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

from signorini.pipeline.jobenv import job_environment

job_environment()  # one thread: CPU time = one core (before numpy loads its BLAS)

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
GOAL = 0.15
SOLVERS = ["active_set", "active_set_cold", "osqp", "clarabel", "scs"]
PEERS = ["petsc_tron_boomeramg", "petsc_rsls_cholmod"]


def busy_worker(kind: str, stop) -> None:
    """Keep one core busy until ``stop`` is set."""
    if kind == "spin":
        x = 0
        while not stop.is_set():
            for _ in range(100_000):
                x += 1
        return
    a, m = np.ones(2_000_000), np.random.default_rng(0).random((200, 200))
    while not stop.is_set():
        a += 1.0  # 16 MB streamed: memory bandwidth
        m = m @ m
        m /= np.abs(m).max()


class Busy:
    """``n`` busy processes while the ``with`` block runs."""

    def __init__(self, n: int, kind: str):
        self.n, self.kind = n, kind
        self.stop = mp.Event()
        self.procs: list = []

    def __enter__(self):
        for _ in range(self.n):
            p = mp.Process(target=busy_worker, args=(self.kind, self.stop), daemon=True)
            p.start()
            self.procs.append(p)
        time.sleep(2.0)  # let them run before the first sample
        return self

    def __exit__(self, *exc):
        self.stop.set()
        for p in self.procs:
            p.join(timeout=10)
            if p.is_alive():
                p.terminate()
        return False


def shipped_study() -> dict:
    """The ``study`` block of the shipped work-precision scene (the config loaded and checked as
    the workflow does)."""
    from signorini.pipeline.config import load_config

    return load_config(ROOT / "workflow/config.yaml")["scenes"]["work_precision"]["study"]


def configs(names: list[str]):
    from signorini.solvers import installed_qp_solvers
    from signorini.studies.work_precision.study import study_configs

    found = study_configs(shipped_study(), installed_qp_solvers())
    missing = [n for n in names if n not in found]
    if missing:
        raise SystemExit(f"not configurations of the study: {missing}")
    return {n: found[n] for n in names}


def one_run(Ns: list[int], chosen: dict, tol: float, timer, python: str, probe: dict, limit: float) -> dict:
    """The slice once: per N, the race of every chosen configuration."""
    from race import race  # benchmarks/race.py, next to this script

    from signorini.fem.discrete import build
    from signorini.fem.problem import Problem
    from signorini.peers import PeerRoute

    out = {}
    for N in Ns:
        disc = build(Problem(), N, "sw_ne")
        with tempfile.TemporaryDirectory(prefix="timing-robustness-") as tmp:
            system = Path(tmp) / "system.npz"
            A = disc.A.tocsr()
            np.savez(
                system, data=A.data, indices=A.indices, indptr=A.indptr, shape=A.shape, b=disc.b, boundary=disc.boundary
            )
            route = PeerRoute(python, str(ROOT / "workflow/peers/petsc_peer.py"), str(system), probe)
            t0 = time.perf_counter()
            out[str(N)] = race(disc, chosen, tol, timer, route, limit)
            out[str(N)]["wall_s"] = time.perf_counter() - t0
        for name, rec in out[str(N)]["configs"].items():
            print(
                f"  N={N} {name}: {rec['status']} {rec.get('time_s', math.nan):.3f} s CPU, "
                f"{rec.get('wall_s', math.nan):.3f} s wall, {rec.get('time_ref', math.nan):.2f} ref, "
                f"load {rec.get('load1', math.nan):.1f}",
                flush=True,
            )
    return out


def loads(run: dict) -> dict:
    values = [rec["load1"] for n in run.values() for rec in n["configs"].values() if "load1" in rec]
    return {"median": statistics.median(values), "min": min(values), "max": max(values)} if values else {}


def ratio_changes(quiet: dict, loaded: dict, key: str) -> dict[str, float]:
    """Per (N, solver) answered in both runs: |ratio_loaded / ratio_quiet − 1| of ``key``."""
    out = {}
    for N, q in quiet.items():
        for name, rq in q["configs"].items():
            rl = loaded.get(N, {}).get("configs", {}).get(name)
            if rl is None or "failed" in (rq["status"], rl["status"]) or name == "active_set":
                continue
            a, b = rq.get(key, math.nan), rl.get(key, math.nan)
            if math.isfinite(a) and math.isfinite(b) and a > 0:
                out[f"N{N}/{name}"] = abs(b / a - 1.0)
    return out


def time_change(quiet: dict, loaded: dict, key: str) -> float:
    """Median over (N, solver) of loaded / quiet absolute time ``key``."""
    factors = [
        rl[key] / rq[key]
        for N, q in quiet.items()
        for name, rq in q["configs"].items()
        if (rl := loaded.get(N, {}).get("configs", {}).get(name)) and rq.get(key, 0) > 0 and key in rl
    ]
    return statistics.median(factors) if factors else math.nan


def main(argv: list[str] | None = None) -> int:
    from signorini.peers import PEER_PYTHON, probe
    from signorini.pipeline.artifacts import save_json
    from signorini.timing import Protocol, Timer

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", default="201,501", help="meshes, comma-separated")
    parser.add_argument("--tol", type=float, default=1e-6, help="tolerance of the QP solvers and peers")
    parser.add_argument("--solvers", default=",".join(SOLVERS))
    parser.add_argument("--peers", default=",".join(PEERS), help="PETSc peers, when petsc4py is there ('' for none)")
    parser.add_argument("--python", default=PEER_PYTHON)
    parser.add_argument("--busy", type=int, default=2)
    parser.add_argument("--busy-kind", choices=["numpy", "spin"], default="numpy")
    parser.add_argument("--time-limit", type=float, default=300.0)
    parser.add_argument(
        "--max-load",
        type=float,
        default=None,
        help="the protocol's load limit (default: the cores; the loaded run is meant to exceed it)",
    )
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/timing_robustness.json")
    args = parser.parse_args(argv)
    Ns = [int(n) for n in args.N.split(",")]
    found = probe(args.python, ROOT / "workflow/peers/petsc_peer.py")
    names = args.solvers.split(",") + ([p for p in args.peers.split(",") if p] if found.get("petsc4py") else [])
    chosen = configs(names)
    # the study's protocol; the load limit of one process (the study's allows for its two jobs)
    protocol = Protocol.from_mapping({**shipped_study().get("timing", {}), "max_load": args.max_load})
    started = time.time()
    print(f"quiet run (load {os.getloadavg()[0]:.1f}): {', '.join(chosen)} at N = {Ns}", flush=True)
    quiet = one_run(Ns, chosen, args.tol, Timer(protocol), args.python, found, args.time_limit)
    print(f"loaded run: {args.busy} busy processes ({args.busy_kind})", flush=True)
    with Busy(args.busy, args.busy_kind):
        # the busy processes are the point: the load gate must not wait for them to stop
        loaded_protocol = Protocol(**{**protocol.as_dict(), "retries": 0, "wait_s": 0.0})
        loaded = one_run(Ns, chosen, args.tol, Timer(loaded_protocol), args.python, found, args.time_limit)
    changes = {k: ratio_changes(quiet, loaded, k) for k in ("ratio_ref", "ratio_cpu", "ratio_wall")}
    worst = {k: max(v.values(), default=math.nan) for k, v in changes.items()}
    result = {
        "N": Ns,
        "tol": args.tol,
        "solvers": {n: c.label for n, c in chosen.items()},
        "reference_solver": "active_set",
        "petsc": {k: found.get(k) for k in ("petsc4py", "petsc_version", "error")},
        "busy": {"processes": args.busy, "kind": args.busy_kind},
        "cores": os.cpu_count(),
        "protocol": protocol.as_dict(),
        "quiet": quiet,
        "loaded": loaded,
        "loads": {"quiet": loads(quiet), "loaded": loads(loaded)},
        "time_change": {k: time_change(quiet, loaded, k) for k in ("wall_s", "time_s", "time_ref")},
        "ratio_changes": changes,
        "worst_ratio_change": worst["ratio_cpu"],
        "worst_ratio_change_ref": worst["ratio_ref"],
        "worst_ratio_change_wall": worst["ratio_wall"],
        "goal": GOAL,
        "met": bool(worst["ratio_cpu"] <= GOAL),
        "started": started,
        "wall_s": time.time() - started,
        "python": sys.version.split()[0],
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    save_json(args.out, result)
    print(f"absolute times loaded/quiet: {result['time_change']}")
    print(
        f"worst ratio change: CPU {worst['ratio_cpu']:.3f}, reference units {worst['ratio_ref']:.3f}, "
        f"wall {worst['ratio_wall']:.3f} (goal ≤ {GOAL}) -> {args.out}"
    )
    return 0


if __name__ == "__main__":
    sys.exit(main())
