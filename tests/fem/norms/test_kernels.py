"""The compiled kernels of the norms against the numpy code they replace: the true norms' survey
bit for bit, their rules over triangles to round-off and whole true norms to round-off with the same
refinement; a P1 function's norms under the conventions to round-off (its maxima to the bit), for
every rule placement, point set, norm family and form, on the paper's, graded, Delaunay and
clockwise meshes; and where each is taken."""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.mesh_families import delaunay, graded
from signorini.fem.norms import conventional, kernels, true
from signorini.fem.norms.conventions import Conventions
from signorini.fem.norms.families import PARTS, define
from signorini.fem.problem import Problem, compiled_points


def _assert_round_off_apart(a: true.TrueNorm, b: true.TrueNorm) -> None:
    """Two evaluations of a true norm that differ only in the order of a rule's sums: the same
    levels (what each evaluated at which rule), values and error estimates apart by round-off."""
    assert a.converged == b.converged and len(a.levels) == len(b.levels)
    for la, lb in zip(a.levels, b.levels, strict=True):
        assert {k: v for k, v in la.items() if k not in ("value", "error_estimate")} == {
            k: v for k, v in lb.items() if k not in ("value", "error_estimate")
        }
        assert la["value"] == pytest.approx(lb["value"], rel=1e-13)
        if lb["error_estimate"] is not None:
            assert la["error_estimate"] == pytest.approx(lb["error_estimate"], rel=1e-6, abs=1e-13 * lb["value"])


def _meshes():
    """The paper's mesh, a graded and a Delaunay mesh (vertices off the grid, varied triangles)."""
    return [friedrichs_keller(40), graded(24), delaunay(20, seed=3)]


def _u_h(mesh, P: Problem) -> np.ndarray:
    """A P1 function near u: its interpolant, perturbed smoothly (e of both signs)."""
    return P.u(mesh.p) + 1e-3 * np.sin(5.0 * mesh.p[0] + 3.0 * mesh.p[1])


def test_the_part_codes_of_the_rule_kernel_follow_the_parts():
    codes = [kernels.PART_E, kernels.PART_E_PLUS, kernels.PART_E_MINUS]
    codes += [kernels.PART_D1, kernels.PART_D2, kernels.PART_GRAD]
    assert [PARTS[c] for c in codes] == ["e", "e+", "e-", "d1", "d2", "grad"]


@pytest.mark.parametrize("params", [{}, {"x0": 0.43, "R": 0.31, "A": 2.5}])
@pytest.mark.parametrize("gradient", [False, True])
def test_the_survey_kernel_gives_the_numpy_survey_bit_for_bit(params, gradient):
    P = Problem(**params)
    for mesh in _meshes():
        u_h = _u_h(mesh, P)
        numpy_survey = true._survey(P, mesh, u_h, gradient)
        with compiled_points():
            compiled = true._compiled_survey(P, mesh, u_h, gradient)
            compiled_survey = true._survey(P, mesh, u_h, gradient)
        assert compiled is not None
        assert compiled_survey[0] == numpy_survey[0]
        for a, b in zip(compiled_survey[1:], numpy_survey[1:], strict=True):
            assert np.array_equal(a, b)
        assert numpy_survey[1].any() and numpy_survey[2].any() and not numpy_survey[2].all()  # every branch
        start = mesh.t.shape[1] // 3
        v = mesh.p[:, mesh.t[:, start:]]
        _, r_lo, r_hi, diameter = compiled(start, v.shape[2])
        assert np.array_equal(r_lo, true._radii(P, v)[0]) and np.array_equal(r_hi, true._radii(P, v)[1])
        assert np.array_equal(diameter, true._diameters(v))


@pytest.mark.parametrize("name", ["L4", "L3", "L2.5", "L16", "L4plus", "L3minus", "W14", "W13", "H1"])
@pytest.mark.parametrize("form", ["components", "gradient"])
def test_the_rule_kernel_agrees_with_the_numpy_rule_to_round_off(name, form):
    from signorini.fem.norms.conventions import Conventions

    norm = define(name, Conventions(w1p_form=form))
    integrand, gradient = true._integrand(norm)
    scale = 2.0**-9
    for params in ({}, {"x0": 0.43, "R": 0.31, "A": 2.5}):
        P = Problem(**params)
        for mesh in _meshes():
            u_h = _u_h(mesh, P)
            elements = np.arange(0, mesh.t.shape[1], 3)
            aff = true._Affine.of(mesh, u_h, elements)
            with compiled_points():
                rule = true._CompiledRule.of(P, mesh, u_h, norm, scale)
            for n in (3, 5, 10):
                expected = true._rule_integrals(
                    P, aff, lambda e, de: integrand(e / scale, None if de is None else de / scale), gradient, n, aff.v
                )
                got = rule.integrals(elements, n)
                assert np.all(np.abs(got - expected) <= 1e-13 * np.abs(expected))
                assert np.count_nonzero(expected) > elements.size // 4


def test_there_is_no_compiled_rule_outside_the_block_or_for_u_vanishing():
    mesh, P = friedrichs_keller(8), Problem()
    norm = define("L4")
    assert true._CompiledRule.of(P, mesh, P.u(mesh.p), norm, 1.0) is None
    with compiled_points():
        assert true._CompiledRule.of(P.vanishing(), mesh, P.u(mesh.p), norm, 1.0) is None
        assert true._compiled_survey(P.vanishing(), mesh, P.u(mesh.p), False) is None


