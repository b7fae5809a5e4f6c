"""The atlas configuration (``signorini.studies.stability.atlas``)."""

from __future__ import annotations

import json

import numpy as np
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
            assert disc.b.size == (disc.mesh.p.shape[1] if case.mesh else (case.N + 1) ** 2)
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
        ({"mesh": {"family": "nosuch"}}, "cases[0].mesh: unknown mesh family"),
        ({"mesh": {"family": "graded", "seed": 1}}, "cases[0].mesh: mesh family 'graded' has no parameter 'seed'"),
        ({"mesh": {"family": "delaunay"}, "jitter": 0.1}, "cases[0]: jitter and seed belong in the mesh block"),
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


def test_a_case_on_a_mesh_family_is_built_on_that_mesh():
    from signorini.fem.assembly import assemble
    from signorini.fem.mesh import boundary_nodes
    from signorini.fem.mesh_families import union_jack

    scene = {"N": [11], "norms": ["L4"], "problem": Problem().as_dict(),
             "atlas": {"solvers": {"active_set": {"solver": "active_set"}},
                       "cases": [{"name": "uj", "group": "mesh", "mesh": {"family": "union_jack"}}]}}
    case = stab_atlas.parse_atlas(scene).cases[0]
    assert case.mesh == {"family": "union_jack"} and case.as_dict()["mesh"] == {"family": "union_jack"}
    disc = stab_cases.build_case(case)
    A, b = assemble(union_jack(11), Problem())
    assert abs(disc.A - A).max() == 0.0 and np.array_equal(disc.b, b)
    assert np.array_equal(disc.boundary, boundary_nodes(union_jack(11)))
