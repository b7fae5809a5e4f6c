"""The stages of the Snakemake workflow, one function per stage.

Every ``workflow/scripts/*.py`` calls exactly one function of this module with the
job's inputs, outputs and parameters; the mathematics stays in the other modules
(``discrete``, ``norms``, ``convergence``) and the rendering in ``tables`` and
``figures``.  Heavy imports happen inside the stage functions, so that the
package modules a stage *runs* are exactly those listed in ``STAGE_MODULES``
(the Snakefile declares them as the rule's inputs; ``tests/test_pipeline.py``
checks the lists against what a stage really imports).

Cached artifacts are written atomically (``signorini.artifacts``); a corrupt
one raises ``CorruptArtifactError`` when a stage reads it, and
``quarantine_corrupt`` lets the workflow move such a file aside while it plans
the jobs, so that Snakemake rebuilds it instead of trusting it.
"""

from __future__ import annotations

import contextlib
import csv
import io
import logging
import math
import os
import sys
import time
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

from signorini.artifacts import CorruptArtifactError, atomic_write_text, load_json, load_npz, save_json, save_npz

log = logging.getLogger(__name__)

# --- the package modules each stage runs (paths relative to src/signorini/) ------------------

_BASE = ("__init__.py", "problem.py", "artifacts.py", "pipeline.py")
SOLVER_MODULES = (
    "solvers/__init__.py",
    "solvers/active_set.py",
    "solvers/certificate.py",
    "solvers/cvxpy_qp.py",
    "solvers/linalg.py",
    "solvers/result.py",
)
STAGE_MODULES: dict[str, tuple[str, ...]] = {
    "solve": (*_BASE, "mesh.py", "assembly.py", "discrete.py", *SOLVER_MODULES),
    "norm": (*_BASE, "mesh.py", "quadrature.py", "norms.py"),
    "sample": _BASE,
    "errors": (*_BASE, "mesh.py"),
    "eoc": (*_BASE, "convergence.py"),
    "tables": (*_BASE, "mesh.py", "tables.py"),
    "figures": (*_BASE, "mesh.py", "figures.py"),
    "reproduction": (*_BASE, "tables.py"),
    "runtime": _BASE,
    "stability_case": (
        *_BASE,
        "mesh.py",
        "assembly.py",
        "discrete.py",
        "quadrature.py",
        "norms.py",
        *SOLVER_MODULES,
        "stability.py",
    ),
    "stability_atlas": (*_BASE, "figures.py", "stability.py", "stability_report.py"),
    "theory": (*_BASE, "mesh.py", "assembly.py", "quadrature.py", "theory.py", *SOLVER_MODULES),
    "theory_report": (*_BASE, "mesh.py", "convergence.py", "theory.py", "theory_report.py"),
    "work_precision_system": (*_BASE, "mesh.py", "assembly.py", "discrete.py", *SOLVER_MODULES, "work_precision.py"),
    "work_precision_measure": (
        *_BASE,
        "mesh.py",
        "assembly.py",
        "discrete.py",
        "quadrature.py",
        "norms.py",
        *SOLVER_MODULES,
        "work_precision.py",
    ),
    "work_precision_table": (*_BASE, "work_precision.py"),
    "work_precision_figures": (*_BASE, "work_precision.py", "work_precision_report.py", "figures.py"),
    "work_precision_report": (*_BASE, "convergence.py", "tables.py", "work_precision.py", "work_precision_report.py"),
}

PATHS = {
    "solution_npz": "results/{scene}/N{N}/solution.npz",
    "solution_json": "results/{scene}/N{N}/solution.json",
    "norm_json": "results/{scene}/N{N}/norms/{norm}.json",
    "fields_npz": "results/{scene}/fields.npz",
    "errors_csv": "results/{scene}/errors.csv",
    "eoc_csv": "results/{scene}/eoc.csv",
    "theory_json": "results/{scene}/N{N}/theory.json",
}


# --- configuration checks beyond the JSON schema ---------------------------------------------


class ConfigError(ValueError):
    """The workflow configuration is invalid; the message names the offending field."""


