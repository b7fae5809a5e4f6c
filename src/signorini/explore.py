"""Read-only helpers for the notebooks in ``notebooks/``: find a scene, read its artifacts.

The notebooks explore what the pipeline computed; they call these helpers and the
package's own functions and never re-implement the mathematics.  Nothing here writes
into ``results/`` except ``build_scene``, which runs Snakemake for a scene's targets
(the same command a user would type).

Where the notebooks look:

- ``SIGNORINI_ROOT``: the project directory (``Snakefile``, ``results/``, ``paper_figures/``);
  default: the repository this package was installed from (editable install), else the
  first parent of the working directory that holds a ``Snakefile``.
- ``SIGNORINI_SCENE``: the scene to read; default ``paper`` if its ``errors.csv`` and
  ``eoc.csv`` exist, else ``smoke`` (built with Snakemake if it is missing, which is quick:
  docs/evidence/design-measurements.md#smoke-scene).
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

import numpy as np

from signorini.fem.mesh import DEFAULT_DIAGONAL
from signorini.fem.problem import ExactProblem, Problem, make_problem
from signorini.pipeline.artifacts import CorruptArtifactError, load_json, load_npz
from signorini.pipeline.integrity import artifact_ok
from signorini.pipeline.paths import PATHS, REFERENCES
from signorini.studies.paper.sample import sample_fields
from signorini.studies.scene.store import SceneMesh, read_errors_csv, read_norm, read_uncertainties

ROOT_ENV = "SIGNORINI_ROOT"
SCENE_ENV = "SIGNORINI_SCENE"
PREFERRED_SCENES = ("paper", "smoke")
SMOKE_SCENE = "smoke"


# --- where ----------------------------------------------------------------------------------------


def project_root() -> Path:
    """The project directory: ``$SIGNORINI_ROOT``, else the repository of this package, else
    the nearest parent of the working directory with a ``Snakefile``."""
    env = os.environ.get(ROOT_ENV)
    if env:
        return Path(env).resolve()
    repo = Path(__file__).resolve().parents[2]  # src/signorini/explore.py -> repository
    if (repo / "Snakefile").exists():
        return repo
    for parent in (Path.cwd(), *Path.cwd().parents):
        if (parent / "Snakefile").exists():
            return parent
    raise FileNotFoundError(f"no project directory found: set {ROOT_ENV} to the directory holding the Snakefile")


def _path(root: Path, key: str, scene: str, **kw) -> Path:
    return root / PATHS[key].format(scene=scene, **kw)


def scene_built(scene: str, root: str | os.PathLike | None = None) -> bool:
    """True if the scene's ``errors.csv`` and ``eoc.csv`` exist and are complete."""
    root = Path(root) if root is not None else project_root()
    paths = [_path(root, "errors_csv", scene), _path(root, "eoc_csv", scene)]
    return all(p.exists() and artifact_ok(p) for p in paths)


def build_scene(scene: str = SMOKE_SCENE, root: str | os.PathLike | None = None, cores: int = 2) -> float:
    """Run ``snakemake -c<cores> results/<scene>/errors.csv results/<scene>/eoc.csv`` in the
    project directory; returns the wall time.  Raises ``RuntimeError`` with the log tail on failure."""
    root = Path(root) if root is not None else project_root()
    exe = Path(sys.executable).with_name("snakemake")
    cmd = [str(exe) if exe.exists() else "snakemake", f"-c{int(cores)}"]
    cmd += [PATHS["errors_csv"].format(scene=scene), PATHS["eoc_csv"].format(scene=scene)]
    t0 = time.perf_counter()
    proc = subprocess.run(
        cmd, cwd=root, capture_output=True, encoding="utf-8", env={**os.environ, "PYTHONDONTWRITEBYTECODE": "1"}
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} (in {root}) failed:\n{proc.stdout[-2000:]}\n{proc.stderr[-4000:]}")
    return time.perf_counter() - t0


