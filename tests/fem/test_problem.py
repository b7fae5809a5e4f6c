"""The manufactured solution of Section 7: ψ, u, ∇u, f and the Signorini conditions; the problems
with closed-form solutions and ``make_problem``.

Reference values are computed independently of ``signorini.fem.problem``: ψ from the
ten Hermite conditions (a 10×10 solve), u and ∇u from the paper's polar formula
``10 ψ(r) (−r^{3/2} sin(3θ/2))`` with ``θ = arccos((x₁ − x0)/r)``, and ``−Δu + c u``
from finite differences of the implemented ``u``.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from helpers import ROOT
from helpers import same_bits as _same_bits
from numpy.polynomial import Polynomial

from signorini.fem.problem import (
    DEFAULT_KIND,
    PROBLEM_KINDS,
    ConstantProblem,
    ExactProblem,
    FullContactProblem,
    Problem,
    ProblemBase,
    ProblemParameterError,
    make_problem,
)

PROBLEMS = [Problem(), Problem(x0=0.47, c=3.0), Problem(x0=0.4, R=0.3, A=2.0, c=0.0), Problem(x0=0.62, R=0.35)]
PROBLEM_IDS = ["default", "x0=0.47,c=3", "x0=0.4,R=0.3,A=2,c=0", "x0=0.62,R=0.35"]


# ---------------------------------------------------------------------------------
# independent references
# ---------------------------------------------------------------------------------


def hermite_cutoff() -> Polynomial:
    """The unique degree-9 p on [0, 1] with p(0) = 1, p^{(k)}(0) = 0 (k = 1..4), p^{(k)}(1) = 0 (k = 0..4)."""
    rows, rhs = [], []
    for point in (0.0, 1.0):
        for k in range(5):
            row = [math.perm(j, k) * point ** (j - k) if j >= k else 0.0 for j in range(10)]
            rows.append(row)
            rhs.append(1.0 if (point == 0.0 and k == 0) else 0.0)
    return Polynomial(np.linalg.solve(np.array(rows), np.array(rhs)))


def polar_u(problem: Problem, x: np.ndarray) -> np.ndarray:
    """The paper's formula (25): A ψ(r) (−r^{3/2} sin(3θ/2)), θ = arccos((x₁ − x0)/r), on x₂ ≥ 0."""
    p = hermite_cutoff()
    dx, dy = x[0] - problem.x0, x[1]
    r = np.hypot(dx, dy)
    theta = np.arccos(np.clip(np.divide(dx, r, out=np.ones_like(r), where=r > 0), -1.0, 1.0))
    psi = np.where(r < problem.R, p(np.minimum(r / problem.R, 1.0)), 0.0)
    return problem.A * psi * (-(r**1.5) * np.sin(1.5 * theta))


def polar_grad_u(problem: Problem, x: np.ndarray) -> np.ndarray:
    """∇u = A [(ψ' ũ + ψ ∂_r ũ) e_r + ψ (∂_θ ũ / r) e_θ] with the Hermite ψ (r > 0)."""
    p = hermite_cutoff()
    dp = p.deriv()
    dx, dy = x[0] - problem.x0, x[1]
    r = np.hypot(dx, dy)
    theta = np.arccos(np.clip(dx / r, -1.0, 1.0))
    s = np.minimum(r / problem.R, 1.0)
    inside = r < problem.R
    psi = np.where(inside, p(s), 0.0)
    dpsi = np.where(inside, dp(s) / problem.R, 0.0)
    ut = -(r**1.5) * np.sin(1.5 * theta)
    dr_ut = -1.5 * r**0.5 * np.sin(1.5 * theta)
    dth_ut_over_r = -1.5 * r**0.5 * np.cos(1.5 * theta)
    radial = dpsi * ut + psi * dr_ut
    angular = psi * dth_ut_over_r
    e_r = np.array([np.cos(theta), np.sin(theta)])
    e_t = np.array([-np.sin(theta), np.cos(theta)])
    return problem.A * (radial * e_r + angular * e_t)


