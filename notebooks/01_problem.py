# ---
# jupyter:
#   jupytext:
#     formats: ipynb,py:percent
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.6
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # 01 · The problem: manufactured solution, contact set, discrete solution, error map
#
# Christof & Haubner, Section 7: on the unit square, find `u ≥ 0` on `∂Ω` with
# `-Δu + c u = f` and the Signorini conditions `u ≥ 0`, `∂_n u ≥ 0`, `u ∂_n u = 0` on `∂Ω`.
# The exact solution is manufactured: `u = A ψ(r) ũ(r, θ)` with `ũ = -r^{3/2} sin(3θ/2)`
# in polar coordinates around the free point `(x0, 0) = (0.5, 0)`, a degree-9 cut-off
# `ψ` with support radius `R = 0.45`, and `f = -Δu + c u` (`signorini.fem.problem.Problem`).
#
# This notebook reads the scene chosen by `signorini.explore.locate_scene`: `paper` if the
# pipeline has built it (`make all`), else `smoke` (built here with Snakemake if missing;
# override with `SIGNORINI_SCENE=<name>`). Everything is computed by the package: the
# notebook only plots.

# %%
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from matplotlib.colors import LogNorm
from matplotlib.tri import Triangulation

from signorini import explore
from signorini.fem.mesh import boundary_nodes, mesh_width
from signorini.studies.paper.figures import figure2

scene = explore.locate_scene()
problem = scene.problem
print(f"scene {scene.name!r} under {scene.dir}: N = {scene.Ns}")
print(problem)

# %% [markdown]
# ## The solution `u` and the right-hand side `f` (the paper's Figure 2)
#
# Surfaces (top) and contour views (bottom) of the sampled fields (`results/<scene>/fields.npz`
# when the `sample` rule has run, else the same grid evaluated through `Problem`). The
# white dot is the free point `(0.5, 0)`: left of it `u > 0` on the bottom edge, right of it
# `u = 0` (contact).

# %%
fields = scene.fields()
X, Y = fields["x"], fields["y"]
fig = plt.figure(figsize=(11, 9))
surfaces, contours = fig.subfigures(2, 1)
figure2(fields, fig=surfaces)  # the paper's Figure 2, as in paper_figures/figure2.png
titles = {"u": "solution $u$", "f": r"right-hand side $f = -\Delta u + c\,u$"}
for ax, key in zip(contours.subplots(1, 2), ("u", "f"), strict=True):
    cs = ax.contourf(X, Y, fields[key], levels=30, cmap="viridis")
    ax.contour(X, Y, fields[key], levels=[0.0], colors="w", linewidths=0.8)
    ax.plot(problem.x0, 0.0, "o", color="w", markeredgecolor="k")
    ax.set(xlabel="$x_1$", ylabel="$x_2$", aspect="equal", title=f"{titles[key]} (contours, white: 0)")
    contours.colorbar(cs, ax=ax, shrink=0.8)
plt.show()

# %% [markdown]
# ## The cut-off `ψ`
#
# `ψ(r) = 1 - S(r/R)` with the degree-9 smoothstep `S`: `ψ(0) = 1`, `ψ^{(k)}(0) = 0` for
# `k = 1..4` and `ψ^{(k)}(R) = 0` for `k = 0..4` (so `u ∈ C⁴` away from the free point,
# and `f` stays bounded).

# %%
r = np.linspace(0.0, 1.1 * problem.R, 400)
fig, ax = plt.subplots(figsize=(7, 3.5))
ax.plot(r, problem.psi(r), label=r"$\psi$")
ax.plot(r, problem.R * problem.dpsi(r), label=r"$R\,\psi'$")
ax.plot(r, problem.R**2 * problem.d2psi(r) / 10, label=r"$R^2\,\psi''/10$")
ax.axvline(problem.R, color="k", linewidth=0.6, linestyle=":")
ax.set(xlabel="$r$", title=f"cut-off, support radius R = {problem.R}")
ax.legend()
ax.grid(alpha=0.3)
plt.show()

# %% [markdown]
# ## The exact contact set on the boundary
#
# `∂Ω` unrolled counter-clockwise from `(0, 0)`: `s ∈ [0, 1)` bottom, `[1, 2)` right,
# `[2, 3)` top, `[3, 4)` left edge. The contact set `{u = 0}` is all of `∂Ω` except the
# segment `(x0 − R, x0) × {0}` of the bottom edge; the normal derivative (the multiplier of
# the continuous problem) is positive only on `(x0, x0 + R) × {0}`, the strictly active part.
# Elsewhere on the contact set `u = ∂_n u = 0` (biactive).

