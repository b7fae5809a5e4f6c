"""Why runs of the stability atlas fail: one function per failure class.

Each function takes the atlas table (``table.atlas_table``'s frame, or ``stability.csv`` read back
by pandas) and, where it needs them, the solver columns (``atlas.SolverSpec`` by label), and
returns the paragraph of ``stability.md`` that explains the class, or None when its condition
does not hold in the table.  The condition is computed from the table; where the table cannot
give it, from the case's definition (the ``problem`` column), and the paragraph says which.
Every paragraph states its strength (``STRENGTHS``).  ``open_failures`` lists the runs no other
class explains, so that every failure of the page is accounted for.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Mapping

import pandas as pd

from signorini.studies.stability.atlas import SolverSpec

EXACT = "active_set"  # the reference column: Δu vs exact is measured against it
SAME_SOLUTION_RTOL = 1e-12  # max |Δu| ≤ SAME_SOLUTION_RTOL · max |u|: the same discrete solution
INTERIOR_POINT_ROUTES = ("cvxpy_clarabel",)  # Clarabel: primal-dual interior point
ADMM_ROUTES = ("cvxpy_osqp", "cvxpy_scs")  # OSQP, SCS: first-order splitting (ADMM)
# cvxpy's default iteration limit where a column sets none (cvxpy's OSQP interface: max_iter 10000)
DEFAULT_MAX_ITER = {"cvxpy_osqp": 10_000}
TIME_LIMIT_OPTIONS = ("time_limit", "time_limit_secs")  # OSQP and Clarabel; SCS
MAX_ITER_OPTIONS = ("max_iter", "max_iters")
RESIDUALS = ("stationarity", "primal", "dual", "complementarity")

STRENGTHS = (
    "Each finding is selected by a condition computed from `stability.csv` and carries its strength: "
    "*by construction* = follows from the definition of the case or of the solver; *measured* = read off "
    "the CSV; *explained* = derived from the mathematics or the solver's design, consistent with the "
    "CSV but not measured by the atlas; *open* = no cause established."
)

Specs = Mapping[str, SolverSpec] | None


# --- reading the table ---------------------------------------------------------------------------


def _e(x: float) -> str:
    return "∞" if math.isinf(x) else f"{x:.1e}"


def _s(x: float) -> str:
    return f"{x:.1f} s" if x < 10 else f"{x:.0f} s"


def _true(x) -> bool:
    """A flag of the table: bools from ``atlas_table``, bools or NaN (not compared) from the CSV."""
    return x == "True" if isinstance(x, str) else not _nan(x) and bool(x)


def _nan(x) -> bool:
    return x is None or (isinstance(x, float) and math.isnan(x))


def _problem(row) -> dict:
    return json.loads(row["problem"])


def _run(row) -> str:
    return f"{row['case']}/{row['solver']}"


def _runs(rows: pd.DataFrame) -> str:
    return ", ".join(_run(r) for _, r in rows.iterrows())


def _worst_residual(row) -> tuple[str, float]:
    """The KKT residual that decides the status: its name and value."""
    values = {k: row[f"kkt_{k}"] for k in RESIDUALS if not _nan(row[f"kkt_{k}"])}
    name = max(values, key=values.get) if values else "stationarity"
    return name, values.get(name, math.nan)


def failures(df: pd.DataFrame) -> pd.DataFrame:
    """The runs that should be ok and are not (bad-input cases, where failing is right, excluded)."""
    return df[(df["expected"] != "error") & (df["status"] != "ok")]


def _exact_row(df: pd.DataFrame, case: str):
    rows = df[(df["case"] == case) & (df["solver"] == EXACT)]
    return rows.iloc[0] if len(rows) else None


# --- degenerate complementarity: interior point on biactive cases --------------------------------


def _data_vanish(problem: Mapping) -> bool:
    """f ≡ 0 by the case's definition: the manufactured and full-contact kinds scale with A, the
    constant kind is its value."""
    key = "value" if problem.get("kind") == "constant" else "A"
    return float(problem.get(key, math.nan)) == 0.0


def biactive_cases(df: pd.DataFrame) -> list[str]:
    """Cases whose every constrained node is biactive: f ≡ 0 by definition (b = 0, so u_h = 0 and
    λ = A u_h − b = 0), confirmed by the exact solver having all 4N constrained nodes in contact."""
    out = []
    for case in df["case"].unique():
        r = _exact_row(df, case)
        if r is not None and r["status"] == "ok" and _data_vanish(_problem(r)) and r["n_active"] == 4 * r["N"]:
            out.append(case)
    return out


def degenerate_runs(df: pd.DataFrame) -> pd.DataFrame:
    """The interior-point failures on the cases of ``biactive_cases``."""
    fails = failures(df)
    return fails[fails["case"].isin(biactive_cases(df)) & fails["route"].isin(INTERIOR_POINT_ROUTES)]


def degenerate_complementarity(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """The interior-point failures on cases where every constrained node is biactive."""
    runs = degenerate_runs(df)
    if runs.empty:
        return None
    cases = list(runs["case"].unique())
    exact = [_exact_row(df, c) for c in cases]
    counts = ", ".join(f"{int(r['n_active'])}/{4 * int(r['N'])} in {r['case']}" for r in exact)
    measured = "; ".join(
        f"{_run(r)} complementarity {_e(r['kkt_complementarity'])}, stationarity {_e(r['kkt_stationarity'])}, "
        f"{int(r['n_active'])} nodes in contact"
        for _, r in runs.iterrows()
    )
    text = (
        f"*Degenerate complementarity* ({_runs(runs)}). In {', '.join(cases)} the data vanish (f ≡ 0, so b = 0): "
        "u_h = 0 and λ = A u_h − b = 0, so every constrained node is biactive, u_i = 0 and λ_i = 0 (the exact "
        f"solver puts all of them in contact: {counts}). An interior-point method keeps u_i > 0 and λ_i > 0 "
        "and follows the central path u_i λ_i = μ → 0; with b = 0 that path is a ray, (u, λ) = √μ (v, A v) for "
        "one fixed vector v, so the certificate's relative complementarity max_i |u_i λ_i| / (‖u‖∞ σ) is the "
        f"same for every μ: no point of the path passes it. Recorded: {measured}."
    )
    singular = [c for c in cases if float(_problem(_exact_row(df, c)).get("c", math.nan)) == 0.0]
    if singular:
        worst = runs[runs["case"].isin(singular)]["kkt_stationarity"].max()
        text += (
            f" With c = 0 as well ({', '.join(singular)}), A = K is singular (κ₂(A) = ∞) and 1ᵀK = 0, where 1 is "
            "the vector of ones, so 1ᵀλ = 1ᵀ(A u − b) = 0: no λ > 0 exists, there is no central path at all, and "
            f"the stationarity residual fails too (up to {_e(worst)})."
        )
    admm = df[df["case"].isin(cases) & df["route"].isin(ADMM_ROUTES)]
    if len(admm) and (admm["status"] == "ok").all():
        text += (
            f" The ADMM columns ({', '.join(admm['solver'].unique())}), whose convergence needs no strict "
            f"complementarity, are ok on the same cases (largest KKT residual {_e(admm['kkt_worst'].max())})."
        )
    return text + " Strength: by construction (the biactivity and the ray follow from b = 0); the residuals measured."


# --- iteration or time limit -----------------------------------------------------------------------


def user_limit_runs(df: pd.DataFrame) -> pd.DataFrame:
    """The failures with cvxpy's status 'user_limit' (an iteration or time limit of the solver)."""
    fails = failures(df)
    return fails[fails["reason"].fillna("").astype(str).str.contains("'user_limit'")]


