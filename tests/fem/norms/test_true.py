"""The split boundary rule and the ``_true`` norms against closed forms with a singularity.

References are independent of the package: integrals over the unit square of ``r^a g(θ)``
around the singular point ``P = (x0, 0)`` reduce to ``∫_0^π g(θ) ρ(θ)^{a+2}/(a+2) dθ``
(``ρ(θ)`` the distance from ``P`` to ∂Ω in direction θ), evaluated by ``scipy.integrate.quad``
between the corner angles; maxima on ∂Ω by bounded scalar maximisation along the edges.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.optimize import minimize_scalar

from signorini.fem.boundary import boundary_rule, singular_points
from signorini.fem.derivatives import ManufacturedBounds, derivative_bounds, u_and_grad_u
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms.conventional import Conventions, boundary_error, evaluate_norms, parse_norm
from signorini.fem.norms.families import define
from signorini.fem.norms.names import UnknownNormError, parse_norm_name, true_name
from signorini.fem.norms.true import RTOL, true_norm
from signorini.fem.problem import Problem, ProblemBase
from signorini.published import label_md

X0 = 0.5 + 0.3 / 7  # inside a bottom boundary edge of the N = 7 mesh, not at its midpoint


class Kink(ProblemBase):
    """u = max(a − x₁, 0)^{3/2}: ``∂_t u`` has a square-root kink at x₁ = a on the bottom and top edges."""

    def __init__(self, a: float, declared: bool = True):
        self.a, self.declared = a, declared

    def u(self, x):
        return np.maximum(self.a - x[0], 0.0) ** 1.5

    def grad_u(self, x):
        return np.stack([-1.5 * np.maximum(self.a - x[0], 0.0) ** 0.5, np.zeros(np.shape(x[1]))])

    def singular_points(self):
        return np.array([[self.a, self.a], [0.0, 1.0]]) if self.declared else np.zeros((2, 0))

    def closed_form(self) -> tuple[float, float]:
        """‖u − 1‖²_{L²(∂Ω)} and |u − 1|²_{H¹(∂Ω)} (u_h ≡ 1)."""
        a = self.a
        along = a**4 / 4.0 - 0.8 * a**2.5 + 1.0  # ∫_0^1 (u − 1)² on the bottom (and the top) edge
        l2 = 2.0 * along + (a**1.5 - 1.0) ** 2 + 1.0  # + left edge (u = a^{3/2}) + right edge (u = 0)
        return l2, 2.25 * a**2  # ∫ (3/2)² (a − x₁) on the bottom and top edges


class Harmonic(ProblemBase):
    """ũ = −Im z^{3/2}, z = (x₁ − x0) + i x₂: u ~ r^{3/2}, ∇u ~ r^{1/2} at P = (x0, 0); no cut-off."""

    def __init__(self, x0: float = X0):
        self.x0 = x0

    def _roots(self, x):
        dx, dy = x[0] - self.x0, np.abs(x[1])
        r = np.hypot(dx, dy)
        return np.sqrt(np.maximum(r + dx, 0.0) / 2.0), np.sqrt(np.maximum(r - dx, 0.0) / 2.0)

    def u(self, x):
        re, im = self._roots(x)
        return -im * (3.0 * re * re - im * im)

    def grad_u(self, x):
        re, im = self._roots(x)
        return -1.5 * np.stack([im, re])

    def singular_points(self):
        return np.array([[self.x0], [0.0]])


def polar_integral(terms, x0: float = X0) -> float:
    """∫ over the unit square of Σ c r^a g(θ) around (x0, 0), for ``terms`` = [(a, g(θ))]."""

    def rho(th):
        out = 1.0 / math.sin(th) if math.sin(th) > 0 else math.inf
        c = math.cos(th)
        return min(out, (1.0 - x0) / c if c > 0 else (-x0 / c if c < 0 else math.inf))

    def integrand(th):
        return sum(g(th) * rho(th) ** (a + 2.0) / (a + 2.0) for a, g in terms)

    corners = sorted([math.atan2(1.0, 1.0 - x0), math.atan2(1.0, -x0)])
    knots = [0.0, *corners, math.pi]
    pieces = zip(knots[:-1], knots[1:], strict=True)
    return sum(quad(integrand, lo, hi, epsabs=0, epsrel=1e-13, limit=200)[0] for lo, hi in pieces)


def s3(th):  # sin(3θ/2): ũ = −r^{3/2} sin(3θ/2)
    return math.sin(1.5 * th)


# --- the boundary rule -------------------------------------------------------------------------


def test_split_boundary_rule_is_exact_across_a_kink_where_whole_edges_fail():
    N = 7
    mesh = friedrichs_keller(N)
    ones = np.ones(mesh.p.shape[1])
    for a in (X0, 0.5 + 0.5 / N):  # inside an edge; at a mesh node
        l2_ref, semi_ref = Kink(a).closed_form()
        eb, dt, ds = boundary_error(Kink(a), mesh, ones, 8)
        assert ds.sum() == pytest.approx(4.0, rel=1e-14)
        assert np.sum(eb**2 * ds) == pytest.approx(l2_ref, rel=1e-12)
        assert np.sum(dt**2 * ds) == pytest.approx(semi_ref, rel=1e-12)
    # the same 8 points on whole edges (no split): visibly wrong where the kink is inside an edge
    eb, dt, ds = boundary_error(Kink(X0, declared=False), mesh, ones, 8)
    assert abs(np.sum(dt**2 * ds) / Kink(X0).closed_form()[1] - 1.0) > 1e-6  # 7e-6: one kinked edge of 28


def test_boundary_rule_splits_the_manufactured_edge_at_the_free_point_and_the_cut_off():
    problem = Problem(x0=0.37, R=0.3)
    rule = boundary_rule(friedrichs_keller(20), problem, 4)
    x = rule.points(friedrichs_keller(20).p)
    pieces = rule.edge.size
    assert pieces == 4 * 20 + 3  # one edge split at x0, two at x0 ± R
    # the pieces meet at the break points: no Gauss point sits on them, and the weights add up
    assert np.min(np.abs(x[0][x[1] == 0.0][:, None] - np.array([0.07, 0.37, 0.67]))) > 0
    assert rule.ds.sum() == pytest.approx(4.0, rel=1e-14)


def test_manufactured_h12_converged_by_the_split_rule_unlike_whole_edges(cache):
    problem, N = Problem(), 21
    mesh, u_h = cache.discrete({}, N).mesh, cache.solution({}, N).u
    values = {}
    for n, split in ((8, True), (32, True), (8, False)):
        eb, dt, ds = boundary_error(problem, mesh, u_h, n, split)
        values[(n, split)] = np.sum(dt**2 * ds)
    assert values[(8, True)] == pytest.approx(values[(32, True)], rel=1e-9)
    assert abs(values[(8, False)] / values[(32, True)] - 1.0) > 1e-3  # the kink under-integrated


# --- the grammar --------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "name", ["L4", "L2.5", "Linf", "L4plus", "Linfminus", "W14", "W1inf", "H1", "H12", "L2boundary"]
)
def test_every_norm_has_a_true_variant(name):
    spec, base = parse_norm_name(true_name(name)), parse_norm_name(name)
    assert spec.true and not base.true and spec.base == name
    assert (spec.family, spec.p, spec.part) == (base.family, base.p, base.part)
    assert label_md(true_name(name)) == label_md(name) + " (true)"
    assert not spec.is_lp_family  # no second point of a rate-against-p curve


@pytest.mark.parametrize("name", ["L4_true_true", "true", "_true", "W14plus_true", "L4_TRUE", "H12true"])
def test_malformed_true_names_are_rejected(name):
    with pytest.raises(UnknownNormError):
        parse_norm_name(name)


def test_a_true_name_is_refused_under_the_conventions():
    with pytest.raises(UnknownNormError, match="fem.norms.true"):
        parse_norm("L4_true")
    mesh = friedrichs_keller(7)
    with pytest.raises(UnknownNormError, match="evaluate_named_norms"):
        evaluate_norms(Harmonic(), mesh, np.zeros(mesh.p.shape[1]), ["L4", "L4_true"])


def test_norms_evaluated_together_are_bit_identical_to_each_alone():
    """The per-mesh norm job's saving: one error field per chunk and rule for all the norms under
    the conventions, each value the one the norm alone gives (chunks of 50 triangles: several)."""
    from signorini.fem.solve import solve_discrete

    disc = build(Problem(), 24)
    u_h = solve_discrete(disc).u
    names = ["L2", "L4", "L16", "Linf", "W14", "W116", "W1inf", "H1", "H12", "L2boundary", "L4plus", "L4minus"]
    for conv in (Conventions(), Conventions(quadrature="dunavant8", linf_points="vertices", w1p_form="gradient")):
        together = evaluate_norms(Problem(), disc.mesh, u_h, names, conv, chunk=50)
        for name in names:
            alone = evaluate_norms(Problem(), disc.mesh, u_h, [name], conv, chunk=50)[name]
            assert np.float64(together[name]).tobytes() == np.float64(alone).tobytes(), name


# --- integrals with the r^{3/2} singularity ---------------------------------------------------


def _reference(name: str) -> float:
    """The norm of ũ (u_h = 0) by polar integrals, form ``components``."""
    c, s = (lambda th: math.cos(th / 2)), (lambda th: math.sin(th / 2))
    terms = {
        "L2": ([(3.0, lambda th: s3(th) ** 2)], 2),
        "L4": ([(6.0, lambda th: s3(th) ** 4)], 4),
        "H1": ([(3.0, lambda th: s3(th) ** 2), (1.0, lambda th: 2.25)], 2),
        "W14": ([(6.0, lambda th: s3(th) ** 4), (2.0, lambda th: 1.5**4 * (s(th) ** 4 + c(th) ** 4))], 4),
        "W116": ([(24.0, lambda th: s3(th) ** 16), (8.0, lambda th: 1.5**16 * (s(th) ** 16 + c(th) ** 16))], 16),
    }[name]
    return polar_integral(terms[0]) ** (1.0 / terms[1])


@pytest.mark.parametrize("name", ["L2", "L4", "H1", "W14", "W116"])
def test_true_integral_norms_of_the_singular_function(name):
    mesh = friedrichs_keller(7)
    result = true_norm(Harmonic(), mesh, np.zeros(mesh.p.shape[1]), name + "_true")
    assert result.converged and result.error_estimate <= RTOL * result.value
    assert result.value == pytest.approx(_reference(name), rel=RTOL)


def test_true_l2_norm_with_a_nonzero_p1_part():
    """e = ũ − ℓ with ℓ = c0 + c1 x₁ + c2 x₂ the (exact) P1 interpolant of a linear function:
    ∫ e² = ∫ ũ² − 2 ∫ ũ ℓ + ∫ ℓ², with ℓ = α + r (c1 cos θ + c2 sin θ), α = c0 + c1 x0."""
    c0, c1, c2 = 0.3, -0.8, 0.5
    alpha = c0 + c1 * X0

    def beta(th):
        return c1 * math.cos(th) + c2 * math.sin(th)

    terms = [
        (3.0, lambda th: s3(th) ** 2),
        (1.5, lambda th: 2.0 * alpha * s3(th)),  # −2 ũ ℓ = 2 r^{3/2} sin(3θ/2) ℓ
        (2.5, lambda th: 2.0 * beta(th) * s3(th)),
        (0.0, lambda th: alpha**2),
        (1.0, lambda th: 2.0 * alpha * beta(th)),
        (2.0, lambda th: beta(th) ** 2),
    ]
    mesh = friedrichs_keller(9)
    u_h = c0 + c1 * mesh.p[0] + c2 * mesh.p[1]
    result = true_norm(Harmonic(), mesh, u_h, "L2_true")
    assert result.value == pytest.approx(math.sqrt(polar_integral(terms)), rel=RTOL)


class Scaled(ProblemBase):
    """A·u of another exact solution (linear: every norm of u − A·u_h is A times that of u − u_h)."""

    def __init__(self, base, amplitude: float):
        self.base, self.A = base, amplitude

    def u(self, x):
        return self.A * self.base.u(x)

    def grad_u(self, x):
        return self.A * self.base.grad_u(x)

    def singular_points(self):
        return self.base.singular_points()


@pytest.mark.parametrize("amplitude", [1e-200, 1e300])
def test_true_norms_scale_with_the_amplitude(amplitude):
    """No power |e|^p of a true integral norm overflows (A = 10^300) or underflows to a silent zero
    (A = 10^-200): the integrands are evaluated on e / 2^k, with 2^k near the largest error."""
    mesh = friedrichs_keller(9)
    u_h = 0.3 * mesh.p[0] - 0.1 * mesh.p[1]
    for name in ("L4", "L32", "W116", "H1", "L4plus", "Linf", "W1inf", "H12"):
        one = true_norm(Harmonic(), mesh, u_h, f"{name}_true").value
        scaled = true_norm(Scaled(Harmonic(), amplitude), mesh, amplitude * u_h, f"{name}_true").value
        assert scaled / amplitude == pytest.approx(one, rel=1e-12), name


def test_true_norms_of_the_manufactured_error_and_the_gap_to_the_paper_conventions(cache):
    """At N = 21: the true values are converged; the maxima over Ω are at least the maxima over
    the conventions' point sets; L^16 and W^{1,∞} under the conventions are visibly off."""
    mesh, u_h = cache.discrete({}, 21).mesh, cache.solution({}, 21).u
    names = ["L4", "L16", "Linf", "W14", "W1inf", "H12"]
    paper = evaluate_norms(Problem(), mesh, u_h, names)
    true = {name: true_norm(Problem(), mesh, u_h, name) for name in names}
    assert all(t.converged and t.error_estimate <= RTOL * t.value for t in true.values())
    assert true["Linf"].value >= paper["Linf"] and true["W1inf"].value >= paper["W1inf"]
    assert abs(paper["L16"] / true["L16"].value - 1.0) > 5e-3
    assert true["W1inf"].value / paper["W1inf"] - 1.0 > 3e-2
    assert paper["H12"] == pytest.approx(true["H12"].value, rel=1e-9)  # the split boundary rule


