"""The atlas configuration (``signorini.studies.stability.atlas``)."""

from __future__ import annotations

import json

import pytest
from helpers import ROOT

from signorini.fem.problem import Problem
from signorini.pipeline.config import load_config
from signorini.studies.stability import atlas as stab_atlas
from signorini.studies.stability import cases as stab_cases

# ---------------------------------------------------------------------------------
# configuration
# ---------------------------------------------------------------------------------


def test_shipped_atlas_parses_and_every_case_builds():
    config = load_config(ROOT / "workflow/config.yaml")
    atlas = stab_atlas.scene_atlas(config, "stability")
    assert {c.group for c in atlas.cases} == set(stab_atlas.GROUPS)
    for case in atlas.cases:
        if case.N <= 201 and case.corrupt != "nan_parameter":
            disc = stab_cases.build_case(case)
            assert disc.b.size == (case.N + 1) ** 2
        job = atlas.job(case.name)
        json.dumps(job)
        assert stab_atlas.Atlas.from_job(job).cases[0] == case


@pytest.mark.parametrize(
    "change, field",
    [
        ({"group": "nosuch"}, "cases[0].group"),
        ({"name": "a b"}, "cases[0].name"),
        ({"solvers": ["nosuch"]}, "cases[0].solvers"),
        ({"problem": {"R": 0.9}}, "cases[0].problem"),
        ({"problem": {"kind": "constant", "value": -1.0}}, "cases[0].problem"),
        ({"reference": "nosuch"}, "cases[0].reference"),
        ({"corrupt": "nosuch"}, "cases[0].corrupt"),
        ({"N": 0}, "cases[0].N"),
        ({"jitter": 0.5}, "cases[0].jitter"),
    ],
)
def test_atlas_config_errors_name_the_field(change, field):
    scene = {
        "N": [11],
        "norms": ["L4"],
        "problem": Problem().as_dict(),
        "atlas": {"solvers": {"active_set": {"solver": "active_set"}}, "cases": [{"name": "a", "group": "mesh"}]},
    }
    scene["atlas"]["cases"][0].update(change)
    with pytest.raises(stab_atlas.AtlasConfigError, match=field.replace("[", r"\[").replace("]", r"\]")):
        stab_atlas.parse_atlas(scene)