def random_points(rng, n, problem: Problem, r_min=0.0, x2_min=0.0) -> np.ndarray:
    """Points of the unit square with x₂ ≥ x2_min and distance ≥ r_min from the free point."""
    pts = rng.uniform(0.0, 1.0, size=(2, 4 * n))
    pts[1] = x2_min + (1.0 - x2_min) * pts[1]
    keep = np.hypot(pts[0] - problem.x0, pts[1]) >= r_min
    pts = pts[:, keep][:, :n]
    assert pts.shape[1] == n
    return pts


# ---------------------------------------------------------------------------------
# ψ
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_psi_is_the_unique_degree9_hermite_cutoff(problem):
    r = np.linspace(0.0, problem.R, 401)
    np.testing.assert_allclose(problem.psi(r), hermite_cutoff()(r / problem.R), rtol=0, atol=1e-11)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_psi_meets_its_ten_conditions_by_polynomial_fit(problem):
    """Fit a degree-9 polynomial in s = r/R to the implemented ψ; it must be exact and
    satisfy ψ(0) = 1, ψ^{(k)}(0) = 0 (k = 1..4), ψ^{(k)}(R) = 0 (k = 0..4)."""
    s = 0.5 - 0.5 * np.cos(np.linspace(0.0, np.pi, 60))  # Chebyshev–Lobatto points on [0, 1]
    values = problem.psi(problem.R * s)
    fit = Polynomial.fit(s, values, deg=9, domain=[0.0, 1.0])
    assert np.abs(fit(s) - values).max() < 1e-13, "ψ is not a polynomial of degree ≤ 9 in r/R"
    grid = np.linspace(0.0, 1.0, 1001)
    assert fit(0.0) == pytest.approx(1.0, abs=1e-13)
    assert abs(fit(1.0)) < 1e-13
    for k in range(1, 5):
        dk = fit.deriv(k)
        scale = np.abs(dk(grid)).max()  # ψ^{(k)} is O(1)–O(10³) in s; compare relative to its size
        assert abs(dk(0.0)) < 1e-9 * scale, f"ψ^({k})(0) = {dk(0.0)}"
        assert abs(dk(1.0)) < 1e-9 * scale, f"ψ^({k})(R) = {dk(1.0)}"
    # C⁴ but not C⁵ at R (else it would be ≡ 0): the fifth derivative does not vanish there
    assert abs(fit.deriv(5)(1.0)) > 1.0


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_psi_derivatives_match_finite_differences(problem):
    R = problem.R
    r = np.linspace(0.01 * R, 0.99 * R, 97)
    h = 1e-6 * R
    fd1 = (problem.psi(r + h) - problem.psi(r - h)) / (2 * h)
    fd2 = (problem.dpsi(r + h) - problem.dpsi(r - h)) / (2 * h)
    np.testing.assert_allclose(problem.dpsi(r), fd1, rtol=0, atol=1e-7 / R)
    np.testing.assert_allclose(problem.d2psi(r), fd2, rtol=0, atol=1e-6 / R**2)
    np.testing.assert_allclose(problem.dpsi_over_r(r), problem.dpsi(r) / r, rtol=1e-13, atol=0)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_psi_derivatives_match_the_hermite_polynomial(problem):
    p = hermite_cutoff()
    s = np.linspace(0.0, 1.0, 201)
    r = problem.R * s
    scale1, scale2 = 1.0 / problem.R, 1.0 / problem.R**2
    np.testing.assert_allclose(problem.dpsi(r), p.deriv(1)(s) * scale1, rtol=0, atol=1e-11 * scale1)
    np.testing.assert_allclose(problem.d2psi(r), p.deriv(2)(s) * scale2, rtol=0, atol=1e-10 * scale2)
    # ψ'/r stays finite at r = 0 (ψ' = O(r⁴))
    assert problem.dpsi_over_r(np.array([0.0]))[0] == 0.0


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_psi_vanishes_identically_beyond_R(problem):
    r = problem.R * np.array([1.0, 1.0 + 1e-12, 1.01, 1.5, 2.0, 10.0, 1e6])
    for fn in (problem.psi, problem.dpsi, problem.dpsi_over_r, problem.d2psi):
        assert np.all(fn(r) == 0.0), fn.__name__


