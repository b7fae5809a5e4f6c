"""A small atlas run once for the tests of its table, report and figure: a scaling case and its
reference on N = 6, and a bad-input case, each solved by the exact solver."""

from __future__ import annotations

import pytest
from helpers import ROOT

from signorini.fem.problem import Problem
from signorini.pipeline.config import load_config
from signorini.studies.stability.atlas import Atlas, Case, parse_atlas
from signorini.studies.stability.cases import run_case

NORMS = ("L4", "H12")


@pytest.fixture(scope="session")
def small_atlas():
    """(case infos, case arrays, norms) as the stage ``stability_case`` leaves them."""
    scene = load_config(ROOT / "workflow/config.yaml")["scenes"]["stability"]
    solvers = parse_atlas(scene).solvers
    only = ("active_set",)
    cases = (
        Case("A_10", "scaling", Problem().as_dict(), 6, solvers=only),
        Case("A_1e-6", "scaling", Problem(A=1e-6).as_dict(), 6, solvers=only, reference="A_10"),
        Case("bad_spd", "bad_input", Problem().as_dict(), 6, corrupt="non_spd", solvers=only),
    )
    atlas = Atlas(cases, solvers, NORMS, timeout_s=60)
    results = [run_case(atlas, case) for case in cases]
    return [info for info, _ in results], [arrays for _, arrays in results], NORMS
