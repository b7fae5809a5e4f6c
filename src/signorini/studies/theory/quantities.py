"""Quantities behind the paper's theorems that its tables do not show, and the stage
``theory_quantities`` that computes them per mesh.

- ``ritz_projection``: ``R_h u ∈ V_h`` with ``(R_h u, w_h)_{H¹} = (u, w_h)_{H¹}`` for all
  ``w_h`` (Definition 3.1, with the problem's reaction coefficient: ``∫ ∇R_h u·∇w + c R_h u w
  = ∫ ∇u·∇w + c u w``), its right-hand side from the exact ``u`` and ``∇u`` by quadrature over
  chunks of triangles, its system ``(K + c M) r = ...`` solved by conjugate gradients with the
  multigrid route's V-cycle (``ritz_solve``): time and memory in O(n), where
  a sparse factorisation took more than twice the time and memory at N = 2001
  (``docs/evidence/stage_jobs_N2001.json``, baseline against tree) and needs more than this
  machine at N = 4001.  It is
  not the unconstrained problem with ``f``: ``u`` carries the boundary flux ``∂_n u``.
- ``supercloseness``: ``‖R_h u - u_h‖_{H¹}``, Theorem 3.6 predicts ``O(h^{3/2-ε})``.
- ``boundary_h12_norm``: the discrete interpolation norm ``vᵀ M (M⁻¹(K + M))^{1/2} v`` of
  ``H^{1/2}(∂Ω) = [L²(∂Ω), H¹(∂Ω)]_{1/2}`` for the error interpolated on a refined
  boundary mesh, the "true" counterpart of the paper's interpolation estimate.
- ``contact_set``: the discrete contact set ``{x ∈ ∂Ω : u_h(x) = 0}`` as boundary
  segments, its end points near the free points and its Hausdorff distance to the
  exact contact set ``∂Ω \\ (x0 - R, x0) × {0}``.
"""

from __future__ import annotations

import logging
import os
import time
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from skfem import MeshTri
from skfem.quadrature import get_quadrature
from skfem.refdom import RefTri

from signorini.fem.assembly import CHUNK_ELEMENTS, INTORDER, accumulate, p1_values, quadrature_chunks, system_matrix
from signorini.fem.derivatives import u_and_grad_u
from signorini.fem.mesh import boundary_nodes
from signorini.fem.problem import Problem, compiled_points_for

if TYPE_CHECKING:
    from signorini.studies.scene.store import SceneMesh

log = logging.getLogger(__name__)

RITZ_TOL = 1e-14  # energy-relative accuracy of R_h u: the multigrid route's final accuracy
RITZ_MAX_ITER = 500
# the gradients of the P1 shape functions on the reference triangle, (shape function, coordinate)
_REFERENCE_GRADIENTS = np.array([[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]])


def ritz_rhs(problem: Problem, mesh: MeshTri, chunk: int = CHUNK_ELEMENTS) -> np.ndarray:
    """``(∫ ∇u·∇φ_i + c u φ_i)_i`` from the exact ``u`` and ``∇u``, the right-hand side of ``R_h u``.

    The package's 16-point degree-8 rule on every triangle, over chunks of at most ``chunk``
    triangles (bounded memory at N = 4001); ``u`` and ``∇u`` are evaluated once per quadrature
    point, and the P1 gradients, constant on a triangle, once per triangle; the triangles outside
    the problem's ``support`` (where ``u`` and ``∇u`` are ``+0.0``) add nothing and are left out.
    """
    X, _ = get_quadrature(RefTri, INTORDER)
    values = np.stack(p1_values(X))  # (shape function, q)
    n = mesh.p.shape[1]
    b = np.zeros(n)
    for t, x, dx, inv in quadrature_chunks(mesh, chunk, support=problem.support()):
        u, gu = u_and_grad_u(problem, x)
        flux = np.stack([np.sum(gu[d] * dx, axis=1) for d in range(2)])  # ∫_T ∇u, (2, E)
        mass = (u * dx) @ values.T  # ∫_T u φ_k, (E, 3)
        for k in range(3):
            grad_phi = np.einsum("ije,i->je", inv, _REFERENCE_GRADIENTS[k])  # J⁻ᵀ ∇̂φ_k, (2, E)
            accumulate(b, t[k], flux[0] * grad_phi[0] + flux[1] * grad_phi[1] + problem.c * mass[:, k])
        del x, dx, u, gu, flux, mass
    return b