# ---------------------------------------------------------------------------------
# u, ∇u, f
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_u_matches_the_polar_formula(problem, rng):
    pts = random_points(rng, 2000, problem)
    # add the bottom edge (both sides of the free point), the free point and points beyond R
    edge = np.vstack([np.linspace(0.0, 1.0, 501), np.zeros(501)])
    pts = np.hstack([pts, edge, [[problem.x0], [0.0]]])
    np.testing.assert_allclose(problem.u(pts), polar_u(problem, pts), rtol=0, atol=1e-13 * problem.A)


def test_u_paper_default_has_amplitude_ten_and_the_paper_geometry():
    problem = Problem()
    assert (problem.x0, problem.R, problem.A, problem.c) == (0.5, 0.45, 10.0, 1.0)
    # at θ = π (left of the free point on the bottom edge) u = 10 ψ(r) r^{3/2}
    r = 0.1
    expected = 10.0 * hermite_cutoff()(r / 0.45) * r**1.5
    assert problem.u(np.array([[0.5 - r], [0.0]]))[0] == pytest.approx(expected, rel=1e-13)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_polar_coordinates(problem, rng):
    pts = random_points(rng, 500, problem, r_min=1e-3)
    r, theta = problem.polar(pts)
    np.testing.assert_allclose(r, np.hypot(pts[0] - problem.x0, pts[1]), rtol=1e-14)
    np.testing.assert_allclose(theta, np.arccos((pts[0] - problem.x0) / r), rtol=0, atol=1e-12)
    assert np.all((theta >= 0) & (theta <= np.pi))


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_grad_u_matches_the_polar_formula(problem, rng):
    pts = random_points(rng, 2000, problem, r_min=1e-3)
    edge = np.vstack([np.linspace(0.0, 1.0, 500), np.zeros(500)])  # 500 points: none hits x0 exactly
    pts = np.hstack([pts, edge[:, np.hypot(edge[0] - problem.x0, 0.0) > 1e-3]])
    np.testing.assert_allclose(problem.grad_u(pts), polar_grad_u(problem, pts), rtol=0, atol=1e-12 * problem.A)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_grad_u_matches_finite_differences(problem, rng):
    pts = random_points(rng, 1000, problem, r_min=0.02, x2_min=0.01)
    h = 1e-6
    e1, e2 = np.array([[h], [0.0]]), np.array([[0.0], [h]])
    fd = np.array(
        [
            (problem.u(pts + e1) - problem.u(pts - e1)) / (2 * h),
            (problem.u(pts + e2) - problem.u(pts - e2)) / (2 * h),
        ]
    )
    np.testing.assert_allclose(problem.grad_u(pts), fd, rtol=0, atol=1e-7 * problem.A)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_normal_derivative_on_bottom_edge_matches_one_sided_differences(problem):
    x1 = np.linspace(0.0, 1.0, 400)
    x1 = x1[np.abs(x1 - problem.x0) > 0.02]
    pts = np.vstack([x1, np.zeros_like(x1)])
    h = 1e-5
    u = [problem.u(np.vstack([x1, np.full_like(x1, k * h)])) for k in range(3)]
    d2_fd = (-3 * u[0] + 4 * u[1] - u[2]) / (2 * h)  # one-sided, second order, inside Ω
    np.testing.assert_allclose(problem.grad_u(pts)[1], d2_fd, rtol=0, atol=1e-6 * problem.A)