@pytest.mark.parametrize("name", ["L4", "L16", "W14", "W116", "L4plus"])
def test_true_norms_by_the_kernels_agree_with_numpy_to_round_off(name):
    for params in ({}, {"x0": 0.43, "R": 0.31, "A": 2.5}):
        P = Problem(**params)
        for mesh in _meshes()[:2]:
            u_h = _u_h(mesh, P)
            expected = true.true_norm(P, mesh, u_h, name)
            with compiled_points():
                got = true.true_norm(P, mesh, u_h, name)
            _assert_round_off_apart(got, expected)


def _clockwise(mesh):
    """The mesh with every triangle's vertices in the other orientation."""
    return type(mesh)(mesh.p, mesh.t[[0, 2, 1]])


@pytest.mark.parametrize("role", [0, 1, 2, -1])
def test_the_rule_placement_is_rolled_t_s(role):
    for mesh in [*_meshes(), _clockwise(friedrichs_keller(6, "nw_se"))]:
        p, t = np.ascontiguousarray(mesh.p), np.ascontiguousarray(mesh.t)
        placed = np.array([kernels._rolled(p[0], p[1], t, el, role) for el in range(t.shape[1])]).T
        assert np.array_equal(placed, t if role < 0 else conventional._rolled_t(p, t, role))


NAMES = ["L4", "L3", "L2.5", "L16", "L4plus", "L3minus", "W14", "W13", "W116", "H1"]


@pytest.mark.parametrize("quadrature", ["stroud4_right", "stroud4_acute1", "stroud4_acute2", "dunavant8"])
@pytest.mark.parametrize("form", ["components", "gradient", "seminorm"])
def test_a_p1_function_s_norm_by_the_kernels_agrees_with_numpy_to_round_off(quadrature, form):
    conv = Conventions(quadrature=quadrature, w1p_form=form)
    zero = Problem().vanishing()
    for mesh in [*_meshes(), _clockwise(friedrichs_keller(12))]:
        v = 1e-15 * np.sin(7.0 * mesh.p[0] - 4.0 * mesh.p[1]) + 3e-16 * np.cos(11.0 * mesh.p[1])
        norms = {name: define(name, conv) for name in NAMES}
        for name, norm in norms.items():
            with compiled_points():
                got = conventional._p1_norms(zero, mesh, v, conv, {name: norm})
            expected = conventional.evaluate_norms(zero, mesh, v, [name], conv)
            assert got[name] == pytest.approx(expected[name], rel=1e-13)


def test_the_p1_kernels_take_one_norm_of_a_vanishing_u_on_large_meshes_only():
    mesh, conv = friedrichs_keller(8), Conventions()
    P, v = Problem(), np.linspace(0.0, 1e-12, friedrichs_keller(8).p.shape[1])
    one = {"L4": define("L4", conv)}
    assert conventional._p1_norms(P.vanishing(), mesh, v, conv, one) == {}  # outside compiled_points
    with compiled_points():
        assert conventional._p1_norms(P.vanishing(), mesh, v, conv, one).keys() == {"L4"}
        assert conventional._p1_norms(P, mesh, v, conv, one) == {}  # u ≢ 0
        assert conventional._p1_norms(P.vanishing(), mesh, v, conv, {"Linf": define("Linf", conv)}).keys() == {"Linf"}
        two = one | {"W14": define("W14", conv)}  # several share numpy's error field
        assert conventional._p1_norms(P.vanishing(), mesh, v, conv, two) == {}
        inside = (
            conventional.evaluate_norms(P.vanishing(), mesh, v, ["L4"], conv),
            conventional.evaluate_norms(P.vanishing(), mesh, v, ["L4", "W14"], conv),
        )
    with compiled_points():
        assert inside[0] == conventional._p1_norms(P.vanishing(), mesh, v, conv, one)  # the kernels' value
    assert inside[1] == conventional.evaluate_norms(P.vanishing(), mesh, v, ["L4", "W14"], conv)  # numpy's bits


@pytest.mark.parametrize("points", ["vertices", "midpoints", "quadrature", "all"])
@pytest.mark.parametrize("quadrature", ["stroud4_right", "stroud4_acute2", "dunavant8"])
def test_a_p1_function_s_maxima_by_the_kernels_are_numpys(points, quadrature):
    zero = Problem().vanishing()
    for form in ("components", "gradient", "seminorm"):
        conv = Conventions(quadrature=quadrature, linf_points=points, w1inf_points=points, w1p_form=form)
        for mesh in [*_meshes(), _clockwise(friedrichs_keller(12))]:
            v = 1e-15 * np.sin(7.0 * mesh.p[0] - 4.0 * mesh.p[1]) + 3e-16 * np.cos(11.0 * mesh.p[1])
            for name in ("Linf", "Linfplus", "Linfminus", "W1inf"):
                with compiled_points():
                    got = conventional._p1_norms(zero, mesh, v, conv, {name: define(name, conv)})
                expected = conventional.evaluate_norms(zero, mesh, v, [name], conv)
                assert got[name] == pytest.approx(expected[name], rel=1e-15)
