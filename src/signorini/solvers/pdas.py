"""The primal–dual active set (semismooth Newton) iteration that every exact route shares.

For an active set 𝒜 ⊂ B the Newton step solves ``u_𝒜 = 0``, ``(A u)_F = b_F``
(F the complement), i.e. ``Ã u = D b`` with ``Ã = D A D + (I - D)`` and ``D`` the
indicator of F; then ``λ = (A u - b)_𝒜`` and the next set is
``{i ∈ 𝒜 : λ_i > -ε_λ} ∪ {i ∈ B \\ 𝒜 : u_i < -ε_u}`` with relative thresholds ε (scale-free).
The iteration stops when the set repeats and the step that repeated it was solved to full
accuracy.

The routes differ only in how they solve the Newton systems (a ``NewtonSystems``): the direct
route (``active_set``) with a sparse factorisation and bordered updates, the multigrid route
(``multigrid``) with preconditioned conjugate gradients, inexact while the set moves, a step
that only releases nodes settled on a patch around them (``solvers.local``).  Both
report one row per Newton step (``SolveResult.history``, and ``callback`` as it happens).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable
from typing import Protocol

import numpy as np
import scipy.sparse as sp

from signorini.solvers.certificate import KKTError, NotConvergedError, check_qp_data, kkt_certificate
from signorini.solvers.result import SolveResult
from signorini.solvers.stencil import StencilOperator, as_csr, entries

StepCallback = Callable[[dict], None]
# settles a release: (u, the set before the step, the set after it) -> (u, set, row of counters) | None
Settle = Callable[[np.ndarray, np.ndarray, np.ndarray], "tuple[np.ndarray, np.ndarray, dict] | None"]
MAX_SETTLES = 8  # releases settled locally per solve, at most (each costs a small exact solve)
CREEP_STEPS = 3  # frontier steps of one node per end before the frontier's reach starts doubling
# the frontier's reach in the first Newton step from a warm start the caller gives (the cascade's
# interpolant); one node from the routes' own starts (docs/evidence/design-measurements.md#frontier-first-reach)
WARM_START_REACH = 2


class NewtonSystems(Protocol):
    """How a route solves ``Ã(F) u = D b`` for the free sets F the iteration visits."""

    exact: bool  # every solve is accurate to round-off (no inexact mode)

    def __call__(self, free: np.ndarray, accurate: bool) -> np.ndarray:
        """The solution ``u`` (``u = 0`` outside ``free``), to full accuracy if ``accurate``."""

    def counters(self) -> dict:
        """The route's counters after the last solve (a row of the history)."""


def prepare_qp(
    A: sp.spmatrix | StencilOperator, b: np.ndarray, constrained: np.ndarray, keep_stencil: bool = False
) -> tuple[sp.csr_matrix | StencilOperator, np.ndarray, np.ndarray]:
    """``A`` as CSR with sorted, summed indices, ``b`` and ``B`` as arrays, checked.  A CSR matrix in
    that form already is used as it is (no route changes ``A``: at N = 4001 a copy is 1.3 GB);
    any other is copied first, so the caller's matrix is never changed.  An operator standing in
    for ``A`` (``solvers.stencil``) is checked through its CSR copy, and kept as it is where the
    route solves with it (``keep_stencil``: the multigrid route)."""
    if isinstance(A, StencilOperator):
        csr = A.tocsr()
        csr, b, B = prepare_qp(csr, b, constrained)
        return (A if keep_stencil else csr), b, B
    A = sp.csr_matrix(A)  # the same matrix for a CSR input
    if not A.has_canonical_format:
        A = A.copy()
        A.sum_duplicates()
        A.sort_indices()
    b = np.asarray(b, dtype=float)
    B = np.asarray(constrained, dtype=np.int64)
    check_qp_data(A, b, B)
    return A, b, B


def clamped_values(
    A: sp.csr_matrix | StencilOperator, rows: np.ndarray, free: np.ndarray, positions: np.ndarray | None = None
) -> np.ndarray:
    """CSR values of Ã = D A D + (I - D) in ``A``'s own sparsity pattern (explicit zeros kept,
    so every active set shares one symbolic factorisation or one matrix layout); ``rows`` is the
    row of each stored entry.  With ``positions``: the values at those positions of ``A.data``,
    ``rows`` the row of each of them."""
    if positions is None:  # every stored entry
        pos, values = slice(None), as_csr(A).data
    else:
        pos, values = positions, entries(A, positions, rows)
    r, c = rows, A.indices[pos]
    data = np.where(free[r] & free[c], values, 0.0)
    data[(r == c) & ~free[r]] = 1.0
    return data