def minus_laplacian_fd(problem: Problem, pts: np.ndarray, h: float) -> np.ndarray:
    """Five-point −Δu with step h."""
    e1, e2 = np.array([[h], [0.0]]), np.array([[0.0], [h]])
    u = problem.u
    return (4 * u(pts) - u(pts + e1) - u(pts - e1) - u(pts + e2) - u(pts - e2)) / h**2


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_f_matches_finite_difference_operator(problem, rng):
    """f = −Δu + c u against a Richardson-extrapolated five-point Laplacian at random
    interior points at least 0.05 from the free point (the stencil stays in x₂ > 0)."""
    pts = random_points(rng, 1000, problem, r_min=0.05, x2_min=0.01)
    h = 2e-3
    lap = (4.0 * minus_laplacian_fd(problem, pts, h / 2) - minus_laplacian_fd(problem, pts, h)) / 3.0
    fd_f = lap + problem.c * problem.u(pts)
    scale = max(np.abs(problem.f(pts)).max(), 1.0)
    np.testing.assert_allclose(problem.f(pts), fd_f, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(problem.minus_laplace_u(pts), lap, rtol=0, atol=1e-6 * scale)
    np.testing.assert_allclose(problem.f(pts), problem.minus_laplace_u(pts) + problem.c * problem.u(pts), atol=1e-12)


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_f_is_bounded_and_continuous_at_the_free_point(problem):
    """−Δu = −A ũ (4ψ'/r + ψ''), with ψ' = O(r⁴): f → 0 at the free point, no singularity."""
    r = np.logspace(-12, -1, 60)
    for theta in (0.0, 0.3, np.pi / 2, 2.9, np.pi):
        pts = np.vstack([problem.x0 + r * np.cos(theta), r * np.sin(theta)])
        vals = problem.minus_laplace_u(pts)
        assert np.all(np.isfinite(vals)) and np.all(np.isfinite(problem.f(pts)))
        assert np.all(np.abs(vals) <= 6000.0 * abs(problem.A) * r**4.5 / problem.R**5)
    assert problem.f(np.array([[problem.x0], [0.0]]))[0] == 0.0


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
def test_u_vanishes_outside_the_support(problem, rng):
    pts = rng.uniform(0, 1, size=(2, 5000))
    outside = np.hypot(pts[0] - problem.x0, pts[1]) >= problem.R
    assert outside.any()
    assert np.all(problem.u(pts[:, outside]) == 0.0)
    assert np.all(problem.grad_u(pts[:, outside]) == 0.0)
    assert np.all(problem.f(pts[:, outside]) == 0.0)


def test_evaluation_keeps_the_shape_of_the_point_array(rng):
    problem = Problem()
    pts = rng.uniform(0, 1, size=(2, 7, 16))  # e.g. (2, triangles, quadrature points)
    assert problem.u(pts).shape == (7, 16)
    assert problem.f(pts).shape == (7, 16)
    assert problem.minus_laplace_u(pts).shape == (7, 16)
    assert problem.grad_u(pts).shape == (2, 7, 16)
    flat = problem.u(pts.reshape(2, -1)).reshape(7, 16)
    np.testing.assert_array_equal(problem.u(pts), flat)


# ---------------------------------------------------------------------------------
# the Signorini conditions (26) on every edge
# ---------------------------------------------------------------------------------

EDGES = {
    # name: (points as a function of t ∈ [0, 1], outward normal)
    "bottom": (lambda t: np.vstack([t, np.zeros_like(t)]), np.array([0.0, -1.0])),
    "right": (lambda t: np.vstack([np.ones_like(t), t]), np.array([1.0, 0.0])),
    "top": (lambda t: np.vstack([t, np.ones_like(t)]), np.array([0.0, 1.0])),
    "left": (lambda t: np.vstack([np.zeros_like(t), t]), np.array([-1.0, 0.0])),
}


@pytest.mark.parametrize("problem", PROBLEMS, ids=PROBLEM_IDS)
@pytest.mark.parametrize("edge", sorted(EDGES))
def test_u_meets_the_signorini_conditions_on_every_edge(problem, edge):
    param, normal = EDGES[edge]
    t = np.linspace(0.0, 1.0, 2001)
    t = t[np.abs(t - problem.x0) > 1e-9] if edge == "bottom" else t  # ∇u is singular only at the free point
    pts = param(t)
    u = problem.u(pts)
    dn = np.einsum("i,i...->...", normal, problem.grad_u(pts))
    scale = problem.A
    assert np.all(u >= 0.0), "u ≥ 0 on ∂Ω"
    assert np.all(dn >= -1e-13 * scale), "∂n u ≥ 0 on ∂Ω"
    assert np.all(np.abs(u * dn) <= 1e-13 * scale**2), "u ∂n u = 0 on ∂Ω"

    if edge == "bottom":
        # (x0 − R, x0) × {0}, away from the rounded end point x0 − R where ψ = 0
        lifted = (t > problem.x0 - problem.R + 1e-12) & (t < problem.x0)
    else:
        lifted = np.zeros_like(t, dtype=bool)
    # on (x0 − R, x0) × {0}: u > 0 and ∂n u = 0
    assert np.all(u[lifted] > 0.0)
    assert np.all(np.abs(dn[lifted]) <= 1e-13 * scale)
    # elsewhere on ∂Ω: u = 0 (exactly: ũ vanishes at θ = 0 without round-off).  At the end
    # point x0 − R itself (up to the rounding of x0 − R), ψ = 1 − S(r/R) is evaluated with
    # cancellation and leaves a round-off residue of ~1e-16 instead of 0.
    end = (edge == "bottom") & (np.abs(t - (problem.x0 - problem.R)) < 1e-9)
    assert np.all(u[~lifted & ~end] == 0.0)
    assert np.all(u[end] <= 1e-13 * scale)
    if edge == "bottom":
        contact = (t > problem.x0) & (t < problem.x0 + problem.R)
        assert contact.any() and np.all(dn[contact] > 0.0), "strict contact force on (x0, x0 + R)"


def test_paper_contact_geometry():
    """With the paper's parameters the lifted part is (0.05, 0.5) × {0}, as stated in (26)."""
    problem = Problem()
    x1 = np.array([0.049, 0.051, 0.3, 0.499, 0.501, 0.9])
    u = problem.u(np.vstack([x1, np.zeros_like(x1)]))
    assert u[0] == 0.0 and u[1] > 0.0 and u[2] > 0.0 and u[3] > 0.0
    assert u[4] == 0.0 and u[5] == 0.0


# ---------------------------------------------------------------------------------
# parameter validation
# ---------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "params",
    [
        dict(x0=0.3),  # default R = 0.45: the support leaves through the left edge
        dict(x0=0.6),  # ... through the right edge
        dict(x0=0.5, R=0.5),  # touches both corners
        dict(x0=0.5, R=1.2),
        dict(x0=0.0),
        dict(x0=1.0),
        dict(x0=-0.1),
        dict(x0=1.3),
        dict(R=0.0),
        dict(R=-0.1),
        dict(c=-1.0),
        dict(x0=float("nan")),
        dict(R=float("nan")),
        dict(A=float("nan")),
        dict(c=float("nan")),
        dict(A=float("inf")),
        dict(c=float("-inf")),
        dict(x0="0.5"),
    ],
    ids=lambda p: ",".join(f"{k}={v}" for k, v in p.items()),
)
def test_invalid_parameters_raise(params):
    with pytest.raises(ProblemParameterError):
        Problem(**params)


