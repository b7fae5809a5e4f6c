"""Time the true norms of Table 2 (``<norm>_true``) before and after the bounds that exclude
triangles, on one mesh at a time, and compare their values.

    python benchmarks/true_norm_pruning.py --N 201 501 2001 --which new
    python benchmarks/true_norm_pruning.py --N 2001 --which old --baseline 34dc782
    python benchmarks/true_norm_pruning.py --N 2001 --which convention

``new`` is ``signorini.fem.norms.true`` of this tree; ``old`` is the same module as it is at the
git revision ``--baseline`` (loaded from ``git show``, its imports resolved in this tree: only
``true_norms`` differs); ``convention`` times the norm of the same name under the paper's
conventions (``fem.norms.conventional.evaluate_norms``: fixed rules and point sets), the unit of cost.
``u_h`` of the paper's problem (x0 = 0.5, R = 0.45, A = 10, c = 1, diagonal ``sw_ne``) is solved
once per mesh by the ``auto`` route and kept in ``/tmp/wt-truenorms-uh<N>.npy``.  Each row
records the wall and CPU time, the value, its estimated error, whether it converged, the levels
and the load average (``/proc/loadavg``) before and after; the rows are merged into ``--out``
(keyed by N, norm and variant), so the variants can be measured in separate runs.  One thread
(``signorini.pipeline.jobenv``).  ``--interpolant`` takes the nodal interpolant ``I_h u`` for ``u_h``
instead (variant ``<which>-interpolant``: no solve, so meshes beyond the solver's reach on this
machine, N = 4001, show how the levels scale).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path

from signorini.pipeline.jobenv import THREAD_VARIABLES, job_environment

job_environment()  # before numpy loads its BLAS

import numpy as np  # noqa: E402

from signorini.fem.mesh import friedrichs_keller  # noqa: E402
from signorini.fem.problem import Problem  # noqa: E402
from signorini.published import TABLE2_NORMS  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
PROBLEM = {"x0": 0.5, "R": 0.45, "A": 10.0, "c": 1.0}
OLD_MODULE = "src/signorini/fem/true_norms.py"  # its path at the baseline
# the modules it imports, as they are named in this tree
OLD_IMPORTS = {
    "signorini.fem.conventions": "signorini.fem.norms.conventions",
    "signorini.fem.norm_names": "signorini.fem.norms.names",
    "signorini.fem.norms": "signorini.fem.norms.conventional",
}


def load_avg() -> list[float]:
    return [float(x) for x in Path("/proc/loadavg").read_text(encoding="utf-8").split()[:3]]


def solution(N: int) -> np.ndarray:
    """u_h of the paper's problem on the N mesh, solved once and cached in /tmp."""
    path = Path(f"/tmp/wt-truenorms-uh{N}.npy")
    if not path.exists():
        from signorini.fem.discrete import build
        from signorini.fem.solve import solve_discrete

        np.save(path, solve_discrete(build(Problem(**PROBLEM), N, "sw_ne"), "auto").u)
    return np.load(path)


def module(which: str, baseline: str):
    """``signorini.fem.norms.true`` of this tree (``new``) or of the revision ``baseline`` (``old``)."""
    if which == "new":
        import signorini.fem.norms.true as new

        return new
    source = subprocess.run(
        ["git", "-C", str(ROOT), "show", f"{baseline}:{OLD_MODULE}"],
        check=True,
        capture_output=True,
        text=True,
        encoding="utf-8",
    ).stdout
    for old_name, name in OLD_IMPORTS.items():
        source = re.sub(rf"^(\s*)from {re.escape(old_name)} import", rf"\1from {name} import", source, flags=re.M)
    spec = importlib.util.spec_from_loader("old_true_norms", loader=None)
    old = importlib.util.module_from_spec(spec)
    sys.modules["old_true_norms"] = old  # dataclasses look their module up
    exec(compile(source, f"{baseline}:{OLD_MODULE}", "exec"), old.__dict__)
    return old


class Convention:
    """A convention norm's value in the shape of a ``TrueNorm`` (no error estimate, no levels)."""

    def __init__(self, value: float):
        self.value, self.error_estimate, self.converged, self.levels = value, float("nan"), False, []


def summary(levels: list[dict]) -> list[dict]:
    """The levels without long lists (every key but the per-level arrays)."""
    return [{k: v for k, v in lv.items() if not isinstance(v, list) or len(v) <= 8} for lv in levels]


