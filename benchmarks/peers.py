"""Our active set against the strongest PETSc methods, timed round-robin in one run: from the
same warm start and cold against cold.

    python benchmarks/peers.py --N 501     # -> results/benchmarks/peers_N501.json
    python benchmarks/peers.py --N 201     # the ratio on a coarser mesh
    python benchmarks/peers.py --N 501 --route multigrid   # our multigrid route: peers_N501_multigrid.json
    python benchmarks/peers.py --N 512 --route multigrid --methods petsc_rsls_pcmg,petsc_tron_boomeramg
        # geometric multigrid on PETSc's DMDA (GRID_METHODS), on a grid whose cells halve

The configurations (of the shipped work-precision study, ``workflow/config.yaml``): our
``solve_discrete`` by ``--route`` (the direct route, ``active_set``, or ``multigrid``) from the
cascade (coarse levels included) and cold, and each PETSc method of
``--methods`` (default: TAO TRON with hypre BoomerAMG, ``vinewtonrsls`` with CHOLMOD and with
CG/BoomerAMG: the fastest peers of the study that reach Table 1's digits on every mesh) from
u = 0 and from the cascade's interpolated coarse solution (``<method>_ws``; the start's cost
added to its time, as the cascade's coarse levels are part of ours), through the study's driver
(``workflow/peers/petsc_peer.py`` under ``--python``) at tolerance ``--tol`` (1e-10, where every
converging peer agrees with our certified solution).  They are timed round-robin under the
protocol of ``signorini.timing`` (``race.race``, ``benchmarks/race.py``): CPU time of each call,
reference units against a sparse kernel timed before and after it, the load recorded, samples
under a load above the cores redone.

Keys: ``configs`` (per configuration: CPU ``time_s``, ``wall_s``, ``time_ref``, status under our
KKT certificate, agreement with our solution, the protocol's counts and loads);
``same_warm_start`` (each method from the cascade start against our cascade) and
``cold_against_cold`` (each method from u = 0 against our cold start): each method's CPU time over
ours with its bootstrap interval and verdict (``signorini.intervals``: ``above``, ours faster;
``tie``, the interval contains 1); ``fastest``: the fastest certified method of each comparison
and its ratio, against the target (``TARGET_RATIO``: ours at least 5× faster, met when the whole
interval lies above it).  Written atomically.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from signorini.pipeline.jobenv import job_environment

job_environment()  # one thread, like the peers (before numpy loads its BLAS)

import numpy as np  # noqa: E402
import yaml  # noqa: E402
from race import cpu_time, race  # noqa: E402  (benchmarks/race.py, next to this script)

from signorini import intervals  # noqa: E402
from signorini.fem.discrete import build  # noqa: E402
from signorini.fem.problem import Problem  # noqa: E402
from signorini.formatting import fmt_ratio  # noqa: E402
from signorini.peers import PEER_PYTHON, PeerRoute, probe  # noqa: E402
from signorini.pipeline.artifacts import save_json  # noqa: E402
from signorini.pipeline.paths import PEER_DRIVER  # noqa: E402
from signorini.studies.work_precision.study import WARM_SUFFIX, study_configs  # noqa: E402
from signorini.timing import Protocol, Timer  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
METHODS = ["petsc_tron_boomeramg", "petsc_rsls_cholmod", "petsc_rsls_boomeramg"]
TARGET_RATIO = 5.0
TIME_LIMIT_S = 600.0
# peers outside the study: geometric multigrid on the grid's DMDA with Galerkin coarse operators (the
# set-up of PETSc's obstacle example, on our matrix), for grids whose cells halve (N = 512, 1024,
# ...); on the study's meshes (N = 101 ... 501, none of them even) the driver answers "unavailable"
GRID_METHODS = {
    "petsc_rsls_pcmg": {
        "solver": "petsc_snes",
        "label": "vinewtonrsls + CG/PCMG (DMDA, Galerkin)",
        "options": {"snes_type": "vinewtonrsls", "ksp_type": "cg", "pc_type": "mg", "dm_type": "da"},
    },
}


def race_configs(names: list[str], route: str = "active_set") -> dict:
    """Ours by ``route`` (cascade, cold) and the named peers of the shipped study or of
    ``GRID_METHODS``, each also from the cascade start."""
    config = yaml.safe_load((ROOT / "workflow/config.yaml").read_text(encoding="utf-8"))
    study = config["scenes"]["work_precision"]["study"]
    study = {**study, "configs": {**study["configs"], **GRID_METHODS}, "same_warm_start": True}
    configs = study_configs(study)
    unknown = [n for n in names if n not in configs or not configs[n].peer]
    if unknown:
        peers = sorted(k for k, c in configs.items() if c.peer and not k.endswith(WARM_SUFFIX))
        raise SystemExit(f"not a PETSc peer of the study: {unknown}; choose from {peers}")
    chosen = [route, f"{route}_cold", *names, *(n + WARM_SUFFIX for n in names)]
    return {n: configs[n] for n in chosen}


def write_system(disc, path: Path) -> None:
    """The arrays the driver reads (those of the ``discretise`` archive)."""
    A = disc.A.tocsr()
    np.savez(path, data=A.data, indices=A.indices, indptr=A.indptr, shape=A.shape, b=disc.b, boundary=disc.boundary)


def comparison(configs: dict, ours: str, methods: list[str], suffix: str) -> dict:
    """Each method's CPU time over ours with its interval and verdict, and the fastest certified one."""
    mine = cpu_time(ours, configs[ours])
    ratios = {}
    for m in methods:
        rec = configs.get(m + suffix)
        if rec is not None and "time_s" in rec:
            r = intervals.ratio(cpu_time(m + suffix, rec), mine)
            ratios[m] = r.summary() | {"verdict": intervals.verdict(r)}
    certified = [m for m in ratios if configs[m + suffix]["status"] == "ok"]
    fastest = min(certified, key=lambda m: ratios[m]["value"]) if certified else None
    verdict = None
    if fastest is not None:
        r = ratios[fastest]
        verdict = {"method": fastest, "ratio": r, "target_min": TARGET_RATIO}
        verdict["met"] = bool(r["interval"] and r["lo"] >= TARGET_RATIO)
    return {"ours": ours, "ratios": ratios, "fastest": verdict}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, default=501)
    parser.add_argument("--tol", type=float, default=1e-10)
    parser.add_argument("--methods", default=",".join(METHODS), help="peer configurations of the study")
    parser.add_argument("--python", default=PEER_PYTHON, help="the interpreter with petsc4py")
    parser.add_argument("--max-wait", type=float, default=600.0, help="longest total wait for a quiet machine [s]")
    parser.add_argument("--route", choices=["active_set", "multigrid"], default="active_set", help="our route")
    parser.add_argument("--out", type=Path, default=None)
    args = parser.parse_args(argv)
    name = f"peers_N{args.N}" + ("" if args.route == "active_set" else f"_{args.route}")
    out = args.out or ROOT / "results" / "benchmarks" / f"{name}.json"
    methods = args.methods.split(",")
    configs = race_configs(methods, args.route)
    found = probe(args.python, ROOT / PEER_DRIVER)
    if not found.get("petsc4py"):
        raise SystemExit(f"PETSc peers unavailable: {found.get('error')} (make setup-peers)")
    load_start = os.getloadavg()
    disc = build(Problem(), args.N, "sw_ne")
    timer = Timer(Protocol(max_wait_total_s=args.max_wait))
    with tempfile.TemporaryDirectory(prefix="peers-bench-") as tmp:
        system = Path(tmp) / "system.npz"
        write_system(disc, system)
        route = PeerRoute(args.python, str(ROOT / PEER_DRIVER), str(system), found)
        raced = race(disc, configs, args.tol, timer, route, TIME_LIMIT_S, reference=args.route)
    timed = raced["configs"]
    result = {
        "N": args.N,
        "n_dofs": int(disc.b.size),
        "tol": args.tol,
        "petsc": {k: found.get(k) for k in ("petsc_version", "python", "available")},
        "protocol": timer.protocol.as_dict(),
        "kernel": raced["kernel"],
        "start": raced["start"],
        "configs": timed,
        "route": args.route,
        "same_warm_start": comparison(timed, args.route, methods, WARM_SUFFIX),
        "cold_against_cold": comparison(timed, f"{args.route}_cold", methods, ""),
        "load_average_start": list(load_start),
        "load_average_end": list(os.getloadavg()),
        "python": sys.version.split()[0],
        "note": "times: CPU seconds of the call (ours: solve_discrete; PETSc: the solve call, set-up apart); "
        "ratios of CPU times with 95 % bootstrap intervals",
    }
    out.parent.mkdir(parents=True, exist_ok=True)
    save_json(out, result)
    for key in ("same_warm_start", "cold_against_cold"):
        c = result[key]
        print(f"{key}: " + ", ".join(f"{m} {fmt_ratio(r)}" for m, r in c["ratios"].items()))
        if c["fastest"]:
            print(f"  fastest certified PETSc method: {c['fastest']['method']} {fmt_ratio(c['fastest']['ratio'])}")
    print(f"-> {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