# %%
trace = explore.boundary_trace(problem)
s, ub, dn = trace["s"], trace["u"], trace["dn_u"]
free = s[ub > 0]
strict = s[dn > 0]
print(f"u > 0 on the bottom edge for x1 in ({free.min():.3f}, {free.max():.3f}); exact: (x0 - R, x0) = "
      f"({problem.x0 - problem.R:g}, {problem.x0:g})")
print(f"∂_n u > 0 for x1 in ({strict.min():.3f}, {strict.max():.3f}); exact: (x0, x0 + R) = "
      f"({problem.x0:g}, {problem.x0 + problem.R:g})")
print(f"min over ∂Ω: u = {ub.min():.2e}, ∂_n u = {dn.min():.2e}  (Signorini: both ≥ 0)")

fig, ax = plt.subplots(figsize=(10, 3.5))
ax.plot(s, ub, label="$u$")
ax.plot(s, dn, label=r"$\partial_n u$")
ax.fill_between(s, 0, 1, where=ub <= 0, transform=ax.get_xaxis_transform(), color="0.85", label="contact $u = 0$")
for k in range(1, 4):
    ax.axvline(k, color="k", linewidth=0.5)
ax.set(xlabel="arc length $s$ (bottom, right, top, left)", title="boundary traces")
ax.legend(loc="upper right")
plt.show()

# %% [markdown]
# ## The discrete solution `u_h` and the multiplier `λ` on one mesh
#
# `N` below picks the mesh (default: the finest mesh of the scene with `N ≤ 201`). The
# solution is the pipeline's cached `results/<scene>/N<N>/solution.npz` (checksum
# verified); its KKT certificate comes from `solution.json`.
#
# `λ = A u_h − b` on the boundary nodes is the discrete counterpart of `∂_n u`: with the
# P1 hat function `φ_i`, `λ_i ≈ ∫ ∂_n u φ_i ds ≈ h ∂_n u(x_i)` on an edge, so `λ_i / h` is
# plotted against `∂_n u`.

# %%
N = max([n for n in scene.Ns if n <= 201] or scene.Ns[:1])
sol, info = scene.solution(N), scene.solution_info(N)
mesh = scene.mesh(N)
h = mesh_width(N)
B = boundary_nodes(mesh)
print(f"N = {N}, h = 1/{N}: {info['n_dofs']} unknowns, {info['n_constrained']} constrained, "
      f"{sol['active'].size} in contact; solver {info['summary']['solver']}, "
      f"{info['summary']['iterations']} iterations; certificate worst residual "
      f"{info['summary']['certificate']['worst']:.1e}")

tri = Triangulation(mesh.p[0], mesh.p[1], mesh.t.T)
fig, axes = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1, 1.3]})
ax = axes[0]
tc = ax.tripcolor(tri, sol["u"], shading="gouraud", cmap="viridis")
contact = mesh.p[:, sol["active"]]
ax.plot(contact[0], contact[1], "s", markersize=2.5, color="r", label="discrete contact set")
ax.plot(problem.x0, 0.0, "o", color="w", markeredgecolor="k", label="free point")
ax.set(aspect="equal", title=f"$u_h$, N = {N}", xlabel="$x_1$", ylabel="$x_2$")
ax.legend(loc="upper right", fontsize=8)
fig.colorbar(tc, ax=ax, shrink=0.85)

ax = axes[1]
sB = explore.boundary_arclength(mesh.p[:, B])
order = np.argsort(sB)
ax.plot(s, dn, label=r"$\partial_n u$ (exact)")
ax.plot(sB[order], sol["lam"][order] / h, ".", markersize=4, label=r"$\lambda_i / h$")
ax.plot(sB[order], sol["u"][B][order], ".", markersize=3, label=r"$u_h$ on $\partial\Omega$")
ax.plot(s, ub, linewidth=0.8, label="$u$ on $\\partial\\Omega$")
ax.set(xlim=(0, 1), xlabel="$x_1$ on the bottom edge", title="multiplier and boundary values (bottom edge)")
ax.legend(fontsize=8)
fig.tight_layout()
plt.show()

on_bottom = mesh.p[1, sol["active"]] == 0.0
x_contact = mesh.p[0, sol["active"][on_bottom]]
exact_contact = problem.u(mesh.p[:, B]) == 0.0
print(f"discrete contact set: {sol['active'].size} of {B.size} boundary nodes; on the bottom edge "
      f"x1 in [{x_contact.min():.4f}, {x_contact.max():.4f}] (exact strictly active part: "
      f"({problem.x0:g}, {problem.x0 + problem.R:g}))")
