"""Write ``src/signorini/fem/quadrature_tables.py``: the quadrature rules the norms use, as
scikit-fem and SciPy computed them (hexadecimal floats):

    python scripts/quadrature_tables.py

The table, not SciPy, fixes the bits the committed outputs hold: SciPy computes its Gauss rules at
run time, and the last bits depend on the machine (docs/evidence/design-measurements.md#quadrature-tables).
A rule already in the table is therefore written again as it stands; only a new number of points
(added to ``LEGENDRE_N`` or ``JACOBI_N``) is computed by SciPy.  ``--recompute`` takes every rule
from SciPy afresh, which may move the committed outputs in their last digits (``make check``).
``tests/fem/test_quadrature_tables.py`` checks that every rule is the libraries' within a few units
in the last place, and that every rule the norms ask for is tabulated.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "src/signorini/fem/quadrature_tables.py"
# n of the Gauss–Legendre and Gauss–Jacobi(0, 1) rules the norms ask for: the conical rules of
# the conventions (4) and of the P1 norms (8), the true norms' levels (fem.norms.true
# INTEGRAL_LEVELS, NEAR_LEVELS: conical and fan rules) and the boundary rules
# (conventional.BOUNDARY_POINTS, true.BOUNDARY_LEVELS); tests/fem/test_quadrature_tables.py checks the list
LEGENDRE_N = (3, 4, 5, 7, 8, 10, 14, 16, 20, 28, 32, 64)
JACOBI_N = (3, 4, 5, 7, 8, 10, 14, 20, 28)


def hex_tuple(values: np.ndarray, indent: str = "    ") -> str:
    """A tuple of the values as hexadecimal strings, four to a line."""
    items = [f'"{float(v).hex()}",' for v in np.ravel(values)]
    rows = [indent + " ".join(items[i : i + 4]) for i in range(0, len(items), 4)]
    return "(\n" + "\n".join(rows) + "\n" + indent[:-4] + ")"


def render(recompute: bool = False) -> str:
    """The module's text; a rule already tabulated keeps its bits unless ``recompute``."""
    from scipy.special import roots_jacobi, roots_legendre
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    X, W = get_quadrature(RefTri, 8)
    lines = [
        '"""Quadrature rules as scikit-fem and SciPy computed them (hexadecimal floats), so that a job',
        "evaluating norms needs neither library (their import is most of such a job's time) and gives",
        "the same bits on every machine (SciPy's last bits depend on the machine:",
        "docs/evidence/design-measurements.md#quadrature-tables).  Written by",
        "``scripts/quadrature_tables.py``; ``tests/fem/test_quadrature_tables.py`` checks every rule",
        'against the libraries."""',
        "",
        "# scikit-fem's degree-8 rule on the reference triangle: points (2, 16) row by row, weights (16,)",
        f"DUNAVANT8_POINTS = {hex_tuple(X)}",
        f"DUNAVANT8_WEIGHTS = {hex_tuple(W)}",
        "# scipy.special.roots_legendre(n): n -> (points, weights) on [-1, 1]",
        "LEGENDRE = {",
    ]
    from signorini.fem import quadrature
    from signorini.fem.quadrature_tables import JACOBI01, LEGENDRE

    for n in LEGENDRE_N:  # the package's reader of the table, or SciPy for a rule not yet in it
        x, w = quadrature.roots_legendre(n) if n in LEGENDRE and not recompute else roots_legendre(n)
        lines.append(f"    {n}: ({hex_tuple(x, ' ' * 12)}, {hex_tuple(w, ' ' * 12)}),")
    lines += ["}", "# scipy.special.roots_jacobi(n, 0, 1): n -> (points, weights), weight (1 + x) on [-1, 1]"]
    lines.append("JACOBI01 = {")
    for n in JACOBI_N:
        x, w = quadrature.roots_jacobi01(n) if n in JACOBI01 and not recompute else roots_jacobi(n, 0.0, 1.0)
        lines.append(f"    {n}: ({hex_tuple(x, ' ' * 12)}, {hex_tuple(w, ' ' * 12)}),")
    lines.append("}")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--recompute", action="store_true", help="take every rule from SciPy afresh")
    args = parser.parse_args(argv)
    OUT.write_text(render(args.recompute), encoding="utf-8")
    print(f"-> {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