def measure(N: int, names: list[str], which: str, baseline: str, interpolant: bool = False):
    """One row per norm (a generator: each row is written as soon as it is measured)."""
    mod = None if which == "convention" else module(which, baseline)
    mesh, problem = friedrichs_keller(N, "sw_ne"), Problem(**PROBLEM)
    u_h = problem.u(mesh.p) if interpolant else solution(N)
    for name in names:
        load0, t0, c0 = load_avg(), time.perf_counter(), time.process_time()
        if mod is None:
            from signorini.fem.norms.conventional import evaluate_norms

            result = Convention(evaluate_norms(problem, mesh, u_h, [name])[name])
        else:
            result = mod.true_norm(problem, mesh, u_h, name + "_true")
        wall, cpu = time.perf_counter() - t0, time.process_time() - c0
        yield {
            "N": N,
            "norm": name + "_true",
            "variant": which + ("-interpolant" if interpolant else ""),
            "u_h": "interpolant I_h u" if interpolant else "finite element solution",
            "revision": baseline if which == "old" else "worktree",
            **({"convention_norm": name} if which == "convention" else {}),
            "wall_s": wall,
            "cpu_s": cpu,
            "value": result.value,
            "error_estimate": result.error_estimate,
            "converged": bool(result.converged),
            "levels": summary(result.levels),
            "loadavg_before": load0,
            "loadavg_after": load_avg(),
        }
        print(
            f"N={N} {name}_true [{which}]: {wall:.1f} s, {result.value:.10e} ± {result.error_estimate:.1e}"
            f" converged={result.converged}",
            flush=True,
        )


def merge(path: Path, rows: list[dict]) -> dict:
    """The rows merged into the JSON at ``path`` (a row replaces the one of the same N, norm, variant),
    with the relative differences of the new values to the old ones where both are there."""
    data = json.loads(path.read_text(encoding="utf-8")) if path.exists() else {"rows": []}
    key = lambda r: (r["N"], r["norm"], r["variant"])  # noqa: E731
    table = {key(r): r for r in data["rows"]}
    table.update({key(r): r for r in rows})
    data["rows"] = sorted(table.values(), key=lambda r: (r["N"], TABLE2_NORMS.index(r["norm"][:-5]), r["variant"]))
    comparison = []
    for (N, norm, variant), row in table.items():
        old, convention = table.get((N, norm, "old")), table.get((N, norm, "convention"))
        if variant == "new" and old is not None:
            comparison.append(
                {
                    "N": N,
                    "norm": norm,
                    "old_s": old["wall_s"],
                    "new_s": row["wall_s"],
                    "old_cpu_s": old["cpu_s"],
                    "new_cpu_s": row["cpu_s"],
                    "speedup_cpu": old["cpu_s"] / row["cpu_s"],
                    **({"new_cpu_over_convention_cpu": row["cpu_s"] / convention["cpu_s"]} if convention else {}),
                    "relative_difference": row["value"] / old["value"] - 1.0,
                    "new_relative_error_estimate": row["error_estimate"] / row["value"],
                    "old_converged": old["converged"],
                    "new_converged": row["converged"],
                }
            )
    data["comparison"] = sorted(comparison, key=lambda r: (r["N"], TABLE2_NORMS.index(r["norm"][:-5])))
    threads = {name: os.environ.get(name) for name in THREAD_VARIABLES}
    data["machine"] = {"cpu_count": os.cpu_count(), "threads": threads}
    data["problem"] = PROBLEM
    data["note"] = (
        "wall_s and cpu_s of one evaluation each, single thread, on a 2-core machine shared with another "
        "developer: loadavg_before/after (1, 5, 15 min) say how loaded it was; cpu_s is less sensitive to "
        "the load than wall_s, not immune to it (shared cores and caches). The old rows (every triangle at "
        "every level) ran at loads 3-10, the new ones at 3-7."
    )
    return data


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--N", type=int, nargs="+", default=[201, 501])
    parser.add_argument("--norms", nargs="+", default=list(TABLE2_NORMS))
    parser.add_argument("--which", choices=("old", "new", "convention"), default="new")
    parser.add_argument("--baseline", default="34dc782", help="the git revision of the old module")
    parser.add_argument("--interpolant", action="store_true", help="u_h = I_h u instead of the solution")
    parser.add_argument("--out", default=str(ROOT / "docs/evidence/true_norm_pruning.json"))
    args = parser.parse_args()
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    for N in args.N:
        for row in measure(N, args.norms, args.which, args.baseline, args.interpolant):
            data = merge(out, [row])
            tmp = out.with_suffix(".tmp")
            tmp.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
            tmp.replace(out)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
