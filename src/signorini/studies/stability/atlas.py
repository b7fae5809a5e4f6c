"""The stability atlas's configuration: the ``atlas`` block of a scene parsed into solver
columns and cases (the groups and what the mathematics predicts for them: ``cases``)."""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field

from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.published import PAPER_NORMS

GROUPS = ("scaling", "reaction", "mesh", "degenerate", "bad_input")
CORRUPTIONS = {
    "nan_b": "one entry of the load vector b is NaN (NaN data f)",
    "inf_A": "one diagonal entry of the matrix is +Inf",
    "nan_parameter": "problem parameter A = NaN",
    "non_spd": "A = K - M (the reaction c = -1): symmetric, positive diagonal, indefinite",
    "nonsymmetric": "one off-diagonal entry of A scaled by 1.5 (A ≠ Aᵀ)",
    "empty_constraints": "no constrained node (B = ∅)",
}
STATUSES = ("ok", "inaccurate", "failed")
CASE_NAME = re.compile(r"^[A-Za-z0-9_.+-]+$")


class AtlasConfigError(ValueError):
    """The ``atlas`` block of a scene is invalid; the message names the field."""


@dataclass(frozen=True)
class SolverSpec:
    """One column of the atlas: a solver route of ``solve_discrete`` with its options, and the
    KKT tolerance for status ``ok``."""

    label: str
    solver: str
    options: Mapping = field(default_factory=dict)
    kkt_tol: float = 1e-6


@dataclass(frozen=True)
class Case:
    """One row group of the atlas (see the module docstring for the groups)."""

    name: str
    group: str
    problem: Mapping  # make_problem parameters (kind + parameters), complete
    N: int
    diagonal: str = DEFAULT_DIAGONAL
    jitter: float = 0.0
    seed: int = 0
    corrupt: str | None = None
    solvers: tuple[str, ...] = ()
    reference: str | None = None  # scaling: compare u_h / A with this case's
    note: str = ""
    mesh: Mapping = field(default_factory=dict)  # a mesh family and its parameters (fem.mesh_families)

    @property
    def expect(self) -> str:
        """``error`` for bad input (a clear error is the correct outcome), else ``ok``."""
        return "error" if self.corrupt else "ok"

    def as_dict(self) -> dict:
        return {**asdict(self), "problem": dict(self.problem), "solvers": list(self.solvers), "mesh": dict(self.mesh)}