def ritz_solve(
    A: sp.spmatrix, rhs: np.ndarray, start: np.ndarray | None = None, info: dict | None = None
) -> np.ndarray:
    """``x`` with ``A x = rhs`` (``A`` symmetric positive definite) by conjugate gradients
    preconditioned with one V-cycle of the multigrid route (its ``GalerkinHierarchy`` of ``A``,
    every node free, and its ``pcg``), from ``start`` (zero if None) to the energy-relative
    accuracy ``RITZ_TOL``.  ``info``, when given, receives the iterations, the final energy
    residual and the seconds of the set-up and of the iteration.  Raises ``NotConvergedError``
    when CG does not reach ``RITZ_TOL`` within ``RITZ_MAX_ITER`` iterations."""
    from signorini.solvers.multigrid import GalerkinHierarchy, pcg

    A = sp.csr_matrix(A)
    t0 = time.perf_counter()
    vcycle = GalerkinHierarchy(A)
    t1 = time.perf_counter()
    x0 = np.zeros_like(rhs) if start is None else np.asarray(start, dtype=float)
    x, iterations, ratio = pcg(vcycle.matrix, rhs, x0, vcycle, RITZ_TOL, RITZ_MAX_ITER)
    if info is not None:
        info.update(
            method="CG, geometric multigrid V-cycle" if vcycle.grid else "CG, classical AMG V-cycle",
            levels=len(vcycle.levels),
            operator_complexity=float(vcycle.operator_complexity()),
            tol=RITZ_TOL,
            iterations=iterations,
            energy_residual=float(ratio),
            setup_s=t1 - t0,
            cg_s=time.perf_counter() - t1,
        )
    return x


def ritz_projection(
    problem: Problem,
    mesh: MeshTri,
    A: sp.spmatrix | None = None,
    chunk: int = CHUNK_ELEMENTS,
    start: np.ndarray | None = None,
    info: dict | None = None,
) -> np.ndarray:
    """Nodal values of ``R_h u``: ``A r = (∫ ∇u·∇φ_i + c u φ_i)_i`` with ``A = K + c M`` solved by
    ``ritz_solve`` from ``start`` (``info`` receives how).

    ``A`` is assembled (over chunks of ``chunk`` triangles) unless given; the right-hand
    side is ``ritz_rhs``.
    """
    A = system_matrix(mesh, problem.c, chunk=chunk) if A is None else A
    return ritz_solve(A, ritz_rhs(problem, mesh, chunk), start, info)


def h1_norm_p1(mesh: MeshTri, v: np.ndarray, A1: sp.spmatrix | None = None, chunk: int = CHUNK_ELEMENTS) -> float:
    """‖v‖_{H¹} = (vᵀ (K + M) v)^{1/2} for a P1 function (exact); ``A1`` = K + M if already assembled."""
    A1 = system_matrix(mesh, 1.0, chunk=chunk) if A1 is None else A1
    return float(np.sqrt(max(v @ (A1 @ v), 0.0)))


def supercloseness(
    problem: Problem,
    mesh: MeshTri,
    u_h: np.ndarray,
    chunk: int = CHUNK_ELEMENTS,
    A: sp.spmatrix | None = None,
    info: dict | None = None,
) -> float:
    """‖R_h u - u_h‖_{H¹} (Theorem 3.6: O(h^{3/2-ε})); ``A = K + c M`` (the discrete problem's
    matrix) assembled unless given, and reused for the H¹ norm when c = 1.  ``R_h u`` is computed
    from ``u_h`` (the two differ by O(h^{3/2})), ``info`` receives how (``ritz_solve``).

    Every assembly runs over chunks of at most ``chunk`` triangles (bounded memory).
    """
    A = system_matrix(mesh, problem.c, chunk=chunk) if A is None else A
    A1 = A if problem.c == 1.0 else None
    r = ritz_projection(problem, mesh, A, chunk, start=u_h, info=info)
    return h1_norm_p1(mesh, r - u_h, A1, chunk)


def _boundary_loop(mesh: MeshTri) -> np.ndarray:
    """Boundary vertices of the unit square in counter-clockwise order, starting at (0, 0)."""
    nodes = boundary_nodes(mesh)
    x, y = mesh.p[0, nodes], mesh.p[1, nodes]
    # arc-length parameter along bottom, right, top, left edges
    s = np.where(y <= 1e-12, x, np.where(x >= 1 - 1e-12, 1 + y, np.where(y >= 1 - 1e-12, 3 - x, 4 - y)))
    s[(x <= 1e-12) & (y <= 1e-12)] = 0.0
    return nodes[np.argsort(s)], np.sort(s)