def test_problem_parameter_error_is_a_value_error():
    assert issubclass(ProblemParameterError, ValueError)


@pytest.mark.parametrize("params", [dict(x0=0.3, R=0.29), dict(x0=0.8, R=0.19), dict(A=2.0), dict(c=0.0)])
def test_valid_parameters_are_accepted(params):
    problem = Problem(**params)
    assert problem.as_dict() == {**dataclasses.asdict(Problem()), **{k: float(v) for k, v in params.items()}}


def test_problem_is_immutable():
    with pytest.raises(dataclasses.FrozenInstanceError):
        Problem().x0 = 0.4  # type: ignore[misc]


def test_closed_form_problems_satisfy_their_pde():
    """-Δu + c u = f by finite differences, u ≥ 0 / ∂_ν u ≥ 0 on the boundary."""
    x = np.random.default_rng(0).uniform(0.1, 0.9, size=(2, 50))
    d = 1e-4
    for p in (FullContactProblem(2.0, 3.0), ConstantProblem(2.0, 4.0), ConstantProblem(0.0, 0.0)):
        lap = sum((p.u(x + d * e[:, None]) - 2 * p.u(x) + p.u(x - d * e[:, None])) / d**2 for e in np.eye(2))
        np.testing.assert_allclose(-lap + p.c * p.u(x), p.f(x), atol=1e-5 * (1 + np.abs(p.f(x)).max()))
        g = p.grad_u(x)
        fd = np.stack([(p.u(x + d * e[:, None]) - p.u(x - d * e[:, None])) / (2 * d) for e in np.eye(2)])
        np.testing.assert_allclose(g, fd, atol=1e-6)
    s = np.linspace(0, 1, 11)
    fc = FullContactProblem(1.0, 1.0)
    bottom = np.stack([s, 0 * s])
    assert np.all(np.abs(fc.u(bottom)) < 1e-15) and np.all(-fc.grad_u(bottom)[1] >= 0)  # ∂_ν = -∂_y


