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
# # 02 · Convergence: Tables 1–2 next to the paper, Figure 3, the EOCs, any `p`
#
# The pipeline's `results/<scene>/errors.csv` (one row per mesh, one column per norm of
# `u − u_h`) and `eoc.csv` (`EOC_k = log(e_k/e_{k−1}) / log(h_k/h_{k−1})`, then the
# least-squares slope), next to the published values transcribed in
# `workflow/reference/paper_table{1,2}.csv`.
#
# Scene: `paper` if built (`make all`), else `smoke` (`N = 11, 21, 41`); set `SIGNORINI_SCENE`
# to choose any scene, your own included. The published values appear only next to the paper's
# scene (its problem, triangulation, norm conventions and meshes,
# `signorini.explore.published_mismatch`): any other scene's tables show its own values, and the
# notebook says why. The expected orders come from `signorini.published.expected_rate` for every norm
# of the grammar; where the paper states none the column says "no theory".

# %%
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
from IPython.display import display

from signorini import explore
from signorini.published import FIGURE3_NORMS, expected_rate, label_md, label_tex
from signorini.studies.paper.figures import figure3
from signorini.studies.theory.report import table2_rows

scene = explore.locate_scene()
print(f"scene {scene.name!r} under {scene.dir}: N = {scene.Ns}, norms {scene.norms}")
pd.set_option("display.width", 200)
errors, eoc = scene.errors(), scene.eoc()
published = explore.scene_published_mismatch(scene) is None
display(errors)

# %% [markdown]
# ## Table 1: absolute errors, ours | paper | relative deviation in %

# %%
table1 = explore.side_by_side(scene, 1)
print(table1.attrs.get("published", "next to the published Table 1"))
table1.style.format("{:.4e}", subset=[c for c in table1.columns if c[1] != "dev. %"], na_rep="–").format(
    "{:+.2f}", subset=[c for c in table1.columns if c[1] == "dev. %"], na_rep="–"
)

# %% [markdown]
# ## Table 2: EOCs, ours | paper | relative deviation in %
#
# Rows are labelled by the finer mesh of each pair; `regr.` is the least-squares slope over
# all meshes, `theo.` the expected order (minus ε).

# %%
table2 = explore.side_by_side(scene, 2)
print(table2.attrs.get("published", "next to the published Table 2"))
table2.style.format("{:.4f}", subset=[c for c in table2.columns if c[1] != "dev. %"], na_rep="–").format(
    "{:+.2f}", subset=[c for c in table2.columns if c[1] == "dev. %"], na_rep="–"
)

# %% [markdown]
# ## Figure 3: `L⁴` and `W^{1,4}` errors against `h`
#
# As `paper_figures/figure3.png` (`signorini.studies.paper.figures.figure3`, drawn on this
# notebook's axes): reference lines `h²` and `h` through the coarsest point, halved; for the
# paper's scene its published values added as crosses. A scene without these norms has no Figure 3.

# %%
h = errors["h"].to_numpy()
if all(norm in scene.norms for norm in FIGURE3_NORMS):
    fig, ax = plt.subplots(figsize=(6.5, 4.8))
    figure3(errors, ax=ax)
    if published:
        paper1 = explore.paper_reference(1, scene.root)
        paper_h = np.array([1.0 / int(lab[2:]) for lab in paper1.index])
        for line, norm in zip(ax.get_lines()[::2], FIGURE3_NORMS, strict=True):
            ax.loglog(paper_h, paper1[norm], "x", color=line.get_color(), markersize=8,
                      label=f"{norm} (paper, Table 1)")
    ax.legend(fontsize=8)
    plt.show()
else:
    print(f"no Figure 3: scene {scene.name!r} has no {' and '.join(FIGURE3_NORMS)} errors (norms {scene.norms})")

# %% [markdown]
# ## Every norm of the scene: errors and EOCs
#
# Left: the errors against `h`. Right: the EOC of each mesh pair (plotted at the finer `h`)
# with the expected order (dashed) and the regression slope (dotted).

