"""The rates of the mesh-family study, computed from each scene's ``errors.csv`` and its meshes.

Per scene (a mesh family with its parameters) and norm: the regression slope of ``log e`` against
``log h`` over all meshes (``h`` the longest edge; ``1/N`` on the paper's mesh), the last EOC, and
the *order against the unknowns*, ``−2 ×`` the slope of ``log e`` against ``log n`` (``n`` the
number of vertices), which equals the slope against ``h`` on quasi-uniform meshes (``n ∼ h⁻²``) and
compares meshes of other grading at equal cost.  Verdicts compare each slope with the order of the
a priori estimate (``published.expected_rate``) and with the reference scene (the paper's mesh),
within a tolerance per norm (``tolerances``): the larger of ``RATE_TOL`` and the spread of the
slopes over the scenes that differ only by their random seed.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from signorini.fem.convergence import eoc, regression_slope
from signorini.fem.norms.names import parse_norm_name
from signorini.published import expected_rate
from signorini.studies.theory.report import RATE_TOL, rate_verdict

# a family is quasi-uniform on its meshes when the ratio of its largest to its smallest triangle
# diameter grows by at most this factor from the coarsest to the finest mesh (a graded mesh's ratio
# grows like a power of 1/h)
QUASI_UNIFORM_GROWTH = 1.5
TITLES = {
    "friedrichs_keller": "Friedrichs–Keller",
    "union_jack": "union-jack",
    "graded": "graded",
    "delaunay": "Delaunay",
}


@dataclass(frozen=True)
class FamilyScene:
    """One scene of the study: its name, mesh family and parameters, errors (``N``, ``h``, one
    column per norm) and meshes (``N``, ``n_vertices``, ``longest_edge``, ``smallest_diameter``,
    ``min_angle_deg``, ``free_point_vertex``)."""

    scene: str
    family: str
    params: Mapping
    errors: pd.DataFrame
    meshes: pd.DataFrame

    @property
    def label(self) -> str:
        """``Delaunay (seed 1)``, ``graded (grading 2)``, ``Friedrichs–Keller, N even``."""
        title = TITLES.get(self.family, self.family.replace("_", " "))
        extra = ", ".join(f"{k} {v:g}" if isinstance(v, float) else f"{k} {v}" for k, v in self.params.items())
        title += f" ({extra})" if extra else ""
        if self.family == "friedrichs_keller" and (self.meshes["N"] % 2 == 0).all():
            title += ", N even"
        return title

    @property
    def norms(self) -> list[str]:
        return [c for c in self.errors.columns if c not in ("N", "h")]

    @property
    def diameter_ratio(self) -> np.ndarray:
        """Per mesh: its longest edge over its smallest triangle diameter."""
        return (self.meshes["longest_edge"] / self.meshes["smallest_diameter"]).to_numpy(dtype=float)

    @property
    def quasi_uniform(self) -> bool:
        """Measured: the ratio of the largest to the smallest triangle diameter (``diameter_ratio``)
        grows by at most ``QUASI_UNIFORM_GROWTH`` over the meshes."""
        ratio = self.diameter_ratio
        return bool(ratio[-1] <= QUASI_UNIFORM_GROWTH * ratio[0])

    def rates(self) -> pd.DataFrame:
        """One row per norm: ``slope_h``, ``last_eoc``, ``order_n``, ``expected``."""
        h, n = self.errors["h"].to_numpy(dtype=float), self.meshes["n_vertices"].to_numpy(dtype=float)
        rows = []
        for norm in self.norms:
            e = self.errors[norm].to_numpy(dtype=float)
            rows.append(
                {
                    "scene": self.scene,
                    "family": self.label,
                    "norm": norm,
                    "slope_h": regression_slope(h, e),
                    "last_eoc": float(eoc(h, e)[-1]),
                    "order_n": -2.0 * regression_slope(n, e),
                    "expected": expected_rate(parse_norm_name(norm).base),
                }
            )
        return pd.DataFrame(rows)


def seed_groups(scenes: Sequence[FamilyScene]) -> list[list[FamilyScene]]:
    """The groups of scenes that differ only by their ``seed`` (same family, other parameters and
    meshes), each with more than one scene."""
    groups: dict[tuple, list[FamilyScene]] = {}
    for s in scenes:
        if "seed" in s.params:
            key = (s.family, tuple(sorted((k, v) for k, v in s.params.items() if k != "seed")), tuple(s.errors["N"]))
            groups.setdefault(key, []).append(s)
    return [g for g in groups.values() if len(g) > 1]


def tolerances(scenes: Sequence[FamilyScene], rate_tol: float = RATE_TOL) -> dict[str, float]:
    """{norm: the tolerance within which two slopes are the same}: the larger of ``rate_tol`` and
    the largest spread (max − min) of the slope against ``h`` over a group of seeds."""
    tol = {norm: rate_tol for s in scenes for norm in s.norms}
    for group in seed_groups(scenes):
        rates = pd.concat([s.rates() for s in group])
        for norm, slopes in rates.groupby("norm")["slope_h"]:
            tol[norm] = max(tol[norm], float(slopes.max() - slopes.min()))
    return tol


# a family's order against the paper mesh's, in the words of a comparison of two meshes
AGAINST_REFERENCE = {"agrees": "same", "faster": "better", "slower": "worse"}


def rates_table(scenes: Sequence[FamilyScene], reference: str, rate_tol: float = RATE_TOL) -> pd.DataFrame:
    """Every scene's ``rates`` with the tolerance of its norm, the verdict of its slope against the
    expected order (``agrees``, ``faster``, ``slower``: the slope against ``h`` on quasi-uniform
    meshes, the order against the unknowns on others) and against the reference scene's (``same``,
    ``better``, ``worse``: the orders against the unknowns)."""
    tol = tolerances(scenes, rate_tol)
    frames = []
    for s in scenes:
        rates = s.rates()
        rates["quasi_uniform"] = s.quasi_uniform
        frames.append(rates)
    table = pd.concat(frames, ignore_index=True)
    table["tol"] = table["norm"].map(tol)
    ref = table[table["scene"] == reference].set_index("norm")["order_n"]
    measured = np.where(table["quasi_uniform"], table["slope_h"], table["order_n"])
    table["vs_expected"] = [
        rate_verdict(m, e, t) if e is not None else ""
        for m, e, t in zip(measured, table["expected"], table["tol"], strict=True)
    ]
    table["vs_reference"] = [
        AGAINST_REFERENCE[rate_verdict(o, ref[norm], t)] if norm in ref else ""
        for o, norm, t in zip(table["order_n"], table["norm"], table["tol"], strict=True)
    ]
    return table