def check_config(config: Mapping) -> None:
    """Semantic checks of a schema-valid config: integer ``N`` (not ``101.0``), unique ``N``,
    norm names the registry knows, admissible problem parameters and conventions."""
    from signorini.norms import Conventions, UnknownNormError, parse_norm
    from signorini.problem import Problem, ProblemParameterError

    scenes = config.get("scenes") or {}
    if not scenes:
        raise ConfigError("scenes: at least one scene is required")
    for name, scene in scenes.items():
        where = f"scenes.{name}"
        Ns = scene.get("N", [])
        for i, N in enumerate(Ns):
            if isinstance(N, bool) or not isinstance(N, int):
                raise ConfigError(f"{where}.N[{i}]: {N!r} is not an integer (cells per side)")
            if N < 1:
                raise ConfigError(f"{where}.N[{i}]: {N} must be ≥ 1")
        if len(set(Ns)) != len(Ns):
            raise ConfigError(f"{where}.N: values must be unique, got {Ns}")
        norms = scene.get("norms", [])
        for i, norm in enumerate(norms):
            try:
                parse_norm(norm)
            except UnknownNormError as err:
                raise ConfigError(f"{where}.norms[{i}]: {err}") from None
        if len(set(norms)) != len(norms):
            raise ConfigError(f"{where}.norms: names must be unique, got {norms}")
        try:
            Problem(**scene.get("problem", {}))
        except (ProblemParameterError, TypeError) as err:
            raise ConfigError(f"{where}.problem: {err}") from None
        try:
            Conventions(**scene.get("conventions", {}))
        except (ValueError, TypeError) as err:
            raise ConfigError(f"{where}.conventions: {err}") from None
    fig = config.get("figures_scene")
    if fig is not None and fig not in scenes:
        raise ConfigError(f"figures_scene: {fig!r} is not one of the scenes {sorted(scenes)}")


# --- corrupt cached artifacts ------------------------------------------------------------------


def _csv_ok(path: Path) -> bool:
    """A complete table CSV: ends with a newline, every row has the header's number of
    fields, no empty cell except ``h`` in the ``regression`` row of ``eoc.csv``."""
    text = path.read_text()
    if not text.endswith("\n"):
        return False
    rows = list(csv.reader(io.StringIO(text)))
    if len(rows) < 2 or rows[0][:2] != ["N", "h"]:
        return False
    for row in rows[1:]:
        if len(row) != len(rows[0]):
            return False
        if any(cell == "" for i, cell in enumerate(row) if not (i == 1 and row[0] == "regression")):
            return False
    return path.name != "eoc.csv" or rows[-1][0] == "regression"


def artifact_ok(path: str | os.PathLike) -> bool:
    """True unless ``path`` exists and fails its check (npz checksum, JSON completeness
    marker, complete rows of ``errors.csv``/``eoc.csv``)."""
    path = Path(path)
    if not path.exists():
        return True
    try:
        if path.suffix == ".npz":
            load_npz(path)
        elif path.suffix == ".json":
            load_json(path)
        elif path.suffix == ".csv":
            return _csv_ok(path)
    except (CorruptArtifactError, OSError, UnicodeDecodeError, csv.Error):
        return False
    return True


def quarantine_corrupt(paths: Iterable[str | os.PathLike]) -> list[str]:
    """Move every existing but corrupt artifact among ``paths`` to ``<name>.corrupt``.

    The Snakefile calls it for ``cached_artifacts`` before Snakemake looks at any file.
    The artifact is then missing, so Snakemake rebuilds it as soon as a job of the run
    needs it (a requested target, or the input of a job that has to run), instead of
    handing a truncated file to the next stage.  Outputs already derived from it stay
    valid: they were computed before the damage (it was written atomically and checked
    when read).
    """
    moved = []
    for path in paths:
        if not artifact_ok(path):
            target = f"{path}.corrupt"
            os.replace(path, target)
            print(f"signorini: corrupt artifact {path} moved to {target}; rebuilt when a job needs it", file=sys.stderr)
            moved.append(str(path))
    return moved