def locate_scene(
    root: str | os.PathLike | None = None, preferred: Sequence[str] = PREFERRED_SCENES, build: bool = True
) -> Scene:
    """The scene the notebooks read: ``$SIGNORINI_SCENE`` if set, else the first built one of
    ``preferred`` (``paper``, then ``smoke``); if none is built, the smoke scene is built with
    Snakemake (``build=True``) or ``FileNotFoundError`` is raised."""
    root = Path(root) if root is not None else project_root()
    forced = os.environ.get(SCENE_ENV)
    candidates = [forced] if forced else list(preferred)
    for name in candidates:
        if scene_built(name, root):
            return Scene(name, root)
    name = forced or SMOKE_SCENE
    if not build:
        raise FileNotFoundError(f"scene {name!r} is not built under {root / 'results'}")
    seconds = build_scene(name, root)
    print(f"built scene {name!r} with Snakemake in {seconds:.0f} s (results under {root / 'results' / name})")
    return Scene(name, root)


# --- one scene's artifacts --------------------------------------------------------------------------


@dataclass
class Scene:
    """A built scene under ``<root>/results/<name>``: tables, solutions, meshes, parameters.

    Problem parameters, diagonal and norm conventions are read from the artifacts
    themselves (``solution.json``, the norm JSONs), so scenes added with ``--configfile``
    work too.
    """

    name: str
    root: Path
    _solutions: dict = field(default_factory=dict, repr=False)

    @property
    def dir(self) -> Path:
        return self.root / "results" / self.name

    def errors(self):
        """``errors.csv`` as a DataFrame (``N`` as int)."""
        df = read_errors_csv(_path(self.root, "errors_csv", self.name))
        return df.astype({"N": int})

    def eoc(self):
        """``eoc.csv`` as a DataFrame (``N``: the finer mesh of each pair, then ``regression``)."""
        return read_errors_csv(_path(self.root, "eoc_csv", self.name))

    @cached_property
    def Ns(self) -> list[int]:
        return [int(N) for N in self.errors()["N"]]

    @property
    def norms(self) -> list[str]:
        return list(self.errors().columns[2:])

    def solution_info(self, N: int) -> dict:
        """``solution.json``: certificate, iterations, timers, problem parameters."""
        return load_json(_path(self.root, "solution_json", self.name, N=N))

    @cached_property
    def problem_params(self) -> dict:
        """The problem block the scene's solve jobs recorded (scenes added with ``--configfile`` too)."""
        return dict(self.solution_info(self.Ns[0])["problem"])

    def at(self, N: int) -> SceneMesh:
        """The scene's mesh ``N`` as the pipeline's stages see it (``studies.scene.store``): a mesh
        family's from the mesh job's artifact, where the scene names one."""
        spec = dict(self.solution_info(int(N)).get("mesh", {}))
        mesh_npz = _path(self.root, "mesh_npz", self.name, N=N)
        return SceneMesh(self.problem_params, int(N), self.diagonal, spec, str(mesh_npz) if spec else None)

    def solution(self, N: int) -> dict[str, np.ndarray]:
        """``solution.npz``, read through the store (checksum, size, diagonal and problem checked):
        ``u`` (nodal values), ``lam`` (one entry per boundary node, sorted as
        ``mesh.boundary_nodes``), ``active`` (contact nodes)."""
        if N not in self._solutions:
            self._solutions[N] = self.at(N).solution(_path(self.root, "solution_npz", self.name, N=N))
        return self._solutions[N]

    @cached_property
    def problem(self) -> ExactProblem:
        return make_problem(self.problem_params)

    @cached_property
    def diagonal(self) -> str:
        return str(self.solution_info(self.Ns[0]).get("diagonal", DEFAULT_DIAGONAL))

    @cached_property
    def conventions(self):
        """The norm conventions the scene's norm jobs used (from a norm JSON), else the defaults."""
        from signorini.fem.norms.conventions import Conventions

        for path in sorted((self.dir / f"N{self.Ns[0]}" / "norms").glob("*.json")):
            return Conventions(**load_json(path)["conventions"])
        return Conventions()

    def mesh(self, N: int):
        return self.at(N).mesh()

    def norm_json(self, N: int, norm: str) -> Path:
        return _path(self.root, "norm_json", self.name, N=N, norm=norm)

    def cached_norm(self, N: int, norm: str) -> float | None:
        """The value of a norm job's artifact (read through the store, checked), if that norm was
        computed by the pipeline."""
        path = self.norm_json(N, norm)
        return read_norm(path, norm, N) if path.exists() else None

    def uncertainties(self, norms: Sequence[str]):
        """The norms' algebraic-error uncertainties per mesh (the frame of ``read_uncertainties``),
        or None where an artifact records none (the tables then print the paper's digits)."""
        try:
            return read_uncertainties(self.Ns, {n: [self.norm_json(N, n) for N in self.Ns] for n in norms})
        except (OSError, CorruptArtifactError):
            return None

    def fields(self) -> dict[str, np.ndarray]:
        """``u`` and ``f`` on a grid (Figure 2's data): ``fields.npz`` if the pipeline sampled it,
        else ``sample_fields``, the sample stage's own function."""
        path = _path(self.root, "fields_npz", self.name)
        return load_npz(path) if path.exists() else sample_fields(self.problem)

    def norms_for(self, names: Sequence[str], Ns: Sequence[int] | None = None):
        """The named norms of ``u − u_h`` for each ``N`` (DataFrame ``N``, ``h``, names): the
        pipeline's cached value where a norm job exists, else evaluated on the cached
        solution with the scene's conventions (``fem.norms.evaluate.evaluate_named_norms``)."""
        import pandas as pd

        from signorini.fem.norms.evaluate import evaluate_named_norms

        rows = []
        for N in Ns or self.Ns:
            cached = {n: self.cached_norm(N, n) for n in names}
            missing = [n for n, v in cached.items() if v is None]
            if missing:
                u_h = self.solution(N)["u"]
                cached.update(evaluate_named_norms(self.problem, self.mesh(N), u_h, missing, self.conventions))
            rows.append({"N": int(N), "h": self.at(N).h, **{n: cached[n] for n in names}})
        return pd.DataFrame(rows)