# --- maxima --------------------------------------------------------------------------------------


def _boundary_max(f) -> float:
    """max of f(x₁, x₂) over the top, left and right edges (dense grid, then bounded refinement)."""
    best = 0.0
    for edge in (lambda s: (s, 1.0), lambda s: (0.0, s), lambda s: (1.0, s)):
        s = np.linspace(0.0, 1.0, 4001)
        k = int(np.argmax([f(*edge(v)) for v in s]))
        lo, hi = s[max(k - 1, 0)], s[min(k + 1, s.size - 1)]
        res = minimize_scalar(
            lambda v, edge=edge: -f(*edge(v)), bounds=(lo, hi), method="bounded", options={"xatol": 1e-13}
        )
        best = max(best, -res.fun, f(*edge(s[k])))
    return best


def _pointwise(problem, name: str):
    """(x1, x2) ↦ the function whose maximum the norm ``name`` (Linf, W1inf) of u − 0 is."""

    def f(x1, x2):
        x = np.array([[x1], [x2]])
        g = [np.abs(problem.u(x))] + ([np.abs(problem.grad_u(x)[k]) for k in (0, 1)] if name == "W1inf" else [])
        return float(np.max(g))

    return f


def _true_max_of_u(problem, name: str):
    """The true norm ``name`` of u itself (u_h = 0) on the 7 × 7 mesh."""
    mesh = friedrichs_keller(7)
    return true_norm(problem, mesh, np.zeros(mesh.p.shape[1]), name + "_true")