def test_problem_factory_and_validation():
    assert make_problem({"x0": 0.5, "R": 0.45, "A": 10, "c": 1}) == Problem()
    assert make_problem({"kind": "constant", "value": 2.0, "c": 4.0}).exact == 0.5
    assert make_problem({"kind": "full_contact"}).as_dict() == {"kind": "full_contact", "A": 1.0, "c": 1.0}
    bad = [
        {"kind": "constant", "value": -1.0},  # Dirichlet solution: no closed form (and u ≡ 0 is wrong)
        {"kind": "constant", "value": 1.0, "c": 0.0},
        {"kind": "constant", "value": float("nan")},
        {"kind": "full_contact", "A": -1.0},
        {"kind": "nosuch"},
        {"kind": "constant", "wrong": 1.0},
    ]
    for params in bad:
        with pytest.raises(ProblemParameterError):
            make_problem(params)


def test_the_factory_builds_a_scene_problem_as_the_scenes_always_did():
    """Without ``kind`` the paper's problem, numbers as floats (``Problem.from_params``); the
    recorded ``as_dict`` of each kind builds the same problem again."""
    params = {"x0": 0.5, "R": 0.45, "A": 10, "c": 1}
    problem = make_problem(params)
    assert DEFAULT_KIND == "manufactured" and problem == Problem.from_params(params) and problem.as_dict() == {
        "x0": 0.5, "R": 0.45, "A": 10.0, "c": 1.0
    }
    assert all(type(v) is float for v in problem.as_dict().values())
    for p in (Problem(x0=0.4, R=0.3), ConstantProblem(2.0, 4.0), FullContactProblem(3.0, 0.5)):
        assert make_problem(p.as_dict()) == p
    with pytest.raises(ProblemParameterError, match="unknown parameter 'value'") as info:
        make_problem({"x0": 0.5, "value": 1.0})
    assert info.value.parameter == "value"
    with pytest.raises(ProblemParameterError, match="unknown problem kind 'nosuch'") as info:
        make_problem({"kind": "nosuch"})
    assert info.value.parameter == "kind"


def test_the_schema_lists_the_problem_kinds():
    import yaml

    schema = yaml.safe_load((ROOT / "workflow/schemas/config.schema.yaml").read_text(encoding="utf-8"))
    assert schema["$defs"]["problem_kind"]["enum"] == list(PROBLEM_KINDS)


@pytest.mark.parametrize("kind", sorted(PROBLEM_KINDS))
def test_every_kind_has_the_members_of_the_protocol(kind):
    members = {name for name in dir(ExactProblem) if not name.startswith("_")} | set(ExactProblem.__annotations__)
    problem = PROBLEM_KINDS[kind]()
    assert all(hasattr(problem, name) for name in members), kind
    assert problem.kind == kind and issubclass(PROBLEM_KINDS[kind], ProblemBase)


def test_the_base_states_no_capability_and_the_manufactured_problem_its_own(rng):
    x = rng.uniform(0.0, 1.0, (2, 7))
    constant, manufactured = ConstantProblem(2.0, 4.0), Problem()
    assert constant.singular_points().shape == constant.boundary_breaks().shape == (2, 0)
    assert constant.derivative_bounds() is None
    assert manufactured.singular_points().shape == (2, 1) and manufactured.boundary_breaks().shape == (2, 2)
    u, grad = constant.u_and_grad_u(x)
    assert np.array_equal(u, constant.u(x)) and np.array_equal(grad, constant.grad_u(x))


def test_the_vanishing_problem_keeps_the_points_and_has_u_zero(rng):
    x = rng.uniform(0.0, 1.0, (2, 5))
    assert Problem().vanishing() == Problem(A=0.0)
    zero = FullContactProblem(2.0, 3.0).vanishing()
    assert zero.c == 3.0 and not zero.u(x).any() and not zero.grad_u(x).any() and not zero.f(x).any()
    assert zero.singular_points().shape == (2, 0)
    assert not zero.derivative_bounds().hessian_bound(np.array([0.0]), np.array([0.1])).any()