# --- tables next to the paper's -------------------------------------------------------------------


def paper_reference(table: int, root: str | os.PathLike | None = None):
    """The published Table 1 or 2 (``workflow/reference/paper_table<k>.csv``) as a DataFrame indexed by row label."""
    import pandas as pd

    from signorini.studies.paper.reference import read_table_csv

    root = Path(root) if root is not None else project_root()
    rows = read_table_csv(root / REFERENCES[f"paper_table{table}"])
    return pd.DataFrame.from_dict(rows, orient="index")


def published_mismatch(
    problem: Problem, diagonal: str, conventions, Ns: Sequence[int], paper_Ns: Sequence[int]
) -> str | None:
    """Why the published values do not belong to a scene (None: they do).  They are the errors of
    the paper's problem (``Problem()``) on its triangulation (``DEFAULT_DIAGONAL``) under the
    default norm conventions on the meshes of its tables (``paper_Ns``): another problem or other
    meshes give other numbers, which a table next to the paper's would pass off as comparable."""
    from signorini.fem.norms.conventions import Conventions

    if problem != Problem():
        return f"its problem {problem.as_dict()} is not the paper's {Problem().as_dict()}"
    if diagonal != DEFAULT_DIAGONAL:
        return f"its triangulation (diagonal {diagonal!r}) is not the paper's ({DEFAULT_DIAGONAL!r})"
    if conventions != Conventions():
        return f"its norm conventions {conventions.as_dict()} are not the defaults {Conventions().as_dict()}"
    if [int(N) for N in Ns] != [int(N) for N in paper_Ns]:
        return f"its meshes N = {list(Ns)} are not the paper's N = {list(paper_Ns)}"
    return None


def scene_published_mismatch(scene: Scene) -> str | None:
    """``published_mismatch`` of a built scene (its problem, diagonal and conventions from its
    artifacts; the paper's meshes from ``workflow/reference/paper_table1.csv``)."""
    paper_Ns = [_denominator(lab) for lab in paper_reference(1, scene.root).index]
    return published_mismatch(scene.problem, scene.diagonal, scene.conventions, scene.Ns, paper_Ns)


