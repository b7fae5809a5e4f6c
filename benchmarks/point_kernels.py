"""What the compiled point kernels of the manufactured problem cost and save, per point and per
process.

    python benchmarks/point_kernels.py                     # -> docs/evidence/point_kernels.json

Per point: ``Problem.u`` and ``Problem.u_and_grad_u`` with numpy and inside
``fem.problem.compiled_points``, on chunks of 16 384 × 25 points (a chunk of the true norms at
their second rule) drawn in the box around the support where the true norms evaluate (most of them
inside it), the best of three passes over 40 chunks.  Per process: importing numba and loading
both kernels in a fresh interpreter, less the same interpreter importing numpy only, the best of
three.  The 1-minute load average is recorded.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from signorini.fem.problem import Problem, compiled_points

ROOT = Path(__file__).resolve().parents[1]
CHUNK = 16384 * 25
CHUNKS = 40
LOAD_KERNELS = (
    "import time; t = time.perf_counter(); import numpy as np; from signorini.fem import point_kernels as k; "
    "a = np.zeros(2); u = np.empty(2); k.manufactured_u_and_grad(a, a, 0.5, 0.45, 10.0, u, u.copy(), u.copy()); "
    "k.manufactured_u(a, a, 0.5, 0.45, 10.0, u); print(time.perf_counter() - t)"
)
LOAD_NUMPY = "import time; t = time.perf_counter(); import numpy as np; print(time.perf_counter() - t)"


def ns_per_point(evaluate, x: np.ndarray) -> float:
    """The best of three passes of ``evaluate`` over the chunks of ``x``, in ns per point."""
    best = []
    for _ in range(3):
        t0 = time.perf_counter()
        for k in range(CHUNKS):
            evaluate(x[:, k * CHUNK : (k + 1) * CHUNK])
        best.append((time.perf_counter() - t0) / x.shape[1] * 1e9)
    return round(min(best), 2)


def process_cost() -> float:
    """Seconds a fresh process spends importing numba and loading the kernels beyond numpy's import."""
    seconds = {}
    for name, code in (("kernels", LOAD_KERNELS), ("numpy", LOAD_NUMPY)):
        runs = [
            subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, encoding="utf-8", check=True)
            for _ in range(3)
        ]
        seconds[name] = min(float(r.stdout) for r in runs)
    return round(seconds["kernels"] - seconds["numpy"], 3)


def measure() -> dict:
    problem, rng = Problem(), np.random.default_rng(0)
    x = np.stack([rng.uniform(0.05, 0.95, CHUNKS * CHUNK), rng.uniform(0.0, 0.45, CHUNKS * CHUNK)])
    out: dict = {"date": time.strftime("%Y-%m-%d"), "load1_before": os.getloadavg()[0]}
    with compiled_points():  # compiled (or loaded from the cache) before timing
        problem.u_and_grad_u(x[:, :2]), problem.u(x[:, :2])
    for name in ("u", "u_and_grad_u"):
        out[f"{name}_numpy_ns_per_point"] = ns_per_point(getattr(problem, name), x)
        with compiled_points():
            out[f"{name}_compiled_ns_per_point"] = ns_per_point(getattr(problem, name), x)
    out["inside_support_fraction"] = round(float(np.mean(np.hypot(x[0] - problem.x0, x[1]) < problem.R)), 3)
    out["process_cost_s"] = process_cost()
    out["break_even_points"] = int(
        out["process_cost_s"]
        / ((out["u_and_grad_u_numpy_ns_per_point"] - out["u_and_grad_u_compiled_ns_per_point"]) * 1e-9)
    )
    out["load1_after"] = os.getloadavg()[0]
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs/evidence/point_kernels.json")
    args = parser.parse_args(argv)
    result = measure()
    args.out.write_text(json.dumps(result, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
