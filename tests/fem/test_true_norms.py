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

from signorini.fem.boundary import boundary_rule
from signorini.fem.discrete import build
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norm_names import UnknownNormError, parse_norm_name, true_name
from signorini.fem.norms import Conventions, boundary_error, evaluate_norms, parse_norm
from signorini.fem.problem import Problem
from signorini.fem.true_norms import RTOL, evaluate_named_norms, true_norm
from signorini.paper import label_md

X0 = 0.5 + 0.3 / 7  # inside a bottom boundary edge of the N = 7 mesh, not at its midpoint


class Kink:
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


class Harmonic:
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


def test_a_true_name_is_evaluated_by_the_dispatcher_not_under_the_conventions():
    with pytest.raises(UnknownNormError, match="true_norms"):
        parse_norm("L4_true")
    mesh, problem = friedrichs_keller(7), Harmonic()
    zero = np.zeros(mesh.p.shape[1])
    with pytest.raises(UnknownNormError, match="evaluate_named_norms"):
        evaluate_norms(problem, mesh, zero, ["L4", "L4_true"])
    out = evaluate_named_norms(problem, mesh, zero, ["L4_true", "L4"])
    assert list(out) == ["L4_true", "L4"]  # the order asked for
    assert out["L4_true"] == true_norm(problem, mesh, zero, "L4").value
    assert out["L4"] == evaluate_norms(problem, mesh, zero, ["L4"])["L4"]
    detailed = evaluate_named_norms(problem, mesh, zero, ["L4_true", "L4"], details=True)
    assert detailed["L4_true"].as_dict() == true_norm(problem, mesh, zero, "L4_true").as_dict()
    assert detailed["L4"] == out["L4"]
    with pytest.raises(UnknownNormError):
        evaluate_named_norms(problem, mesh, zero, ["L4", "nonsense"])


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


class Scaled:
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


@pytest.mark.parametrize("name", ["Linf", "W1inf"])
def test_true_maxima_of_the_singular_function(name):
    problem = Harmonic()

    def f(x1, x2):
        x = np.array([[x1], [x2]])
        g = [np.abs(problem.u(x))] + ([np.abs(problem.grad_u(x)[k]) for k in (0, 1)] if name == "W1inf" else [])
        return float(np.max(g))

    mesh = friedrichs_keller(7)
    result = true_norm(problem, mesh, np.zeros(mesh.p.shape[1]), name + "_true")
    assert result.value == pytest.approx(_boundary_max(f), rel=1e-9)


class Bump:
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


def test_true_norm_artifacts_of_the_second_case_carry_their_accuracy(built_repo):
    from signorini.pipeline.artifacts import load_json

    for name in ("L4_true", "Linf_true", "W14_true", "W1inf_true", "H12_true"):
        art = load_json(built_repo / f"results/case2/N241/norms/{name}.json")
        acc = art["quadrature_error"]
        assert acc["converged"] and acc["rtol"] == RTOL and len(acc["levels"]) >= 2
        assert acc["error_estimate"] <= RTOL * art["value"]
        assert acc["levels"][-1]["value"] == art["value"]


def test_true_norms_target_renders_every_norm_of_table_2(built_repo):
    """The test workflow renders the smoke scene (N = 11, 21, 41): a row per mesh and norm, converged."""
    import pandas as pd

    from signorini.paper import TABLE2_NORMS

    t1 = pd.read_csv(built_repo / "paper_figures/table1_true.csv")
    assert list(t1["norm"]) == list(TABLE2_NORMS) * 3 and list(t1["h"].unique()) == ["1/11", "1/21", "1/41"]
    assert (t1["quadrature_error"] <= RTOL * t1["true"]).all()
    assert t1["paper"].isna().all()  # the paper has no row for these meshes
    t2 = pd.read_csv(built_repo / "paper_figures/table2_true.csv")
    assert list(t2.columns) == ["h", *(true_name(n) for n in TABLE2_NORMS)]
    assert "## Gap per norm" in (built_repo / "paper_figures/table1_true.md").read_text()