def test_outside_its_support_the_problem_is_exactly_positive_zero():
    """``support``: at every point with r ≥ R, u, ∇u and f are +0.0 (what lets the load vector leave
    out the triangles outside the disc without changing a bit).  r as the problem computes it,
    ``√(dx² + dy²)``; ``hypot`` may differ from it in the last bit, which the margin of
    ``triangles_meeting_disc`` covers."""
    problem = Problem(x0=0.47, R=0.3, A=7.0, c=2.0)
    centre, radius = problem.support()
    rng = np.random.default_rng(5)
    angle = np.linspace(0, np.pi, 50)
    ring = centre[:, None] + radius * np.array([np.cos(angle), np.sin(angle)])  # on the circle, up to round-off
    for points in (rng.uniform(0.0, 1.0, (2, 20000)), ring):
        dx, dy = points[0] - centre[0], points[1] - centre[1]
        points = points[:, np.sqrt(dx * dx + dy * dy) >= radius]
        for values in (problem.f(points), problem.u(points), problem.grad_u(points)):
            assert np.all(values == 0.0) and not np.signbit(values).any()
    assert ProblemBase.support(problem) is None  # the default: anywhere
    x = rng.uniform(0.0, 1.0, (2, 2000))
    for zero in (problem.vanishing(), FullContactProblem(2.0, 3.0).vanishing()):
        assert zero.support()[1] == 0.0  # the empty disc: +0.0 everywhere
        for values in (zero.f(x), zero.u(x), zero.grad_u(x), *zero.u_and_grad_u(x)):
            assert np.all(values == 0.0) and not np.signbit(values).any()


def test_u_grad_u_and_f_do_not_depend_on_the_points_evaluated_with_them():
    """Where most points are inside the support ``u`` is evaluated at every point, where few are only
    inside (a compress), where all are without a mask: each point's values are the same bits in
    every case."""
    problem = Problem(x0=0.47, R=0.3, A=7.0, c=2.0)
    rng = np.random.default_rng(11)
    angle, radius = rng.uniform(0.0, np.pi, 4000), 0.3 * np.sqrt(rng.uniform(0.0, 1.6, 4000))
    x = np.array([0.47 + radius * np.cos(angle), radius * np.sin(angle)])  # about 60 % inside
    inside = np.hypot(x[0] - 0.47, x[1]) < 0.3
    subsets = [np.arange(4000), np.flatnonzero(inside), np.r_[np.flatnonzero(~inside), np.flatnonzero(inside)[:50]]]
    subsets += [np.array([k]) for k in range(0, 4000, 397)]
    whole = (problem.u(x), problem.grad_u(x), problem.f(x), *problem.u_and_grad_u(x))
    for subset in subsets:
        part = (problem.u(x[:, subset]), problem.grad_u(x[:, subset]), problem.f(x[:, subset]),
                *problem.u_and_grad_u(x[:, subset]))
        for a, b in zip(whole, part, strict=True):
            assert _same_bits(np.ascontiguousarray(a[..., subset]), b)
    x3 = x[:, :3960].reshape(2, 60, 66)  # a (2, elements, q) array: the shape the norms pass
    assert _same_bits(problem.u(x3).ravel(), whole[0][:3960])


def test_one_point_of_shape_two_gives_scalars_equal_to_the_same_point_in_an_array():
    """``x`` of shape (2,), inside the support, outside it and on the contact part: ``u`` and ``f``
    of shape (), ``∇u`` of shape (2,), the bits of the point evaluated in a (2, 1) array."""
    problem = Problem(x0=0.47, R=0.3, A=7.0, c=2.0)
    for point in ([0.5, 0.1], [0.9, 0.9], [0.6, 0.0]):
        x = np.array(point)
        u, grad = problem.u_and_grad_u(x)
        assert u.shape == problem.f(x).shape == () and grad.shape == problem.grad_u(x).shape == (2,)
        u1, grad1 = problem.u_and_grad_u(x[:, None])
        assert _same_bits(u.reshape(1), u1) and _same_bits(grad.reshape(2, 1), grad1)
        assert _same_bits(problem.f(x).reshape(1), problem.f(x[:, None]))
