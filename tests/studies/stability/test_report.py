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