@pytest.mark.parametrize("name", ["Linf", "W1inf"])
def test_true_maxima_of_the_singular_function(name):
    problem = Harmonic()
    f, result = _pointwise(problem, name), _true_max_of_u(problem, name)
    assert result.value == pytest.approx(_boundary_max(f), rel=1e-9)


class Bump(ProblemBase):
    """u = 1 − |x − c|², maximum 1 at c inside a triangle, |∇u| = 2 |x − c|."""

    c = np.array([0.4137, 0.2719])

    def u(self, x):
        return 1.0 - ((x[0] - self.c[0]) ** 2 + (x[1] - self.c[1]) ** 2)

    def grad_u(self, x):
        return -2.0 * np.stack([x[0] - self.c[0], x[1] - self.c[1]])


def test_true_maxima_find_an_interior_maximum_the_point_sets_miss():
    mesh = friedrichs_keller(5)
    zero = np.zeros(mesh.p.shape[1])
    assert evaluate_norms(Bump(), mesh, zero, ["Linf"])["Linf"] < 1.0 - 1e-5
    assert true_norm(Bump(), mesh, zero, "Linf_true").value == pytest.approx(1.0, rel=1e-10)
    corner = 2.0 * float(np.max(np.hypot(*(np.array([[0, 1, 0, 1], [0, 0, 1, 1]]) - Bump.c[:, None]))))
    gradient = Conventions(w1p_form="seminorm")
    assert true_norm(Bump(), mesh, zero, "W1inf_true", gradient).value == pytest.approx(corner, rel=1e-10)


