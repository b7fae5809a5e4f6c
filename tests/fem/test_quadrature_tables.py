"""The tabulated quadrature rules (``signorini.fem.quadrature_tables``, written by
``scripts/quadrature_tables.py``): the libraries' own to the last few bits, the same on every machine,
and every rule the norms ask for."""

from __future__ import annotations


def test_the_tabulated_rules_are_the_libraries():
    """``fem.quadrature_tables`` holds scikit-fem's degree-8 rule bit for bit (constants in its
    source) and SciPy's Gauss–Legendre and Gauss–Jacobi(0, 1) rules within a few units in the last
    place: SciPy computes those at run time, and its last bits depend on the machine (2 units at
    n = 14 and 28 on one of the machines CI runs on), which is why the norms read the table."""
    import numpy as np
    from scipy.special import roots_jacobi, roots_legendre
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    from signorini.fem import quadrature, quadrature_tables

    for ours, theirs in zip(quadrature.dunavant8(), get_quadrature(RefTri, 8), strict=True):
        assert ours.shape == theirs.shape and ours.dtype == theirs.dtype and ours.tobytes() == theirs.tobytes()
    for table, ours, theirs in (
        (quadrature_tables.LEGENDRE, quadrature.roots_legendre, roots_legendre),
        (quadrature_tables.JACOBI01, quadrature.roots_jacobi01, lambda n: roots_jacobi(n, 0.0, 1.0)),
    ):
        for n in [*table, 6, 9]:  # the tabulated rules, and two that SciPy computes
            for a, b in zip(ours(n), theirs(n), strict=True):
                assert a.shape == b.shape == (n,)
                np.testing.assert_array_max_ulp(a, b, maxulp=4)


def test_writing_the_table_again_keeps_its_bits(tmp_path, monkeypatch):
    """``scripts/quadrature_tables.py`` run on any machine writes the module as it stands (a rule
    already tabulated keeps its bits); ``--recompute`` would take SciPy's afresh."""
    import importlib.util
    from pathlib import Path

    script = Path(__file__).resolve().parents[2] / "scripts/quadrature_tables.py"
    spec = importlib.util.spec_from_file_location("quadrature_tables_script", script)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.render() == module.OUT.read_text(encoding="utf-8")
    out = tmp_path / "table.py"
    monkeypatch.setattr(module, "OUT", out)
    assert module.main(["--recompute"]) == 0 and out.read_text(encoding="utf-8").startswith('"""Quadrature')


def test_every_rule_the_norms_ask_for_is_tabulated():
    """The conical rules of the conventions (4) and of the P1 norms (8), the true norms' levels and
    the boundary rules: none of them falls back to SciPy in a norm job."""
    from signorini.fem.norms import conventional, true
    from signorini.fem.quadrature_tables import JACOBI01, LEGENDRE

    conical = {4, 8, *true.INTEGRAL_LEVELS, *true.NEAR_LEVELS}
    assert conical <= set(JACOBI01) and conical <= set(LEGENDRE)
    assert {conventional.BOUNDARY_POINTS, *true.BOUNDARY_LEVELS, *true.NEAR_LEVELS} <= set(LEGENDRE)
