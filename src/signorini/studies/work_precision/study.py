"""The work-precision study's configuration: the solver routes a configuration can take
(``ROUTES``, ``kind_of``), the solver configurations of a scene's ``study`` block and the checks
that the scene may reuse its source scene's artifacts."""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.peers import PEER_SOLVERS
from signorini.published import FIGURE3_NORMS
from signorini.solvers import EXACT_SOLVERS
from signorini.studies.work_precision import routes
from signorini.studies.work_precision.routes import QP_PREFIX, Kind, Runner

FIGURE_NORMS = FIGURE3_NORMS  # the panel rows of work_precision.{pdf,png}
EXACT_LABEL = "exact"  # the tolerance label of the exact (active-set) runs
DEFAULT_LABEL = "default"  # the tolerance label of a solver's own default tolerance
GROWTH_EXPONENT = 1.5  # predicted time ∝ (number of unknowns)^GROWTH_EXPONENT
CASCADE_START = "cascade"
WARM_SUFFIX = "_ws"  # name of a peer's variant started from the cascade (``same_warm_start``)
# the prose of work_precision.md (report.prose): a file of the package that no import names, so the
# report's rule lists it with its code inputs itself (workflow/rules/work_precision.smk)
REPORT_TEMPLATE = Path(__file__).with_name("report.tmpl")
# the routes of the study's configurations, name → its runner (a name ending in "_" is a prefix:
# cvxpy_<solver>); spelled as the scenes and the stability atlas spell them
ROUTES: dict[str, Runner] = {
    **dict.fromkeys(EXACT_SOLVERS, routes.EXACT),
    QP_PREFIX: routes.CVXPY,
    **dict.fromkeys(PEER_SOLVERS, routes.PEER),
}


INACCURATE = "KKT residual above the tolerance"  # the reason of an answer the certificate does not accept


def tolerance_key(label: str) -> tuple[int, float]:
    """Orders tolerance labels: ``exact`` and ``default`` first, then the swept tolerances loose to tight."""
    return (0, 0.0) if label in (EXACT_LABEL, DEFAULT_LABEL) else (1, -float(label))


def accuracy_status(worst: float, required: float) -> tuple[str, str]:
    """``("ok", "")`` when the worst relative KKT residual of an answer meets the ``required``
    tolerance, else ``("inaccurate", INACCURATE)``; the two numbers are recorded as they are
    (``kkt_worst``, ``kkt_required``) and only the report formats them."""
    return ("ok", "") if math.isfinite(worst) and worst <= required else ("inaccurate", INACCURATE)


class StudyConfigError(ValueError):
    """The ``study`` block of a scene is inconsistent with its source scene."""


class UnknownSolverError(StudyConfigError):
    """A solver name that is none of the study's routes (``ROUTES``)."""


def route(solver: str) -> Runner:
    """The runner of a route: a name of ``ROUTES``, or a prefix of it followed by a solver's name
    (``cvxpy_osqp``); any other name raises ``UnknownSolverError``."""
    if solver in ROUTES and not solver.endswith("_"):
        return ROUTES[solver]
    for prefix, runner in ROUTES.items():
        if prefix.endswith("_") and solver.startswith(prefix) and len(solver) > len(prefix):
            return runner
    known = ", ".join(f"{r}<solver> (e.g. {r}osqp)" if r == QP_PREFIX else r + "<solver>" if r.endswith("_") else r
                      for r in ROUTES)
    hint = f" ({QP_PREFIX}{solver.lower()} for cvxpy's {solver})" if solver.isupper() else ""
    raise UnknownSolverError(f"unknown solver {solver!r}{hint}; choose one of the routes {known}")


def kind_of(solver: str) -> Kind:
    """The kind of a route (``routes.Kind``): exact, QP or peer; an unknown name raises
    ``UnknownSolverError``."""
    return route(solver).kind


def table_solver(solver: str) -> str:
    """How ``work_precision.csv`` names a route's solver: a cvxpy route by cvxpy's name of its QP
    solver (``cvxpy_osqp`` → ``OSQP``), any other route by itself."""
    return route(solver).table_name(solver)


def table_route(name: str) -> str:
    """The route of a solver named as ``table_solver`` names it (``OSQP`` → ``cvxpy_osqp``)."""
    return name if name in ROUTES else QP_PREFIX + name.lower()


@dataclass(frozen=True)
class SolverConfig:
    """One solver configuration: ``solver`` is a route of ``ROUTES``: an exact route (``active_set``,
    ``multigrid``, ``auto``), a cvxpy QP solver (``cvxpy_osqp``, …), a PETSc peer (``petsc_snes``,
    ``petsc_tao``) or another in-process route; ``options`` go to its call (``solve_discrete``:
    ``warm_start``, ``backend``, …; ``cvxpy_solve``: solver options such as ``polishing``) or into
    PETSc's options database (``snes_type``, ``pc_type``, …, without the dash)."""

    name: str
    solver: str
    label: str
    options: dict = field(default_factory=dict)
    start: str = "cold"  # a peer's initial guess: "cold" (u = 0) or "cascade" (CASCADE_START)

    @property
    def runner(self) -> Runner:
        """What runs the configuration's route (``route``)."""
        return route(self.solver)

    @property
    def kind(self) -> Kind:
        """Exact, QP or peer (``kind_of``)."""
        return self.runner.kind

    @property
    def exact(self) -> bool:
        """A certified active-set route (direct, multigrid or auto)."""
        return self.kind is Kind.EXACT

    @property
    def initial(self) -> str:
        """Where the solver starts: ``cascade`` (the cascade's interpolated coarse solution) or ``cold``."""
        if self.exact:  # warm_start: null is the cold start
            return "cold" if self.options.get("warm_start", "cascade") is None else "cascade"
        return self.start

    @property
    def peer(self) -> bool:
        """A PETSc method, run by the external driver (``peers``)."""
        return self.kind is Kind.PEER

    def as_dict(self) -> dict:
        out = {"name": self.name, "solver": self.solver, "label": self.label, "options": dict(self.options)}
        return out if self.start == "cold" else {**out, "start": self.start}