# --- the pipeline: norm artifacts and the true tables ---------------------------------------------


def test_true_tables_stage_renders_convention_true_and_printed_values(tmp_path):
    """Synthetic norm artifacts (N = 101, 201): every cell, gap and EOC of the tables follows from them."""
    import pandas as pd

    from signorini.pipeline.artifacts import save_json
    from signorini.studies.paper.true_tables import true_tables_stage

    paper = tmp_path / "paper_table1.csv"
    paper.write_text("# published\nh,L4\n1/101,1.0e-3\n1/201,2.6e-4\n")
    Ns, conv, true = [101, 201], {"L4": [1.0e-3, 2.5e-4]}, {"L4_true": [1.01e-3, 2.5e-4]}
    jsons: dict[str, list[str]] = {}
    for name, values in (*conv.items(), *true.items()):
        for N, value in zip(Ns, values, strict=True):
            path = tmp_path / f"{name}_{N}.json"
            accuracy = {"error_estimate": 1e-9, "rtol": 1e-4, "converged": True}
            extra = {"quadrature_error": accuracy} if name.endswith("_true") else {}
            save_json(path, {"N": N, "norm": name, "value": value, **extra})
            jsons.setdefault(name, []).append(str(path))
    outs = {k: tmp_path / f"{k}.{k.split('_')[1]}" for k in ("table1_csv", "table1_md", "table2_csv", "table2_md")}
    true_tables_stage(Ns, jsons, paper, outs)
    t1 = pd.read_csv(outs["table1_csv"])
    assert list(t1["convention"]) == conv["L4"] and list(t1["true"]) == true["L4_true"]
    assert t1["convention_vs_true"].iloc[0] == pytest.approx(1.0e-3 / 1.01e-3 - 1.0)
    assert t1["paper_vs_true"].iloc[1] == pytest.approx(2.6e-4 / 2.5e-4 - 1.0)
    t2 = pd.read_csv(outs["table2_csv"])
    assert list(t2["h"]) == ["1/201", "regr.", "theo."]
    assert float(t2["L4_true"].iloc[0]) == pytest.approx(math.log(1.01e-3 / 2.5e-4) / math.log(201 / 101))
    assert "| L⁴(Ω) | -0.99 % … +0.00 % | -0.99 % … +4.00 % | 4.0e-06 |" in outs["table1_md"].read_text()


