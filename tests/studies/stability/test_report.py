"""``stability.md`` (``signorini.studies.stability.report``): the summary numbers and one line per
case, grouped."""

from __future__ import annotations

from signorini.studies.stability.report import atlas_report
from signorini.studies.stability.table import atlas_table


def test_the_report_counts_the_runs_and_has_one_line_per_case(small_atlas):
    infos, arrays, norms = small_atlas
    md = atlas_report(atlas_table(infos, arrays, norms), infos, norms)
    assert md.startswith("# Numerical stability atlas")
    assert "- 3 runs (3 cases × up to 1 solvers): 2 ok, 0 inaccurate, 1 failed; 3 as expected." in md
    assert "- Exact solver (active_set) not as expected: none." in md
    assert md.index("### scaling") < md.index("**A_1e-6**") < md.index("### bad_input") < md.index("**bad_spd**")
    assert sum(line.startswith("- **") for line in md.splitlines()) == 3
    assert "- scaling, active_set (A_1e-6 ok): over the 1 solved amplitudes" in md
    bad = next(line for line in md.splitlines() if line.startswith("- **bad_spd**"))
    assert "all 1 solvers failed as required with BadInputError: matrix is not positive semidefinite" in bad


def test_the_summary_compares_the_other_exact_columns_with_the_direct_one():
    """A multigrid column must return the direct route's discrete solution: the summary gives its
    largest distance to ``active_set`` and whether the contact sets agree."""
    from helpers import ROOT

    from signorini.fem.problem import Problem
    from signorini.pipeline.config import load_config
    from signorini.studies.stability.atlas import Atlas, Case, parse_atlas
    from signorini.studies.stability.cases import run_case

    solvers = parse_atlas(load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]).solvers
    case = Case("A_10", "scaling", Problem().as_dict(), 30, solvers=("active_set", "multigrid", "multigrid_cold"))
    info, arrays = run_case(Atlas((case,), solvers, ("L4",), timeout_s=60), case)
    df = atlas_table([info], [arrays], ("L4",))
    assert list(df["route"]) == ["active_set", "multigrid", "multigrid"]
    line = next(x for x in atlas_report(df, [info], ("L4",)).splitlines() if x.startswith("- The other exact"))
    for solver in ("multigrid", "multigrid_cold"):
        assert f"{solver} (1 cases, 1 ok; max Δu vs exact " in line and " in A_10, " in line
    assert line.count("within 1e-12; the same contact set in all") == 2


def test_the_page_defines_its_symbols_and_flags_exact_differences_only_above_the_rounding_floor(monkeypatch):
    """On the committed table: the notation (σ the certificate's scale, not also the eigenvalue
    shift), the failures explained between the summary and the cases, and the multigrid route's
    largest difference from the direct one (above 1e-12) at the rounding floor of its case, ABOVE
    once that floor is gone; the figures read from the table."""
    import pandas as pd
    from helpers import ROOT

    from signorini.pipeline.config import load_config
    from signorini.studies.stability.atlas import parse_atlas

    df = pd.read_csv(ROOT / "paper_figures/stability.csv", encoding="utf-8")
    specs = parse_atlas(load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]).solvers
    md = atlas_report(df, [], ("L4",), specs)
    assert "σ = max(‖A u‖∞, ‖b‖∞)" in md and "σ = −" not in md and "shift −1e-10 λ_max" in md
    assert md.index("## Notation") < md.index("## Summary") < md.index("## Failures explained")
    assert md.index("## Failures explained") < md.index("## Findings per case")
    summary = next(x for x in md.splitlines() if x.startswith("- The other exact"))
    runs = df[(df["case"] == "no_contact_N201") & df["solver"].isin(["active_set", "multigrid"])]
    difference = float(runs.loc[runs["solver"] == "multigrid", "diff_to_active_set"].iloc[0])
    assert difference == df.loc[df["solver"] == "multigrid", "diff_to_active_set"].max() and difference > 1e-12
    multigrid = df[(df["solver"] == "multigrid") & df["diff_to_active_set"].notna()]  # compared with the exact
    cases, ok = len(multigrid), int((multigrid["status"] == "ok").sum())
    assert (f"multigrid ({cases} cases, {ok} ok; max Δu vs exact {difference:.1e} in no_contact_N201, above 1e-12 "
            f"but at the rounding floor of that case ({runs['kkt_threshold'].min():.1e});") in summary
    assert "ABOVE" not in summary
    row = (df["case"] == "no_contact_N201") & (df["solver"] == "active_set")
    md = atlas_report(df.assign(kkt_threshold=df["kkt_threshold"].where(~row, 1e-10)), [], ("L4",), specs)
    summary = next(x for x in md.splitlines() if x.startswith("- The other exact"))
    assert "in no_contact_N201, ABOVE 1e-12 and any recorded rounding floor in no_contact_N201;" in summary
    assert "*Rounding floor*" not in md


def test_a_case_on_a_mesh_family_counts_contact_among_its_own_boundary_nodes():
    """On a graded mesh B has more nodes than the 4N of a Friedrichs–Keller mesh: the case line
    states the contact among the mesh's own m nodes, and the notation does not say m = 4N."""
    from helpers import ROOT

    from signorini.fem.problem import Problem
    from signorini.pipeline.config import load_config
    from signorini.studies.stability.atlas import Atlas, Case, parse_atlas
    from signorini.studies.stability.cases import run_case

    solvers = parse_atlas(load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]).solvers
    case = Case("graded", "mesh", Problem().as_dict(), 8, solvers=("active_set",), mesh={"family": "graded"})
    info, arrays = run_case(Atlas((case,), solvers, ("L4",), timeout_s=60), case)
    m = info["n_constrained"]
    assert m > 4 * case.N  # the grading adds boundary nodes near the free point
    md = atlas_report(atlas_table([info], [arrays], ("L4",)), [info], ("L4",))
    line = next(line for line in md.splitlines() if line.startswith("- **graded**"))
    assert f"/{m} in contact" in line and "the m = 4N of B" not in md and "among the m nodes of B" in md
