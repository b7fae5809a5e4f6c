"""Write ``src/signorini/fem/quadrature_tables.py``: the quadrature rules the norms use, as
scikit-fem and SciPy compute them, bit for bit (hexadecimal floats):

    python scripts/quadrature_tables.py

``tests/fem/test_quadrature.py`` checks that every tabulated rule is the one the libraries return
today; run this script again when it fails (a new library version, a new number of points).
"""

from __future__ import annotations

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


def render() -> str:
    from scipy.special import roots_jacobi, roots_legendre
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    X, W = get_quadrature(RefTri, 8)
    lines = [
        '"""Quadrature rules as scikit-fem and SciPy compute them, bit for bit (hexadecimal floats),',
        "so that a job evaluating norms needs neither library (their import is most of such a job's",
        "time).  Written by ``scripts/quadrature_tables.py``; ``tests/fem/test_quadrature.py`` checks",
        'every rule against the libraries."""',
        "",
        "# scikit-fem's degree-8 rule on the reference triangle: points (2, 16) row by row, weights (16,)",
        f"DUNAVANT8_POINTS = {hex_tuple(X)}",
        f"DUNAVANT8_WEIGHTS = {hex_tuple(W)}",
        "# scipy.special.roots_legendre(n): n -> (points, weights) on [-1, 1]",
        "LEGENDRE = {",
    ]
    for n in LEGENDRE_N:
        x, w = roots_legendre(n)
        lines.append(f"    {n}: ({hex_tuple(x, ' ' * 12)}, {hex_tuple(w, ' ' * 12)}),")
    lines += ["}", "# scipy.special.roots_jacobi(n, 0, 1): n -> (points, weights), weight (1 + x) on [-1, 1]"]
    lines.append("JACOBI01 = {")
    for n in JACOBI_N:
        x, w = roots_jacobi(n, 0.0, 1.0)
        lines.append(f"    {n}: ({hex_tuple(x, ' ' * 12)}, {hex_tuple(w, ' ' * 12)}),")
    lines.append("}")
    return "\n".join(lines) + "\n"


def main() -> int:
    OUT.write_text(render(), encoding="utf-8")
    print(f"-> {OUT.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