def _limits(spec: SolverSpec, route: str) -> tuple[float | None, int | None, bool]:
    """The column's time limit in s (None: none set), its iteration limit (its own, else cvxpy's
    default for the route; None: unknown) and whether the column sets the latter itself."""
    options = dict(spec.options)
    time = next((float(options[k]) for k in TIME_LIMIT_OPTIONS if options.get(k)), None)
    own = next((int(options[k]) for k in MAX_ITER_OPTIONS if options.get(k)), None)
    return time, own if own is not None else DEFAULT_MAX_ITER.get(route), own is not None


def _which_limit(r, time: float | None, iters: int | None) -> tuple[str, str]:
    """("max_iter" | "time", the run's sentence) for a run with known limits."""
    if time is None or r["total_s"] < time:
        why = "its column sets no time limit" if time is None else f"before its time limit of {_s(time)}"
        return "max_iter", f"{_run(r)} ended after {_s(r['total_s'])}, {why}"
    sentence = f"{_run(r)} ran {_s(r['total_s'])}, past its time limit of {_s(time)}"
    if iters:  # the rate max_iter would have needed to come first
        sentence += (f"; reaching max_iter first would have taken {r['total_s'] / iters * 1e3:.1f} ms or less per "
                     f"iteration on {(int(r['N']) + 1) ** 2:,} unknowns")
    return "time", sentence


