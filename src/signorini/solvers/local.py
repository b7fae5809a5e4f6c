"""Settling a release of contact nodes on a patch: the multigrid route's shortcut through the
release phase of the active-set iteration.

From a contact set that is too large at a *degenerate* end of the contact zone, where u and λ
both vanish to second order (on the paper's problem the end on the right edge, where the exact
solution is biactive), each Newton step releases about half of the nodes still in excess: the
iteration is Newton's method at a double root.  The cascade's start is such a superset, in
excess there by a few coarse cells, so the fine solve spends log₂ of the excess in Newton steps
of a few global V-cycles each, every one of them moving only the end of the zone.

``settle_release`` solves the obstacle problem on a patch instead: the nodes within
``patch_levels`` graph neighbours of the released ones, every other node held at the current
iterate (its Dirichlet data), by the direct route (exact, certified).  The patch's contact set
and values replace the iterate's there, and the global iteration goes on from them; its final
test (the set repeats on an accurate global solve, ``pdas.iterate``) is unchanged, so the
solution and its certificate are the plain iteration's.

Only pure releases are settled.  Where a step adds nodes the local problem is ill-informed: near
a degenerate end u is of the order of the inexact global solve's error, and adding contact at
one end of the zone lifts the other end, which the patch's frozen data cannot see; a local solve
there moves the end as far as the patch reaches (measured on the paper's problem at N = 501 and
1001: docs/evidence/design-measurements.md#multigrid-local-release).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from signorini.solvers.certificate import KKTError, NotConvergedError
from signorini.solvers.stencil import StencilOperator, concatenated_ranges, entries

PATCH_MIN_LEVELS = 32  # a patch reaches at least this many graph neighbours beyond the released nodes
PATCH_REACH = 4  # … and this many times as far as nodes were released (the end may move as far again)
PATCH_MAX_FRACTION = 1 / 16  # a larger patch is not local: the global iteration goes on instead


def neighbourhood(A: sp.csr_matrix | StencilOperator, seeds: np.ndarray, levels: int, limit: int) -> np.ndarray | None:
    """The mask of the nodes within ``levels`` steps of ``seeds`` in the graph of ``A``, or None
    once they exceed ``limit`` nodes.  Work in O(the nodes found), besides the mask."""
    inside = np.zeros(A.shape[0], dtype=bool)
    inside[seeds] = True
    front, count = np.asarray(seeds), len(seeds)
    for _ in range(levels):
        reached = np.unique(A.indices[concatenated_ranges(A.indptr[front], A.indptr[front + 1])])
        front = reached[~inside[reached]]
        if front.size == 0:
            break
        inside[front] = True
        count += front.size
        if count > limit:
            return None
    return inside


def patch_problem(
    A: sp.csr_matrix | StencilOperator, b: np.ndarray, u: np.ndarray, patch: np.ndarray, inside: np.ndarray
) -> tuple[sp.csr_matrix, np.ndarray]:
    """The matrix ``A`` restricted to the sorted nodes ``patch`` (``inside`` their mask) and the load
    with the rest of ``u`` as Dirichlet data, ``b_p - A_{p,outside} u_outside``.  Work in O(the
    patch's stored entries): no pass over all n nodes, no column slicing (which maps all n)."""
    starts, ends = A.indptr[patch], A.indptr[patch + 1]
    positions = concatenated_ranges(starts, ends)
    row = np.repeat(np.arange(patch.size), ends - starts)
    cols, data = A.indices[positions], entries(A, positions, patch[row])
    keep = inside[cols]
    outside = np.bincount(row[~keep], weights=data[~keep] * u[cols[~keep]], minlength=patch.size)
    indptr = np.concatenate([[0], np.cumsum(np.bincount(row[keep], minlength=patch.size))])
    matrix = sp.csr_matrix((data[keep], np.searchsorted(patch, cols[keep]), indptr), shape=(patch.size,) * 2)
    return matrix, b[patch] - outside


def settle_release(
    A: sp.csr_matrix | StencilOperator,
    b: np.ndarray,
    B: np.ndarray,
    u: np.ndarray,
    before: np.ndarray,
    active: np.ndarray,
    kkt_tol: float,
) -> tuple[np.ndarray, np.ndarray, dict] | None:
    """The iterate ``u`` (solved with the contact set ``before``) and the contact set ``active``
    a Newton step shrank it to (masks over ``B``) settled on the patch around the released nodes:
    ``(u, active, row)``, ``u`` changed in place on the patch (a copy would be n numbers), ``row``
    the patch's unknowns, its Newton steps, the nodes it changed and its seconds.  None (``u``
    unchanged) when nothing was released, the patch is not local (``PATCH_MAX_FRACTION``) or its
    solve fails."""
    from signorini.solvers.active_set import active_set_solve

    t0 = time.perf_counter()
    released = B[before & ~active]
    if released.size == 0:
        return None
    levels = max(PATCH_MIN_LEVELS, PATCH_REACH * released.size)
    inside = neighbourhood(A, released, levels, int(PATCH_MAX_FRACTION * A.shape[0]))
    if inside is None:
        return None
    patch = np.flatnonzero(inside)
    matrix, load = patch_problem(A, b, u, patch, inside)
    at = np.flatnonzero(inside[B])  # the constrained nodes in the patch: positions in B …
    local_B = np.searchsorted(patch, B[at])  # … and in the patch
    # the start: the step's contact set (zeros) and the iterate elsewhere, kept off zero so the
    # route's first set is exactly the step's
    start = np.maximum(u[patch], np.finfo(float).tiny)
    start[local_B[active[at]]] = 0.0
    try:
        result = active_set_solve(matrix, load, local_B, warm_start=start, kkt_tol=kkt_tol)
    except (NotConvergedError, KKTError):
        return None
    u[patch] = result.u
    in_contact = np.zeros(patch.size, dtype=bool)
    in_contact[result.active] = True
    settled = active.copy()
    settled[at] = in_contact[local_B]
    row = {
        "local_unknowns": int(patch.size),
        "local_iterations": int(result.iterations),
        "local_changes": int(np.count_nonzero(settled != active)),
        "local_s": time.perf_counter() - t0,
    }
    return u, settled, row