def study_configs(study: Mapping, installed: Sequence[str] = ()) -> dict[str, SolverConfig]:
    """The configurations of a ``study`` block: its ``configs`` (name → ``{solver, label, options}``,
    ``solver`` a route of ``ROUTES``) plus, with ``qp_solvers: installed`` (the cvxpy QP solvers
    ``installed``, by cvxpy's names, e.g. ``signorini.solvers.installed_qp_solvers()``) or a list of
    QP routes (``cvxpy_osqp``, …), one configuration per QP solver, named and labelled as the table
    names the solver (``osqp``, ``OSQP``), unless a configuration of that name exists.  With
    ``same_warm_start: true`` every PETSc peer also gets a variant ``<name>_ws`` that starts from the
    cascade's interpolated coarse solution (cvxpy's QP interfaces take no initial guess: their
    ``warm_start`` reuses the previous solve of the same problem only).  An unknown solver raises
    ``UnknownSolverError``."""
    from signorini.pipeline.solver_options import check_options

    out: dict[str, SolverConfig] = {}
    for name, spec in (study.get("configs") or {}).items():
        options = dict(spec.get("options") or {})
        out[name] = SolverConfig(name, str(spec["solver"]), str(spec.get("label", name)), options)
    qp = study.get("qp_solvers", [])
    for solver in [QP_PREFIX + s.lower() for s in installed] if qp == "installed" else qp:
        if kind_of(solver) is not Kind.QP:
            raise StudyConfigError(f"study.qp_solvers: {solver!r} is not a QP solver (e.g. {QP_PREFIX}osqp)")
        label = table_solver(solver)
        out.setdefault(label.lower(), SolverConfig(label.lower(), solver, label, {}))
    if study.get("same_warm_start"):
        for name, config in list(out.items()):
            if config.peer and config.start == "cold" and name + WARM_SUFFIX not in out:
                warm, label = name + WARM_SUFFIX, f"{config.label} (cascade start)"
                out[warm] = SolverConfig(warm, config.solver, label, config.options, CASCADE_START)
    for name, config in out.items():
        if not re.fullmatch(r"[a-z0-9_]+", name):
            raise StudyConfigError(f"configuration name {name!r}: use lower-case letters, digits and _")
        try:
            route(config.solver)
        except UnknownSolverError as err:
            raise UnknownSolverError(f"study.configs.{name}.solver: {err}") from None
        problem = check_options(f"study.configs.{name}.options", config.solver, config.options)
        if problem:
            raise StudyConfigError(problem)
    return out


def check_study(scenes: Mapping, name: str) -> None:
    """The scene ``name`` may reuse its source scene's artifacts: same problem and diagonal,
    its ``N`` a subset of the source's, its norms among the source's and containing L4, W14."""
    scene = scenes[name]
    study = scene.get("study")
    where = f"scenes.{name}.study"
    if not study:
        raise StudyConfigError(f"{where}: missing")
    source = study.get("source")
    if source not in scenes:
        raise StudyConfigError(f"{where}.source: {source!r} is not one of the scenes {sorted(scenes)}")
    src = scenes[source]
    if dict(src["problem"]) != dict(scene["problem"]):
        raise StudyConfigError(f"{where}.source: problem {scene['problem']} differs from {source}'s {src['problem']}")
    if src.get("diagonal", DEFAULT_DIAGONAL) != scene.get("diagonal", DEFAULT_DIAGONAL):
        raise StudyConfigError(f"{where}.source: diagonal differs from {source}'s")
    if src.get("conventions", {}) != scene.get("conventions", {}):
        raise StudyConfigError(f"{where}.source: conventions differ from {source}'s")
    missing = [N for N in scene["N"] if N not in src["N"]]
    if missing:
        raise StudyConfigError(f"scenes.{name}.N: {missing} not among {source}'s N {src['N']}")
    if list(scene["N"]) != sorted(scene["N"]):
        raise StudyConfigError(f"scenes.{name}.N: must be increasing (the time prediction uses the previous N)")
    norms = [n for n in scene["norms"] if n not in src["norms"]]
    if norms:
        raise StudyConfigError(f"scenes.{name}.norms: {norms} not computed by {source}")
    for n in FIGURE_NORMS:
        if n not in scene["norms"]:
            raise StudyConfigError(f"scenes.{name}.norms: the figure needs {n}")
    for N in study.get("figure_N", []):
        if N not in scene["N"]:
            raise StudyConfigError(f"{where}.figure_N: {N} is not one of the scene's N")
    study_configs(study, installed=[])  # names
