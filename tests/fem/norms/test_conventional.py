"""Norms of e = u − u_h (``signorini.fem.norms.conventional``) where the answer is known in closed form, and the
norm-name registry.

``error_field`` only calls ``problem.u(x)`` and ``problem.grad_u(x)``, so small
duck-typed classes stand in for the manufactured problem here.  References are
closed forms or tensor Gauss–Legendre integrals over the square (exact for the
polynomials used), independent of the package.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.polynomial.legendre import leggauss

from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventional import (
    Conventions,
    UnknownNormError,
    boundary_part_norm,
    compute_norms,
    element_points,
    error_field,
    parse_norm,
    triangle_rule,
)
from signorini.fem.norms.conventions import MAX_POINTS, QUADRATURES, W1P_FORMS
from signorini.fem.problem import ProblemBase

PAPER_NORMS = ["L4", "L16", "Linf", "W14", "W116", "W1inf", "H12"]


class Linear(ProblemBase):
    """u(x) = a0 + a1 x₁ + a2 x₂."""

    def __init__(self, a0: float, a1: float, a2: float):
        self.a = (a0, a1, a2)

    def u(self, x):
        return self.a[0] + self.a[1] * x[0] + self.a[2] * x[1]

    def grad_u(self, x):
        return np.stack([np.full(x.shape[1:], self.a[1]), np.full(x.shape[1:], self.a[2])])


class Quadratic(ProblemBase):
    """u(x) = x₁ (1 − x₁): maximum 1/4 on the line x₁ = 1/2."""

    def u(self, x):
        return x[0] * (1.0 - x[0])

    def grad_u(self, x):
        return np.stack([1.0 - 2.0 * x[0], np.zeros(x.shape[1:])])


ZERO = Linear(0.0, 0.0, 0.0)


# --- independent references -------------------------------------------------------


def square_integral(g, n: int = 20) -> float:
    """∫_{(0,1)²} g by an n×n Gauss–Legendre tensor rule (exact to degree 2n − 1 per variable)."""
    t, w = leggauss(n)
    t, w = (t + 1) / 2, w / 2
    X, Y = np.meshgrid(t, t, indexing="ij")
    return float(np.sum(np.outer(w, w) * g(np.array([X, Y]))))


def boundary_integral(g, n: int = 20) -> float:
    """∮_{∂Ω} g(x, tangent) ds, edge by edge (counter-clockwise)."""
    t, w = leggauss(n)
    t, w = (t + 1) / 2, w / 2
    total = 0.0
    for start, end in [((0, 0), (1, 0)), ((1, 0), (1, 1)), ((1, 1), (0, 1)), ((0, 1), (0, 0))]:
        a, b = np.array(start, float), np.array(end, float)
        x = a[:, None] + (b - a)[:, None] * t[None, :]
        total += float(np.sum(w * g(x, b - a)))
    return total


def norm(f, name: str) -> float:
    """The norm ``name`` of the error field ``f`` under its conventions."""
    return parse_norm(name)(f)


def linf(f) -> float:
    """``max |e|`` over the field's ``L^∞`` point set."""
    return norm(f, "Linf")


def field(problem, N=8, u_h=None, diagonal="sw_ne", **conventions):
    mesh = friedrichs_keller(N, diagonal)
    uh = np.zeros(mesh.p.shape[1]) if u_h is None else u_h(mesh.p)
    return error_field(problem, mesh, uh, Conventions(**conventions))


# ---------------------------------------------------------------------------------
# closed forms: e = x₁ (u = x₁, u_h = 0)
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("quadrature", QUADRATURES)
@pytest.mark.parametrize("p", [1, 2, 3, 4, 7])
def test_lp_norm_of_x1_is_exact(p, quadrature):
    """‖x₁‖_{L^p} = (1/(p+1))^{1/p}; |x₁|^p has degree ≤ 7, within every rule's degree."""
    f = field(Linear(0, 1, 0), quadrature=quadrature)
    assert f.dx.sum() == pytest.approx(1.0, rel=1e-14)
    assert norm(f, f"L{p}") == pytest.approx((1.0 / (p + 1)) ** (1.0 / p), rel=1e-13)
    assert compute_norms(f, [f"L{p}"])[f"L{p}"] == norm(f, f"L{p}")


