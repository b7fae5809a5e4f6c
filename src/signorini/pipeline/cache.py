"""Checks of the cached artifacts before Snakemake plans a run.

A cached artifact damaged after it was written (a truncated ``.npz``, an incomplete JSON, a
cut-off ``errors.csv``) is moved to ``<name>.corrupt`` by ``quarantine_corrupt``, so that
Snakemake rebuilds it when a job needs it instead of handing it to the next stage.  Only a
Snakemake call that runs jobs moves anything (``executes``): a dry run, ``--lint``, ``--report``,
``-l`` or ``--summary`` names the damaged artifacts (``warn_corrupt``) and leaves the cache as it is.
"""

from __future__ import annotations

import csv
import io
import os
import re
import sys
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path

from signorini.pipeline.artifacts import CorruptArtifactError, load_json, load_npz


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


def corrupt_artifacts(paths: Iterable[str | os.PathLike]) -> list[str]:
    """The existing but damaged artifacts among ``paths``."""
    return [str(path) for path in paths if not artifact_ok(path)]


def warn_corrupt(paths: Iterable[str | os.PathLike]) -> list[str]:
    """Name every damaged artifact among ``paths`` on stderr, touching nothing (read-only calls)."""
    damaged = corrupt_artifacts(paths)
    for path in damaged:
        print(
            f"signorini: damaged artifact {path}; a run that needs it moves it aside and rebuilds it", file=sys.stderr
        )
    return damaged


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


def cached_artifacts(root: str | os.PathLike, scenes: Mapping[str, Mapping]) -> Iterator[Path]:
    """The checkable cached artifacts (``.npz``, ``.json``, ``errors.csv``, ``eoc.csv``) of the
    given scenes under ``root`` (the results directory), atlas cases included."""
    for scene in scenes:
        base = Path(root) / scene
        yield from base.glob("*.npz")
        yield from (base / name for name in ("errors.csv", "eoc.csv"))
        yield from base.glob("N*/system.*")
        yield from base.glob("N*/solution.*")
        yield from base.glob("N*/norms/*.json")
        if "atlas" in scenes[scene]:
            yield from base.glob("atlas/*.json")
            yield from base.glob("atlas/*.npz")
