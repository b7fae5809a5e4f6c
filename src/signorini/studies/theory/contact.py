"""The discrete contact sets ``Ã_h = {x ∈ ∂Ω : u_h(x) = 0}`` of the theory scene against the exact
contact set ``{x ∈ ∂Ω : u(x) = 0}``, condition (A_h) of the paper (Definition 5.5), and the stage
``contact_set``.

**The unrolled boundary.**  A point of ``∂Ω`` is its arc length ``s ∈ [0, 4)``, counter-clockwise
from the corner (0, 0): the bottom edge is ``s ∈ [0, 1]``, the right ``[1, 2]``, the top ``[2, 3]``,
the left ``[3, 4)``; the corners are ``s = 0, 1, 2, 3``.  A subset of ``∂Ω`` is a list of ``Arc``s.

**The discrete contact set.**  ``u_h`` is P1: on a boundary edge it vanishes identically when it
vanishes at both end nodes, and at one point only when it vanishes at one of them.  ``Ã_h`` is the
union of the arcs of consecutive contact nodes (its components); a contact node between two
non-contact nodes is a component of its own, a *singleton*, with an empty relative interior.  A
node is a contact node when ``|u_h| ≤ τ = ROUNDOFF_FACTOR · ε · ‖u_h‖∞`` (``zero_threshold``: the
factor of the KKT certificate's rounding floor, ``signorini.solvers.certificate``): the exact
solvers set ``u_h`` to exactly 0 on their active set, and ``τ`` only admits the round-off another
solver may leave there.  The stage logs whether this set is the solver's active set (the archive's
``active``).  ``sign_margin`` is the smallest ``u_h`` at a non-contact boundary node divided by its
uncertainty ``|δ_i| + τ`` (``δ`` the archive's algebraic error, ``u_h − u_h*``): above 1, round-off
in ``u_h`` cannot move that node into the contact set.

**The exact contact set** (``exact_sets``).  ``u = A ψ(r) ũ`` with ``ũ = −r^{3/2} sin(3θ/2)`` about
the free point ``(x0, 0)``.  On the bottom edge ``ũ = 0`` right of ``x0`` (θ = 0) and
``ũ = r^{3/2} > 0`` left of it (θ = π); ``ψ > 0`` for ``r < R`` and ``ψ = 0`` for ``r ≥ R``; the
other edges lie at distance ``≥ min(x0, 1 − x0) > R`` from the free point (``Problem`` requires
``R < x0`` and ``x0 + R < 1``), so ``u`` vanishes near them.  Hence ``{u = 0} ∩ ∂Ω = ∂Ω \\ (x0 − R,
x0) × {0}``, one arc from ``(x0, 0)`` counter-clockwise to ``(x0 − R, 0)``.  On ``(x0, x0 + R) ×
{0}`` the normal derivative is ``∂_n u = −∂₂u = (3/2) A ψ(r) r^{1/2} > 0``: *strict* contact.
Where ``r ≥ R`` the function vanishes on a neighbourhood, and at the free point ``∇ũ = O(r^{1/2})``,
so ``u = ∂_n u = 0`` there: the *biactive* set ``{(x0, 0)} ∪ ∂Ω \\ (x0 − R, x0 + R) × {0}``.  A
discrete solution may vanish or not on a biactive arc: neither choice violates the Signorini
conditions of ``u``, and the sign of ``u_h`` there is that of its error.
"""

from __future__ import annotations

import logging
import math
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd

from signorini.fem.convergence import regression_slope
from signorini.studies.verdict import Verdict

if TYPE_CHECKING:
    from signorini.fem.problem import Problem
    from signorini.studies.scene.store import SceneMesh

log = logging.getLogger(__name__)

PERIMETER = 4.0  # the length of ∂Ω
CORNERS = {0.0: "(0, 0)", 1.0: "(1, 0)", 2.0: "(1, 1)", 3.0: "(0, 1)"}  # arc length: the corner
EDGE_TOL = 1e-12  # a node within this of x = 0, 1 or y = 0, 1 lies on ∂Ω (Friedrichs–Keller nodes are exact)
SET_NAMES = ("discrete", "exact", "strict", "biactive")  # the column ``set`` of the table