@pytest.mark.parametrize("p", [2.5, 16])
def test_lp_norm_of_x1_beyond_the_rule_degree_is_accurate(p):
    f = field(Linear(0, 1, 0), N=16)
    assert norm(f, f"L{p}") == pytest.approx((1.0 / (p + 1)) ** (1.0 / p), rel=1e-7)


@pytest.mark.parametrize("form", W1P_FORMS)
@pytest.mark.parametrize("p", [1, 2, 4])
def test_w1p_norm_of_x1(p, form):
    f = field(Linear(0, 1, 0), w1p_form=form)
    lp = 1.0 / (p + 1)
    expected = {"components": (lp + 1 + 0) ** (1 / p), "gradient": (lp + 1) ** (1 / p), "seminorm": 1.0}[form]
    assert norm(f, f"W1{p}") == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("w1inf_points", MAX_POINTS)
@pytest.mark.parametrize("linf_points", MAX_POINTS)
@pytest.mark.parametrize("form", W1P_FORMS)
def test_maxima_of_x1(form, linf_points, w1inf_points):
    f = field(Linear(0, 1, 0), w1p_form=form, linf_points=linf_points, w1inf_points=w1inf_points)
    # |∇x₁| = 1 and |x₁| ≤ 1: W^{1,∞} = 1 in every form and on every point set
    assert norm(f, "W1inf") == pytest.approx(1.0, rel=1e-14)
    if linf_points == "quadrature":  # interior points of the triangles at x₁ = 1
        assert 1.0 - 1.0 / 8 < linf(f) < 1.0
    else:  # vertices and edge midpoints on x₁ = 1
        assert linf(f) == pytest.approx(1.0, rel=1e-14)


def test_h1_and_boundary_norms_of_x1():
    f = field(Linear(0, 1, 0))
    assert norm(f, "H1") == pytest.approx(math.sqrt(1 / 3 + 1), rel=1e-13)
    # ∮ x₁² = 1/3 (bottom) + 1 (right) + 1/3 (top) + 0 (left); ∮ (∂_t x₁)² = 1 + 0 + 1 + 0
    l2, semi = math.sqrt(5 / 3), math.sqrt(2.0)
    assert boundary_part_norm(f, "e") == pytest.approx(l2, rel=1e-13)
    assert boundary_part_norm(f, "dt") == pytest.approx(semi, rel=1e-13)
    assert parse_norm("L2boundary")(f) == pytest.approx(l2, rel=1e-13)
    assert norm(f, "H12") == pytest.approx(math.sqrt(l2 * math.sqrt(l2**2 + semi**2)), rel=1e-13)
    g = field(Linear(0, 1, 0), h12_form="geometric_semi")
    assert norm(g, "H12") == pytest.approx(math.sqrt(l2 * semi), rel=1e-13)


# ---------------------------------------------------------------------------------
# a gradient that distinguishes the W^{1,p} forms: e = 2x₁ − x₂ + 0.3
# ---------------------------------------------------------------------------------

TILTED = Linear(0.3, 2.0, -1.0)


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
@pytest.mark.parametrize("form", W1P_FORMS)
def test_w1p_forms_against_tensor_gauss_integrals(form, diagonal):
    f = field(TILTED, N=6, diagonal=diagonal, w1p_form=form)
    p = 4
    int_e = square_integral(lambda x: TILTED.u(x) ** 4)
    grad_part = {"components": 2.0**4 + 1.0**4, "gradient": 5.0**2, "seminorm": 5.0**2}[form]
    expected = ((0.0 if form == "seminorm" else int_e) + grad_part) ** (1 / p)
    assert norm(f, f"W1{p}") == pytest.approx(expected, rel=1e-13)
    assert norm(f, "L4") == pytest.approx(int_e**0.25, rel=1e-13)
    assert norm(f, "H1") == pytest.approx(math.sqrt(square_integral(lambda x: TILTED.u(x) ** 2) + 5.0), rel=1e-13)