# %%
eoc_rows = eoc[eoc["N"] != "regression"]
regr = eoc[eoc["N"] == "regression"].iloc[0]
fig, axes = plt.subplots(1, 2, figsize=(13, 4.8))
for norm in scene.norms:
    (line,) = axes[0].loglog(h, errors[norm], marker="o", markersize=4, label=label_tex(norm))
    color = line.get_color()
    axes[1].semilogx(eoc_rows["h"].astype(float), eoc_rows[norm].astype(float), marker="o", color=color,
                     label=label_tex(norm))
    if expected_rate(norm) is not None:
        axes[1].axhline(expected_rate(norm), color=color, linestyle="--", linewidth=0.8)
    axes[1].axhline(float(regr[norm]), color=color, linestyle=":", linewidth=0.8)
axes[0].set(xlabel="$h$", ylabel=r"$\|u-u_h\|$", title="errors")
axes[1].set(xlabel="$h$ (finer mesh of the pair)", ylabel="EOC", title="EOCs (dashed: theory, dotted: regression)")
for ax in axes:
    ax.grid(True, which="both", linewidth=0.3, alpha=0.6)
axes[1].invert_xaxis()
axes[0].legend(fontsize=8, ncol=2)
plt.show()

expected = {n: expected_rate(n) for n in scene.norms}  # None: the paper states no order
summary = pd.DataFrame({
    "regression slope": [round(float(regr[n]), 4) for n in scene.norms],
    "expected (− ε)": [("no theory" if r is None else r) for r in expected.values()],
    "slope − expected": [("–" if r is None else round(float(regr[n]) - r, 4)) for n, r in expected.items()],
}, index=[label_md(n) for n in scene.norms])
display(summary)

# %% [markdown]
# ## Your `p`: the `L^p` and `W^{1,p}` rates against the theory
#
# Set `p` (any `p ≥ 1`, or `math.inf`) and run the cell. The paper's expected orders (each
# minus ε) are `2` and `1` for `p ≤ 4`, and `3/2 + 2/p` and `1/2 + 2/p` beyond
# (`signorini.explore.expected_orders`). The errors are the pipeline's cached norm values
# where a norm job exists (e.g. `p = 4, 16, ∞`), else they are evaluated now on the cached
# solutions with `signorini.fem.norms.conventional.evaluate_norms` and the scene's conventions (a few seconds
# per mesh of the paper scene).

# %%
p = 6

lp_name, w1p_name = explore.norm_names(p)
rate_errors, rates = explore.rates_for_p(scene, p)
print(f"p = {p}: expected orders {lp_name} {explore.expected_orders(p)[0]:.4f}, "
      f"{w1p_name} {explore.expected_orders(p)[1]:.4f} (each minus ε)")
display(rate_errors)
display(rates.round(4))

# %% [markdown]
# ## Beyond the paper: the theory scene
#
# `snakemake -c2 theory` (not part of `all`) extends the meshes to `N = 1001, 2001` and adds
# the rate against `p`, supercloseness, the discrete `H^{1/2}(∂Ω)` norm, the one-sided `L⁴`
# parts and the contact set (`paper_figures/theory.*`). The cell shows the rendered findings
# and figures when they exist, and Table 2 continued to the finest meshes from the scene's
# cached `results/theory/errors.csv` (`signorini.studies.theory.report.table2_rows`).

# %%
theory_outputs = explore.existing(
    scene.root, "paper_figures/theory_rates.png", "paper_figures/theory_extra.png", "paper_figures/theory.md"
)
for obj in explore.display_artifacts(theory_outputs):
    display(obj)
theory_errors = scene.root / "results" / "theory" / "errors.csv"
if theory_errors.exists():
    display(table2_rows(pd.read_csv(theory_errors, encoding="utf-8")).set_index("pair").round(3))
elif not theory_outputs:
    print("The theory scene has not been built: run `.venv/bin/snakemake -c2 theory` (about an hour with N = 2001).")
