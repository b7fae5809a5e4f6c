"""The tabulated quadrature rules (``signorini.fem.quadrature_tables``, written by
``scripts/quadrature_tables.py``): the libraries' own, bit for bit, and every rule the norms ask for."""

from __future__ import annotations


def test_the_tabulated_rules_are_the_libraries_bit_for_bit():
    """``fem.quadrature_tables`` (written by ``scripts/quadrature_tables.py``) holds scikit-fem's
    degree-8 rule and SciPy's Gauss–Legendre and Gauss–Jacobi(0, 1) rules exactly: the norms give
    the same bits with or without the libraries.  A failure here means the libraries changed: run
    the script again."""
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
                assert a.shape == b.shape == (n,) and a.tobytes() == b.tobytes(), n


def test_every_rule_the_norms_ask_for_is_tabulated():
    """The conical rules of the conventions (4) and of the P1 norms (8), the true norms' levels and
    the boundary rules: none of them falls back to SciPy in a norm job."""
    from signorini.fem.norms import conventional, true
    from signorini.fem.quadrature_tables import JACOBI01, LEGENDRE

    conical = {4, 8, *true.INTEGRAL_LEVELS, *true.NEAR_LEVELS}
    assert conical <= set(JACOBI01) and conical <= set(LEGENDRE)
    assert {conventional.BOUNDARY_POINTS, *true.BOUNDARY_LEVELS, *true.NEAR_LEVELS} <= set(LEGENDRE)