def cached_artifacts(root: str | os.PathLike, scenes: Iterable[str]) -> Iterator[Path]:
    """The checkable cached artifacts (``.npz``, ``.json``) of the given scenes under ``root``."""
    for scene in scenes:
        base = Path(root) / scene
        yield from base.glob("*.npz")
        yield from (base / name for name in ("errors.csv", "eoc.csv"))
        yield from base.glob("N*/solution.*")
        yield from base.glob("N*/norms/*.json")


# --- logging -----------------------------------------------------------------------------------


@contextlib.contextmanager
def job_log(path: str | os.PathLike | None) -> Iterator[logging.Logger]:
    """Log to the job's log file (and stderr); an exception is logged with its traceback, then re-raised."""
    root = logging.getLogger()
    handlers: list[logging.Handler] = [logging.StreamHandler(sys.stderr)]
    if path:
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(path, mode="w"))
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    for handler in handlers:
        handler.setFormatter(fmt)
        root.addHandler(handler)
    pkg = logging.getLogger("signorini")
    old_level = pkg.level
    pkg.setLevel(logging.INFO)  # the package's messages; other libraries stay at WARNING
    try:
        yield log
    except BaseException:
        log.exception("job failed")
        raise
    finally:
        for handler in handlers:
            root.removeHandler(handler)
            handler.close()
        pkg.setLevel(old_level)


# --- stages ------------------------------------------------------------------------------------


def _problem(params: Mapping):
    from signorini.problem import Problem

    return Problem(**{k: float(v) for k, v in params.items()})


def solve_stage(
    problem_params: Mapping,
    N: int,
    solver: str,
    out_npz: str | os.PathLike,
    out_json: str | os.PathLike,
    diagonal: str = "sw_ne",
    solver_options: Mapping | None = None,
) -> dict:
    """Mesh, assemble and solve (S_h); save ``u``, ``λ``, the contact set and the diagnostics.

    A solution without a valid KKT certificate raises ``KKTError`` (the residuals are in
    its message, hence in the job's log) and nothing is written.
    """
    from signorini.discrete import build, solve_discrete
    from signorini.mesh import mesh_width

    problem = _problem(problem_params)
    t0 = time.perf_counter()
    disc = build(problem, int(N), diagonal)
    t1 = time.perf_counter()
    result = solve_discrete(disc, solver=solver, **dict(solver_options or {}))
    t2 = time.perf_counter()
    summary = result.summary()
    log.info(
        "N=%d solver=%s iterations=%d active=%d certificate: %s",
        N,
        solver,
        result.iterations,
        result.active.size,
        result.certificate.describe(),
    )
    info = {
        "N": int(N),
        "h": mesh_width(int(N)),
        "diagonal": diagonal,
        "problem": problem.as_dict(),
        "solver_requested": solver,
        "solver_options": dict(solver_options or {}),
        "n_dofs": int(result.u.size),
        "n_constrained": int(disc.boundary.size),
        "timings": {
            "build_s": t1 - t0,
            "solve_s": t2 - t1,
            "note": "perf_counter timers inside the job: build = mesh + assembly; "
            "solve = solve_discrete incl. the warm-start cascade; summary.wall_time_s = final solver call only",
        },
        "summary": summary,
    }
    save_npz(out_npz, u=result.u, lam=result.lam, active=result.active, N=int(N), diagonal=diagonal)
    save_json(out_json, info)
    return info


def load_solution(solution_npz: str | os.PathLike, N: int, diagonal: str = "sw_ne"):
    """``u_h`` from a solve artifact, checked against the mesh it is used on.

    Raises ``CorruptArtifactError`` for a truncated file, a wrong length or another diagonal.
    """
    sol = load_npz(solution_npz)
    u_h = sol["u"]
    if u_h.shape != ((N + 1) ** 2,):
        raise CorruptArtifactError(f"{solution_npz}: u has shape {u_h.shape}, expected ({(N + 1) ** 2},) for N={N}")
    if "diagonal" in sol and str(sol["diagonal"]) != diagonal:
        raise CorruptArtifactError(f"{solution_npz}: solved with diagonal {sol['diagonal']}, not {diagonal}")
    return u_h