print(f"on the rest of the exact contact set (biactive, u = ∂_n u = 0) u_h ≥ 0 need not vanish: "
      f"max u_h there = {sol['u'][B][exact_contact].max():.1e} (max u = {ub.max():.2f}, h² = {h * h:.1e})")

# %% [markdown]
# ## Where the error sits: the pointwise error map
#
# Per triangle, `max |u − u_h|` over the `L^∞` point set and `max |∇(u − u_h)|` over the
# `W^{1,∞}` point set (the scene's norm conventions; `signorini.fem.norms.conventional.error_field`). The
# gradient error is singular at the free point `(0.5, 0)`, where `u ~ r^{3/2}`. The value
# error concentrates there too, but only once `h` is small enough: its `O(h^{3/2})` peak at
# the free point competes with the `O(h²)` interpolation error of the smooth but strongly
# curved part of `u` (its minimum near `(0.6, 0.16)`). On the paper's meshes the maximum moves
# to the free point between `h = 1/101` and `h = 1/201` — which is also why the published
# `L^∞` EOC at `h = 1/201` (1.64) lies above the asymptotic 3/2. The table after the maps
# shows it for every mesh of the scene.

# %%
err = explore.element_errors(problem, mesh, sol["u"], scene.conventions)
r_T = np.hypot(err["centroid"][0] - problem.x0, err["centroid"][1])  # distance of each triangle to the free point
fig, axes = plt.subplots(2, 2, figsize=(12, 9.5), gridspec_kw={"height_ratios": [1.5, 1]})
labels = {"e": r"$\max_T |u-u_h|$", "grad_e": r"$\max_T |\nabla(u-u_h)|$"}
for col, key in enumerate(("e", "grad_e")):
    vmax = err[key].max()
    i = err[key].argmax()
    where = f"({err['centroid'][0, i]:.3f}, {err['centroid'][1, i]:.3f})"
    ax = axes[0, col]
    norm = LogNorm(vmin=vmax * 1e-4, vmax=vmax)
    tp = ax.tripcolor(tri, facecolors=np.clip(err[key], vmax * 1e-4, None), norm=norm, cmap="magma")
    ax.plot(*err["centroid"][:, i], "c*", markersize=14, label=f"max {vmax:.2e} at {where}")
    ax.plot(problem.x0, 0.0, "o", color="w", markeredgecolor="k", label="free point")
    ax.set(aspect="equal", xlabel="$x_1$", ylabel="$x_2$", title=f"{labels[key]}, N = {N}")
    ax.legend(loc="upper right", fontsize=8)
    fig.colorbar(tp, ax=ax, shrink=0.8)
    ax = axes[1, col]
    ax.loglog(r_T, err[key], ",", color="0.3", alpha=0.5)
    ax.loglog(r_T[i], err[key][i], "c*", markersize=14)
    ax.axvline(h, color="k", linestyle=":", label="$r = h$")
    ax.set(xlabel="distance $r$ of the triangle to the free point", ylabel=labels[key], ylim=(vmax * 1e-4, 2 * vmax),
           title="the same values against the distance to the free point")
    ax.legend(loc="lower left", fontsize=8)
fig.tight_layout()
plt.show()

# %% [markdown]
# On every mesh of the scene: where is the maximum, and how does the error near the free point
# (triangles with centroid at distance `r < 0.05` from it) compare with the rest?

# %%
rows = []
for n in scene.Ns:
    m = scene.mesh(n)
    ee = explore.element_errors(problem, m, scene.solution(n)["u"], scene.conventions)
    c = ee["centroid"]
    near = np.hypot(c[0] - problem.x0, c[1]) < 0.05
    i, j = ee["e"].argmax(), ee["grad_e"].argmax()
    rows.append({
        "h": f"1/{n}",
        "argmax |e|": f"({c[0, i]:.3f}, {c[1, i]:.3f})",
        "max |e| near": ee["e"][near].max(),
        "max |e| elsewhere": ee["e"][~near].max(),
        "argmax |∇e|": f"({c[0, j]:.4f}, {c[1, j]:.4f})",
        "max |∇e| near": ee["grad_e"][near].max(),
        "max |∇e| elsewhere": ee["grad_e"][~near].max(),
    })
pd.DataFrame(rows).set_index("h")