def ours_table(scene: Scene, table: int):
    """Our Table 1 (errors) or Table 2 (EOCs, ``regr.``, ``theo.``) of a scene, indexed like the
    paper's: the cells of the pipeline's tables (``studies.paper.tables``), with their digits."""
    import pandas as pd

    from signorini.published import TABLE1_NORMS, TABLE2_NORMS, expected_rate
    from signorini.studies.paper.tables import eoc_rows, eoc_uncertainties, error_rows

    errors = scene.errors()
    norms = [n for n in (TABLE1_NORMS if table == 1 else TABLE2_NORMS) if n in errors.columns]
    uncertainties = scene.uncertainties(norms)
    if table == 1:
        labels, rows = error_rows(errors, uncertainties, norms)
    else:
        per_row = None if uncertainties is None else eoc_uncertainties(errors, uncertainties, norms)
        labels, rows = eoc_rows(scene.eoc(), per_row, norms)
        rows = [[(round(v, k), k) for v, k in row] for row in rows]
    out = pd.DataFrame([[v for v, _ in row] for row in rows], index=labels, columns=norms, dtype=float)
    if table == 2:
        out.loc["theo."] = [expected_rate(n) for n in norms]
    return out


def side_by_side(scene: Scene, table: int):
    """Ours, the paper's and the relative deviation per norm (MultiIndex columns ``(norm, what)``)
    for the paper's scene; for any other scene (``scene_published_mismatch``) ours only, the
    reason in ``.attrs["published"]``."""
    import pandas as pd

    from signorini.studies.paper.reference import relative_deviation

    ours = ours_table(scene, table)
    mismatch = scene_published_mismatch(scene)
    if mismatch is not None:
        out = pd.DataFrame({(norm, "ours"): ours[norm] for norm in ours.columns}, index=ours.index)
        out.attrs["published"] = f"no published values: scene {scene.name!r} is not the paper's ({mismatch})"
        return out
    paper = paper_reference(table, scene.root)
    labels = list(ours.index) + [lab for lab in paper.index if lab not in ours.index]
    order = {lab: i for i, lab in enumerate(labels)}
    tail = ("regr.", "theo.")
    labels.sort(key=lambda lab: (lab in tail, tail.index(lab) if lab in tail else _denominator(lab), order[lab]))
    cols = {}
    for norm in [n for n in ours.columns if n in paper.columns]:
        o = ours[norm].reindex(labels)
        p = paper[norm].reindex(labels)
        dev = [
            100.0 * relative_deviation(a, b) if np.isfinite(a) and np.isfinite(b) else math.nan
            for a, b in zip(o, p, strict=True)
        ]
        cols[(norm, "ours")] = o
        cols[(norm, "paper")] = p
        cols[(norm, "dev. %")] = pd.Series(dev, index=labels)
    return pd.DataFrame(cols, index=labels)


def _denominator(label: str) -> int:
    return int(label[2:]) if label.startswith("1/") else 0


# --- rates for any p ----------------------------------------------------------------------------------


def expected_orders(p: float) -> tuple[float, float]:
    """The paper's expected orders (each minus ε) of ``‖u − u_h‖_{L^p}`` and ``‖u − u_h‖_{W^{1,p}}``
    (``signorini.published.expected_order``): ``(2, 1)`` for ``p ≤ 4``, ``(3/2 + 2/p, 1/2 + 2/p)`` beyond."""
    from signorini.published import expected_order

    return expected_order("L", p), expected_order("W1", p)


def norm_names(p: float) -> tuple[str, str]:
    """The names of the ``L^p`` and ``W^{1,p}`` norms (``L6``, ``W16``, ``L2.5``, ``Linf``)."""
    from signorini.fem.norms.names import lp_names

    return lp_names(p)


def rates_for_p(scene: Scene, p: float):
    """Errors, EOCs and regression slopes of the ``L^p`` and ``W^{1,p}`` norms on the scene's
    meshes, next to the expected orders.  Returns ``(errors, rates)`` DataFrames."""
    import pandas as pd

    from signorini.fem.convergence import eoc, regression_slope

    names = norm_names(p)
    errors = scene.norms_for(names)
    h = errors["h"].to_numpy()
    rates = {}
    for name, theory in zip(names, expected_orders(p), strict=True):
        e = errors[name].to_numpy()
        col = {f"EOC 1/{N}": v for N, v in zip(errors["N"].iloc[1:], eoc(h, e)[1:], strict=True)}
        col["regr."] = regression_slope(h, e)
        col["theory (− ε)"] = theory
        rates[name] = col
    return errors, pd.DataFrame(rates)