# --- the bounds that let the maxima exclude triangles ------------------------------------------


class BoundedHarmonic(Harmonic):
    """ũ with the bounds of its derivatives: ‖D²ũ‖₂ = (3/4) r^{-1/2}, ∇ũ Hölder-1/2 with H = 3/2."""

    def derivative_bounds(self):
        return self

    def hessian_bound(self, r_lo, r_hi):
        with np.errstate(divide="ignore"):
            return 0.75 / np.sqrt(np.asarray(r_lo, dtype=float))

    def gradient_holder_bound(self, r_hi):
        return np.full(np.shape(r_hi), 1.5)


class Understated(ProblemBase):
    """A problem that states ``factor`` times its bounds (too small ones for factor < 1)."""

    def __init__(self, base, factor: float):
        self.base, self.factor = base, factor

    def u(self, x):
        return self.base.u(x)

    def grad_u(self, x):
        return self.base.grad_u(x)

    def singular_points(self):
        return self.base.singular_points()

    def derivative_bounds(self):
        return self

    def hessian_bound(self, r_lo, r_hi):
        return self.factor * derivative_bounds(self.base).hessian_bound(r_lo, r_hi)

    def gradient_holder_bound(self, r_hi):
        return self.factor * derivative_bounds(self.base).gradient_holder_bound(r_hi)


def _hessian_norm(problem, x: np.ndarray, step: np.ndarray) -> np.ndarray:
    """‖D²u‖₂ at the points x (2, K) by central differences of ∇u (steps (K,), symmetrised)."""
    cols, zero = [], np.zeros_like(step)
    for d in (np.stack([step, zero]), np.stack([zero, step])):
        cols.append((problem.grad_u(x + d) - problem.grad_u(x - d)) / (2.0 * step))
    H = np.stack(cols, axis=1)  # H[i, j] = ∂_j ∂_i u
    H = 0.5 * (H + H.transpose(1, 0, 2))
    return np.max(np.abs(np.linalg.eigvalsh(H.transpose(2, 0, 1))), axis=1)


def test_the_manufactured_solution_bounds_its_second_derivatives_tightly_near_the_free_point(rng):
    """``hessian_bound(r, r) ≥ ‖D²u‖₂`` at points of every distance r from the free point (by
    central differences, step ≪ r), within 10 % of it near the free point: a bound understated
    by 10 % fails there."""
    problem = Problem()
    bounds = ManufacturedBounds(problem)
    r = np.concatenate([np.geomspace(1e-5, 0.44, 400), np.linspace(0.44, 0.6, 100)])
    th = rng.uniform(0.0, np.pi, r.size)
    x = np.array([problem.x0 + r * np.cos(th), r * np.sin(th)])
    x[1] = np.maximum(x[1], 1e-3 * r)  # inside Ω, so the differences stay on one side of the bottom edge
    r = np.hypot(x[0] - problem.x0, x[1])
    exact = _hessian_norm(problem, x, 1e-4 * r)
    bound = bounds.hessian_bound(0.999 * r, 1.001 * r)
    assert np.all(exact[bound == 0.0] == 0.0) and (bound == 0.0).sum() > 50  # beyond the cut-off
    ratio = exact[bound > 0.0] / bound[bound > 0.0]
    assert ratio.max() <= 1.0
    assert ratio[r[bound > 0.0] < 1e-3].max() > 0.9
    assert np.all(bounds.hessian_bound(np.array([0.45, 0.7]), np.array([0.5, 0.9])) == 0.0)  # u ≡ 0 beyond R
    assert bounds.hessian_bound(np.array([0.0]), np.array([0.1]))[0] == np.inf


def test_the_manufactured_gradient_is_holder_continuous_with_the_stated_constant(rng):
    """|∇u(x) − ∇u(y)| ≤ H(r_hi) |x − y|^{1/2} on random pairs around the free point, nearly an
    equality for pairs along the bottom edge through it."""
    problem = Problem()
    bounds, worst = ManufacturedBounds(problem), 0.0
    for r_hi in (1e-6, 1e-3, 0.05, 0.3, 0.6):
        rad, th = r_hi * np.sqrt(rng.uniform(0, 1, (2, 4000))), rng.uniform(0.0, np.pi, (2, 4000))
        x = np.array([problem.x0 + rad[0] * np.cos(th[0]), rad[0] * np.sin(th[0])])
        y = np.array([problem.x0 + rad[1] * np.cos(th[1]), rad[1] * np.sin(th[1])])
        y[:, :200] = [[problem.x0] * 200, [0.0] * 200]  # pairs with the free point itself
        x[:, :100] = [problem.x0 - rad[0, :100], np.zeros(100)]  # and along the bottom edge
        quotient = np.hypot(*(problem.grad_u(x) - problem.grad_u(y))) / np.hypot(*(x - y)) ** 0.5
        ratio = quotient / bounds.gradient_holder_bound(r_hi)
        assert ratio.max() <= 1.0
        worst = max(worst, ratio.max())
    assert worst > 0.9


