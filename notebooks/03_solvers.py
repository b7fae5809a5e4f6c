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
# # 03 · Solvers: work-precision results and one solver's iteration history
#
# Part 1 shows the outputs of the work-precision study (`paper_figures/work_precision.*`,
# `cost_of_accuracy.*`: error against run time for every solver and tolerance) when it has
# been built. Part 2 is a **live demonstration** computed here on one small mesh, not the
# study's results: the exact active-set solver's iteration history (from its own log
# messages) and cvxpy/OSQP at its default and at a tight tolerance, against the certified
# solution.

# %%
import time

import matplotlib.pyplot as plt
import pandas as pd
from IPython.display import display

from signorini import explore
from signorini.fem.discrete import build
from signorini.fem.mesh import mesh_width
from signorini.fem.norms.conventional import evaluate_norms
from signorini.fem.solve import solve_discrete

scene = explore.locate_scene()
print(f"scene {scene.name!r} under {scene.dir}: N = {scene.Ns}")

# %% [markdown]
# ## Part 1: the work-precision study (when built)

# %%
outputs = explore.existing(
    scene.root,
    "paper_figures/work_precision.md",
    "paper_figures/work_precision.csv",
    "paper_figures/work_precision.png",
    "paper_figures/cost_of_accuracy.png",
)
if outputs:
    for obj in explore.display_artifacts(outputs):
        display(obj)
else:
    print(f"The work-precision study has not been built under {scene.root / 'paper_figures'} "
          "(no work_precision.* files): only the live demonstration below is shown.")
runs = scene.root / "results" / "work_precision"
if runs.exists():
    print(f"cached runs: {sum(1 for _ in runs.rglob('*.json'))} JSON artifacts under {runs}")

# %% [markdown]
# ## Part 2 (live demonstration): the active-set solver, step by step
#
# One cold solve (no warm start) on the mesh `N_demo`. Each row is one semismooth Newton
# step: the size of the active (contact) set, how many boundary nodes change status, and
# the cumulative factorisations and correction columns (a small change of the active set is a
# low-rank update: the old factor bordered by one column per changed node, each column one
# triangular solve, computed once and reused by later steps). The iteration stops when the set
# repeats; the answer is certified by its relative KKT residuals.

# %%
N_demo = 41
disc = build(scene.problem, N_demo, scene.diagonal)
exact, history = explore.active_set_history(disc, warm_start=None)
summary = exact.summary()
print(f"N = {N_demo}: {disc.b.size} unknowns, {disc.boundary.size} constrained; {exact.iterations} iterations, "
      f"{summary['factorizations']} factorisations, {summary['correction_columns']} correction columns, "
      f"{1e3 * exact.wall_time_s:.0f} ms; KKT worst residual {exact.certificate.worst:.1e}")
fig, ax = plt.subplots(figsize=(7, 3.8))
ax.plot(history["iteration"], history["active"], "o-", label="active nodes")
ax.bar(history["iteration"], history["changes"], color="C1", alpha=0.6, label="nodes changing status")
ax.set(xlabel="Newton step", ylabel="nodes", title=f"primal-dual active set, cold start, N = {N_demo}")
ax.legend()
plt.show()
display(history.set_index("iteration"))

# %% [markdown]
# ## Part 2 (live demonstration): cvxpy/OSQP at two tolerances
#
# OSQP's default tolerance (`1e-3`) and a tight one (`1e-8`), without the certificate check
# (`check=False`), against the certified active-set solution: KKT residuals, the largest
# nodal difference, the contact set, and the total errors `‖u − u_h‖` in `L⁴` and `W^{1,4}`.

# %%
mesh = disc.mesh
names = ["L4", "W14"]
rows = []
for label, result in [("direct (exact)", exact)] + [
    (f"cvxpy_osqp tol={tol:g}", solve_discrete(disc, "cvxpy_osqp", tol=tol, check=False)) for tol in (1e-3, 1e-8)
]:
    t0 = time.perf_counter()
    err = evaluate_norms(scene.problem, mesh, result.u, names, scene.conventions)
    rows.append({
        "solver": label,
        "iterations": result.iterations,
        "wall time [ms]": 1e3 * result.wall_time_s,
        "KKT worst": result.certificate.worst,
        "max |u_h − u_h^exact|": float(abs(result.u - exact.u).max()),
        "contact nodes": result.active.size,
        **{f"‖u − u_h‖_{n}": err[n] for n in names},
    })
table = pd.DataFrame(rows).set_index("solver")
for n in names:
    table[f"{n} vs exact [%]"] = 100 * (table[f"‖u − u_h‖_{n}"] / table.loc["direct (exact)", f"‖u − u_h‖_{n}"] - 1)
print(f"h = 1/{N_demo} = {mesh_width(N_demo):.4f}")
display(table)