def boundary_adjacency(A: sp.csr_matrix | StencilOperator, B: np.ndarray) -> sp.csr_matrix:
    """The boundary graph (int8): a node may enter the contact set next to one already in it."""
    rows = A.row_block(B) if isinstance(A, StencilOperator) else A[B]
    return (abs(rows[:, B]) > 0).astype(np.int8)


def initial_active(
    A: sp.csr_matrix, b: np.ndarray, B: np.ndarray, warm_start: np.ndarray | None, dilation: int = 0
) -> np.ndarray:
    """The first active set (a mask over ``B``): where the warm start vanishes, grown by
    ``dilation`` boundary neighbours; without a warm start, the nodes pushed outwards."""
    if warm_start is None:
        return b[B] <= 0.0
    w = np.asarray(warm_start, dtype=float)
    if w.shape != b.shape or not np.all(np.isfinite(w)):
        raise ValueError(f"warm start must be a finite vector of length {b.size}")
    # predicted contact: where the warm start vanishes (its residual A w - b is no
    # multiplier estimate when w is interpolated from a coarser mesh)
    active = w[B] <= 0.0
    # Grow the predicted contact set by a few boundary neighbours: for an M-matrix (P1 on
    # Friedrichs–Keller meshes, c h² small) starting from a superset of the true contact set
    # keeps the iterates feasible and the active set shrinks monotonically in small steps; an
    # undersized start instead swings the whole far boundary (where u_h is O(h²)) into contact.
    if dilation > 0:
        pattern = boundary_adjacency(A, B)
        for _ in range(dilation):
            active = (pattern @ active.astype(np.int8)) > 0
    return active


class Frontier:
    """Frontier growth: violated nodes enter only within ``reach`` boundary neighbours of the
    contact set while any such exists; ``reach`` is ``first_reach`` nodes in the first step, one
    node for the first ``CREEP_STEPS`` steps that hold nodes back and doubles with each one after
    them.

    Growing the contact set only at its ends keeps an undersized set near the free point from
    pushing the whole far boundary (where u_h is O(h²)-small and biactive in the limit) into
    contact: the plain PDAS step would clamp all of it and release it again, two large changes.
    With a fixed reach of one node a set that must grow by m nodes takes about m/2 steps (one
    per end and step); the doubling reach takes about log₂ m more after the first few, and a set
    a few nodes short still grows one node per end and step.  The full step is taken when no
    violated node is within reach, so termination is PDAS's own.

    From a warm start interpolated from a coarser mesh the first step reaches ``WARM_START_REACH``
    nodes: the interpolant misses the fine nodes at a contact zone's end where the coarse solution
    is still positive, often two, which one node per step admits in two Newton steps (a reach of
    three admits nodes at the zone's biactive end that the next steps release again)."""

    def __init__(self, adjacency: sp.csr_matrix, first_reach: int = 1):
        self.adjacency = adjacency
        self.first_reach = first_reach
        self.steps = 0  # steps restricted so far
        self.held = 0  # steps that held violated nodes back

    @property
    def reach(self) -> int:
        if self.steps == 0:
            return self.first_reach
        return 1 << max(0, self.held - CREEP_STEPS)

    def restrict(self, grow: np.ndarray, active: np.ndarray) -> np.ndarray:
        """The nodes of the mask ``grow`` that enter the contact set ``active`` in this step."""
        near = active
        for _ in range(min(self.reach, active.size)):
            near = near | ((self.adjacency @ near.astype(np.int8)) > 0)
        self.steps += 1
        frontier = grow & near
        if not frontier.any():
            return grow
        if np.count_nonzero(frontier) < np.count_nonzero(grow):
            self.held += 1
        return frontier


def next_active(
    A: sp.csr_matrix,
    b: np.ndarray,
    B: np.ndarray,
    u: np.ndarray,
    active: np.ndarray,
    frontier: Frontier | None,
) -> np.ndarray:
    """The PDAS update of the mask ``active`` from the Newton iterate ``u``; with ``frontier``
    (frontier growth) violated nodes enter only near the contact set while any such exists."""
    lam = np.where(active, (A @ u - b)[B], 0.0)
    # hysteresis below round-off keeps degenerate (u = λ = 0) nodes from flip-flopping;
    # ≥ keeps them when everything vanishes (f ≡ 0: eps_lam = 0), where releasing the
    # whole boundary would leave the singular K of c = 0 to factorise
    eps_lam = 1e-13 * max(np.abs(lam).max(initial=0.0), np.abs(b).max(initial=0.0))
    eps_u = 1e-13 * np.abs(u).max(initial=0.0)
    keep = active & (lam >= -eps_lam)
    grow = ~active & (u[B] < -eps_u)
    if frontier is not None:
        grow = frontier.restrict(grow, active)
    return keep | grow


