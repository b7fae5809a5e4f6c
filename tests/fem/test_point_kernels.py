"""The compiled point kernels of the manufactured problem give numpy's bits: ``u`` and ``∇u``
inside ``compiled_points`` against the same calls outside it, on points inside and outside the
support, on its rim, on the contact part and below the bottom edge, for the paper's parameters and
others; and the norm evaluators take them only on large meshes, with the same values (the true
norms' rules, whose sums run in the kernels' order, to round-off)."""

from __future__ import annotations

import numpy as np
import pytest

from signorini.fem import point_kernels, problem
from signorini.fem.mesh import friedrichs_keller
from signorini.fem.norms import evaluate
from signorini.fem.problem import Problem, compiled_points


def _points(rng: np.random.Generator, P: Problem) -> np.ndarray:
    """Random points of the square, the free point, the contact part, the rim r = R, the support's
    ends on the edge, and all of them mirrored below the edge (|x₂| enters ũ)."""
    angle = np.linspace(0.0, np.pi, 501)
    special = np.array(
        [[P.x0, P.x0 + 0.3 * P.R, P.x0 - 0.3 * P.R, P.x0 + P.R, P.x0 - P.R, 0.0, 1.0], [0.0] * 5 + [0.5, 1.0]]
    )
    rim = np.stack([P.x0 + P.R * np.cos(angle), P.R * np.sin(angle)])
    x = np.concatenate([rng.uniform(0.0, 1.0, (2, 20_000)), special, rim], axis=1)
    return np.concatenate([x, x * np.array([[1.0], [-1.0]])], axis=1)


@pytest.mark.parametrize("params", [{}, {"x0": 0.3, "R": 0.2, "A": 3.0}, {"x0": 0.6, "R": 0.35, "A": 1}])
def test_the_compiled_values_are_numpys_bits(params):
    P = Problem(**params)
    x = _points(np.random.default_rng(1), P)
    shaped = x[:, :600].reshape(2, 20, 30)[:, ::2, 1::3]  # a strided, non-contiguous block
    for points in (x, shaped, x[:, 0]):
        u, (value, grad) = P.u(points), P.u_and_grad_u(points)
        with compiled_points():
            cu, (cvalue, cgrad) = P.u(points), P.u_and_grad_u(points)
        for a, b in ((u, cu), (value, cvalue), (grad, cgrad)):
            assert a.shape == b.shape and a.tobytes() == b.tobytes()
    with compiled_points():
        inside = P.u(x) != 0.0
    assert inside.any() and not inside.all()  # both branches of the kernel ran


def test_the_block_restores_the_numpy_path_and_a_vanishing_problem_skips_the_kernels(monkeypatch):
    calls = []
    monkeypatch.setattr(point_kernels, "manufactured_u", lambda *args: calls.append(args))
    x = np.array([[0.5, 0.6], [0.1, 0.0]])
    with compiled_points():
        Problem().u(x)
        with compiled_points(False):
            Problem().u(x)
        assert Problem(A=0.0).u(x).tolist() == [0.0, 0.0]
    Problem().u(x)
    assert len(calls) == 1


def test_norms_take_the_kernels_from_the_threshold_with_the_same_values(monkeypatch):
    mesh, P = friedrichs_keller(24), Problem()
    u_h = P.u(mesh.p) * (1.0 + 0.01 * np.sin(7.0 * mesh.p[0]))
    names = ["L4", "W14", "Linf", "H12", "L4_true", "W14_true"]
    numpy_values = evaluate.evaluate_named_norms(P, mesh, u_h, names, details=True)
    calls = []
    real = point_kernels.manufactured_u_and_grad
    monkeypatch.setattr(point_kernels, "manufactured_u_and_grad", lambda *a: calls.append(1) or real(*a))
    monkeypatch.setattr(problem, "COMPILED_MIN_ELEMENTS", mesh.t.shape[1])
    compiled_values = evaluate.evaluate_named_norms(P, mesh, u_h, names, details=True)
    assert calls and problem._COMPILED.get() is False
    for name in ("L4", "W14", "Linf", "H12"):  # bit for bit
        assert repr(compiled_values[name]) == repr(numpy_values[name])
    for name in ("L4_true", "W14_true"):  # the rules' sums in their order (tests/fem/norms/test_kernels.py)
        a, b = compiled_values[name], numpy_values[name]
        assert a.value == pytest.approx(b.value, rel=1e-13)
        assert [level["evaluated"] for level in a.levels] == [level["evaluated"] for level in b.levels]
    monkeypatch.setattr(problem, "COMPILED_MIN_ELEMENTS", mesh.t.shape[1] + 1)
    calls.clear()
    evaluate.evaluate_named_norms(P, mesh, u_h, ["W14"])
    assert not calls