@pytest.mark.parametrize("form", W1P_FORMS)
def test_w1inf_forms(form):
    f = field(TILTED, N=6, w1p_form=form, w1inf_points="vertices")
    # max |e| = 2.3 at (1, 0); |∂₁e| = 2, |∂₂e| = 1, |∇e| = √5 ≈ 2.236
    expected = {"components": 2.3, "gradient": 2.3, "seminorm": math.sqrt(5.0)}[form]
    assert norm(f, "W1inf") == pytest.approx(expected, rel=1e-14)
    g = field(Linear(0.0, 2.0, -1.0), N=6, w1p_form=form, w1inf_points="vertices")  # max |e| = 2
    expected = {"components": 2.0, "gradient": math.sqrt(5.0), "seminorm": math.sqrt(5.0)}[form]
    assert norm(g, "W1inf") == pytest.approx(expected, rel=1e-14)


def test_boundary_norms_against_edge_gauss_integrals():
    f = field(TILTED, N=6)
    l2 = math.sqrt(boundary_integral(lambda x, d: TILTED.u(x) ** 2))
    semi = math.sqrt(boundary_integral(lambda x, d: np.full(x.shape[1], (2.0 * d[0] - d[1]) ** 2)))
    assert boundary_part_norm(f, "e") == pytest.approx(l2, rel=1e-13)
    assert boundary_part_norm(f, "dt") == pytest.approx(semi, rel=1e-13)


def test_norms_on_a_jittered_mesh_are_still_exact():
    mesh = friedrichs_keller(6, jitter=0.3, seed=1)
    f = error_field(TILTED, mesh, np.zeros(mesh.p.shape[1]))
    assert f.dx.sum() == pytest.approx(1.0, rel=1e-13)
    assert norm(f, "L4") == pytest.approx(square_integral(lambda x: TILTED.u(x) ** 4) ** 0.25, rel=1e-13)
    l2 = math.sqrt(boundary_integral(lambda x, d: TILTED.u(x) ** 2))
    assert boundary_part_norm(f, "e") == pytest.approx(l2, rel=1e-13)


# ---------------------------------------------------------------------------------
# the point sets of the maxima
# ---------------------------------------------------------------------------------


def test_linf_point_sets_see_what_they_should():
    """e = x₁(1 − x₁) on N = 7: the maximum 1/4 sits at x₁ = 1/2, which is no vertex
    but an edge midpoint ((3.5)/7); vertices only reach x₁ = 3/7."""
    vertices = linf(field(Quadratic(), N=7, linf_points="vertices"))
    midpoints = linf(field(Quadratic(), N=7, linf_points="midpoints"))
    everything = linf(field(Quadratic(), N=7, linf_points="all"))
    quadrature = linf(field(Quadratic(), N=7, linf_points="quadrature"))
    assert vertices == pytest.approx(3 / 7 * 4 / 7, rel=1e-14)
    assert midpoints == pytest.approx(0.25, rel=1e-14)
    assert everything == pytest.approx(0.25, rel=1e-14)
    assert vertices < quadrature < 0.25


# ---------------------------------------------------------------------------------
# one-sided parts, the sign of e, and u_h ≠ 0
# ---------------------------------------------------------------------------------