def releases_only(before: np.ndarray, after: np.ndarray) -> bool:
    """Whether the step from the contact set ``before`` to ``after`` (masks) releases nodes and adds none."""
    return bool((before & ~after).any() and not (after & ~before).any())


def free_mask(n: int, B: np.ndarray, active: np.ndarray) -> np.ndarray:
    """The free set F of the active set ``active`` (a mask over ``B``), as a mask over all nodes."""
    free = np.ones(n, dtype=bool)
    free[B[active]] = False
    return free


def iterate(
    systems: NewtonSystems,
    A: sp.csr_matrix,
    b: np.ndarray,
    B: np.ndarray,
    active: np.ndarray,
    max_iter: int,
    frontier_growth: bool,
    callback: StepCallback | None,
    log: logging.Logger,
    settle: Settle | None = None,
    first_reach: int = 1,
) -> tuple[np.ndarray, np.ndarray, list[dict]]:
    """Newton steps from the mask ``active`` until the set repeats on an accurate solve:
    ``(u, active, history)``.  Inexact solves while the set moves; a set that repeats on one is
    solved again accurately, and a change found then goes on inexactly.  A cycle of sets switches
    to accurate solves for good; a cycle of accurate ones, or ``max_iter`` steps, raises
    ``NotConvergedError``.  With ``settle``, an inexact step that only releases nodes is handed to
    it (at most ``MAX_SETTLES`` times), and the iteration goes on from the set and iterate it
    returns (``solvers.local``); the final test is the same.  ``first_reach``: the frontier's reach
    in the first step (``Frontier``)."""
    t0 = time.perf_counter()
    frontier = Frontier(boundary_adjacency(A, B), first_reach) if frontier_growth else None
    seen: set[bytes] = set()
    history: list[dict] = []
    accurate = always = systems.exact
    settles = 0
    for it in range(1, max_iter + 1):
        u = None  # the previous iterate is not needed: one vector less while the next step solves
        u = systems(free_mask(b.size, B, active), accurate)
        new_active = next_active(A, b, B, u, active, frontier)
        counters = systems.counters()
        if settle is not None and not accurate and settles < MAX_SETTLES and releases_only(active, new_active):
            settled = settle(u, active, new_active)
            if settled is not None:
                u, new_active, local = settled
                counters |= local
                settles += 1
        row = {
            "iteration": it,
            "active": int(active.sum()),
            "changes": int(np.count_nonzero(new_active != active)),
            **counters,
            "elapsed_s": time.perf_counter() - t0,
        }
        history.append(row)
        extra = ", ".join(f"{k}={v:.1e}" if isinstance(v, float) else f"{k}={v}" for k, v in counters.items())
        # progress of long solves: one line per Newton step
        log.info(
            "iteration %d: %d active, %d changes, %s, %.2f s",
            it,
            row["active"],
            row["changes"],
            extra,
            row["elapsed_s"],
        )
        if callback is not None:
            callback(dict(row))
        if np.array_equal(new_active, active):
            if accurate:
                return u, active, history
            accurate = True  # the set repeated on an inexact solve: the same set again, accurately
            continue
        key = np.packbits(new_active).tobytes()
        if key in seen:
            if always:
                raise NotConvergedError(f"active set cycles after {it} iterations")
            always = True  # a cycle of inexact steps: go on with accurate ones only
            seen.clear()
        seen.add(np.packbits(active).tobytes())
        active, accurate = new_active, always
    raise NotConvergedError(f"active set did not repeat within max_iter={max_iter} iterations")


def certified_result(
    A: sp.csr_matrix,
    b: np.ndarray,
    B: np.ndarray,
    u: np.ndarray,
    active: np.ndarray,
    kkt_tol: float,
    t0: float,
    solver: str,
    info: dict,
    history: list[dict],
) -> SolveResult:
    """The multiplier ``λ = (A u - b)_𝒜`` of the final set, the KKT certificate, the result;
    ``KKTError`` when the certificate exceeds ``kkt_tol``."""
    lam = np.where(active, (A @ u - b)[B], 0.0)
    u[B[active]] = 0.0
    cert = kkt_certificate(A, b, B, u, lam, kkt_tol)
    result = SolveResult(
        u=u,
        lam=lam,
        active=B[active],
        iterations=len(history),
        wall_time_s=time.perf_counter() - t0,
        certificate=cert,
        solver=solver,
        info=info,
        history=history,
    )
    if not cert.ok:
        raise KKTError(f"{solver} solution fails its KKT certificate", cert)
    return result