@dataclass(frozen=True)
class Arc:
    """A closed arc of ``∂Ω``: from ``start`` (arc length in ``[0, 4)``) counter-clockwise over
    ``length`` (``0``: one point; ``4``: all of ``∂Ω``); ``nodes``: its mesh nodes (discrete arcs)."""

    start: float
    length: float
    nodes: int = 0

    @property
    def end(self) -> float:
        return (self.start + self.length) % PERIMETER

    @property
    def ends(self) -> list[float]:
        """Its relative boundary in ``∂Ω``: none for all of ``∂Ω``, one point for a point, else two."""
        if self.length >= PERIMETER:
            return []
        return [self.start] if self.length == 0.0 else [self.start, self.end]

    def contains(self, s: np.ndarray, tol: float = 0.0) -> np.ndarray:
        """Whether the arc lengths ``s`` lie on the arc (within ``tol``)."""
        return (np.asarray(s, dtype=float) - self.start + tol) % PERIMETER <= self.length + 2.0 * tol

    def samples(self, spacing: float) -> np.ndarray:
        """Arc lengths along the arc, at most ``spacing`` apart, its ends and corners included."""
        n = max(1, math.ceil(self.length / spacing))
        t = np.linspace(0.0, self.length, n + 1)
        corners = np.arange(math.floor(self.start) + 1, self.start + self.length) - self.start
        return np.sort(np.concatenate([t, corners])) + self.start


def points(s: np.ndarray) -> np.ndarray:
    """(2, n): the points of ``∂Ω`` at arc lengths ``s`` (taken modulo 4)."""
    s = np.mod(np.asarray(s, dtype=float), PERIMETER)
    side = np.minimum(np.floor(s).astype(int), 3)
    r = s - side
    x = np.choose(side, [r, np.ones_like(r), 1.0 - r, np.zeros_like(r)])
    y = np.choose(side, [np.zeros_like(r), r, np.ones_like(r), 1.0 - r])
    return np.vstack([x, y])


def arc_length(p: np.ndarray) -> np.ndarray:
    """The arc lengths of points ``p`` (2, n) of ``∂Ω``."""
    x, y = np.asarray(p[0], dtype=float), np.asarray(p[1], dtype=float)
    s = np.where(y <= EDGE_TOL, x, np.where(x >= 1 - EDGE_TOL, 1 + y, np.where(y >= 1 - EDGE_TOL, 3 - x, 4 - y)))
    return np.where((x <= EDGE_TOL) & (y <= EDGE_TOL), 0.0, s)