def test_plus_and_minus_parts():
    """e = x₁ − 1/4 on N = 8 (the kink lies on a mesh line, so the rule stays exact)."""
    f = field(Linear(-0.25, 1.0, 0.0), N=8)
    plus, minus = (0.75**5 / 5) ** 0.25, (0.25**5 / 5) ** 0.25
    norms = compute_norms(f, ["L4plus", "L4minus", "L4", "Linfplus", "Linfminus", "Linf"])
    assert norms["L4plus"] == pytest.approx(plus, rel=1e-13)
    assert norms["L4minus"] == pytest.approx(minus, rel=1e-13)
    assert norms["L4"] ** 4 == pytest.approx(plus**4 + minus**4, rel=1e-13)
    assert norms["Linfplus"] == pytest.approx(0.75, rel=1e-14)
    assert norms["Linfminus"] == pytest.approx(0.25, rel=1e-14)
    assert norms["Linf"] == pytest.approx(0.75, rel=1e-14)


def test_error_is_u_minus_uh():
    """u = 0, u_h = x₂: e = −x₂, so all of e lies in the negative part."""
    f = field(ZERO, N=5, u_h=lambda p: p[1])
    norms = compute_norms(f, ["L4", "L4plus", "L4minus", "Linf", "W1inf", "H1"])
    assert norms["L4plus"] == 0.0
    assert norms["L4minus"] == pytest.approx(0.2**0.25, rel=1e-13)
    assert norms["L4"] == pytest.approx(0.2**0.25, rel=1e-13)
    assert norms["Linf"] == pytest.approx(1.0, rel=1e-14)
    assert norms["W1inf"] == pytest.approx(1.0, rel=1e-14)
    assert norms["H1"] == pytest.approx(math.sqrt(1 / 3 + 1), rel=1e-13)
    np.testing.assert_allclose(f.de[1], -1.0, rtol=1e-13)
    np.testing.assert_allclose(f.de[0], 0.0, atol=1e-13)


@pytest.mark.parametrize("quadrature", QUADRATURES)
@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_interpolant_of_a_linear_function_has_zero_error(diagonal, quadrature):
    f = field(TILTED, N=7, u_h=TILTED.u, diagonal=diagonal, quadrature=quadrature)
    norms = compute_norms(f, PAPER_NORMS + ["L2", "H1", "L4plus", "L4minus", "L2boundary"])
    assert max(norms.values()) < 1e-13, norms


def test_manufactured_solution_interpolation_error_decreases():
    """u_h = nodal interpolant of the real u: every norm of the error shrinks under refinement."""
    from signorini.fem.problem import Problem

    problem = Problem()
    coarse = field(problem, N=10, u_h=lambda p: problem.u(p))
    fine = field(problem, N=20, u_h=lambda p: problem.u(p))
    nc, nf = compute_norms(coarse, PAPER_NORMS), compute_norms(fine, PAPER_NORMS)
    for name in PAPER_NORMS:
        assert 0.0 < nf[name] < nc[name], name


# ---------------------------------------------------------------------------------
# the registry of norm names
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name",
    [
        "L0.5",
        "foo",
        "W1infplus",
        "W14plus",
        "W14minus",
        "L",
        "W1",
        "",
        "l4",
        "Lp",
        "L-2",
        "H1/2",
        "W2,4",
        "L4 ",
        "Linfinity",
        "L4plusminus",
        "W1,4",
        "H",
    ],
)
def test_parse_norm_rejects_unknown_names(name):
    with pytest.raises(UnknownNormError):
        parse_norm(name)


def test_unknown_norm_error_is_a_value_error_naming_the_norm():
    assert issubclass(UnknownNormError, ValueError)
    f = field(Linear(0, 1, 0))
    with pytest.raises(UnknownNormError, match="foo"):
        compute_norms(f, ["L4", "foo"])


@pytest.mark.parametrize(
    "name",
    [
        "L1",
        "L2",
        "L2.5",
        "L4",
        "L16",
        "Linf",
        "L4plus",
        "L4minus",
        "Linfplus",
        "W11",
        "W14",
        "W116",
        "W12.5",
        "W1inf",
        "H1",
        "H12",
        "L2boundary",
    ],
)
def test_parse_norm_accepts_known_names(name):
    f = field(TILTED, N=4)
    value = parse_norm(name)(f)
    assert np.isfinite(value) and value >= 0.0


