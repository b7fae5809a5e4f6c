"""How far this machine's norm values lie from the committed ones, in units of each value's stated
uncertainty:

    .venv/bin/snakemake -c2 theory true_norms      # cold, on the machine to compare
    python benchmarks/cross_machine.py --out docs/evidence/cross_machine.json

The committed tables hold values computed on the machine that committed them; a run on another
processor rounds differently (SciPy's and BLAS's kernels, numpy's SIMD reductions) and gives other
last digits.  Each value of a norm artifact states how far round-off can move it
(``algebraic_error.uncertainty``; a true norm also its ``quadrature_error.error_estimate``), and
the committed digits are chosen from those statements.  This script reads every error value of
``paper_figures/theory_rates.csv`` (columns ``e_N<N>``) and ``paper_figures/table1_true.csv``
(``convention``, ``true``) as committed, the same value from this checkout's artifacts
(``results/<scene>/N<N>/norms/<norm>.json``), and writes per table the largest ratio
``|Δ| / uncertainty`` and how many values exceed 1 (a change larger than the statement allows).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import platform
from pathlib import Path

import numpy as np
import pandas as pd

from signorini.fem.norms.names import parse_norm_name
from signorini.pipeline.check import git_reference
from signorini.studies.scene.store import read_norm, read_quadrature_error, read_uncertainty

ROOT = Path(__file__).resolve().parents[1]


def _committed(path: str) -> pd.DataFrame:
    """The committed version of a table (git's HEAD, read as ``make check`` reads it)."""
    return pd.read_csv(io.BytesIO(git_reference(ROOT)(path)), encoding="utf-8")


def _artifact(scene: str, N: int, norm: str) -> tuple[float, float] | None:
    """(value, stated uncertainty) of one norm artifact of this checkout, None where absent: the
    algebraic-error uncertainty, and for a true norm its quadrature error estimate besides."""
    path = ROOT / f"results/{scene}/N{N}/norms/{norm}.json"
    if not path.exists():
        return None
    uncertainty = read_uncertainty(path, norm, N)
    if parse_norm_name(norm).true:
        uncertainty += float(read_quadrature_error(path, norm, N)["error_estimate"])
    return read_norm(path, norm, N), uncertainty


def _pairs() -> dict[str, list[tuple[str, int, float]]]:
    """{table: [(norm, N, committed value)]} with the scene whose artifacts hold each value."""
    rates = _committed("paper_figures/theory_rates.csv")
    theory = [
        (str(row.norm), int(column[3:]), float(getattr(row, column)))
        for row in rates.itertuples()
        for column in rates.columns
        if column.startswith("e_N")
    ]
    true = _committed("paper_figures/table1_true.csv")
    table1 = [
        (str(row.norm) + suffix, int(str(row.h).split("/")[1]), float(getattr(row, column)))
        for row in true.itertuples()
        for column, suffix in (("convention", ""), ("true", "_true"))
    ]
    return {"theory_rates": [("theory", *p) for p in theory], "table1_true": [("paper", *p) for p in table1]}


def compare() -> dict:
    """Per table: values compared, the largest |Δ| / uncertainty (and where), values above 1."""
    out = {}
    for table, pairs in _pairs().items():
        ratios = []
        for scene, norm, N, committed in pairs:
            found = _artifact(scene, N, norm)
            if found is None or not np.isfinite(committed):
                continue
            value, uncertainty = found
            ratios.append((abs(value - committed) / uncertainty, norm, N, abs(value - committed), uncertainty))
        ratios.sort(reverse=True)
        out[table] = {
            "values": len(ratios),
            "identical": sum(r[3] == 0.0 for r in ratios),
            "above_uncertainty": sum(r[0] > 1.0 for r in ratios),
            "largest_ratio": ratios[0][0] if ratios else None,
            "largest_at": {"norm": ratios[0][1], "N": ratios[0][2], "change": ratios[0][3], "uncertainty": ratios[0][4]}
            if ratios
            else None,
        }
    return out


def _processor() -> dict:
    """The processor's model name and whether it has AVX2 and AVX-512 (what numpy's kernels dispatch on)."""
    cpuinfo = Path("/proc/cpuinfo")
    lines = cpuinfo.read_text(encoding="utf-8").splitlines() if cpuinfo.exists() else []
    fields = dict(line.split(":", 1) for line in lines if ":" in line)
    fields = {key.strip(): value.strip() for key, value in fields.items()}
    flags = set(fields.get("flags", "").split())
    return {
        "model": fields.get("model name", platform.processor()),
        "avx2": "avx2" in flags,
        "avx512f": "avx512f" in flags,
        "cpus": os.cpu_count(),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, help="write the result as JSON here")
    args = parser.parse_args(argv)
    result = {"processor": _processor(), "tables": compare()}
    text = json.dumps(result, indent=1)
    print(text)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