def norm_stage(
    problem_params: Mapping,
    N: int,
    solution_npz: str | os.PathLike,
    norm: str,
    out_json: str | os.PathLike,
    diagonal: str = "sw_ne",
    conventions: Mapping | None = None,
) -> dict:
    """One norm of ``u - u_h`` on the mesh with ``N`` cells per side; saves value and timing."""
    from signorini.mesh import friedrichs_keller, mesh_width
    from signorini.norms import Conventions, evaluate_norms, parse_norm

    parse_norm(norm)  # fail before any work on an unknown name
    problem = _problem(problem_params)
    conv = Conventions(**dict(conventions or {}))
    u_h = load_solution(solution_npz, N, diagonal)
    t0 = time.perf_counter()
    mesh = friedrichs_keller(int(N), diagonal)
    t1 = time.perf_counter()
    value = evaluate_norms(problem, mesh, u_h, [norm], conv)[norm]  # chunked: bounded memory
    t2 = time.perf_counter()
    log.info("N=%d %s = %.6e (mesh %.2f s, norm %.3f s)", N, norm, value, t1 - t0, t2 - t1)
    info = {
        "N": int(N),
        "h": mesh_width(int(N)),
        "norm": norm,
        "value": float(value),
        "conventions": conv.as_dict(),
        "diagonal": diagonal,
        "timings": {
            "mesh_s": t1 - t0,
            "norm_s": t2 - t1,
            "note": "perf_counter timers inside the job: mesh = building the mesh, norm = error evaluation + reduction",
        },
    }
    save_json(out_json, info)
    return info


def theory_stage(
    problem_params: Mapping,
    N: int,
    solution_npz: str | os.PathLike,
    out_json: str | os.PathLike,
    diagonal: str = "sw_ne",
) -> dict:
    """Supercloseness, discrete H^{1/2}(∂Ω) norm and contact-set metrics of one solution."""
    from signorini.mesh import friedrichs_keller, mesh_width
    from signorini.theory import theory_quantities

    problem = _problem(problem_params)
    u_h = load_solution(solution_npz, N, diagonal)
    t0 = time.perf_counter()
    values = theory_quantities(problem, friedrichs_keller(int(N), diagonal), u_h)
    info = {"N": int(N), "h": mesh_width(int(N)), **values, "timings": {"theory_s": time.perf_counter() - t0}}
    log.info("N=%d %s", N, {k: v for k, v in values.items() if k != "contact"})
    save_json(out_json, info)
    return info


def sample_stage(problem_params: Mapping, n: int, out_npz: str | os.PathLike) -> None:
    """``u`` and ``f`` on an ``n × n`` grid of the unit square (the data of Figure 2)."""
    import numpy as np

    problem = _problem(problem_params)
    t = np.linspace(0.0, 1.0, int(n))
    X, Y = np.meshgrid(t, t, indexing="xy")
    x = np.stack([X, Y])
    save_npz(out_npz, x=X, y=Y, u=problem.u(x), f=problem.f(x))


def read_errors(scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str | os.PathLike]]):
    """A DataFrame with columns ``N``, ``h`` and one column per norm (in the order of ``norm_jsons``),
    read from the per-norm JSON artifacts; ``norm_jsons[name][k]`` belongs to ``scene_N[k]``."""
    import pandas as pd

    from signorini.mesh import mesh_width

    Ns = [int(N) for N in scene_N]
    data: dict[str, list] = {"N": Ns, "h": [mesh_width(N) for N in Ns]}
    for name, paths in norm_jsons.items():
        if len(paths) != len(Ns):
            raise ValueError(f"norm {name}: {len(paths)} artifacts for {len(Ns)} meshes")
        column = []
        for N, path in zip(Ns, paths, strict=True):
            art = load_json(path)
            if art.get("norm") != name or int(art.get("N", -1)) != N:
                raise CorruptArtifactError(f"{path}: holds {art.get('norm')} at N={art.get('N')}, not {name} at N={N}")
            column.append(float(art["value"]))
        data[name] = column
    return pd.DataFrame(data)


def _write_csv(df, out_csv: str | os.PathLike) -> None:
    buf = io.StringIO()
    df.to_csv(buf, index=False, lineterminator="\n")  # floats round-trip (shortest repr)
    atomic_write_text(out_csv, buf.getvalue())