def user_limit(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """Which limit a 'user_limit' status was: the time limit cannot have been reached by a run that
    ended sooner (its recorded wall time includes cvxpy's set-up, so the solver's own time is less)."""
    runs = user_limit_runs(df)
    if runs.empty:
        return None
    found: dict[str, list[str]] = {"max_iter": [], "time": [], "unknown": []}
    iter_limits = set()
    for _, r in runs.iterrows():
        spec = (specs or {}).get(r["solver"])
        if spec is None:
            found["unknown"].append(_run(r))
            continue
        time, iters, own = _limits(spec, r["route"])
        iter_limits.add((iters, own))
        kind, sentence = _which_limit(r, time, iters)
        found[kind].append(sentence)
    text = (
        f"*Iteration or time limit* ({_runs(runs)}). cvxpy reports 'user_limit' when the QP solver stops at its "
        "iteration limit max_iter or at its time limit (cvxpy's map of the solver's statuses; the CSV keeps "
        "only cvxpy's status)."
    )
    if len(iter_limits) == 1 and (limit := next(iter(iter_limits)))[0] is not None:
        source = "set by the columns" if limit[1] else "cvxpy's default, as the columns set none"
        text += f" Here max_iter = {limit[0]:,} ({source})."
    if found["max_iter"]:
        text += f" {'; '.join(found['max_iter'])}: the limit was max_iter. Strength: measured."
    if found["time"]:
        text += (f" {'; '.join(found['time'])}: most likely the time limit, but the iteration count of a failed "
                 "run is not recorded. Strength: explained.")
    if found["unknown"]:
        text += f" {', '.join(found['unknown'])}: the column's limits are not known here. Strength: open."
    return text


# --- absolute tolerances: the column as shipped against its normalized twin -------------------


def _twin(label: str, specs: Specs) -> str | None:
    """The column that differs from ``label`` only by ``normalize=True`` (``<label>`` for ``<label>_raw``)."""
    if not label.endswith("_raw"):
        return None
    twin = label.removesuffix("_raw")
    if specs is not None:
        raw, norm = specs.get(label), specs.get(twin)
        if raw is None or norm is None or {**raw.options, "normalize": True} != dict(norm.options):
            return None
    return twin


def unscaled_runs(df: pd.DataFrame, specs: Specs = None) -> pd.DataFrame:
    """Failures of an as-shipped column whose normalized twin is ok on the same case."""
    fails = failures(df)
    keep = []
    for _, r in fails.iterrows():
        twin = _twin(r["solver"], specs)
        rows = df[(df["case"] == r["case"]) & (df["solver"] == twin)] if twin else df.iloc[:0]
        keep.append(len(rows) == 1 and rows.iloc[0]["status"] == "ok" and rows.iloc[0]["route"] == r["route"])
    return fails[keep] if len(fails) else fails


def absolute_tolerances(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """The as-shipped cvxpy columns that fail where the same solver on normalized data is ok."""
    runs = unscaled_runs(df, specs)
    if runs.empty:
        return None
    amplitudes = sorted({_problem(r).get("A") for _, r in runs.iterrows()} - {None})
    sizes = f" (amplitude A = {', '.join(f'{a:g}' for a in amplitudes)})" if amplitudes else ""
    return (
        f"*Absolute tolerances* ({_runs(runs)}). On each of these cases the same QP solver with normalize=True, "
        "the column that differs from it only by dividing A by max A_ii and u by ‖u_D‖∞, is ok. The solvers' "
        "stopping tests are absolute (OSQP's and SCS's eps_abs, Clarabel's absolute gap and feasibility "
        f"tolerances), so these runs fail on the size of the data{sizes}, not on the problem. "
        "Strength: measured (the two columns differ in the scaling alone)."
    )


# --- the exact columns: differences at the certificate's rounding floor ---------------------------


def _floor(row, specs: Specs) -> float | None:
    """The certificate's rounding floor 16 ε ‖|A||u_h|‖∞/σ of a run where the CSV records it: the
    KKT threshold is max(tol, min(floor, 1e-6)), so a threshold above the column's tolerance is the floor."""
    spec = (specs or {}).get(row["solver"])
    if spec is None or _nan(row["kkt_threshold"]) or not row["kkt_threshold"] > spec.kkt_tol:
        return None
    return float(row["kkt_threshold"])


def same_solution_limit(df: pd.DataFrame, row: pd.Series, specs: Specs = None) -> tuple[float, float | None]:
    """(limit, floor): Δu vs exact up to ``limit`` means the same discrete solution; ``limit`` is
    SAME_SOLUTION_RTOL, or the case's rounding floor (the smaller of the two runs' floors) when larger."""
    exact = _exact_row(df, row["case"])
    floors = [_floor(row, specs), _floor(exact, specs) if exact is not None else None]
    floor = min(floors) if None not in floors else None
    return max(SAME_SOLUTION_RTOL, floor or 0.0), floor


def exact_columns(df: pd.DataFrame) -> pd.DataFrame:
    """The runs of the other exact columns that were compared with ``active_set``."""
    from signorini.pipeline.solver_options import exact_routes

    if "route" not in df:
        return df.iloc[:0]
    rows = df[df["route"].isin(exact_routes()) & (df["solver"] != EXACT)]
    return rows[rows["diff_to_active_set"].notna()]


def at_rounding_floor(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """Exact columns whose distance to ``active_set`` exceeds SAME_SOLUTION_RTOL but not the floor."""
    parts = []
    for _, r in exact_columns(df).iterrows():
        limit, floor = same_solution_limit(df, r, specs)
        if SAME_SOLUTION_RTOL < r["diff_to_active_set"] <= limit:
            tol = specs[r["solver"]].kkt_tol  # a recorded floor implies a known column
            parts.append(f"{_run(r)}: Δu vs exact {_e(r['diff_to_active_set'])}, floor {_e(floor)}, tolerance {tol:g}")
    if not parts:
        return None
    return (
        f"*Rounding floor* ({'; '.join(parts)}). Δu vs exact exceeds {SAME_SOLUTION_RTOL:g}, the summary's test of "
        "the same discrete solution, but not the certificate's rounding floor 16 ε ‖|A||u_h|‖∞/σ of the case, "
        "recorded as the KKT threshold of both runs because it exceeds their tolerance: the difference is at "
        "the rounding floor. A change of the residual by r σ can move u_h by as much as ‖A_FF⁻¹‖∞ r σ, which "
        "is at least r ‖u_h‖∞ as u_F = A_FF⁻¹ b_F, so relative differences below the floor are not resolved. "
        "Strength: measured (Δu and the floor are in the CSV)."
    )


# --- the contact set decided by round-off ------------------------------------------------------------


def roundoff_contact_runs(df: pd.DataFrame) -> pd.DataFrame:
    """Exact columns with the same solution as ``active_set`` (within SAME_SOLUTION_RTOL) but a
    different contact set."""
    rows = exact_columns(df)
    same_u = rows["diff_to_active_set"] <= SAME_SOLUTION_RTOL
    other_set = ~rows["same_contact_as_active_set"].map(_true)
    return rows[same_u & other_set]


def contact_set_at_roundoff(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """Which nodes count as in contact, where the exact routes agree on u_h but not on the set."""
    from signorini.pipeline.solver_options import exact_routes

    runs = roundoff_contact_runs(df)
    if runs.empty:
        return None
    texts = []
    for case, sub in runs.groupby("case", sort=False):
        rows = df[(df["case"] == case) & df["n_active"].notna()]
        exact = rows[rows["route"].isin(exact_routes())]
        cvx = rows[rows["route"].str.startswith("cvxpy_")]
        counts = ", ".join(f"{r['solver']} {int(r['n_active'])}" for _, r in exact.iterrows())
        worst = sub["diff_to_active_set"].max()
        texts.append(
            f"In {case} the exact routes agree with {EXACT} to Δu = {_e(worst)} at every node, yet count "
            f"different contact sets ({counts} of {4 * int(sub.iloc[0]['N'])} nodes): on each node where they "
            f"disagree one route has u_i = 0 and the other |u_i| ≤ {_e(worst)} ‖u_h‖∞ (measured: the CSV "
            "records no max |u_h| on ∂Ω, but Δu bounds it on these nodes)."
        )
        if len(cvx):
            others = ", ".join(f"{r['solver']} {int(r['n_active'])}" for _, r in cvx.iterrows())
            texts.append(f"The cvxpy columns count u_i ≤ 1e-8 ‖u_h‖∞ as contact, a different test ({others}).")
    return (
        f"*Contact set decided by round-off* ({_runs(runs)}). {' '.join(texts)} By stationarity λ_i = (A u_h − b)_i "
        "differs between the routes by at most ‖A‖∞ Δu ‖u_h‖∞ plus their residuals, and is 0 in the route that "
        "leaves the node free: on these nodes u_i and λ_i are both at round-off, the nodes are biactive, and "
        "either choice satisfies the KKT conditions, so the solution does not determine the contact set there "
        "and round-off decides which nodes count. Strength: measured (the bound on u_i), explained (that the "
        "nodes are biactive)."
    )


# --- what no class explains -----------------------------------------------------------------------------


def open_failures(df: pd.DataFrame, specs: Specs = None) -> str | None:
    """The failures no other class explains, with the residual or reason that decided each."""
    explained = pd.concat([degenerate_runs(df), user_limit_runs(df), unscaled_runs(df, specs)]).index
    rest = failures(df).drop(index=explained, errors="ignore")
    if rest.empty:
        return None
    parts = []
    for _, r in rest.iterrows():
        if r["status"] == "failed":
            parts.append(f"{_run(r)} failed ({str(r['reason'])[:80]})")
            continue
        name, value = _worst_residual(r)
        parts.append(f"{_run(r)} inaccurate, {name} {_e(value)} > {r['kkt_threshold']:.0e}")
    why = (
        " Each solver stopped by its own convergence test, yet a residual of the certificate is above the "
        "tolerance; the CSV does not show why the two tests disagree." if (rest["status"] == "inaccurate").all() else ""
    )
    return f"*Not explained*: {'; '.join(parts)}.{why} Strength: open."


FINDINGS: tuple[Callable[[pd.DataFrame, Specs], str | None], ...] = (
    degenerate_complementarity,
    user_limit,
    absolute_tolerances,
    at_rounding_floor,
    contact_set_at_roundoff,
    open_failures,
)


def discussion(df: pd.DataFrame, specs: Specs = None) -> list[str]:
    """The section ``Failures explained`` of ``stability.md`` (empty when no finding applies)."""
    found = [text for finding in FINDINGS if (text := finding(df, specs))]
    return ["## Failures explained", "", STRENGTHS, "", *(f"- {text}" for text in found), ""] if found else []