def test_u_and_its_gradient_in_one_evaluation_are_bit_for_bit_the_two(rng):
    problem = Problem(x0=0.37, R=0.3, A=3.0)
    x = rng.uniform(0.0, 1.0, (2, 50, 7))
    value, grad = u_and_grad_u(problem, x)
    assert value.tobytes() == problem.u(x).tobytes() and grad.tobytes() == problem.grad_u(x).tobytes()
    value, grad = u_and_grad_u(Harmonic(), x)  # any other problem: its two methods
    assert np.array_equal(value, Harmonic().u(x)) and np.array_equal(grad, Harmonic().grad_u(x))
    assert derivative_bounds(Harmonic()) is None and derivative_bounds(BoundedHarmonic()) is not None


def _pieces(apex: np.ndarray) -> np.ndarray:
    """Triangles (2, 3, K) of Ω̄ around ``apex``: right-angled (both diagonals) and obtuse, of three
    sizes, with the apex as a vertex, on an edge, near and far; and across the cut-off r = R."""
    out = []
    for h in (1e-3, 1e-2, 5e-2):
        for sx, sy in ((0, 0), (-0.5, 0), (-1, 0), (0.3, 0.2), (2, 0), (-3, 0), (0, 3), (-5, 1), (8, 8)):
            b = apex + h * np.array([sx, sy])
            out += [[b, b + (h, 0), b + (0, h)], [b, b + (h, 0), b + (h, h)], [b, b + (2 * h, 0), b + (h, 0.3 * h)]]
    for r in (0.43, 0.449, 0.46):
        b = apex + (r, 0.0)
        out += [[b, b + (0.02, 0), b + (0, 0.02)], [b - (0.01, 0), b + (0.01, 0.0), b + (0, 0.01)]]
    return np.array(out).transpose(2, 1, 0)


KINDS = {
    "|e|": ("value", lambda e, de: np.abs(e)),
    "|∂₁e|": ("gradient", lambda e, de: np.abs(de[0])),
    "|∂₂e|": ("gradient", lambda e, de: np.abs(de[1])),
    "|∇e|": ("gradient", lambda e, de: np.hypot(de[0], de[1])),
}


