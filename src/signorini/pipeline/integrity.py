"""The integrity of the cached artifacts: checks before Snakemake plans a run, and the table
contract every reader uses.

A cached artifact damaged after it was written (a truncated ``.npz``, an incomplete JSON, a
cut-off ``errors.csv``, a checksum removed by hand) is moved to ``<name>.corrupt`` by
``quarantine_corrupt``, so that Snakemake rebuilds it when a job needs it instead of handing it
to the next stage.  A valid artifact that is out of date (computed by other code, from other
inputs or with other parameters than the current config asks; a scene table holding other meshes
or norms than the scene's) is removed by ``remove_stale``, whether or not Snakemake's metadata
knows about it.  Only a Snakemake call that runs jobs changes anything (``runs_jobs``, asked of
the executor Snakemake starts): a dry run names what it finds and leaves the cache as it is.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import os
import re
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    changed_input,
    content_digest,
    load_json,
    load_npz,
    provenance_of,
)
from signorini.pipeline.paths import BENCHMARKS, PATHS, RESULTS


def table_defect(path: str | os.PathLike) -> str | None:
    """Why a scene table (``errors.csv``, ``eoc.csv``) is damaged, None when it is complete: it ends
    with a newline, its header starts with ``N, h``, every row has the header's number of fields,
    no cell is empty except ``h`` in the ``regression`` row of ``eoc.csv`` (its last row), every
    number is finite (and, in ``errors.csv``, non-negative).  The one check of the table contract,
    used by the cache check and by every reader (``studies.scene.store.read_errors_csv``); which
    meshes and norms a table holds is not damage but currency (``table_mismatch``)."""
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        rows = list(csv.reader(io.StringIO(text)))
    except (OSError, UnicodeDecodeError, csv.Error) as err:
        return f"unreadable ({err})"
    if not text.endswith("\n"):
        return "cut off (no final newline)"
    if len(rows) < 2 or rows[0][:2] != ["N", "h"]:
        return f"expected a header N, h, <norms> and at least one row, got {rows[0] if rows else 'nothing'}"
    for row in rows[1:]:
        if len(row) != len(rows[0]):
            return f"the row {row[:1]} has {len(row)} fields, the header {len(rows[0])}"
        cells = [cell for i, cell in enumerate(row[1:], 1) if not (i == 1 and row[0] == "regression")]
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            return f"the row {row[:1]} holds a cell that is not a number"
        if not all(math.isfinite(v) and (v >= 0.0 or path.name != "errors.csv") for v in values):
            sign = " and non-negative" if path.name == "errors.csv" else ""
            return f"the row {row[:1]} holds a value that is not finite{sign}"
    if path.name == "eoc.csv" and rows[-1][0] != "regression":
        return "its last row is not the regression row"
    return None


@dataclass(frozen=True)
class TableShape:
    """What a scene table must hold: its ``N`` labels (first column) and its header."""

    rows: tuple[str, ...]
    columns: tuple[str, ...]


def expected_shape(path: Path, block: Mapping) -> TableShape | None:
    """The rows and columns ``errors.csv`` / ``eoc.csv`` of a scene with config ``block`` must hold
    (``N``, ``h``, then the scene's norms in scene order, as ``errors_stage`` writes them)."""
    labels = tuple(str(N) for N in block.get("N", []))
    rows = {"errors.csv": labels, "eoc.csv": (*labels[1:], "regression")}.get(path.name)
    return None if rows is None else TableShape(rows, ("N", "h", *block.get("norms", [])))


def _listed(items: Sequence[str]) -> str:
    return ", ".join(items) or "none"


def table_mismatch(path: Path, shape: TableShape | None) -> str | None:
    """Why a (complete) table is out of date: it holds other meshes or norms than ``shape`` asks
    (None when it holds exactly those, or cannot be read: the damage check names that)."""
    if shape is None or not path.is_file() or not artifact_ok(path):
        return None
    try:
        rows = list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    if not rows:
        return None
    held = tuple(row[0] for row in rows[1:] if row)
    if held != shape.rows:
        return f"holds the rows N = {_listed(held)}, the scene asks for {_listed(shape.rows)}"
    if tuple(rows[0]) != shape.columns:
        return f"has the norms {_listed(rows[0][2:])}, the scene asks for {_listed(shape.columns[2:])}"
    return None


def rendered_mismatch(tables: Mapping[str, str | os.PathLike], Ns: Sequence[int]) -> str | None:
    """Why the paper's rendered tables (``{"table1": csv, "table2": csv}``) are out of date: they
    hold other meshes than the rendered scene's ``Ns`` (a changed ``N`` list; Snakemake's own
    record of the inputs may be gone).  None when they hold exactly those, or do not exist."""
    labels = [f"1/{int(N)}" for N in Ns]
    expected = {"table1": labels, "table2": [*labels[1:], "regr.", "theo."]}
    for name, path in tables.items():
        path = Path(path)
        if not path.is_file():
            continue
        try:
            rows = list(csv.reader(io.StringIO(path.read_text(encoding="utf-8"))))
        except (OSError, UnicodeDecodeError, csv.Error):
            return f"{path} cannot be read"
        held = [row[0] for row in rows[1:] if row]
        if held != expected[name]:
            return f"{path} holds the rows h = {_listed(held)}, the rendered scene asks for {_listed(expected[name])}"
    return None


def remove_rendered(outputs: Iterable[str | os.PathLike], reason: str, execute: bool) -> list[str]:
    """Delete the paper's rendered outputs of another state of the rendered scene (``reason``), so
    that ``all`` renders them anew, or, in a read-only call, only name them."""
    present = [str(path) for path in outputs if Path(path).exists()]
    if present:
        verb = "removed; rebuilt when a job needs them" if execute else "a run that needs them rebuilds them"
        print(f"signorini: out of date: {reason}: {', '.join(present)} ({verb})", file=sys.stderr)
        for path in present if execute else ():
            os.remove(path)
    return present


def _benchmark_ok(path: Path) -> bool:
    """A complete Snakemake benchmark file: a header starting with ``s`` (seconds), at least one
    row with the header's number of fields and a finite, non-negative number of seconds."""
    text = path.read_text(encoding="utf-8")
    rows = [line.split("\t") for line in text.splitlines()]
    if not text.endswith("\n") or len(rows) < 2 or rows[0][0] != "s":
        return False
    try:
        return all(len(row) == len(rows[0]) and 0.0 <= float(row[0]) < math.inf for row in rows[1:])
    except ValueError:
        return False


CHECKSUM_MAX_BYTES = 64 * 2**20  # larger archives (the assembled systems of fine meshes) get a structural check


def _zip_complete(path: Path) -> bool:
    """A large archive is complete if its zip directory lists its checksum (a truncated file has
    none); the checksum itself is verified by every job that loads it."""
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            return "_checksum.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def artifact_ok(path: str | os.PathLike) -> bool:
    """True unless ``path`` exists and fails its integrity check (npz checksum, JSON checksum and
    completeness marker, complete rows of ``errors.csv``/``eoc.csv`` and of a benchmark ``.tsv``)."""
    path = Path(path)
    if not path.exists():
        return True
    try:
        if path.suffix == ".npz" and path.stat().st_size > CHECKSUM_MAX_BYTES:
            return _zip_complete(path)
        if path.suffix == ".npz":
            load_npz(path)
        elif path.suffix == ".json":
            load_json(path)
        elif path.suffix == ".csv":
            return table_defect(path) is None
        elif path.suffix == ".tsv":
            return _benchmark_ok(path)
    except (CorruptArtifactError, OSError, UnicodeDecodeError, csv.Error):
        return False
    return True


def runs_jobs(executor_plugin: Any) -> bool:
    """Whether Snakemake runs jobs with the executor plugin it passes to ``Workflow.execute``:
    neither a dry run (``-n`` however spelled, ``dryrun`` in a profile) nor ``--touch``.  Calls
    that plan nothing (``--lint``, ``-l``, ``--summary``, ``--report``, ``--dag``, ...) never reach
    ``execute``, so whatever Snakemake's parser accepts is decided as Snakemake decides it."""
    settings = executor_plugin.common_settings
    return not (settings.dryrun_exec or settings.touch_exec)


def corrupt_artifacts(paths: Iterable) -> list[str]:
    """The existing but damaged artifacts among ``paths`` (a path, or a pair of a table's path and
    the ``N`` labels it must hold, as ``cached_artifacts`` yields them)."""
    checks = [item[0] if isinstance(item, tuple) else item for item in paths]
    return [str(path) for path in checks if not artifact_ok(path)]


def warn_corrupt(paths: Iterable[str | os.PathLike]) -> list[str]:
    """Name every damaged artifact among ``paths`` on stderr, touching nothing (read-only calls)."""
    damaged = corrupt_artifacts(paths)
    for path in damaged:
        print(
            f"signorini: damaged artifact {path}; a run that needs it moves it aside and rebuilds it", file=sys.stderr
        )
    return damaged


ParamsOf = Callable[[str, dict], "dict | None"]


def changed_param(recorded: Mapping, expected: Mapping) -> str | None:
    """The first parameter whose recorded value differs from the expected one, as ``name: old ->
    new`` (None when they agree); compared as JSON text, as recorded (a NaN equals itself there)."""
    for key in sorted(set(recorded) | set(expected)):
        old, new = (json.dumps(side.get(key, "(none)"), sort_keys=True) for side in (recorded, expected))
        if old != new:
            return f"{key}: {old} -> {new}"
    return None


def _recorded(paths: Iterable) -> dict[str, dict]:
    """{path: provenance} of the existing ``.npz``/``.json`` artifacts among ``paths`` (damaged ones
    are left to the damage check)."""
    recorded: dict[str, dict] = {}
    for item in paths:
        path = Path(item[0] if isinstance(item, tuple) else item)
        if path.suffix not in (".npz", ".json") or not path.exists():
            continue
        try:
            recorded[str(path)] = provenance_of(path) or {}
        except CorruptArtifactError:
            continue
    return recorded


def stale_artifacts(
    paths: Iterable, current_code: Callable[[str], str], current_params: ParamsOf | None = None
) -> list[tuple[str, str]]:
    """The artifacts among ``paths`` that are valid but out of date, each with the reason: a recorded
    code digest other than ``current_code(rule)`` of the rule that wrote it (a job that ran older
    code, say an edit during the run, which modification times cannot tell); inputs other than the
    ones now on disk (an input replaced by a copy with an old modification time); parameters other
    than ``current_params(path, provenance)``, the ones a job writing it now would get (a changed
    scene, also when Snakemake's metadata is gone); computed from such an artifact; a scene table
    (a pair of path and ``TableShape``) holding other meshes or norms than its scene's."""
    paths = list(paths)
    recorded = _recorded(paths)
    stale: dict[str, str] = {}
    digest = functools.cache(content_digest)  # the norms of a mesh share its solution
    for path, prov in recorded.items():
        expected = current_params(path, prov) if current_params and "params" in prov else None
        if prov.get("code") and prov["code"] != current_code(prov["rule"]):
            stale[path] = "was computed by other code than the current one"
        elif changed := changed_input(prov, digest):
            stale[path] = f"was computed from another {changed} than the one now on disk"
        elif expected is not None and (changed := changed_param(prov["params"], expected)):
            stale[path] = f"was computed with other parameters than the config asks now ({changed})"
    grown = True
    while grown:  # and everything computed from a stale artifact
        grown = False
        for path, prov in recorded.items():
            source = next((p for p in prov.get("inputs") or {} if p in stale), None)
            if path not in stale and source:
                stale[path], grown = f"was computed from {source}, which is out of date", True
    for item in paths:
        if isinstance(item, tuple) and (reason := table_mismatch(Path(item[0]), item[1])):
            stale[str(item[0])] = reason
    return list(stale.items())


def remove_stale(
    paths: Iterable, current_code: Callable[[str], str], execute: bool, current_params: ParamsOf | None = None
) -> list[str]:
    """Delete the out-of-date artifacts (``stale_artifacts``) and the scene tables computed from them
    (``errors.csv``, ``eoc.csv`` of the same scene), so that a job that needs one rebuilds it and
    everything after it reruns, or, in a read-only call (``execute`` false), only name them.  They
    are valid files of another state, not damage: deleted, not moved to ``.corrupt``."""
    stale = stale_artifacts(paths, current_code, current_params)
    named = {path for path, _ in stale}
    scenes = {Path(*Path(path).parts[:2]) for path, _ in stale}  # results/<scene>/...
    derived = [str(scene / name) for scene in sorted(scenes) for name in ("errors.csv", "eoc.csv")]
    stale += [
        (path, "was derived from an out-of-date artifact of its scene")
        for path in derived
        if Path(path).exists() and path not in named
    ]
    for path, reason in stale:
        if execute:
            os.remove(path)
        verb = "removed; rebuilt when a job needs it" if execute else "a run that needs it rebuilds it"
        print(f"signorini: out of date: {path} {reason} ({verb})", file=sys.stderr)
    return [path for path, _ in stale]


def leftover_temporaries(roots: Iterable[str | os.PathLike], min_age_s: float = 120.0) -> list[Path]:
    """The hidden temporary files of atomic writes (``.<name>.<random>.tmp``) under ``roots`` that a
    killed job left behind: none while another run holds a Snakemake lock on this directory (its
    jobs may be writing them), and none younger than ``min_age_s`` (a run with ``--nolock``)."""
    if any(Path(".snakemake/locks").glob("*")):
        return []
    now = time.time()
    found = [path for root in roots for path in Path(root).rglob(".*.tmp") if path.is_file()]
    return sorted(path for path in found if now - path.stat().st_mtime > min_age_s)


def remove_leftover_temporaries(roots: Iterable[str | os.PathLike], execute: bool) -> list[Path]:
    """Delete ``leftover_temporaries`` (in a run that executes jobs; a read-only call keeps them)."""
    leftovers = leftover_temporaries(roots) if execute else []
    for path in leftovers:
        path.unlink(missing_ok=True)
        print(f"signorini: removed {path}, left behind by a killed job", file=sys.stderr)
    return leftovers


def quarantine_corrupt(paths: Iterable[str | os.PathLike]) -> list[str]:
    """Move every existing but corrupt artifact among ``paths`` to ``<name>.corrupt``.

    The Snakefile calls it for ``cached_artifacts`` before Snakemake looks at any file.
    The artifact is then missing, so Snakemake rebuilds it as soon as a job of the run
    needs it (a requested target, or the input of a job that has to run), instead of
    handing a truncated file to the next stage.  Outputs already derived from it stay
    valid: they were computed before the damage (it was written atomically and checked
    when read).
    """
    moved = corrupt_artifacts(paths)
    for path in moved:
        os.replace(path, f"{path}.corrupt")
        print(
            f"signorini: corrupt artifact {path} moved to {path}.corrupt; rebuilt when a job needs it", file=sys.stderr
        )
    return moved


# the artifacts the cache check reads: every path of the scene chain and the studies that is an
# archive or a JSON record (their checksums), the two scene tables (their contract and shape) and
# the benchmark files of the computing rules
CHECKED_PATHS = tuple(key for key, template in PATHS.items() if template.endswith((".npz", ".json")))
TABLE_PATHS = ("errors_csv", "eoc_csv")


def _pattern(template: str, scene: str) -> str:
    """A path template of ``paths`` as a glob under the results directory, for one scene (every
    other wildcard matches anything)."""
    relative = Path(template).relative_to(RESULTS).as_posix().replace("{scene}", scene)
    return re.sub(r"\{[^}]*\}", "*", relative)


def cached_artifacts(root: str | os.PathLike, scenes: Mapping[str, Mapping]) -> Iterator[Path | tuple]:
    """The checkable cached artifacts of the given scenes under ``root`` (the results directory),
    from the path templates of ``signorini.pipeline.paths`` (``CHECKED_PATHS``, the tables of
    ``TABLE_PATHS`` with what they must hold (``expected_shape``), the benchmark files)."""
    root = Path(root)
    for scene, block in scenes.items():
        for key in CHECKED_PATHS:
            yield from sorted(root.glob(_pattern(PATHS[key], scene)))
        for key in TABLE_PATHS:
            table = root / _pattern(PATHS[key], scene)
            yield table, expected_shape(table, block)
        for template in BENCHMARKS.values():
            yield from sorted(root.glob(_pattern(template, scene)))
