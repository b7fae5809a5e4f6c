"""Our cascade active-set solve against the strongest PETSc methods, timed alternately in one run.

    python benchmarks/peers.py --N 501     # -> results/benchmarks/peers_N501.json
    python benchmarks/peers.py --N 201     # the ratio on a coarser mesh

Per round (``--runs``, 3): our ``solve_discrete`` (cascade warm start, coarse levels included)
in this process, then each PETSc method of ``--methods`` (default: TAO TRON with hypre BoomerAMG,
``vinewtonrsls`` with CHOLMOD and with CG/BoomerAMG: the fastest peers of the work-precision study
that reach Table 1's digits on every mesh; GPCG with BoomerAMG, as fast at loose tolerances, stops
at its iteration limit at 1e-10 from N = 201 on)
through the study's driver (``workflow/peers/petsc_peer.py`` under ``--python``) at tolerance
``--tol`` (1e-10, where every converging peer agrees with our certified solution).  The rounds
alternate the methods so that a change of the machine's load hits all of them alike.

Keys (seconds): ``ours_s`` and, per method, ``solve_s`` (PETSc's ``solve`` call) and ``setup_s``
(matrix, vectors, solver set-up) -- medians over the rounds, every round's value in ``*_runs``;
per method its status under our KKT certificate at ``--tol``, the max-norm difference to our
solution relative to ``‖u‖∞``, PETSc's converged reason and iterations; ``ratios``: each method's
median solve time over ours, and ``fastest``: the fastest method that passed the certificate and
its ratio, against the target (``TARGET_RATIO``: ours at least 5× faster).  Written atomically.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import yaml

from signorini.fem.discrete import build
from signorini.fem.problem import Problem
from signorini.fem.solve import solve_discrete
from signorini.pipeline.artifacts import save_json
from signorini.pipeline.paths import PEER_DRIVER
from signorini.studies.work_precision.peers import PeerRoute, probe, run_peer
from signorini.studies.work_precision.study import PEER_PYTHON, study_configs

ROOT = Path(__file__).resolve().parents[1]
METHODS = ["petsc_tron_boomeramg", "petsc_rsls_cholmod", "petsc_rsls_boomeramg"]
TARGET_RATIO = 5.0
TIME_LIMIT_S = 600.0


def peer_configs(names: list[str]) -> dict:
    """The named peer configurations of the shipped work-precision study."""
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text(encoding="utf-8"))
    configs = study_configs(config["scenes"]["work_precision"]["study"])
    unknown = [n for n in names if n not in configs or not configs[n].peer]
    if unknown:
        peers = sorted(k for k, c in configs.items() if c.peer)
        raise SystemExit(f"not a PETSc peer of the study: {unknown}; choose from {peers}")
    return {n: configs[n] for n in names}


def write_system(disc, path: Path) -> None:
    """The arrays the driver reads (those of the ``discretise`` archive)."""
    A = disc.A.tocsr()
    np.savez(path, data=A.data, indices=A.indices, indptr=A.indptr, shape=A.shape, b=disc.b, boundary=disc.boundary)


def one_round(disc, route: PeerRoute, configs: dict, tol: float, records: dict) -> None:
    """Ours, then every PETSc method once; appends to ``records``."""
    t0 = time.perf_counter()
    ours = solve_discrete(disc, "active_set")
    records["ours"].append(time.perf_counter() - t0)
    records["ours_u"] = ours.u
    scale = float(np.abs(ours.u).max())
    for name, config in configs.items():
        out = run_peer(config, route, disc, tol, TIME_LIMIT_S, repeat_below_s=0.0, repeats=1)
        rec = records.setdefault(name, {"solve_s": [], "setup_s": [], "status": [], "agreement": [], "reason": []})
        rec["solve_s"].append(out.times[0] if out.times else float("nan"))
        rec["setup_s"].append(float(out.extra.get("setup_s", float("nan"))))
        rec["status"].append(out.status)
        rec["reason"].append(out.reason or out.extra.get("converged_reason", ""))
        diff = float(np.abs(out.result.u - ours.u).max()) / scale if out.result is not None else float("nan")
        rec["agreement"].append(diff)
        rec["iterations"] = int(out.result.iterations) if out.result is not None else None
        rec["peer_info"] = out.extra.get("peer_info", "")
        print(f"  {name}: {out.status} solve {rec['solve_s'][-1]:.3f} s, agreement {diff:.1e}", flush=True)
    print(f"  ours: {records['ours'][-1]:.3f} s", flush=True)


def summary(records: dict, configs: dict) -> dict:
    """Medians, ratios to ours and the fastest certified PETSc method."""
    ours = statistics.median(records["ours"])
    methods, ratios = {}, {}
    for name, config in configs.items():
        rec = records[name]
        solve = statistics.median(rec["solve_s"])
        methods[name] = {
            "label": config.label,
            "options": dict(config.options),
            "solve_s": solve,
            "solve_runs_s": rec["solve_s"],
            "setup_s": statistics.median(rec["setup_s"]),
            "setup_runs_s": rec["setup_s"],
            "status": rec["status"],
            "reason": rec["reason"],
            "iterations": rec.get("iterations"),
            "agreement_max_rel": max(rec["agreement"]),
            "peer_info": rec.get("peer_info", ""),
        }
        ratios[name] = solve / ours
    certified = [n for n in configs if all(s == "ok" for s in methods[n]["status"])]
    fastest = min(certified, key=lambda n: methods[n]["solve_s"]) if certified else None
    verdict = None
    if fastest is not None:
        ratio = ratios[fastest]
        verdict = {"method": fastest, "ratio": ratio, "target_min": TARGET_RATIO, "met": ratio >= TARGET_RATIO}
    return {
        "ours_s": ours,
        "ours_runs_s": records["ours"],
        "methods": methods,
        "ratios": ratios,
        "fastest": verdict,
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, default=501)
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument("--methods", default=",".join(METHODS), help="peer configurations of the study")
    parser.add_argument("--python", default=PEER_PYTHON, help="the interpreter with petsc4py")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    out = args.out or ROOT / "results" / "benchmarks" / f"peers_N{args.N}.json"
    configs = peer_configs(args.methods.split(","))
    found = probe(args.python, ROOT / PEER_DRIVER)
    if not found.get("petsc4py"):
        raise SystemExit(f"PETSc peers unavailable: {found.get('error')} (make setup-peers)")
    load_start = os.getloadavg()
    solve_discrete(build(Problem(), 21, "sw_ne"), "active_set")  # loads CHOLMOD & co. outside the timing
    disc = build(Problem(), args.N, "sw_ne")
    records: dict = {"ours": []}
    with tempfile.TemporaryDirectory(prefix="peers-bench-") as tmp:
        system = Path(tmp) / "system.npz"
        write_system(disc, system)
        route = PeerRoute(args.python, str(ROOT / PEER_DRIVER), str(system), found)
        for k in range(args.runs):
            print(f"round {k + 1}/{args.runs} (N = {args.N})", flush=True)
            one_round(disc, route, configs, args.tol, records)
    records.pop("ours_u", None)
    result = {
        "N": args.N,
        "n_dofs": int(disc.b.size),
        "tol": args.tol,
        "runs": args.runs,
        "petsc": {k: found.get(k) for k in ("petsc_version", "python", "available")},
        **summary(records, configs),
        "load_average_start": list(load_start),
        "load_average_end": list(os.getloadavg()),
        "python": sys.version.split()[0],
        "note": "ours: solve_discrete with the cascade warm start; PETSc: the solve call (setup_s apart)",
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    save_json(out, result)
    fastest = result["fastest"]
    print(f"ours {result['ours_s']:.3f} s; " + ", ".join(f"{k} ×{v:.1f}" for k, v in result["ratios"].items()))
    if fastest:
        print(f"fastest certified PETSc method: {fastest['method']} ×{fastest['ratio']:.1f} (target ≥ {TARGET_RATIO})")
    print(f"-> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