def boundary_h12_norm(problem: Problem, mesh: MeshTri, u_h: np.ndarray, refine: int = 2) -> float:
    """Discrete H^{1/2}(∂Ω) norm of ``e = u - u_h`` on the boundary polygon refined ``refine`` times.

    On the closed boundary curve (arc length s ∈ [0, 4)) with P1 hat functions,
    ``‖v‖²_{1/2} = Σ_k μ_k^{1/2} (φ_kᵀ M v)²`` where ``(K + M) φ_k = μ_k M φ_k`` (generalised
    eigenpairs, M-orthonormal): the interpolation norm between L² and H¹ of the curve.
    On a uniformly spaced loop (Friedrichs–Keller meshes) K and M are circulant and the
    eigenpairs are Fourier modes, so the FFT evaluates the norm in O(n log n).
    The error is interpolated at the refined nodes (``u`` exact, ``u_h`` linear per edge).
    """
    loop, s = _boundary_loop(mesh)
    m = refine
    # refined arc-length nodes: m sub-points per coarse edge
    s_next = np.append(s[1:], 4.0)
    t = (np.arange(m) / m)[None, :]
    s_ref = (s[:, None] + (s_next - s)[:, None] * t).ravel()
    u_next = np.append(u_h[loop][1:], u_h[loop][0])
    uh_ref = (u_h[loop][:, None] * (1 - t) + u_next[:, None] * t).ravel()
    e = problem.u(_loop_points(s_ref)) - uh_ref
    n = s_ref.size
    hlen = np.diff(np.append(s_ref, 4.0))
    if np.allclose(hlen, hlen[0], rtol=1e-10):
        # uniform spacing: K and M are circulant, diagonalised by the FFT
        hh = hlen[0]
        theta = 2.0 * np.pi * np.arange(n) / n
        lam_k = (2.0 - 2.0 * np.cos(theta)) / hh
        lam_m = hh * (4.0 + 2.0 * np.cos(theta)) / 6.0
        coef2 = np.abs(np.fft.fft(e)) ** 2 / n
        return float(np.sqrt(np.sum(np.sqrt(lam_m * (lam_k + lam_m)) * coef2)))
    # general spacing: generalised eigenpairs of the periodic P1 matrices (dense)
    i, j = np.arange(n), (np.arange(n) + 1) % n
    rows, cols = np.concatenate([i, j, i, j]), np.concatenate([i, j, j, i])
    K = sp.coo_matrix((np.concatenate([1 / hlen, 1 / hlen, -1 / hlen, -1 / hlen]), (rows, cols)), shape=(n, n))
    M = sp.coo_matrix((np.concatenate([hlen / 3, hlen / 3, hlen / 6, hlen / 6]), (rows, cols)), shape=(n, n))
    K, M = K.toarray(), M.toarray()
    mu, phi = sla.eigh(K + M, M)
    coef = phi.T @ (M @ e)
    return float(np.sqrt(np.sum(np.sqrt(np.maximum(mu, 0.0)) * coef**2)))


def _loop_points(s: np.ndarray) -> np.ndarray:
    """Points of ∂Ω for arc-length parameters s ∈ [0, 4) (counter-clockwise from (0, 0))."""
    s = np.mod(s, 4.0)
    side = np.minimum(np.floor(s).astype(int), 3)
    r = s - side
    px = np.choose(side, [r, np.ones_like(r), 1 - r, np.zeros_like(r)])
    py = np.choose(side, [np.zeros_like(r), r, np.ones_like(r), 1 - r])
    return np.vstack([px, py])


