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
# # 04 · Stability: the atlas and a drill-down
#
# Part 1 shows the stability atlas (`paper_figures/stability.*`: every extreme case × solver,
# coloured by status) when it has been built. Part 2 is a **live demonstration** computed
# here with the exact active-set solver on small meshes, not the atlas's results:
#
# - *data scaling*: the amplitude `A` multiplied by `10⁶` must scale `u_h` and `λ` by `10⁶`
#   and leave the contact set, the relative errors and the relative KKT residuals unchanged;
# - *mesh extremes*: `N = 2` (the free point `(0.5, 0)` is a node) and `N = 3` (the free
#   segment `(0.05, 0.5) × {0}` holds one boundary node) must still give a certified answer.

# %%
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from IPython.display import display

from signorini import explore
from signorini.fem.discrete import build
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.problem import ExactProblem, make_problem
from signorini.fem.solve import solve_discrete

scene = explore.locate_scene()
print(f"scene {scene.name!r} under {scene.dir}: N = {scene.Ns}")
NAMES = ["L4", "Linf", "W14", "W1inf", "H12"]

# %% [markdown]
# ## Part 1: the stability atlas (when built)

# %%
outputs = explore.existing(
    scene.root, "paper_figures/stability.md", "paper_figures/stability.csv", "paper_figures/stability.png"
)
if outputs:
    for obj in explore.display_artifacts(outputs):
        display(obj)
    if "paper_figures/stability.csv" in outputs:
        atlas = pd.read_csv(outputs["paper_figures/stability.csv"], comment="#", encoding="utf-8")
        if "status" in atlas.columns:
            print("status counts:", atlas["status"].value_counts().to_dict())
else:
    print(f"The stability atlas has not been built under {scene.root / 'paper_figures'} "
          "(no stability.* files): only the live demonstration below is shown.")


# %% [markdown]
# ## Part 2 (live demonstration): data scaling, `A = 10` against `A = 10⁷`

# %%
def solve_case(problem: ExactProblem, N: int):
    """Assemble, solve exactly (certified), and return the relative errors ‖u − u_h‖ / ‖u‖
    (‖u‖ evaluated as the error of u_h = 0, with the same quadrature)."""
    disc = build(problem, N, scene.diagonal)
    result = solve_discrete(disc, "direct", warm_start=None)
    err = evaluate_norms(problem, disc.mesh, result.u, NAMES, scene.conventions)
    size = evaluate_norms(problem, disc.mesh, np.zeros_like(result.u), NAMES, scene.conventions)
    return disc, result, {n: err[n] / size[n] for n in NAMES}


N_scale = 41
base = scene.problem
scale = 1e6
disc1, res1, rel1 = solve_case(base, N_scale)
disc2, res2, rel2 = solve_case(make_problem({**base.as_dict(), "A": base.A * scale}), N_scale)
same_set = np.array_equal(res1.active, res2.active)
comparison = pd.DataFrame({f"A = {base.A:g}": rel1, f"A = {base.A * scale:g}": rel2})
comparison["relative difference"] = (comparison.iloc[:, 1] - comparison.iloc[:, 0]) / comparison.iloc[:, 0].abs()
comparison.index.name = "‖u − u_h‖ / ‖u‖"
print(f"N = {N_scale}: same contact set: {same_set} ({res1.active.size} nodes); iterations "
      f"{res1.iterations} and {res2.iterations}; KKT worst residuals {res1.certificate.worst:.1e} and "
      f"{res2.certificate.worst:.1e}")
print(f"max |u_h(A·{scale:g}) / {scale:g} − u_h(A)| / max |u_h(A)| = "
      f"{abs(res2.u / scale - res1.u).max() / abs(res1.u).max():.1e}; for the multiplier λ: "
      f"{abs(res2.lam / scale - res1.lam).max() / abs(res1.lam).max():.1e}")
display(comparison)

# %% [markdown]
# ## Part 2 (live demonstration): the coarsest meshes, `N = 2` and `N = 3`

# %%
rows, cases = [], {}
for N in (2, 3):
    disc, result, rel = solve_case(base, N)
    cases[N] = (disc, result)
    bottom = disc.boundary[disc.mesh.p[1, disc.boundary] == 0.0]
    rows.append({
        "N": N,
        "unknowns": disc.b.size,
        "bottom nodes x1": np.round(disc.mesh.p[0, bottom], 3).tolist(),
        "u_h on the bottom edge": np.round(result.u[bottom], 4).tolist(),
        "contact nodes": result.active.size,
        "iterations": result.iterations,
        "KKT worst": result.certificate.worst,
        **{f"rel. {n}": rel[n] for n in NAMES},
    })
coarse = pd.DataFrame(rows).set_index("N")
display(coarse.T)

# %%
from matplotlib.tri import Triangulation  # noqa: E402

fig, axes = plt.subplots(1, 2, figsize=(10, 4.4))
for ax, (N, (disc, result)) in zip(axes, cases.items(), strict=True):
    m = disc.mesh
    tri = Triangulation(m.p[0], m.p[1], m.t.T)
    tc = ax.tripcolor(tri, result.u, shading="gouraud", cmap="viridis")
    ax.triplot(tri, color="w", linewidth=0.6)
    ax.plot(base.x0, 0.0, "o", color="w", markeredgecolor="k", markersize=10, label="free point")
    ax.plot(*m.p[:, result.active], "rs", markersize=5, label="contact nodes")
    ax.set(aspect="equal", title=f"$u_h$, N = {N}")
    fig.colorbar(tc, ax=ax, shrink=0.8)
axes[0].legend(loc="upper right", fontsize=8)
fig.tight_layout()
plt.show()