# --- pointwise errors and solver histories ----------------------------------------------------------


def element_errors(problem: Problem, mesh, u_h: np.ndarray, conventions=None) -> dict[str, np.ndarray]:
    """Per triangle: ``max |u − u_h|`` over the ``L^∞`` point set and ``max |∇(u − u_h)|`` over the
    ``W^{1,∞}`` point set (``norms.error_field``), and the centroids — the error map."""
    from signorini.fem.norms.conventional import error_field

    f = error_field(problem, mesh, u_h, conventions, norms=["Linf", "W1inf"])
    return {
        "e": np.abs(f.e_max).max(axis=1),
        "grad_e": np.hypot(f.de_max[0], f.de_max[1]).max(axis=1),
        "centroid": mesh.p[:, mesh.t].mean(axis=1),
    }


def active_set_history(disc, **options):
    """Solve ``disc`` by the direct route and return ``(result, history)``: one row per
    Newton step of the final solve (active nodes, changes, factorisations and low-rank correction
    columns so far, elapsed time), the solver's own ``SolveResult.history``."""
    import pandas as pd

    from signorini.fem.solve import solve_discrete

    result = solve_discrete(disc, "direct", **options)
    return result, pd.DataFrame(result.history)


def existing(root: str | os.PathLike | None, *relpaths: str) -> dict[str, Path]:
    """The given project-relative paths that exist (for optional outputs of other scenes)."""
    root = Path(root) if root is not None else project_root()
    return {rel: root / rel for rel in relpaths if (root / rel).exists()}


def boundary_trace(problem: Problem, n: int = 2001) -> dict[str, np.ndarray]:
    """``u`` and the outward normal derivative ``∂_n u`` along ∂Ω, unrolled counter-clockwise
    from (0, 0) by arc length ``s ∈ [0, 4)`` (bottom, right, top, left edge); ``n`` points per edge."""
    t = np.linspace(0.0, 1.0, n, endpoint=False)
    zero, one = np.zeros_like(t), np.ones_like(t)
    points = [np.stack([t, zero]), np.stack([one, t]), np.stack([1.0 - t, one]), np.stack([zero, 1.0 - t])]
    normals = [(0.0, -1.0), (1.0, 0.0), (0.0, 1.0), (-1.0, 0.0)]
    x = np.concatenate(points, axis=1)
    nrm = np.concatenate([np.tile(np.array(v)[:, None], (1, n)) for v in normals], axis=1)
    return {
        "s": np.concatenate([k + t for k in range(4)]),
        "x": x,
        "u": problem.u(x),
        "dn_u": np.sum(nrm * problem.grad_u(x), axis=0),
    }


def boundary_arclength(x: np.ndarray) -> np.ndarray:
    """The unrolled coordinate ``s`` of ``boundary_trace`` for points ``x`` (2, m) on ∂Ω."""
    x1, x2 = np.asarray(x[0], dtype=float), np.asarray(x[1], dtype=float)
    tol = 1e-12
    return np.select(
        [(x2 <= tol) & (x1 < 1.0 - tol), x1 >= 1.0 - tol, x2 >= 1.0 - tol],
        [x1, 1.0 + x2, 3.0 - x1],
        default=4.0 - x2,
    )


def display_artifacts(paths: dict[str, Path]) -> list:
    """IPython display objects for optional outputs: Markdown for ``.md``, a DataFrame for
    ``.csv``, an image for ``.png`` (other suffixes: the path as text)."""
    import pandas as pd
    from IPython.display import Image, Markdown

    out: list = []
    for rel, path in paths.items():
        out.append(Markdown(f"**`{rel}`**"))
        if path.suffix == ".md":
            out.append(Markdown(path.read_text(encoding="utf-8")))
        elif path.suffix == ".csv":
            out.append(pd.read_csv(path, comment="#", encoding="utf-8"))
        elif path.suffix == ".png":
            out.append(Image(filename=str(path)))
        else:
            out.append(Markdown(f"`{path}`"))
    return out
