"""The direct route: primal–dual active set (semismooth Newton, ``signorini.solvers.pdas``) on
the boundary constraints, each Newton system solved exactly by a sparse factorisation.

Linear algebra: the first system is factorised (CHOLMOD or PARDISO, see linalg.py).  A later
set differs from the factorised one ``Ã₀`` (free set W) in a few nodes: P = nodes now clamped
but free in ``Ã₀``, Q = nodes now free but clamped in ``Ã₀``.  Its system is ``Ã₀`` bordered
by one column per changed node (``BorderedSolver``), solved exactly by block elimination with
the columns ``Ã₀⁻¹ e_p`` and ``Ã₀⁻¹ A_{W,q}``.  The columns are kept across Newton steps, so a
node that changes status costs one extra triangular solve over the whole iteration (batched
per step), not one per step as a Krylov correction would.  Only a large change (more than
``refactor_above`` columns) triggers a new factorisation.  A warm start (e.g. a coarser
solution interpolated) gives the first active set, so a fine solve typically costs one
factorisation plus a handful of triangular solves.  All clamped matrices keep ``A``'s
sparsity pattern, so PARDISO analyses the pattern once and later factorisations are
numerical only.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from signorini.solvers import pdas
from signorini.solvers.certificate import NotConvergedError
from signorini.solvers.linalg import Factorizer, Solve
from signorini.solvers.pdas import StepCallback, certified_result, clamped_values, initial_active, iterate, prepare_qp
from signorini.solvers.result import SolveResult

log = logging.getLogger(__name__)
_clamped_values = clamped_values  # the name the bordered-solver tests use


class BorderedSolver:
    """Solve ``Ã(F) u = D r`` (rows F: ``(A u)_F = r_F``; rows outside F: ``u = 0``, whatever
    ``r`` holds there) for free sets F close to the factorised one, W, with ``factor = Ã(W)⁻¹``.

    With P = W \\ F (newly clamped) and Q = F \\ W (newly free), the system is

        [A_WW   A_WQ  -E_P] [u_W]   [r_W]
        [A_QW   A_QQ   0  ] [u_Q] = [r_Q]        (μ = (A u - r)_P, the multipliers
        [-E_Pᵀ  0      0  ] [ μ ]   [ 0 ]         of the extra clamps u_P = 0)

    Eliminating ``u_W = z - G u_Q + H μ`` with ``z = A_WW⁻¹ r_W``, ``G = A_WW⁻¹ A_WQ`` and
    ``H = A_WW⁻¹ E_P`` leaves the small symmetric (indefinite) system

        [A_QQ - A_QW G   A_QW H] [u_Q]   [r_Q - A_QW z]
        [G_P             -H_P  ] [ μ ] = [z_P         ]

    ``A_WW⁻¹ y`` is ``Ã(W)⁻¹ y`` for ``y`` supported on W.  Columns of G and H are computed
    once per node (in one block solve per call) and cached.
    """

    def __init__(self, A: sp.csr_matrix, factor: Solve, free: np.ndarray):
        self.A, self.factor, self.free = A, factor, free.copy()
        self.columns: dict[int, np.ndarray] = {}
        self.solves = 0  # right-hand sides passed to the factor
        self._last: tuple[np.ndarray, np.ndarray] | None = None  # (r_W, A_WW⁻¹ r_W): b repeats

    def n_columns(self, free: np.ndarray) -> int:
        """Border size (|P| + |Q|) for the free set ``free``."""
        return int(np.count_nonzero(free != self.free))

    def _column(self, nodes: np.ndarray) -> None:
        new = [int(i) for i in nodes if int(i) not in self.columns]
        if not new:
            return
        rhs = np.zeros((self.A.shape[0], len(new)))
        for k, i in enumerate(new):
            if self.free[i]:  # newly clamped node p: H column, A_WW⁻¹ e_p
                rhs[i, k] = 1.0
            else:  # newly free node q: G column, A_WW⁻¹ A_{W,q} (A symmetric: row q)
                lo, hi = self.A.indptr[i], self.A.indptr[i + 1]
                cols = self.A.indices[lo:hi]
                keep = self.free[cols]
                rhs[cols[keep], k] = self.A.data[lo:hi][keep]
        out = self.factor(rhs)
        self.solves += len(new)
        for k, i in enumerate(new):
            self.columns[i] = np.ascontiguousarray(out[:, k])

    def __call__(self, free: np.ndarray, r: np.ndarray) -> np.ndarray:
        W = self.free
        P = np.flatnonzero(W & ~free)
        Q = np.flatnonzero(~W & free)
        rW = np.where(W, r, 0.0)
        if self._last is not None and np.array_equal(self._last[0], rW):
            z = self._last[1]
        else:
            z = self.factor(rW)
            self.solves += 1
            self._last = (rW, z)
        if P.size + Q.size == 0:
            return z.copy()  # z stays cached
        self._column(np.concatenate([P, Q]))
        G = np.column_stack([self.columns[q] for q in Q]) if Q.size else np.zeros((r.size, 0))
        H = np.column_stack([self.columns[p] for p in P]) if P.size else np.zeros((r.size, 0))
        AQ = self.A[Q]
        S = np.block([[AQ[:, Q].toarray() - AQ @ G, AQ @ H], [G[P], -H[P]]])
        rhs = np.concatenate([r[Q] - AQ @ z, z[P]])
        y = sla.solve(S, rhs, assume_a="sym")
        uQ, mu = y[: Q.size], y[Q.size :]
        u = z - G @ uQ + H @ mu  # a new array: z stays cached
        u[Q] = uQ
        u[P] = 0.0  # = 0 up to round-off by the last block row
        return u


class DirectSystems:
    """The Newton systems of the direct route (``pdas.NewtonSystems``): a factorisation of the
    first clamped matrix, bordered updates for later sets, a new factorisation on a large change
    (more than ``refactor_above`` columns) or when the column cache (n numbers per column) is full."""

    exact = True  # every solve is exact

    def __init__(self, A: sp.csr_matrix, b: np.ndarray, refactor_above: int, backend: str):
        self.A, self.b, self.refactor_above = A, b, refactor_above
        self.rows = np.repeat(np.arange(b.size), np.diff(A.indptr))
        self.factorizer = Factorizer(A, backend)
        self.bordered: BorderedSolver | None = None
        self.factorizations = self.retired_solves = self.retired_columns = 0
        self.free = np.ones(b.size, dtype=bool)

    def __call__(self, free: np.ndarray, accurate: bool = True) -> np.ndarray:
        bordered = self.bordered
        if bordered is None or max(bordered.n_columns(free), len(bordered.columns) // 2) > self.refactor_above:
            if bordered is not None:
                self.retired_solves += bordered.solves
                self.retired_columns += len(bordered.columns)
            try:
                factor = self.factorizer(clamped_values(self.A, self.rows, free))
            except np.linalg.LinAlgError as err:  # c = 0 and too few contact nodes: A_FF singular
                raise NotConvergedError(
                    f"active set of {int((~free).sum())} nodes leaves a singular system ({err}); "
                    "with c = 0 the minimiser is then not unique"
                ) from err
            self.bordered = bordered = BorderedSolver(self.A, factor, free)
            self.factorizations += 1
        self.free = free
        return bordered(free, self.b)  # rows outside F are ignored, so b's solve is reused across steps

    def counters(self) -> dict:
        columns = self.retired_columns + (len(self.bordered.columns) if self.bordered else 0)
        return {"factorizations": self.factorizations, "correction_columns": columns}

    def refine(self, u: np.ndarray) -> np.ndarray:
        """One step of iterative refinement on the last free set, always.  The direct solve's
        error is smooth (Cholesky's backward error times ``Ã⁻¹``, growing like N² against a
        long-double-refined solution), and a smooth error has a residual below the rounding noise
        ``ε |A||u|`` of evaluating it, so no residual test can tell when to refine.  One step leaves
        ``Ã⁻¹`` of that noise, which is rough and damped: a few units of round-off of max |u|
        (docs/evidence/design-measurements.md#direct-refinement).  Clamped rows have zero residual:
        u_𝒜 stays 0."""
        residual = np.where(self.free, self.b - self.A @ u, 0.0)
        return u + self.bordered(self.free, residual)

    def info(self) -> dict:
        return {
            "factorizations": self.factorizations,
            "triangular_solves": self.retired_solves + self.bordered.solves,
            "correction_columns": self.counters()["correction_columns"],
            "backend": self.factorizer.backend,
        }


def active_set_solve(
    A: sp.spmatrix,
    b: np.ndarray,
    constrained: np.ndarray,
    warm_start: np.ndarray | None = None,
    max_iter: int = 100,
    kkt_tol: float = 1e-10,
    refactor_above: int = 40,
    frontier_growth: bool = True,
    warm_start_dilation: int = 0,
    backend: str = "auto",
    warm_start_reach: int = pdas.WARM_START_REACH,
    *,
    callback: StepCallback | None = None,
) -> SolveResult:
    """Solve ``min ½ uᵀAu - bᵀu`` s.t. ``u_B ≥ 0`` exactly (to round-off) and certify it.

    ``callback(row)`` receives each Newton step's row of ``SolveResult.history`` (iteration,
    active nodes, changes, factorisations and correction columns so far, elapsed seconds).
    ``warm_start_reach``: the frontier's reach in the first Newton step from ``warm_start``
    (``pdas.Frontier``; one node from the cold start).
    Raises ``NotConvergedError`` when the set has not repeated after ``max_iter``
    Newton steps or cycles, and ``KKTError`` when the final certificate exceeds ``kkt_tol``.
    """
    if warm_start_reach < 1:
        raise ValueError(f"need warm_start_reach >= 1 (nodes), got {warm_start_reach}")
    t0 = time.perf_counter()
    A, b, B = prepare_qp(A, b, constrained)
    active = initial_active(A, b, B, warm_start, warm_start_dilation)
    systems = DirectSystems(A, b, refactor_above, backend)
    reach = warm_start_reach if warm_start is not None else 1
    u, active, history = iterate(systems, A, b, B, active, max_iter, frontier_growth, callback, log, None, reach)
    u = systems.refine(u)
    return certified_result(A, b, B, u, active, kkt_tol, t0, "active_set", systems.info(), history)