def collect_errors(
    scene_N: Sequence[int], norm_jsons: Mapping[str, Sequence[str | os.PathLike]], out_csv: str | os.PathLike
) -> None:
    """``errors.csv``: one row per ``N``; columns ``N``, ``h``, then one per norm in scene order."""
    _write_csv(read_errors(scene_N, norm_jsons), out_csv)


def read_errors_csv(path: str | os.PathLike):
    """``errors.csv`` (or ``eoc.csv``) as a DataFrame; a truncated or malformed file raises
    ``CorruptArtifactError``."""
    import pandas as pd

    try:
        df = pd.read_csv(path, dtype={"N": str})
    except (OSError, ValueError) as err:
        raise CorruptArtifactError(f"{path}: unreadable CSV ({err})") from err
    if list(df.columns[:2]) != ["N", "h"] or df.empty:
        raise CorruptArtifactError(f"{path}: expected columns N, h, <norms>, got {list(df.columns)}")
    return df


def eoc_table(errors_csv: str | os.PathLike, out_csv: str | os.PathLike) -> None:
    """``eoc.csv``: same columns as ``errors.csv``; one EOC row per ``N`` after the first
    (labelled by the finer mesh), then a ``regression`` row (``h`` empty)."""
    import numpy as np
    import pandas as pd

    from signorini.convergence import eoc, regression_slope

    err = read_errors_csv(errors_csv)
    norms = list(err.columns[2:])
    h = err["h"].to_numpy(dtype=float)
    if np.isnan(err[norms].to_numpy(dtype=float)).any():
        raise CorruptArtifactError(f"{errors_csv}: missing values")
    rows = pd.DataFrame({"N": err["N"].iloc[1:].to_list(), "h": h[1:]})
    regr: dict[str, object] = {"N": "regression", "h": math.nan}
    for name in norms:
        e = err[name].to_numpy(dtype=float)
        rows[name] = eoc(h, e)[1:]
        regr[name] = regression_slope(h, e) if len(h) >= 2 else math.nan
    _write_csv(pd.concat([rows, pd.DataFrame([regr])], ignore_index=True), out_csv)


# --- run times ---------------------------------------------------------------------------------

_BENCHMARK_FIELDS = {"s": "benchmark_wall_s", "cpu_time": "benchmark_cpu_s", "max_rss": "benchmark_max_rss_mb"}


def collect_runtime(jobs: Sequence[Mapping], out_csv: str | os.PathLike) -> None:
    """``runtime.csv`` from the jobs' ``benchmark:`` files and their in-job timers.

    ``jobs``: one mapping per job with ``rule``, ``scene``, ``N``, ``norm`` (or ""),
    ``benchmark`` (the TSV path) and ``artifact`` (the job's JSON, holding its timers).
    ``benchmark_*`` columns time the whole job (interpreter start, imports, I/O);
    ``timer_s`` is the timer around the measured call inside the job (``timer_scope``).
    """
    out = io.StringIO()
    columns = ["rule", "scene", "N", "norm", *(_BENCHMARK_FIELDS.values()), "timer_s", "timer_scope"]
    writer = csv.DictWriter(out, columns, lineterminator="\n")
    writer.writeheader()
    for job in jobs:
        with open(job["benchmark"]) as fh:
            rows = list(csv.DictReader(fh, delimiter="\t"))
        if not rows:
            raise CorruptArtifactError(f"{job['benchmark']}: empty benchmark file")
        bench = rows[-1]
        art = load_json(job["artifact"])
        timings = art.get("timings", {})
        if job["rule"] == "solve":
            timer, scope = timings.get("build_s", 0.0) + timings.get("solve_s", 0.0), "build+solve"
        else:
            timer, scope = timings.get("mesh_s", 0.0) + timings.get("norm_s", 0.0), "mesh + error evaluation + norm"
        record = {"rule": job["rule"], "scene": job["scene"], "N": int(job["N"]), "norm": job.get("norm", "")}
        for key, column in _BENCHMARK_FIELDS.items():
            value = bench.get(key, "")
            record[column] = f"{float(value):.3f}" if value not in ("", "NA", "-") else ""
        record["timer_s"] = f"{timer:.3f}"
        record["timer_scope"] = scope
        writer.writerow(record)
    atomic_write_text(out_csv, out.getvalue())
