"""The common result type of every solver route."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from signorini.solvers.certificate import Certificate


@dataclass
class SolveResult:
    """Solution ``u``, multiplier ``lam`` (one entry per constrained node), contact set and diagnostics."""

    u: np.ndarray
    lam: np.ndarray
    active: np.ndarray  # constrained indices with u_i = 0 (the discrete contact set)
    iterations: int
    wall_time_s: float
    certificate: Certificate
    solver: str
    info: dict = field(default_factory=dict)
    # one row per Newton step (iteration, active nodes, changes, the route's counters, elapsed
    # seconds), as the route's ``callback`` received them; empty for routes without steps
    history: list[dict] = field(default_factory=list)
    # the multigrid route's ``GalerkinHierarchy``, Galerkin for the final contact set: what the
    # algebraic-error estimate solves with (``algebraic_error.linearised_error``); None elsewhere
    hierarchy: Any = field(default=None, repr=False, compare=False)

    def summary(self) -> dict:
        """JSON-ready diagnostics (everything but the vectors)."""
        return {
            "solver": self.solver,
            "iterations": int(self.iterations),
            "wall_time_s": float(self.wall_time_s),
            "n_active": int(self.active.size),
            "certificate": self.certificate.as_dict(),
            **self.info,
            "history": [dict(row) for row in self.history],
        }
