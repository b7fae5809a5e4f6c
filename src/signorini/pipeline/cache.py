"""Checks of the cached artifacts before Snakemake plans a run.

A cached artifact damaged after it was written (a truncated ``.npz``, an incomplete JSON, a
cut-off ``errors.csv``) is moved to ``<name>.corrupt`` by ``quarantine_corrupt``, so that
Snakemake rebuilds it when a job needs it instead of handing it to the next stage.  Only a
Snakemake call that runs jobs moves anything (``executes``): a dry run, ``--lint``, ``--report``,
``-l`` or ``--summary`` names the damaged artifacts (``warn_corrupt``) and leaves the cache as it is.
"""

from __future__ import annotations

import csv
import functools
import io
import math
import os
import re
import sys
import time
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from pathlib import Path

from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    changed_input,
    content_digest,
    load_json,
    load_npz,
    provenance_of,
)


def _csv_ok(path: Path, rows_expected: Sequence[str] | None = None) -> bool:
    """A complete table CSV: ends with a newline, every row has the header's number of
    fields, no empty cell except ``h`` in the ``regression`` row of ``eoc.csv``, finite numbers
    (and, in ``errors.csv``, non-negative ones); with ``rows_expected`` exactly these ``N`` labels
    in this order."""
    text = path.read_text()
    if not text.endswith("\n"):
        return False
    rows = list(csv.reader(io.StringIO(text)))
    if len(rows) < 2 or rows[0][:2] != ["N", "h"]:
        return False
    if rows_expected is not None and [row[0] for row in rows[1:]] != list(rows_expected):
        return False
    for row in rows[1:]:
        if len(row) != len(rows[0]):
            return False
        cells = [cell for i, cell in enumerate(row[1:], 1) if not (i == 1 and row[0] == "regression")]
        try:
            values = [float(cell) for cell in cells]
        except ValueError:
            return False
        if not all(math.isfinite(v) and (v >= 0.0 or path.name != "errors.csv") for v in values):
            return False
    return path.name != "eoc.csv" or rows[-1][0] == "regression"


def expected_rows(path: Path, scene_N: Sequence[int]) -> list[str] | None:
    """The ``N`` labels ``errors.csv`` / ``eoc.csv`` of a scene with meshes ``scene_N`` must hold."""
    labels = [str(N) for N in scene_N]
    return {"errors.csv": labels, "eoc.csv": [*labels[1:], "regression"]}.get(path.name)


def _benchmark_ok(path: Path) -> bool:
    """A complete Snakemake benchmark file: a header starting with ``s`` (seconds), at least one
    row with the header's number of fields and a finite, non-negative number of seconds."""
    text = path.read_text()
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


def artifact_ok(path: str | os.PathLike, rows_expected: Sequence[str] | None = None) -> bool:
    """True unless ``path`` exists and fails its check (npz checksum, JSON completeness
    marker, complete rows of ``errors.csv``/``eoc.csv``, with ``rows_expected``: exactly those ``N``,
    complete rows of a benchmark ``.tsv``)."""
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
            return _csv_ok(path, rows_expected)
        elif path.suffix == ".tsv":
            return _benchmark_ok(path)
    except (CorruptArtifactError, OSError, UnicodeDecodeError, csv.Error):
        return False
    return True


# Snakemake options after which a call only plans, lists, lints or reports
READ_ONLY_OPTIONS = frozenset(
    {
        "--dry-run",
        "--dryrun",
        "--lint",
        "--report",
        "--list-rules",
        "--list",
        "--list-target-rules",
        "--lt",
        "--summary",
        "--detailed-summary",
        "--dag",
        "--rulegraph",
        "--filegraph",
        "--d3dag",
        "--list-changes",
        "--lc",
        "--list-input-changes",
        "--li",
        "--list-params-changes",
        "--lp",
        "--list-untracked",
        "--lu",
        "--print-compilation",
        "--unlock",
        "--containerize",
        "--export-cwl",
        "--generate-unit-tests",
        "--archive",
        "--cleanup-metadata",
        "--help",
        "--version",
    }
)
READ_ONLY_SHORT = frozenset("nlSDhv")  # -n, -l, -S, -D, -h, -v, also in clusters such as -np


def executes(argv: list[str]) -> bool:
    """Whether a Snakemake command line (``sys.argv``) runs jobs, i.e. is none of the read-only calls."""
    for arg in argv[1:]:
        if arg == "--":
            break
        if arg.split("=", 1)[0] in READ_ONLY_OPTIONS:
            return False
        if re.fullmatch(r"-[A-Za-z]+", arg) and READ_ONLY_SHORT & set(arg[1:]):
            return False
    return True