@dataclass(frozen=True)
class Atlas:
    """The parsed ``atlas`` block: cases, solver columns and limits."""

    cases: tuple[Case, ...]
    solvers: dict[str, SolverSpec]
    norms: tuple[str, ...]
    timeout_s: float = 600.0
    cond_max_dofs: int = 50_000

    def job(self, name: str) -> dict:
        """What the job of one case needs (its ``params``: a change reruns this case only)."""
        case = self.case(name)
        return {
            "case": case.as_dict(),
            "solvers": {label: asdict(self.solvers[label]) for label in case.solvers},
            "norms": list(self.norms),
            "timeout_s": self.timeout_s,
            "cond_max_dofs": self.cond_max_dofs,
        }

    def runtime_min(self, name: str) -> int:
        """A generous wall-time bound of a case job in minutes (``resources.runtime``): imports,
        assembly, one hard time limit per solver column."""
        case = self.case(name)
        return int(10 + case.N**2 // 20_000 + len(case.solvers) * self.timeout_s // 60)

    @classmethod
    def from_job(cls, job: Mapping) -> Atlas:
        """The one-case atlas of ``job`` (the inverse of ``job``)."""
        raw = dict(job["case"])
        case = Case(**{**raw, "solvers": tuple(raw["solvers"]), "problem": dict(raw["problem"])})
        solvers = {label: SolverSpec(**spec) for label, spec in job["solvers"].items()}
        return cls((case,), solvers, tuple(job["norms"]), float(job["timeout_s"]), int(job["cond_max_dofs"]))

    def case(self, name: str) -> Case:
        for case in self.cases:
            if case.name == name:
                return case
        raise AtlasConfigError(f"unknown atlas case {name!r}; configured: {[c.name for c in self.cases]}")


def _parse_solvers(block: Mapping, where: str) -> tuple[dict[str, SolverSpec], tuple[str, ...]]:
    """The solver columns and the default columns of a case."""
    from signorini.pipeline.solver_options import check_options, exact_routes

    specs: dict[str, SolverSpec] = {}
    for label, spec in (block.get("solvers") or {}).items():
        if not CASE_NAME.match(str(label)) or not isinstance(spec, Mapping) or "solver" not in spec:
            raise AtlasConfigError(f"{where}.atlas.solvers.{label}: needs a name [A-Za-z0-9_.+-] and a 'solver'")
        options = spec.get("options") or {}
        problem = check_options(f"{where}.atlas.solvers.{label}.options", str(spec["solver"]), options)
        if problem:
            raise AtlasConfigError(problem)
        specs[label] = SolverSpec(
            str(label),
            str(spec["solver"]),
            dict(spec.get("options") or {}),
            float(spec.get("kkt_tol", 1e-10 if spec["solver"] in exact_routes() else 1e-6)),
        )
    if not specs:
        raise AtlasConfigError(f"{where}.atlas.solvers: at least one solver column is required")
    default_solvers = tuple(block.get("default_solvers") or specs)
    unknown = [s for s in default_solvers if s not in specs]
    if unknown:
        raise AtlasConfigError(f"{where}.atlas.default_solvers: {unknown} are not columns of {where}.atlas.solvers")
    return specs, default_solvers


def _parse_norms(block: Mapping, scene: Mapping, where: str) -> tuple[str, ...]:
    from signorini.fem.norms.names import UnknownNormError, parse_norm_name

    norms = tuple(block.get("norms") or scene.get("norms") or PAPER_NORMS)
    for i, name in enumerate(norms):
        try:
            parse_norm_name(name)
        except UnknownNormError as err:
            raise AtlasConfigError(f"{where}.atlas.norms[{i}]: {err}") from None
    return norms


def _case_problem(raw: Mapping, base: Mapping, at: str) -> dict:
    """The case's problem: merged over the scene's for the manufactured kind; checked."""
    from signorini.fem.problem import DEFAULT_KIND, ProblemParameterError, make_problem

    own = dict(raw.get("problem") or {})
    if own.get("kind", DEFAULT_KIND) == DEFAULT_KIND:  # over the scene's problem
        params = {**base, **own}
        params.pop("kind", None)
    else:
        params = own
    try:
        make_problem(params)
    except ProblemParameterError as err:
        raise AtlasConfigError(f"{at}.problem: {err}") from None
    return params


def _parse_case(raw, at: str, base: Mapping, default_N: int, specs: Mapping, default_solvers: tuple) -> Case:
    from signorini.fem.mesh import DIAGONALS

    if not isinstance(raw, Mapping):
        raise AtlasConfigError(f"{at}: must be a mapping")
    name = str(raw.get("name", ""))
    if not CASE_NAME.match(name):
        raise AtlasConfigError(f"{at}.name: {name!r} must match {CASE_NAME.pattern}")
    group = raw.get("group")
    if group not in GROUPS:
        raise AtlasConfigError(f"{at}.group: {group!r} is not one of {GROUPS}")
    corrupt = raw.get("corrupt")
    if corrupt is not None and corrupt not in CORRUPTIONS:
        raise AtlasConfigError(f"{at}.corrupt: {corrupt!r} is not one of {sorted(CORRUPTIONS)}")
    params = _case_problem(raw, base, at)
    N = raw.get("N", default_N)
    if isinstance(N, bool) or not isinstance(N, int) or N < 1:
        raise AtlasConfigError(f"{at}.N: {N!r} must be a positive integer")
    diagonal = raw.get("diagonal", DEFAULT_DIAGONAL)
    if diagonal not in DIAGONALS:
        raise AtlasConfigError(f"{at}.diagonal: {diagonal!r} is not one of {DIAGONALS}")
    jitter = float(raw.get("jitter", 0.0))
    if not 0.0 <= jitter < 0.5:
        raise AtlasConfigError(f"{at}.jitter: {jitter} must lie in [0, 0.5)")
    mesh = _case_mesh(raw, at, jitter)
    solvers = tuple(raw.get("solvers") or default_solvers)
    unknown = [s for s in solvers if s not in specs]
    if unknown:
        raise AtlasConfigError(f"{at}.solvers: {unknown} are not columns of {at.rsplit('.cases', 1)[0]}.solvers")
    return Case(
        name, group, params, int(N), diagonal, jitter, int(raw.get("seed", 0)), corrupt, solvers,
        raw.get("reference"), str(raw.get("note", "")), mesh,
    )


def _case_mesh(raw: Mapping, at: str, jitter: float) -> dict:
    """A case's ``mesh`` block (a family of ``fem.mesh_families`` and its parameters), checked;
    ``jitter`` and ``seed`` of a case without one are the Friedrichs–Keller mesh's."""
    from signorini.fem.mesh_families import check_mesh_spec

    mesh = raw.get("mesh") or {}
    if not isinstance(mesh, Mapping):
        raise AtlasConfigError(f"{at}.mesh: must be a mapping (family and its parameters)")
    try:
        check_mesh_spec(mesh)
    except ValueError as err:
        raise AtlasConfigError(f"{at}.mesh: {err}") from None
    if mesh and (jitter or "seed" in raw):
        raise AtlasConfigError(f"{at}: jitter and seed belong in the mesh block when a case has one")
    return dict(mesh)


def parse_atlas(scene: Mapping, where: str = "scenes.stability") -> Atlas:
    """Parse and check the ``atlas`` block of a scene; errors name the field.

    A case's ``problem`` is merged over the scene's ``problem`` when both are of the
    manufactured kind; a case of another kind (``constant``, ``full_contact``) gives all
    its parameters.  ``N`` defaults to the scene's first ``N``, ``solvers`` to the block's
    ``default_solvers`` (all columns if absent).
    """
    block = scene.get("atlas")
    if not isinstance(block, Mapping):
        raise AtlasConfigError(f"{where}.atlas: missing (a mapping with solvers and cases)")
    specs, default_solvers = _parse_solvers(block, where)
    norms = _parse_norms(block, scene, where)
    base, default_N = dict(scene.get("problem") or {}), int((scene.get("N") or [41])[0])
    cases: list[Case] = []
    for i, raw in enumerate(block.get("cases") or []):
        case = _parse_case(raw, f"{where}.atlas.cases[{i}]", base, default_N, specs, default_solvers)
        if any(c.name == case.name for c in cases):
            raise AtlasConfigError(f"{where}.atlas.cases[{i}].name: duplicate case name {case.name!r}")
        cases.append(case)
    if not cases:
        raise AtlasConfigError(f"{where}.atlas.cases: at least one case is required")
    names = {c.name for c in cases}
    for i, case in enumerate(cases):
        if case.reference is not None and case.reference not in names:
            raise AtlasConfigError(f"{where}.atlas.cases[{i}].reference: {case.reference!r} is not a case")
    return Atlas(
        tuple(cases), specs, norms, float(block.get("timeout_s", 600.0)), int(block.get("cond_max_dofs", 50_000))
    )


def scene_atlas(config: Mapping, scene: str) -> Atlas:
    """The parsed atlas of a configured scene (clear errors for a scene without one)."""
    scenes = config.get("scenes") or {}
    if scene not in scenes or "atlas" not in scenes[scene]:
        raise AtlasConfigError(
            f"scene {scene!r} has no atlas block; scenes with one: "
            f"{sorted(n for n, s in scenes.items() if 'atlas' in s)}"
        )
    return parse_atlas(scenes[scene], f"scenes.{scene}")


def case_artifacts(config: Mapping, scene: str, template: str) -> list[str]:
    """``template`` (with ``{scene}``, ``{case}``) for every case of the scene's atlas."""
    return [template.format(scene=scene, case=case.name) for case in scene_atlas(config, scene).cases]


def check_atlases(config: Mapping) -> None:
    """``parse_atlas`` for every scene with an ``atlas`` block (the Snakefile calls it at parse time)."""
    for name, scene in (config.get("scenes") or {}).items():
        if "atlas" in scene:
            parse_atlas(scene, f"scenes.{name}")