def boundary_loop(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The boundary nodes of a mesh of the unit square (node coordinates ``p``, (2, n)) in the
    order of their arc lengths, and the arc lengths."""
    x, y = p
    nodes = np.flatnonzero((x <= EDGE_TOL) | (x >= 1 - EDGE_TOL) | (y <= EDGE_TOL) | (y >= 1 - EDGE_TOL))
    s = arc_length(p[:, nodes])
    order = np.argsort(s, kind="stable")
    return nodes[order], s[order]


def zero_threshold(u_h: np.ndarray) -> float:
    """``τ = ROUNDOFF_FACTOR · ε · ‖u_h‖∞``: a node with ``|u_h| ≤ τ`` is a contact node."""
    from signorini.solvers.certificate import ROUNDOFF_FACTOR

    return ROUNDOFF_FACTOR * float(np.finfo(float).eps) * float(np.abs(u_h).max(initial=0.0))


def components(s: np.ndarray, contact: np.ndarray) -> list[Arc]:
    """The components of the discrete contact set: the runs of consecutive contact nodes
    (``contact``) along the loop of arc lengths ``s`` (sorted), cyclically, sorted by start."""
    contact = np.asarray(contact, dtype=bool)
    if contact.all():
        return [Arc(0.0, PERIMETER, int(contact.size))]
    first_free = int(np.flatnonzero(~contact)[0])
    order = np.roll(np.arange(s.size), -first_free)  # start the loop at a non-contact node: no run wraps
    steps = np.diff(np.concatenate([[0], contact[order].astype(int), [0]]))
    arcs = []
    for a, b in zip(np.flatnonzero(steps == 1), np.flatnonzero(steps == -1) - 1, strict=True):
        start, stop = float(s[order[a]]), float(s[order[b]])
        arcs.append(Arc(start, (stop - start) % PERIMETER, int(b - a + 1)))
    return sorted(arcs, key=lambda arc: arc.start)


def exact_sets(problem: Problem) -> dict[str, list[Arc]]:
    """The exact contact set, its strict part (closure) and its biactive part (module docstring)."""
    x0, R = float(problem.x0), float(problem.R)
    return {
        "exact": [Arc(x0, PERIMETER - R)],
        "strict": [Arc(x0, R)],
        "biactive": [Arc(x0, 0.0), Arc(x0 + R, PERIMETER - 2.0 * R)],
    }


def _rows(name: str, arcs: Sequence[Arc], N: int | None = None, h: float | None = None, **extra) -> list[dict]:
    """The table's rows of one set; an empty discrete set keeps its mesh in one row without a component."""
    if not arcs and name == "discrete":
        return [{"set": name, "N": N, "h": h, "nodes": 0, "singleton": False, **extra}]
    rows = []
    for k, arc in enumerate(arcs):
        (xs, xe), (ys, ye) = points([arc.start, arc.end])
        rows.append(
            {
                "set": name,
                "N": N,
                "h": h,
                "component": k,
                "s_start": arc.start,
                "s_end": arc.end,
                "x_start": xs,
                "y_start": ys,
                "x_end": xe,
                "y_end": ye,
                "length": arc.length,
                "nodes": arc.nodes if name == "discrete" else None,
                "singleton": arc.length == 0.0,
                **extra,
            }
        )
    return rows


def mesh_contact(at: SceneMesh, solution_npz: str | os.PathLike) -> tuple[list[Arc], float]:
    """The components of ``Ã_h`` of one mesh and its ``sign_margin`` (module docstring)."""
    sol = at.solution(solution_npz)
    u_h = sol["u"]
    nodes, s = boundary_loop(at.mesh().p)
    tau = zero_threshold(u_h)
    contact = np.abs(u_h[nodes]) <= tau
    if "active" in sol:
        solver = np.isin(nodes, sol["active"])
        log.info(
            "N=%d: %d contact nodes, %d of them outside the solver's active set, %d active nodes outside",
            at.N,
            contact.sum(),
            (contact & ~solver).sum(),
            (solver & ~contact).sum(),
        )
    delta = np.abs(sol["algebraic_error"][nodes]) if "algebraic_error" in sol else np.zeros(nodes.size)
    free = ~contact
    margin = float(np.min(u_h[nodes][free] / (delta[free] + tau))) if free.any() and tau > 0 else math.inf
    return components(s, contact), margin


def contact_table(
    meshes: Sequence[SceneMesh], solutions: Sequence[str | os.PathLike], problem: Problem | None = None
) -> pd.DataFrame:
    """One row per component: of ``Ã_h`` per mesh (``set`` = ``discrete``), then of the exact
    contact set and its strict and biactive parts (``N`` empty); columns as ``_rows``."""
    rows: list[dict] = []
    for at, path in zip(meshes, solutions, strict=True):
        arcs, margin = mesh_contact(at, path)
        rows += _rows("discrete", arcs, at.N, at.h, sign_margin=margin)
    problem = problem if problem is not None else meshes[0].problem
    for name, arcs in exact_sets(problem).items():
        rows += _rows(name, arcs)
    table = pd.DataFrame(rows)
    table["N"] = table["N"].astype("Int64")
    table["nodes"] = table["nodes"].astype("Int64")
    return table


def arcs_of(table: pd.DataFrame, name: str, N: int | None = None) -> list[Arc]:
    """The arcs of one set of ``contact_table`` (``N`` for the discrete set)."""
    sel = table[(table["set"] == name) & ((table["N"] == N) if N is not None else True)]
    sel = sel[sel["s_start"].notna()]
    nodes = sel["nodes"].fillna(0) if "nodes" in sel else [0] * len(sel)
    return [Arc(float(a), float(b), int(n)) for a, b, n in zip(sel["s_start"], sel["length"], nodes, strict=True)]


def _discrete(table: pd.DataFrame) -> pd.DataFrame:
    return table[table["set"] == "discrete"]


def _meshes(table: pd.DataFrame) -> tuple[np.ndarray, np.ndarray]:
    """The meshes of the table's discrete rows, coarsest first: (N, h)."""
    per = _discrete(table).groupby("N", sort=True)["h"].first()
    return per.index.to_numpy(dtype=int), per.to_numpy(dtype=float)


# --- condition (A_h): the ends of the components across the meshes ------------------------------


def mesh_ends(table: pd.DataFrame) -> dict[int, list[float]]:
    """{N: the sorted arc lengths of the relative boundary points of ``Ã_h``} (``Arc.ends``)."""
    Ns, _ = _meshes(table)
    return {int(N): sorted(s for arc in arcs_of(table, "discrete", N) for s in arc.ends) for N in Ns}


def _inside(lo: float, hi: float, s: float) -> bool:
    """Whether ``s`` lies on the arc ``[lo, hi]`` (arc lengths, ``hi ≥ lo``, cyclic)."""
    return hi - lo >= PERIMETER or (s - lo) % PERIMETER <= hi - lo


def _gap(lo: float, hi: float, lo2: float, hi2: float) -> float:
    """The distance along ``∂Ω`` between the arcs ``[lo, hi]`` and ``[lo2, hi2]`` (0 if they meet)."""
    if _inside(lo, hi, lo2) or _inside(lo2, hi2, lo):
        return 0.0
    return min((lo2 - hi) % PERIMETER, (lo - hi2) % PERIMETER)


def end_families(table: pd.DataFrame) -> pd.DataFrame | None:
    """The k-th end of ``Ã_h`` on every mesh (by arc length), when every mesh has as many ends:
    one row per end with its range over the meshes (``s_min``, ``s_max``, ``spread``), its
    neighbourhood ``[lo, hi]`` (the range widened by the spread on each side: it holds the limit of
    an end converging at a rate ≥ ``beta`` in h, ``end_rate_covered``), the nearest corner and the
    gaps from the neighbourhood to it and to the other ends' neighbourhoods; None otherwise."""
    ends = mesh_ends(table)
    if not ends or len({len(e) for e in ends.values()}) != 1:
        return None
    positions = np.array(list(ends.values()), dtype=float).reshape(len(ends), -1)
    rows = []
    for k in range(positions.shape[1]):
        s = positions[:, k]
        spread = float(s.max() - s.min())
        lo, hi = float(s.min()) - spread, float(s.max()) + spread
        gaps = {c: _gap(lo, hi, c, c) for c in CORNERS}
        corner = min(gaps, key=gaps.get)
        (x, y) = points([s[-1]])[:, 0]
        rows.append(
            {
                "end": k,
                "s_min": s.min(),
                "s_max": s.max(),
                "spread": spread,
                "lo": lo,
                "hi": hi,
                "x_finest": x,
                "y_finest": y,
                "nearest_corner": CORNERS[corner],
                "corner_gap": gaps[corner],
            }
        )
    columns = ["end", "s_min", "s_max", "spread", "lo", "hi", "x_finest", "y_finest", "nearest_corner", "corner_gap"]
    fam = pd.DataFrame(rows, columns=columns)
    fam["other_gap"] = [
        min((_gap(a.lo, a.hi, b.lo, b.hi) for b in fam.itertuples() if b.end != a.end), default=math.inf)
        for a in fam.itertuples()
    ]
    return fam


def end_rate_covered(h: np.ndarray) -> float:
    """The slowest rate β of an end ``s(h) = s* + c h^β`` whose limit ``s*`` lies within the spread
    of its positions on meshes ``h`` from its finest one: ``h_min^β ≤ h_max^β − h_min^β``, that is
    ``β ≥ log 2 / log(h_max/h_min)``; also the rate at which a distance halves over the meshes."""
    h = np.asarray(h, dtype=float)
    return math.log(2.0) / math.log(h.max() / h.min()) if h.size > 1 and h.max() > h.min() else math.inf


def condition_ah(table: pd.DataFrame) -> tuple[Verdict, pd.DataFrame | None]:
    """Condition (A_h) (Definition 5.5) on the meshes of ``contact_table``: no singleton component
    (item 2), the same number of ends on every mesh, each end in a neighbourhood of its own
    (``end_families``) away from the corners and from the other ends (item 1)."""
    Ns, h = _meshes(table)
    disc = _discrete(table)
    failures = []
    singles = sorted(int(N) for N in disc.loc[disc["singleton"].astype(bool), "N"].unique())
    if singles:
        failures.append(f"a component is a single node (empty relative interior, item 2) on N = {_list(singles)}")
    fam = end_families(table)
    if fam is None:
        counts = ", ".join(f"{len(e)} on N = {N}" for N, e in mesh_ends(table).items())
        failures.append(f"the number of ends (relative boundary points) changes with h: {counts}")
    else:
        for r in fam.itertuples():
            if r.corner_gap == 0.0:
                failures.append(
                    f"end {r.end + 1} moves over {r.s_min:.4f}–{r.s_max:.4f}: its neighbourhood "
                    f"reaches the corner {r.nearest_corner}"
                )
            if r.other_gap == 0.0:
                failures.append(f"the neighbourhood of end {r.end + 1} meets another end's")
    counts = sorted({len(arcs_of(table, "discrete", N)) for N in Ns})
    if failures:
        return Verdict(
            holds=False,
            strength="measured",
            text="Condition (A_h) fails on these meshes (measured): " + "; ".join(failures) + ".",
        ), fam
    n_ends = len(fam)
    gap = min([*fam["corner_gap"], *fam["other_gap"]], default=math.inf)
    text = (
        f"Consistent with condition (A_h) on these meshes (measured): on every mesh Ã_h has "
        f"{_list(counts)} component(s), none a single node, and {n_ends} end(s)"
    )
    if n_ends:
        text += (
            f"; each end stays in a neighbourhood of its own (its range over the meshes widened by the "
            f"distance it moved, which holds the limit of an end converging at a rate ≥ "
            f"{end_rate_covered(h):.2f} in h), at least {gap:.3f} along ∂Ω from the corners and from "
            "the other ends' neighbourhoods"
        )
    inside = [name for c, name in CORNERS.items() if all(_covers(table, N, c) for N in Ns)]
    if inside:
        text += (
            f"; the corner(s) {_list(inside)} lie inside Ã_h on every mesh, which (A_h) allows (only the ends "
            "must keep away from the corners)"
        )
    text += ". (A_h) speaks of all small h: finitely many meshes can only be consistent with it."
    return Verdict(holds=True, strength="measured", text=text), fam


def _covers(table: pd.DataFrame, N: int, s: float) -> bool:
    """Whether ``Ã_h`` of mesh ``N`` holds the point at arc length ``s`` away from its ends."""
    return any(bool(a.contains(s)) and s not in a.ends for a in arcs_of(table, "discrete", N))


def _list(values: Sequence) -> str:
    return ", ".join(str(v) for v in values)


# --- the distance between the discrete and the exact contact sets --------------------------------


def directed_distance(a: Sequence[Arc], b: Sequence[Arc], spacing: float) -> tuple[float, float]:
    """``sup_{x ∈ a} dist(x, b)`` (Euclidean) and the arc length of the x attaining it, both sets
    sampled at most ``spacing`` apart (``Arc.samples``): within ``spacing`` of the exact value."""
    from scipy.spatial import cKDTree

    if not a:
        return 0.0, math.nan
    sa = np.concatenate([arc.samples(spacing) for arc in a])
    if not b:
        return math.inf, float(sa[0] % PERIMETER)
    sb = np.concatenate([arc.samples(spacing) for arc in b])
    d, _ = cKDTree(points(sb).T).query(points(sa).T)
    i = int(np.argmax(d))
    return float(d[i]), float(sa[i] % PERIMETER)


def covered_fraction(a: Sequence[Arc], b: Sequence[Arc], spacing: float) -> float:
    """The fraction of the length of ``a`` that ``b`` covers (sampled ``spacing`` apart)."""
    sa = np.concatenate([arc.samples(spacing) for arc in a if arc.length > 0] or [np.empty(0)])
    if sa.size == 0:
        return math.nan
    return float(np.mean(np.any([arc.contains(sa, 1e-12) for arc in b] or [np.zeros(sa.size, bool)], axis=0)))


def contact_distances(table: pd.DataFrame, spacing: float | None = None) -> pd.DataFrame:
    """Per mesh: the Hausdorff distance between ``Ã_h`` and the exact contact set and its two
    directed parts, the exact point farthest from ``Ã_h`` (arc length, x, y) and whether it lies in
    the biactive set outside ``Ã_h`` (where ``u_h > 0``), the share of the biactive set's length in
    ``Ã_h``, and the Hausdorff distance to the (closed) strict part; sampled ``spacing`` apart
    (default: an eighth of the finest h)."""
    Ns, h = _meshes(table)
    spacing = float(h.min()) / 8.0 if spacing is None else spacing
    exact, strict, biactive = (arcs_of(table, name) for name in ("exact", "strict", "biactive"))
    rows = []
    for N, hN in zip(Ns, h, strict=True):
        disc = arcs_of(table, "discrete", N)
        to_disc, far = directed_distance(exact, disc, spacing)
        from_disc, _ = directed_distance(disc, exact, spacing)
        strict_d = max(directed_distance(strict, disc, spacing)[0], directed_distance(disc, strict, spacing)[0])
        in_biactive = bool(np.any([arc.contains(far, spacing) for arc in biactive]))
        (x, y) = points([far])[:, 0]
        rows.append(
            {
                "N": int(N),
                "h": float(hN),
                "hausdorff": max(to_disc, from_disc),
                "exact_to_discrete": to_disc,
                "discrete_to_exact": from_disc,
                "farthest_s": far,
                "farthest_x": x,
                "farthest_y": y,
                "farthest_biactive_free": in_biactive and to_disc > spacing,
                "biactive_covered": covered_fraction(biactive, disc, spacing),
                "strict_hausdorff": strict_d,
                "spacing": spacing,
            }
        )
    return pd.DataFrame(rows)


def decrease_verdict(h: np.ndarray, d: np.ndarray, what: str, floor: float = 0.0) -> Verdict:
    """Whether the distances ``d`` on meshes ``h`` decrease: their regression slope against h at
    least ``end_rate_covered(h)`` (the rate at which they at least halve over the meshes); values
    below ``floor`` (the sampling's resolution) count as ``floor``."""
    h, d = np.asarray(h, dtype=float), np.maximum(np.asarray(d, dtype=float), floor)
    if h.size < 2 or h.max() == h.min():
        return Verdict(
            holds=False, strength="open", text=f"{what}: one mesh width only, no rate can be measured (open)."
        )
    if not np.all(np.isfinite(d)) or np.any(d <= 0.0):
        return Verdict(holds=False, strength="open", text=f"{what}: not finite and positive on every mesh (open).")
    slope, beta = regression_slope(h, d), end_rate_covered(h)
    span = f"from {d[0]:.4f} at h = {h[0]:.2e} to {d[-1]:.4f} at h = {h[-1]:.2e}"
    if slope >= beta:
        return Verdict(
            holds=True, strength="measured", text=f"{what} decreases (measured): {span}, rate {slope:.2f} ≥ {beta:.2f}."
        )
    return Verdict(
        holds=False,
        strength="measured",
        text=f"{what} does not converge to 0 on these meshes (measured): {span}, a fitted "
        f"rate of {slope:.3f}, below {beta:.2f}, the rate at which it would at least halve over them.",
    )


def hausdorff_verdicts(dist: pd.DataFrame) -> list[Verdict]:
    """The convergence of ``Ã_h`` to the exact contact set in the Hausdorff distance
    (``contact_distances``); when it does not converge, its cause (the biactive set) and the
    distance to the strict part."""
    floor, h = float(dist["spacing"].max()), dist["h"].to_numpy()
    what = "The Hausdorff distance between Ã_h and the exact contact set"
    verdicts = [decrease_verdict(h, dist["hausdorff"].to_numpy(), what, floor)]
    if verdicts[0].holds or verdicts[0].strength == "open":
        return verdicts
    last = dist.iloc[-1]
    if bool(dist["farthest_biactive_free"].all()):
        where = f"({last.farthest_x:.3f}, {last.farthest_y:.3f}), {last.exact_to_discrete:.4f} from Ã_h"
        text = (
            "Why (explained): on every mesh the point of the exact contact set farthest from Ã_h (on the finest mesh "
            f"{where}) lies in the biactive set, where u = ∂_n u = 0 but u_h > 0. Since u = 0 there, u_h is the "
            "error u_h − u itself: Ã_h misses every part of the biactive set where the error is positive, however "
            f"small it is, and u_h → u does not bring it closer. Ã_h covers {100 * last.biactive_covered:.0f}% of "
            "the biactive set's length on the finest mesh. "
        )
        inside = float(dist["discrete_to_exact"].max())
        text += (
            f"The other direction is nil: every point of Ã_h lies in the exact contact set (to {floor:.1e})."
            if inside <= floor
            else f"The other direction: every point of Ã_h lies within {inside:.4f} of the exact contact set."
        )
        verdicts.append(Verdict(holds=True, strength="explained", text=text))
    else:
        missed = _list(dist.loc[~dist["farthest_biactive_free"].astype(bool), "N"])
        text = f"Why: not identified (open): on N = {missed} the exact point farthest from Ã_h is not a biactive one."
        verdicts.append(Verdict(holds=False, strength="open", text=text))
    what = "Nor is Ã_h close to the strict contact set [x0, x0 + R] × {0}: its Hausdorff distance to it"
    verdicts.append(decrease_verdict(h, dist["strict_hausdorff"].to_numpy(), what, floor))
    return verdicts


def free_end_verdict(table: pd.DataFrame) -> Verdict:
    """Where ``Ã_h`` ends at the free point: is the end nearest ``(x0, 0)`` the first node at or
    right of it (``⌈x0 N⌉ / N`` on the bottom edge of a Friedrichs–Keller mesh) on every mesh?"""
    x0 = float(arcs_of(table, "exact")[0].start)
    Ns, h = _meshes(table)
    offsets, first = [], []
    for N, ends in mesh_ends(table).items():
        end = min(ends, key=lambda s: abs(s - x0), default=math.nan)
        offsets.append(end - x0)
        first.append(abs(end - math.ceil(x0 * N - 1e-9) / N) <= 1e-9)
    if not all(first):
        missed = _list(int(N) for N, f in zip(Ns, first, strict=True) if not f)
        text = f"At the free point, Ã_h does not end at the first node at or right of (x0, 0) on N = {missed}"
        return Verdict(holds=False, strength="measured", text=text + " (measured).")
    ratio = np.array(offsets) / h
    same = np.allclose(ratio, ratio[0], atol=1e-6)
    grid = f"{ratio[0]:.2f} h" if same else f"between {ratio.min():.2f} h and {ratio.max():.2f} h"
    text = (
        "At the free point, Ã_h ends at the first boundary node at or right of (x0, 0) on every mesh (measured); "
        f"its distance to the free point, {grid} on these meshes, is where the grid puts that node (by "
        "construction: h/2 when x0 = 1/2 and N is odd), not a property of u_h."
    )
    return Verdict(holds=True, strength="measured", text=text)


def figure_marks(table: pd.DataFrame) -> list[tuple[float, str, str]]:
    """The points of the exact sets a figure marks: (arc length, label, line style) of the free
    point and of ``(x0 ± R, 0)``, from the table's strict set."""
    strict = arcs_of(table, "strict")[0]
    x0, R = strict.start, strict.length
    return [(x0, "free point $(x_0, 0)$", "--"), (x0 - R, "$(x_0 - R, 0)$", ":"), (x0 + R, "$(x_0 + R, 0)$", ":")]


def ends_frame(table: pd.DataFrame) -> pd.DataFrame:
    """The ends of ``Ã_h`` in long form: one row per mesh and end (``N``, ``h``, ``end``: its rank
    by arc length, ``s``), coarsest mesh first."""
    Ns, h = _meshes(table)
    ends = mesh_ends(table)
    rows = [
        {"N": int(N), "h": float(hN), "end": k, "s": s}
        for N, hN in zip(Ns, h, strict=True)
        for k, s in enumerate(ends[int(N)])
    ]
    return pd.DataFrame(rows, columns=["N", "h", "end", "s"])


def zoom_windows(table: pd.DataFrame, most: int = 3) -> list[tuple[float, float]]:
    """Arc-length windows around the ends of ``Ã_h`` (at most ``most``): each end's positions over
    the meshes and two coarsest cells either side (``end_families``; without them, three cells
    around the ends of the mesh with most ends)."""
    Ns, h = _meshes(table)
    if not Ns.size:
        return []
    fam = end_families(table)
    if fam is None:
        ends = max(mesh_ends(table).values(), key=len)
        return [(s - 3 * h.max(), s + 3 * h.max()) for s in ends[:most]]
    return [(r.s_min - 2 * h.max(), r.s_max + 2 * h.max()) for r in fam.itertuples()][:most]


def contact_set_stage(
    meshes: Sequence[SceneMesh], solutions: Sequence[str | os.PathLike], outputs: Mapping[str, str | os.PathLike]
) -> pd.DataFrame:
    """Stage ``contact_set``: the table of ``contact_table`` (``outputs["csv"]``) and its figure
    (``outputs["pdf"]``, ``outputs["png"]``, ``figures.contact_figure``)."""
    from signorini.pipeline.artifacts import atomic_write_csv
    from signorini.plotting import save
    from signorini.studies.theory.figures import contact_figure

    table = contact_table(meshes, solutions)
    atomic_write_csv(table, outputs["csv"])
    save(contact_figure(table, figure_marks(table), zoom_windows(table)), outputs["pdf"], outputs["png"])
    verdict, _ = condition_ah(table)
    log.info("%s", verdict.text)
    return table