def contact_set(problem: Problem, mesh: MeshTri, u_h: np.ndarray, samples_per_unit: int = 4000) -> dict:
    """The discrete contact set ``{x ∈ ∂Ω : u_h(x) = 0}`` against the exact one.

    The discrete set is the union of boundary edges with ``u_h = 0`` at both ends (and
    isolated contact vertices).  The exact contact set of the manufactured solution is
    ``C = ∂Ω \\ (x0 - R, x0) × {0}``.  Returns the end point of the discrete contact
    segment at the free point ``(x0, 0)``, the discrete contact point nearest to
    ``(x0 - R, 0)``, and the Hausdorff distance between the two sets (both sampled along
    the boundary at ``samples_per_unit`` points per unit length).
    """
    from scipy.spatial import cKDTree

    loop, s = _boundary_loop(mesh)
    zero = u_h[loop] == 0.0
    s_next = np.append(s[1:], 4.0)
    zero_next = np.append(zero[1:], zero[0])
    edge_in = zero & zero_next
    # sample the discrete set: contact vertices and points on contact edges
    pieces = [s[zero]]
    for a, b in zip(s[edge_in], s_next[edge_in], strict=True):
        pieces.append(np.linspace(a, b, max(2, int((b - a) * samples_per_unit))))
    s_disc = np.concatenate(pieces) if pieces else np.empty(0)
    s_all = np.linspace(0.0, 4.0, 4 * samples_per_unit, endpoint=False)
    in_exact = ~((s_all > problem.x0 - problem.R) & (s_all < problem.x0))  # bottom edge: s = x
    s_exact = s_all[in_exact]
    out = {"n_contact_nodes": int(zero.sum()), "n_boundary_nodes": int(zero.size)}
    if s_disc.size == 0:
        return {
            **out,
            "free_point_end": None,
            "free_point_offset": None,
            "nearest_to_x0_minus_R": None,
            "hausdorff": None,
        }
    disc_pts, exact_pts = _loop_points(s_disc), _loop_points(s_exact)
    d1 = cKDTree(disc_pts.T).query(exact_pts.T)[0].max()  # exact points far from the discrete set
    d2 = cKDTree(exact_pts.T).query(disc_pts.T)[0].max()  # discrete points far from the exact set
    # the discrete contact segment at the free point starts at the first contact vertex at or after x0 - h
    bottom = s_disc[s_disc <= 1.0]
    right_of = bottom[bottom >= problem.x0 - 0.5 * (problem.R)]
    end = float(right_of.min()) if right_of.size else None
    near = float(np.hypot(*(disc_pts - np.array([[problem.x0 - problem.R], [0.0]]))).min())
    return {
        **out,
        "free_point_end": end,
        "free_point_offset": None if end is None else end - problem.x0,
        "nearest_to_x0_minus_R": near,
        "hausdorff": float(max(d1, d2)),
        "hausdorff_exact_to_discrete": float(d1),
        "hausdorff_discrete_to_exact": float(d2),
    }


def theory_quantities(problem: Problem, mesh: MeshTri, u_h: np.ndarray, A: sp.spmatrix | None = None) -> dict:
    """Supercloseness, the discrete H^{1/2}(∂Ω) norm of the error and the contact-set metrics;
    ``A = K + c M`` of the discrete problem if at hand (else assembled), and under ``ritz`` how
    ``R_h u`` was solved (``ritz_solve``).  On large meshes ``u`` and ``∇u`` come from the compiled
    point kernels (``fem.problem.compiled_points_for``: the same bits)."""
    ritz: dict = {}
    with compiled_points_for(mesh.t.shape[1]):
        return {
            "supercloseness_H1": supercloseness(problem, mesh, u_h, A=A, info=ritz),
            "H12_discrete": boundary_h12_norm(problem, mesh, u_h),
            "contact": contact_set(problem, mesh, u_h),
            "ritz": ritz,
        }


def quantities_stage(
    at: SceneMesh, system_npz: str | os.PathLike, solution_npz: str | os.PathLike, out_json: str | os.PathLike
) -> dict:
    """Stage ``theory_quantities``: supercloseness, discrete H^{1/2}(∂Ω) norm and contact-set
    metrics of one solution; the matrix ``A = K + c M`` is the one of the mesh's ``discretise``
    archive."""
    from signorini.pipeline.artifacts import save_json
    from signorini.studies.scene.store import load_system

    u_h = at.load_solution(solution_npz)
    A, _, _ = load_system(system_npz, at.N)
    t0 = time.perf_counter()
    values = theory_quantities(at.problem, at.mesh(), u_h, A)
    info = {"N": at.N, "h": at.h, **values, "timings": {"theory_s": time.perf_counter() - t0}}
    log.info("N=%d %s", at.N, {k: v for k, v in values.items() if k not in ("contact", "ritz")})
    save_json(out_json, info)
    return info
