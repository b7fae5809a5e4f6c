"""Checks of the cached artifacts before Snakemake plans a run.

A cached artifact damaged after it was written (a truncated ``.npz``, an incomplete JSON, a
cut-off ``errors.csv``) is moved to ``<name>.corrupt`` by ``quarantine_corrupt``, so that
Snakemake rebuilds it when a job needs it instead of handing it to the next stage.
"""

from __future__ import annotations

import csv
import io
import os
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
