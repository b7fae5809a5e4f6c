"""Made-up scenes of the mesh-family study: errors of known slopes on meshes of known sizes."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from signorini.studies.meshes.rates import FamilyScene, rates_table

N = np.array([50, 100, 200, 400])


def made_up_scene(name, family="friedrichs_keller", params=None, rates=None, n_factor=1.0, ratio_growth=1.0, N=N):
    """A scene whose error in each norm is ``h^rate`` (``h = 1/N``), with ``n_factor (N + 1)²``
    vertices and a ratio of largest to smallest triangle diameter growing by ``ratio_growth``."""
    rates = rates or {"L4_true": 2.0, "W1inf_true": 0.5}
    h = 1.0 / N
    errors = pd.DataFrame({"N": N, "h": h, **{norm: h**r for norm, r in rates.items()}})
    smallest = h / np.geomspace(1.0, ratio_growth, N.size)
    meshes = pd.DataFrame(
        {
            "N": N,
            "n_vertices": n_factor * (N + 1.0) ** 2,
            "longest_edge": h,
            "smallest_diameter": smallest,
            "min_angle_deg": 45.0,
            "free_point_vertex": N % 2 == 0,
        }
    )
    return FamilyScene(name, family, params or {}, errors, meshes)


RATES = {"L4_true": 2.0, "W1inf_true": 0.5, "H12": 1.5}


def made_up_study(delaunay_rates=RATES):
    """A reference (the paper's mesh, N odd), a Delaunay and a graded scene, and their rates table."""
    scenes = [
        made_up_scene("ref", rates=RATES, N=np.array([51, 101, 201, 401])),
        made_up_scene("dl", "delaunay", {"seed": 0}, delaunay_rates, n_factor=1.15),
        made_up_scene("gr", "graded", {"grading": 2.0}, {**RATES, "W1inf_true": 1.0}, n_factor=5.5, ratio_growth=8.0),
    ]
    return scenes, rates_table(scenes, "ref")


@pytest.fixture
def scene():
    return made_up_scene


@pytest.fixture
def study():
    return made_up_study
