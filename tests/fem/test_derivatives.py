"""What the true norms know of the derivatives of the exact solution (``signorini.fem.derivatives``):
``u`` with ``∇u`` in one evaluation, the bounds a problem states or the manufactured ones, and the
Hölder bound of ``∇u`` on random pairs of points.

The bounds of the second derivatives against the closed form are tested with the true norms in
``tests/fem/norms/test_true.py``.
"""

from __future__ import annotations

import math

import numpy as np

from signorini.fem.derivatives import ManufacturedBounds, derivative_bounds, u_and_grad_u
from signorini.fem.problem import ConstantProblem, Problem


class StatedBounds(ConstantProblem):
    """A problem that states the bounds of its derivatives itself."""

    def derivative_bounds(self):
        return self

    def hessian_bound(self, r_lo, r_hi):
        return np.zeros_like(r_hi)

    def gradient_holder_bound(self, r_hi):
        return np.zeros_like(r_hi)


def test_u_and_its_gradient_in_one_evaluation_are_the_problems_bit_for_bit(rng):
    problem = Problem(x0=0.47, R=0.4, A=3.0, c=2.0)
    x = rng.uniform(0.0, 1.0, (2, 40, 3))
    u, grad = u_and_grad_u(problem, x)
    assert np.array_equal(u, problem.u(x)) and np.array_equal(grad, problem.grad_u(x))
    constant = ConstantProblem(2.0, 4.0)
    u, grad = u_and_grad_u(constant, x)
    assert np.array_equal(u, constant.u(x)) and np.array_equal(grad, constant.grad_u(x))


def test_the_bounds_come_from_the_problem_the_closed_form_or_nowhere():
    stated, problem = StatedBounds(1.0, 1.0), Problem()
    assert derivative_bounds(stated) is stated and derivative_bounds(ConstantProblem(1.0, 1.0)) is None
    bounds = derivative_bounds(problem)
    assert isinstance(bounds, ManufacturedBounds) and bounds.problem is problem
    values = bounds.hessian_bound(np.array([0.0, 0.1, problem.R]), np.array([0.1, 0.2, 1.0]))
    assert math.isinf(values[0]) and 0.0 < values[1] < math.inf and values[2] == 0.0  # u ≡ 0 beyond R


def test_the_gradient_is_hoelder_continuous_with_the_stated_constant(rng):
    """|∇u(x) − ∇u(y)| ≤ H(r) |x − y|^{1/2} for x, y within r of the free point, also across it."""
    problem = Problem(x0=0.5, R=0.45, A=10.0, c=1.0)
    bounds = ManufacturedBounds(problem)
    for r in (0.01, 0.1, 0.5):
        angle, radius = rng.uniform(0.0, np.pi, (2, 2000)), r * np.sqrt(rng.uniform(0.0, 1.0, (2, 2000)))
        x = np.stack([problem.x0 + radius * np.cos(angle), radius * np.sin(angle)], axis=1)  # (2 points, 2, n)
        x[:, 0] = np.clip(x[:, 0], 0.0, 1.0)
        gx, gy = problem.grad_u(x[0]), problem.grad_u(x[1])
        ratio = np.linalg.norm(gx - gy, axis=0) / np.linalg.norm(x[0] - x[1], axis=0) ** 0.5
        assert ratio.max() <= bounds.gradient_holder_bound(r), r
