"""The floor of the fine level's Gauss–Seidel sweep, and what keeping pyamg's bits costs.

    python benchmarks/gs_chain.py --N 4001 --repeats 5 --out docs/evidence/gs_chain.json

One forward sweep over a Friedrichs–Keller 7-point stencil of (N + 1)² unknowns (one thread,
compiled), in four forms:

- ``pyamg_order``: the sweep the multigrid route runs (``solvers.kernels.gauss_seidel``'s
  arithmetic): the off-diagonal sum in CSR order from 0.0, then ``(b - sum) / diagonal``. The
  previous row's new value enters the sum third, so every later addition, the subtraction and the
  division wait for it: a chain of about 40 cycles per row.
- ``west_last``: the same terms, the previous row's added last: the chain is one multiplication,
  two additions and the division.
- ``west_last_reciprocal``: and a multiplication by the diagonal's reciprocal instead of the
  division.
- ``jacobi``: no chain at all (each row from the old values): what streaming the stencil costs,
  the memory-bandwidth floor of a sweep.

The last three change the roundings of every sweep, so every solution would move at round-off;
this records what that would buy.  Written: per form the nanoseconds per row (median and range
over ``--repeats``), the machine's cores and the 1-minute load before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numba
import numpy as np


@numba.njit(cache=True)
def sweep(x, b, offsets, values, diagonal, lo, hi, west, reciprocal):  # pragma: no cover - compiled
    """A forward sweep over rows ``lo:hi``: the off-diagonal sum in CSR order from 0.0, the term of
    the stencil entry ``west`` (the previous row) added last where ``west ≥ 0``; the division by the
    diagonal, or a multiplication by its reciprocal."""
    inverse = 1.0 / diagonal
    for i in range(lo, hi):
        rsum = 0.0
        for k in range(len(offsets)):
            if k != west:
                rsum += values[k] * x[i + offsets[k]]
        if west >= 0:
            rsum += values[west] * x[i - 1]
        x[i] = (b[i] - rsum) * inverse if reciprocal else (b[i] - rsum) / diagonal


@numba.njit(cache=True)
def jacobi(x, y, b, offsets, values, inverse, lo, hi):  # pragma: no cover - compiled
    for i in range(lo, hi):
        rsum = 0.0
        for k in range(len(offsets)):
            rsum += values[k] * x[i + offsets[k]]
        y[i] = (b[i] - rsum) * inverse


def measure(N: int, repeats: int) -> dict:
    side = N + 1
    n = side * side
    # the interior stencil of the paper's problem (c = 1) on the sw_ne mesh, h = 1/N: stiffness
    # plus consistent mass, in CSR (ascending column) order
    h2 = 1.0 / N**2
    offsets = (-side - 1, -side, -1, 1, side, side + 1)
    values = (h2 / 12.0, -1.0 + h2 / 12.0, -1.0 + h2 / 12.0, -1.0 + h2 / 12.0, -1.0 + h2 / 12.0, h2 / 12.0)
    diagonal = 4.0 + h2 / 2.0
    west = offsets.index(-1)
    rng = np.random.default_rng(0)
    b, x0 = rng.standard_normal(n), rng.standard_normal(n)
    lo, hi = side + 1, n - side - 1
    forms = {
        "pyamg_order": lambda x: sweep(x, b, offsets, values, diagonal, lo, hi, -1, False),
        "west_last": lambda x: sweep(x, b, offsets, values, diagonal, lo, hi, west, False),
        "west_last_reciprocal": lambda x: sweep(x, b, offsets, values, diagonal, lo, hi, west, True),
        "jacobi": lambda x: jacobi(x, y, b, offsets, values, 1.0 / diagonal, lo, hi),
    }
    y = np.empty(n)
    out = {}
    for name, run in forms.items():
        x = x0.copy()
        run(x)  # compile, touch the memory
        times = []
        for _ in range(repeats):
            x[:] = x0
            t = time.perf_counter()
            run(x)
            times.append((time.perf_counter() - t) / (hi - lo) * 1e9)
        out[name] = {"ns_per_row_median": float(np.median(times)), "ns_per_row_range": [min(times), max(times)]}
    base = out["pyamg_order"]["ns_per_row_median"]
    for name in out:
        out[name]["ratio_to_pyamg_order"] = out[name]["ns_per_row_median"] / base
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--N", type=int, default=4001)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]
    forms = measure(args.N, args.repeats)
    record = {
        "date": time.strftime("%Y-%m-%d %H:%M"),
        "cores": os.cpu_count(),
        "N": args.N,
        "unknowns": (args.N + 1) ** 2,
        "threads": numba.get_num_threads(),
        "load1": [load_before, os.getloadavg()[0]],
        "forms": forms,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=1) + "\n", encoding="utf-8")
    print(json.dumps(record, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