def test_compute_norms_returns_every_requested_name():
    f = field(TILTED, N=4)
    norms = compute_norms(f, PAPER_NORMS)
    assert list(norms) == PAPER_NORMS
    for name in PAPER_NORMS:
        assert norms[name] == parse_norm(name)(f)


# ---------------------------------------------------------------------------------
# lazy evaluation: error_field(..., norms=[...]) computes only what those norms need
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("name", PAPER_NORMS + ["L4plus", "Linfminus", "H1", "L2boundary"])
def test_partial_error_field_gives_the_same_norm(name):
    mesh = friedrichs_keller(9)
    uh = 0.5 * mesh.p[0] ** 2
    full = error_field(TILTED, mesh, uh)
    part = error_field(TILTED, mesh, uh, norms=[name])
    assert compute_norms(part, [name])[name] == compute_norms(full, [name])[name]


def test_partial_error_field_rejects_unknown_names():
    mesh = friedrichs_keller(3)
    with pytest.raises(UnknownNormError):
        error_field(TILTED, mesh, np.zeros(mesh.p.shape[1]), norms=["L4", "W1infplus"])


def test_p1_at_points_matches_scikit_fem_interpolation():
    """The written-out affine P1 evaluation agrees with scikit-fem's CellBasis."""
    from skfem import CellBasis, ElementTriP1

    from signorini.fem.mesh import friedrichs_keller
    from signorini.fem.norms.conventional import p1_at_points
    from signorini.fem.quadrature import dunavant8

    for diagonal in ("sw_ne", "nw_se"):
        mesh = friedrichs_keller(7, diagonal, jitter=0.2)
        u_h = np.sin(3 * mesh.p[0]) * np.cos(2 * mesh.p[1])
        X, W = dunavant8()
        basis = CellBasis(mesh, ElementTriP1(), quadrature=(X, W))
        field = basis.interpolate(u_h)
        x, value, grad, det = p1_at_points(mesh.p, mesh.t, u_h, X)
        np.testing.assert_allclose(x, np.asarray(basis.global_coordinates()), atol=1e-14)
        np.testing.assert_allclose(value, np.asarray(field), atol=1e-13)
        np.testing.assert_allclose(np.broadcast_to(grad, field.grad.shape), field.grad, atol=1e-12)
        np.testing.assert_allclose(det[:, None] * W[None, :], basis.dx, atol=1e-15)


@pytest.mark.parametrize("chunk", [1, 7, 50, 10**6])
def test_chunked_evaluation_equals_whole_field(chunk):
    """evaluate_norms over chunks of triangles gives the single-pass values."""
    from signorini.fem.discrete import build
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem

    class Everywhere(Problem):  # the same problem without its support: u evaluated at every point
        def support(self) -> None:
            return None
    from signorini.fem.solve import solve_discrete

    problem = Problem()
    disc = build(problem, 9)
    u_h = solve_discrete(disc).u
    names = ["L4", "L16", "Linf", "W14", "W1inf", "H1", "H12", "L4plus", "Linfminus"]
    whole = compute_norms(error_field(problem, disc.mesh, u_h), names)
    chunked = evaluate_norms(problem, disc.mesh, u_h, names, chunk=chunk)
    for name in names:
        assert chunked[name] == pytest.approx(whole[name], rel=1e-12), name