def _bound_ratios(problem, apex) -> tuple[dict[str, tuple[np.ndarray, np.ndarray]], bool]:
    """Per function: (sup over each piece − its vertex maximum) / (the increment ``_increments``), the
    sup on a lattice of 80 subdivisions, u_h the linear interpolant of u on each piece (e = 0 at the
    vertices), and which pieces touch the apex; and whether the bound of every piece sampled on
    its lattice (``_piece_bounds``) is above the sup."""
    from skfem import MeshTri

    from signorini.fem.norms import true as tn

    v = _pieces(apex)
    K = v.shape[2]
    mesh = MeshTri(v.transpose(0, 2, 1).reshape(2, -1), np.arange(3 * K).reshape(K, 3).T)
    u_h, every = problem.u(mesh.p), np.arange(K)
    aff = tn._Affine.of(mesh, u_h, every)
    e, de = aff.error(problem, tn._physical(aff, tn._lattice(80)), True)
    ev, dev = aff.error(problem, v.transpose(0, 2, 1), True)  # at the vertices
    increments, touching = tn._increments(problem, v, v), tn._radii(problem, v)[0] == 0
    out, lattice_ok = {}, True
    for name, (kind, f) in KINDS.items():
        sup = f(e, de).max(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            out[name] = (np.nan_to_num((sup - f(ev, dev).max(axis=1)) / increments[kind]), touching)
        lattice_ok &= bool(np.all(sup <= tn._piece_bounds(problem, mesh, u_h, v, every, [f], [kind], True)[1]))
    return out, lattice_ok


@pytest.mark.parametrize("problem", [Problem(), BoundedHarmonic()], ids=["manufactured", "harmonic"])
def test_the_bound_of_each_triangle_bounds_the_function_on_it(problem):
    """On triangles near and far from the singular point, touching it (Hölder bound) or not
    (Hessian bound): no sample of a lattice exceeds the bound, which the value |e| nearly reaches."""
    ratios, lattice_ok = _bound_ratios(problem, singular_points(problem)[:, 0])
    assert lattice_ok
    for name, (ratio, touching) in ratios.items():
        assert ratio.max() <= 1.0, name
        assert touching.sum() >= 9
    assert ratios["|e|"][0].max() > 0.7
    assert ratios["|e|"][0][ratios["|e|"][1]].max() > 0.3  # the Hölder bound where D²u is unbounded


def test_an_understated_bound_is_caught():
    """The same check with bounds stated at half their value fails: on the triangles away from the
    singular point (Hessian) and on those touching it (Hölder)."""
    ratios, _ = _bound_ratios(Understated(Problem(), 0.5), np.array([0.5, 0.0]))
    ratio, touching = ratios["|e|"]
    assert ratio[~touching].max() > 1.0 and ratio[touching].max() > 0.6  # 0.5 · ratio > 0.3 above
    ratios, _ = _bound_ratios(Understated(BoundedHarmonic(), 0.1), np.array([X0, 0.0]))
    assert ratios["|e|"][0][ratios["|e|"][1]].max() > 1.0


def test_the_interpolation_radius_is_the_largest_weighted_distance_to_the_vertices():
    """max over the triangle of Σ λᵢ |x − vᵢ|² is ρ² (acute, right-angled and obtuse triangles)."""
    from signorini.fem.norms import true as tn

    v = np.array([[[0, 1, 0.4], [0, 0, 0.9]], [[0, 1, 0], [0, 0, 1]], [[0, 1, 0.5], [0, 0, 0.1]]], dtype=float)
    v = v.transpose(1, 2, 0)  # (2, 3, 3)
    X = tn._lattice(400)
    lam = np.vstack([1.0 - X[0] - X[1], X[0], X[1]])  # (3, q)
    x = np.einsum("dik,iq->dkq", v, lam)
    weighted = np.einsum("iq,ikq->kq", lam, np.sum((x[:, None] - v[:, :, :, None]) ** 2, axis=0))
    rho = tn._interpolation_radius(v)
    assert np.all(weighted.max(axis=1) <= rho**2 * (1 + 1e-12))
    assert weighted.max(axis=1) == pytest.approx(rho**2, rel=1e-4)


@pytest.mark.parametrize("N", [21, 41])
def test_pruned_maxima_equal_the_exhaustive_evaluation(cache, N):
    """The branch and bound (every triangle sampled at its vertices, most excluded at once: all
    beyond the cut-off, where e is affine) against
    the lattice of every triangle with local maximisation: the same value to rtol, inside the
    enclosure the branch and bound states."""
    from signorini.fem.norms.true import _sampled_max_norm

    mesh, u_h = cache.discrete({}, N).mesh, cache.solution({}, N).u
    cases = [("Linf", Conventions()), ("Linfplus", Conventions()), ("Linfminus", Conventions())]
    cases += [("W1inf", Conventions(w1p_form=form)) for form in ("components", "gradient", "seminorm")]
    for name, conv in cases:
        pruned = true_norm(Problem(), mesh, u_h, name + "_true", conv)
        exhaustive = _sampled_max_norm(Problem(), mesh, u_h, define(name, conv), RTOL)
        upper = pruned.levels[-1]["upper"]
        assert pruned.converged and exhaustive.converged, name
        assert pruned.value == pytest.approx(exhaustive.value, rel=RTOL), name
        assert pruned.value <= upper and exhaustive.value <= upper * (1 + 1e-12), name
        assert pruned.error_estimate == pytest.approx(upper - pruned.value, abs=1e-15)
        first = pruned.levels[0]
        assert first["sampled"] == mesh.t.shape[1] and first["kept"] + first["settled"] < first["sampled"] / 2, name


@pytest.mark.parametrize("name", ["Linf", "W1inf"])
def test_pruned_maxima_of_the_singular_function(name):
    """ũ with its bounds: the enclosure of the branch and bound holds the maximum along ∂Ω."""
    problem = BoundedHarmonic()

    f, result = _pointwise(problem, name), _true_max_of_u(problem, name)
    reference = _boundary_max(f)
    assert result.converged
    assert result.value <= reference * (1 + 1e-12) <= result.levels[-1]["upper"] * (1 + 1e-12)
    assert result.value == pytest.approx(reference, rel=RTOL)


# --- the integrals, triangle by triangle ---------------------------------------------------------


def _uniform(problem, mesh, u_h, name: str, level: int, conv: Conventions) -> float:
    """The norm with every triangle at the rule of ``level`` (``INTEGRAL_LEVELS``; the graded rule of
    ``NEAR_LEVELS`` near the singular point), no closed form."""
    from signorini.fem.norms import true as tn

    norm = define(name, conv)
    plain, gradient = tn._integrand(norm)
    scale, near_mask, _ = tn._survey(problem, mesh, u_h, gradient)
    near = tn._NearField.of(problem, mesh, u_h, near_mask)

    def integrand(e, de):
        return plain(e / scale, None if de is None else de / scale)

    every = np.arange(mesh.t.shape[1])
    return (
        float(tn._integrals(problem, mesh, u_h, integrand, gradient, (level,), every, near)[0].sum()) ** (1 / norm.p)
        * scale
    )


LAST = 5  # the finest level: rules 20 (28 near the free point)


@pytest.mark.parametrize("N", [21, 41])
def test_integral_norms_agree_with_every_triangle_at_the_finest_rule(cache, N):
    """The integrals triangle by triangle (most at the rule 5 or exactly) against every triangle at
    the finest rule: the same value to rtol, with at most a tenth of the triangles at 14 or 20."""
    mesh, u_h = cache.discrete({}, N).mesh, cache.solution({}, N).u
    for name, conv in [("L4", Conventions()), ("L16", Conventions()), ("L4plus", Conventions()), ("H1", Conventions())]:
        result = true_norm(Problem(), mesh, u_h, name + "_true", conv)
        assert result.converged and result.value == pytest.approx(
            _uniform(Problem(), mesh, u_h, name, LAST, conv), rel=RTOL
        )
    for form in ("components", "gradient", "seminorm"):
        conv = Conventions(w1p_form=form)
        result = true_norm(Problem(), mesh, u_h, "W116_true", conv)
        assert result.converged and result.value == pytest.approx(
            _uniform(Problem(), mesh, u_h, "W116", LAST, conv), rel=RTOL
        )
        counts = result.levels[-1]["elements_per_rule"]
        near = result.levels[-1]["near_elements_per_rule"]
        assert sum(counts.values()) + sum(near.values()) == mesh.t.shape[1]
        assert counts["20"] + counts["14"] < mesh.t.shape[1] / 10


def test_the_closed_form_where_u_is_affine_equals_a_rule_that_is_exact_there():
    """Where u ≡ 0 (beyond the cut-off) e = −u_h is affine: ∫ e^p by the complete homogeneous
    polynomial equals the 12 × 12 conical rule (degree 23 ≥ p) for every integrand with even p."""
    from signorini.fem.norms import true as tn

    problem, mesh = Problem(), friedrichs_keller(21)
    u_h = np.random.default_rng(1).normal(size=mesh.p.shape[1]) * 0.1
    v = mesh.p[:, mesh.t]
    elements = np.flatnonzero(ManufacturedBounds(problem).hessian_bound(*tn._radii(problem, v)) == 0.0)
    assert elements.size > mesh.t.shape[1] / 2
    aff = tn._Affine.of(mesh, u_h, elements)
    for name, form in [
        ("L2", ""),
        ("L4", ""),
        ("L16", ""),
        ("H1", ""),
        ("W14", "components"),
        ("W116", "gradient"),
        ("W14", "seminorm"),
    ]:
        norm = define(name, Conventions(w1p_form=form or "components"))
        plain, gradient = tn._integrand(norm)
        exact = tn._affine_rule(norm, plain, 0.5)(problem, aff)
        rule = tn._rule_integrals(
            problem,
            aff,
            lambda e, de, plain=plain: plain(e / 0.5, None if de is None else de / 0.5),
            gradient,
            12,
            v[:, :, elements],
        )
        assert exact == pytest.approx(rule, rel=1e-12), name
    assert tn._affine_rule(define("L4plus"), None, 1.0) is None
    assert tn._affine_rule(define("L3"), None, 1.0) is None


def test_true_norms_on_an_unstructured_mesh_agree_with_an_independent_computation():
    """On a Delaunay mesh (``fem.mesh_families``: no Friedrichs–Keller triangle, the free point
    inside a triangle) the true norms of ``u − u_h`` agree with the same norm computed apart: the
    mesh refined four times (256 triangles per triangle), ``u_h`` carried over exactly by
    scikit-fem's probes (it is affine on every small triangle) and the 16-point rule on each;
    that computation moves by less than 1e-7 relative from three to four refinements."""
    from skfem import Basis, ElementTriP1

    from signorini.fem.mesh_families import build_mesh

    problem = Problem(x0=0.47, R=0.35)
    mesh = build_mesh("delaunay", 8, seed=5)
    u_h = problem.u(mesh.p) + 0.01 * np.sin(7.0 * mesh.p[0]) * mesh.p[1]
    probes = Basis(mesh, ElementTriP1()).probes
    names = ["L4", "W14", "L16"]
    apart = [evaluate_norms(problem, fine, probes(fine.p) @ u_h, names) for fine in (mesh.refined(3), mesh.refined(4))]
    for name in names:
        assert abs(apart[1][name] - apart[0][name]) < 1e-7 * apart[1][name]
        result = true_norm(problem, mesh, u_h, f"{name}_true")
        assert result.converged and abs(result.value - apart[1][name]) <= result.error_estimate