def corrupt_artifacts(paths: Iterable) -> list[str]:
    """The existing but damaged artifacts among ``paths`` (a path, or a pair of a table's path and
    the ``N`` labels it must hold, as ``cached_artifacts`` yields them)."""
    checks = [item if isinstance(item, tuple) else (item, None) for item in paths]
    return [str(path) for path, rows in checks if not artifact_ok(path, rows)]


def warn_corrupt(paths: Iterable[str | os.PathLike]) -> list[str]:
    """Name every damaged artifact among ``paths`` on stderr, touching nothing (read-only calls)."""
    damaged = corrupt_artifacts(paths)
    for path in damaged:
        print(
            f"signorini: damaged artifact {path}; a run that needs it moves it aside and rebuilds it", file=sys.stderr
        )
    return damaged


def stale_artifacts(paths: Iterable, current_code: Callable[[str], str]) -> list[tuple[str, str]]:
    """The artifacts among ``paths`` whose recorded code digest differs from ``current_code(rule)``
    of the rule that wrote them (a job that ran older code, say an edit during the run, which
    modification times cannot tell), that were computed from other inputs than the ones now on
    disk (an input replaced by a copy with an old modification time), or from such an artifact;
    each with the reason."""
    recorded: dict[str, dict] = {}
    for item in paths:
        path = Path(item[0] if isinstance(item, tuple) else item)
        if path.suffix not in (".npz", ".json") or not path.exists():
            continue
        try:
            recorded[str(path)] = provenance_of(path) or {}
        except CorruptArtifactError:
            continue  # the damage check moves it
    stale: dict[str, str] = {}
    digest = functools.cache(content_digest)  # the norms of a mesh share its solution
    for path, prov in recorded.items():
        if prov.get("code") and prov["code"] != current_code(prov["rule"]):
            stale[path] = "was computed by other code than the current one"
        elif changed := changed_input(prov, digest):
            stale[path] = f"was computed from another {changed} than the one now on disk"
    grown = True
    while grown:  # and everything computed from a stale artifact
        grown = False
        for path, prov in recorded.items():
            source = next((p for p in prov.get("inputs") or {} if p in stale), None)
            if path not in stale and source:
                stale[path], grown = f"was computed from {source}, which is out of date", True
    return list(stale.items())


def remove_stale(paths: Iterable, current_code: Callable[[str], str], execute: bool) -> list[str]:
    """Delete the stale artifacts (``stale_artifacts``) and the scene tables computed from them
    (``errors.csv``, ``eoc.csv`` of the same scene), so that a job that needs one rebuilds it and
    everything after it reruns, or, in a read-only call (``execute`` false), only name them."""
    stale = stale_artifacts(paths, current_code)
    scenes = {Path(*Path(path).parts[:2]) for path, _ in stale}  # results/<scene>/...
    derived = [str(scene / name) for scene in sorted(scenes) for name in ("errors.csv", "eoc.csv")]
    stale += [(path, "was derived from a stale artifact of its scene") for path in derived if Path(path).exists()]
    for path, reason in stale:
        if execute:
            os.remove(path)
        verb = "removed; rebuilt when a job needs it" if execute else "a run that needs it rebuilds it"
        print(f"signorini: {path} {reason} ({verb})", file=sys.stderr)
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


def cached_artifacts(root: str | os.PathLike, scenes: Mapping[str, Mapping]) -> Iterator[Path | tuple]:
    """The checkable cached artifacts (``.npz``, ``.json``, ``errors.csv``, ``eoc.csv``, benchmark
    ``.tsv``) of the given scenes under ``root`` (the results directory), atlas cases included;
    the two tables come with the ``N`` labels they must hold (``expected_rows``)."""
    for scene, block in scenes.items():
        base = Path(root) / scene
        yield from base.glob("*.npz")
        for table in (base / "errors.csv", base / "eoc.csv"):
            yield table, expected_rows(table, block.get("N", []))
        yield from base.glob("N*/system.*")
        yield from base.glob("N*/solution.*")
        yield from base.glob("N*/norms/*.json")
        yield from base.glob("N*/theory.json")
        yield from base.glob("N*/work_precision/*.json")
        yield from base.glob("benchmarks/**/*.tsv")
        if "atlas" in block:
            yield from base.glob("atlas/*.json")
            yield from base.glob("atlas/*.npz")