def test_scaled_power_sums_equal_the_plain_formula_in_range():
    """Scaling by a power of two changes no bit where the plain formula neither overflows nor
    underflows (a non-integer p: pow); an integer p's repeated squaring differs from pow by a few
    roundings, far below the printed digits of the paper's tables."""
    from signorini.fem.norms.conventional import integer_power, scaled_p_sum

    rng = np.random.default_rng(7)
    for p in (2.0, 3.0, 4.0, 16.0, 32.0, 2.5):
        x, y, w = rng.uniform(-3, 3, 500), rng.uniform(-3, 3, 500), rng.uniform(0, 1e-3, 500)
        plain = float(np.sum((np.abs(x) ** p + np.abs(y) ** p) * w) ** (1 / p))
        if p.is_integer():
            assert scaled_p_sum([x, y], p, w) == pytest.approx(plain, rel=4e-16 * p)
        else:
            assert scaled_p_sum([x, y], p, w) == plain
    assert scaled_p_sum([np.zeros(3)], 4.0) == 0.0
    base = rng.uniform(0, 2, 1000)
    for q in (1, 2, 3, 5, 6, 8, 13, 32):
        np.testing.assert_allclose(integer_power(base, q), base**q, rtol=2e-16 * q, atol=0)
    np.testing.assert_array_equal(integer_power(base, 0.5), np.sqrt(base))


@pytest.mark.parametrize("amplitude", [1e-200, 1e-12, 1e12, 1e300])
def test_every_norm_scales_with_the_amplitude(amplitude):
    """u, u_h and every norm of u - u_h are linear in A: no power |e|^p may overflow (A = 10^300,
    or p = 32 at A = 10^12) or underflow to a silent zero (p = 32 at A = 10^-12)."""
    from signorini.fem.discrete import build
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem

    class Everywhere(Problem):  # the same problem without its support: u evaluated at every point
        def support(self) -> None:
            return None
    from signorini.fem.solve import solve_discrete

    names = ["L2", "L4", "L16", "L32", "Linf", "W14", "W116", "W1inf", "H1", "H12", "L4plus", "L4minus"]
    values = {}
    for A in (1.0, amplitude):
        disc = build(Problem(x0=0.5, R=0.45, A=A, c=1.0), 21, "sw_ne")
        values[A] = evaluate_norms(disc.problem, disc.mesh, solve_discrete(disc).u, names, chunk=200)
    for name in names:
        assert values[amplitude][name] / amplitude == pytest.approx(values[1.0][name], rel=1e-12), name


def test_shared_powers_give_each_norm_its_own_value_bit_for_bit():
    """The Lp and W1p norms of one field reduce shared squarings (``PowerCache``): each value is
    ``scaled_p_sum`` of its arrays alone, in any order of the norms, and only one group of arrays
    is held at a time."""
    from signorini.fem.discrete import build
    from signorini.fem.norms.conventional import error_field, field_p_sum, scaled_p_sum
    from signorini.fem.problem import Problem
    from signorini.fem.solve import solve_discrete

    disc = build(Problem(x0=0.47, c=2.0), 21, "sw_ne")
    u_h = solve_discrete(disc).u
    names = {"e": None, "e+": None, "d1": None, "d2": None, "grad": None}
    groups = [("e",), ("e", "d1", "d2"), ("e+",), ("e", "grad"), ("e",)]
    for order in (groups, groups[::-1]):
        f = error_field(disc.problem, disc.mesh, u_h)
        for group in order:
            for p in (2.0, 32.0, 3.0, 2.5, 16.0, 6.0):
                arrays = [f.part(name) for name in group]
                assert field_p_sum(f, group, p) == scaled_p_sum(arrays, p, f.dx), (group, p)
            held = {key[1] for key in f.powers.store}
            assert held <= set(group) and set(names) >= held


def test_the_norms_of_many_chunks_hold_one_chunks_arrays_at_a_time():
    """The memory of ``evaluate_norms`` is that of one chunk, however many chunks a mesh has: the
    arrays of a chunk (its error field, the shared powers) are gone before the next one's, without
    the cycle collector (which large arrays and few objects seldom wake)."""
    import gc
    import tracemalloc

    from signorini.fem.discrete import build
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem

    class Everywhere(Problem):  # the same problem without its support: u evaluated at every point
        def support(self) -> None:
            return None
    from signorini.fem.solve import solve_discrete

    peaks = {}
    for N in (13, 61):  # 338 and 7442 triangles: 2 and 30 chunks of 256
        disc = build(Problem(), N, "sw_ne")
        u_h = solve_discrete(disc).u
        gc.collect()
        gc.disable()
        tracemalloc.start()
        try:
            evaluate_norms(disc.problem, disc.mesh, u_h, ["W14", "L4", "L16", "W116"], chunk=256)
            peaks[N] = tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()
            gc.enable()
    assert peaks[61] < 2.0 * peaks[13], peaks


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
def test_the_triangle_rule_is_placed_at_the_vertex_its_name_says(diagonal):
    """``dunavant8`` keeps the triangles; a Stroud rule's triangles start at the right-angle vertex
    (``stroud4_right``) or the next one counter-clockwise (``stroud4_acute1``, ``stroud4_acute2``),
    each triangle's own vertices in counter-clockwise order; the weights sum to the reference area."""
    mesh = friedrichs_keller(4, diagonal)
    X, W, t = triangle_rule(mesh.p, mesh.t, "dunavant8")
    assert t is mesh.t and X.shape == (2, W.size) and W.sum() == pytest.approx(0.5, rel=1e-14)
    for role, quadrature in enumerate(["stroud4_right", "stroud4_acute1", "stroud4_acute2"]):
        X, W, t = triangle_rule(mesh.p, mesh.t, quadrature)
        assert W.sum() == pytest.approx(0.5, rel=1e-14)
        assert np.array_equal(np.sort(t, axis=0), np.sort(mesh.t, axis=0))  # the same triangles
        v = mesh.p[:, t]  # (2, 3, E)
        e1, e2 = v[:, 1] - v[:, 0], v[:, 2] - v[:, 0]
        assert np.all(e1[0] * e2[1] - e1[1] * e2[0] > 0)  # counter-clockwise
        right = np.roll(v, role, axis=1)  # back to the right-angle vertex first
        a, b = right[:, 1] - right[:, 0], right[:, 2] - right[:, 0]
        np.testing.assert_allclose(np.sum(a * b, axis=0), 0.0, atol=1e-15)


def test_the_point_sets_of_the_maxima():
    assert element_points("vertices").shape == (2, 3) and element_points("midpoints").shape == (2, 3)
    both = np.hstack([element_points("vertices"), element_points("midpoints")])
    np.testing.assert_array_equal(element_points("all"), both)


@pytest.mark.parametrize("diagonal", ["sw_ne", "nw_se"])
@pytest.mark.parametrize("jitter", [0.0, 0.3])
def test_leaving_out_the_triangles_outside_the_support_changes_no_bit(diagonal, jitter, rng):
    """``u`` evaluated only on the triangles that meet its support gives every norm the bits of the
    evaluation everywhere: on the paper's problem, an unseen one (off-centre, small support) and
    ``u ≡ 0`` (an algebraic error's norms), under the paper's conventions and others, with a
    ``u_h`` that is not ``0`` outside the support."""
    from signorini.fem.norms.conventional import evaluate_norms
    from signorini.fem.problem import Problem

    class Everywhere(Problem):  # the same problem without its support: u evaluated at every point
        def support(self) -> None:
            return None

    mesh = friedrichs_keller(27, diagonal, jitter=jitter, seed=3)
    names = ["L2", "L3", "L4", "L16", "Linf", "W12", "W14", "W116", "W1inf", "H1", "H12", "L4plus", "L4minus"]
    convs = [Conventions(), Conventions(quadrature="stroud4_acute1", linf_points="all", w1p_form="gradient")]
    for problem in (Problem(), Problem(x0=0.37, R=0.21, A=3.0, c=2.0), Problem().vanishing()):
        u_h = Problem().u(mesh.p) + 1e-3 * rng.standard_normal(mesh.p.shape[1])
        assert problem.support() is not None
        for conv in convs:
            got = evaluate_norms(problem, mesh, u_h, names, conv, chunk=300)
            expected = evaluate_norms(Everywhere(**problem.as_dict()), mesh, u_h, names, conv, chunk=300)
            assert {k: float(v).hex() for k, v in got.items()} == {k: float(v).hex() for k, v in expected.items()}
