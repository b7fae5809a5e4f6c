"""The integrity of the cached artifacts: the check before Snakemake runs the jobs of a plan, and
the table contract every reader uses.

The check (``judge``) looks at the outputs of the jobs the requested targets need -- the jobs of
this run's DAG, nothing else -- and decides for each existing one:

* **damaged** (a truncated or edited archive, an incomplete JSON, a table whose bytes differ from
  its seal): moved to ``<name>.corrupt`` and rebuilt.  Archives read by a job of this run (and
  requested targets) are verified in full, streaming, whatever their size;
* **not vouched for** (out of date: computed by other code, with other libraries, other parameters,
  from other inputs than the ones now on disk, from an out-of-date artifact; misplaced: it records
  other wildcards than where it sits; or written outside a job of this workflow): moved to
  ``<name>.stale`` and rebuilt;
* **a rendered output** (``paper_figures/``, committed) that is not what its job would render from
  the current cache (never rendered here, edited, rendered from another scene or other inputs): its
  job is forced to run; the file itself is never moved or deleted.

Nothing is deleted: ``make clean-corrupt`` removes what was moved aside.  Only a Snakemake call
that runs jobs changes anything (``runs_jobs``): a dry run names what it finds.
"""

from __future__ import annotations

import csv
import functools
import io
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Mapping, Sequence, Set
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    content_digest,
    is_sealed_kind,
    load_json,
    provenance_of,
    seal_broken,
    verify_npz,
)
from signorini.pipeline.joblog import plain
from signorini.pipeline.paths import FIGDIR


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


def artifact_ok(path: str | os.PathLike) -> bool:
    """True unless ``path`` exists and fails its own integrity check (npz checksum, streamed; JSON
    checksum and completeness marker; complete rows of ``errors.csv``/``eoc.csv`` and of a benchmark
    ``.tsv``).  Whether a table is the one its job wrote is its seal's question (``verify_seal``)."""
    path = Path(path)
    if not path.exists():
        return True
    try:
        if path.suffix == ".npz":
            verify_npz(path)
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




# --- the check of a plan -------------------------------------------------------------------------


@dataclass(frozen=True)
class Planned:
    """An output of a job of this run's plan, as the job would write it now: its rule, the digest
    of its code now, its parameters and wildcards (as artifacts record them:
    ``signorini.pipeline.joblog.plain``), its data inputs, and whether this run reads it in full
    (an input of a job that runs, or a requested target)."""

    path: str
    rule: str
    code: str
    params: Mapping
    wildcards: Mapping
    inputs: tuple[str, ...] = ()
    read: bool = False
    recorded: bool = True  # False: a file that records nothing (a benchmark file): checked for damage only


@dataclass
class Verdicts:
    """What the check decided, each path with its one-line reason: ``corrupt`` (to
    ``<name>.corrupt``), ``stale`` (to ``<name>.stale``), ``rerender`` (rendered outputs whose job
    is forced to run; never moved)."""

    corrupt: dict[str, str] = field(default_factory=dict)
    stale: dict[str, str] = field(default_factory=dict)
    rerender: dict[str, str] = field(default_factory=dict)

    def __bool__(self) -> bool:
        return bool(self.corrupt or self.stale or self.rerender)


def planned_outputs(dag: Any, code_digest: Callable[[Iterable[str]], str]) -> list[Planned]:
    """Every output (and benchmark file) of the jobs of a Snakemake DAG, as its job would write it
    now (``code_digest`` of the job's code inputs, as ``joblog.job_provenance`` records it); read
    in full when a job that runs reads it, or when it is a requested target."""
    read = {str(f) for job in dag.needrun_jobs() for f in job.input}
    read |= {str(f) for job in dag.targetjobs for f in job.output}
    digests: dict[tuple[str, ...], str] = {}
    planned = []
    for job in dag.jobs:
        code = tuple(sorted(str(f) for f in getattr(job.input, "code", [])))
        if code not in digests:
            digests[code] = code_digest(code)
        record = {
            "rule": job.rule.name,
            "code": digests[code],
            "params": plain(job.params.items()),
            "wildcards": plain(job.wildcards.items()),
            "inputs": tuple(str(f) for f in job.input if str(f) not in code),
        }
        planned += [Planned(str(f), read=str(f) in read, **record) for f in job.output]
        if job.benchmark:
            planned.append(Planned(str(job.benchmark), recorded=False, **record))
    return planned


def is_rendered(path: str | os.PathLike) -> bool:
    """A rendered output (``paper_figures/``): committed, so never moved aside, only rendered anew."""
    return Path(os.path.abspath(path)).is_relative_to(Path(os.path.abspath(FIGDIR)))


def damage(path: str | os.PathLike, read: bool) -> str | None:
    """Why an existing output is damaged (None when it is whole).  An archive is verified in full
    (streamed) when this run reads it, else by its zip directory; a file without a checksum of its
    own by its seal (a table edited by hand, a spreadsheet's round trip)."""
    path = Path(path)
    try:
        if path.suffix == ".npz":
            if read:
                verify_npz(path)
            elif not _zip_lists_checksum(path):
                return "truncated (its archive directory lists no checksum)"
        elif path.suffix == ".json":
            load_json(path)
        elif path.suffix == ".tsv" and not _benchmark_ok(path):
            return "an incomplete benchmark file"
        elif is_sealed_kind(path) and (reason := seal_broken(path)):
            return reason
        elif path.name in ("errors.csv", "eoc.csv") and (reason := table_defect(path)):
            return reason
    except (CorruptArtifactError, OSError, UnicodeDecodeError, csv.Error) as err:
        return str(err).removeprefix(f"{path}: ")
    return None


def _zip_lists_checksum(path: Path) -> bool:
    import zipfile

    try:
        with zipfile.ZipFile(path) as archive:
            return "_checksum.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False


def _differs(recorded: Mapping, expected: Mapping) -> str | None:
    """The first key whose recorded value differs from the expected one, as ``key: old -> new``
    (compared as JSON text, as recorded: a NaN equals itself there)."""
    for key in sorted(set(recorded) | set(expected)):
        old, new = (json.dumps(side.get(key, "(none)"), sort_keys=True) for side in (recorded, expected))
        if old != new:
            return f"{key}: {_short(old)} -> {_short(new)}"
    return None


def _short(text: str, limit: int = 60) -> str:
    return text if len(text) <= limit else f"{text[: limit - 1]}…"


def _foreign(out: Planned, prov: Mapping | None) -> str | None:
    """Why an output is not the one its job wrote at this place: no record of a job of this
    workflow, or the record of another place (a file copied from elsewhere)."""
    if not prov:
        return "no record of the job that wrote it (written outside this workflow)"
    if changed := _differs(prov.get("wildcards") or {}, out.wildcards):
        return f"records other wildcards than where it sits ({changed}): a file copied from elsewhere"
    return None


def _unvouched(
    out: Planned, prov: Mapping, environment: Mapping, digest: Callable[[str], str], replaced: Set[str]
) -> str | None:
    """Why an output of its place is not what its job would write now (None when it is).  The
    ``replaced`` inputs (damaged, foreign) are moved aside and rebuilt: they say nothing about it."""
    if prov.get("code") != out.code:
        return "was computed by other code than the current one"
    if changed := _differs(prov.get("environment") or {}, environment):
        return f"was computed with other libraries ({changed})"
    if changed := _differs(prov.get("params") or {}, out.params):
        return f"was computed with other parameters than the config asks now ({changed})"
    recorded = prov.get("inputs") or {}
    if missing := sorted(set(out.inputs) - set(recorded)):
        return f"was not computed from {missing[0]}, which its job reads now"
    for source in (p for p in out.inputs if p not in replaced):
        try:
            if Path(source).is_file() and digest(source) != recorded[source]:
                return f"was computed from another {source} than the one now on disk"
        except CorruptArtifactError:
            continue  # a damaged input is moved aside itself; this output waits for its rebuild
    return None


def judge(planned: Sequence[Planned], environment: Mapping) -> Verdicts:
    """The verdicts on the existing outputs of a plan (``Planned``): damaged; foreign (no record,
    or another place's); out of date, and everything computed from such an output; rendered
    outputs to render anew."""
    verdicts = Verdicts()
    digest = functools.cache(content_digest)  # the norms of a mesh share its solution
    present = [out for out in planned if os.path.lexists(out.path)]
    for out in present:
        if reason := damage(out.path, out.read):
            _verdict(verdicts, out.path, f"damaged: {reason}", damaged=True)
    records = {}
    for out in (o for o in present if o.recorded and o.path not in verdicts.corrupt | verdicts.rerender.keys()):
        try:
            records[out.path] = provenance_of(out.path)
        except CorruptArtifactError as err:
            _verdict(verdicts, out.path, f"damaged: {err}", damaged=True)
            continue
        if (reason := _foreign(out, records[out.path])) and not _committed_and_costly(out, records[out.path]):
            _verdict(verdicts, out.path, reason)
    replaced = set(verdicts.corrupt) | set(verdicts.stale) | set(verdicts.rerender)
    judged = [out for out in present if records.get(out.path) and out.path not in replaced]
    for out in judged:
        if reason := _unvouched(out, records[out.path], environment, digest, replaced):
            _verdict(verdicts, out.path, reason)
    _propagate(judged, verdicts, replaced)
    return verdicts


def _committed_and_costly(out: Planned, prov: Mapping | None) -> bool:
    """A committed rendered output (no record of a run here) whose job's inputs are not all in the
    cache: rendering it anew would recompute them (the work-precision study's measurements take
    long: docs/evidence/design-measurements.md#committed-study-outputs), so it is kept as the
    committed result; ``make check`` says it was not rendered here."""
    return is_rendered(out.path) and not prov and not all(os.path.exists(p) for p in out.inputs)


def _verdict(verdicts: Verdicts, path: str, reason: str, damaged: bool = False) -> None:
    """A rendered output is rendered anew; a cached one is moved aside (damaged or not vouched for)."""
    target = verdicts.rerender if is_rendered(path) else verdicts.corrupt if damaged else verdicts.stale
    target[path] = reason


def _propagate(outputs: Sequence[Planned], verdicts: Verdicts, replaced: Set[str]) -> None:
    """Everything computed from an out-of-date output is out of date too (not from a damaged or
    foreign one, ``replaced``: its rebuild is the artifact the consumers were computed from)."""
    grown = True
    while grown:
        grown = False
        for out in outputs:
            if out.path in verdicts.stale or out.path in verdicts.rerender:
                continue
            source = next((p for p in out.inputs if p in verdicts.stale and p not in replaced), None)
            if source is not None:
                _verdict(verdicts, out.path, f"was computed from {source}, which is out of date")
                grown = True


LISTED = 4  # files named per line of the check's report; the rest are counted


def _grouped(found: Mapping[str, str]) -> dict[str, list[str]]:
    """{reason: paths}: files moved for the same reason share a line; everything computed from
    out-of-date files shares one."""
    groups: dict[str, list[str]] = {}
    for path, reason in found.items():
        key = "was computed from an out-of-date file" if "which is out of date" in reason else reason
        groups.setdefault(key, []).append(path)
    return groups


def _named(paths: Sequence[str]) -> str:
    more = f" and {len(paths) - LISTED} more" if len(paths) > LISTED else ""
    return ", ".join(paths[:LISTED]) + more


def apply_verdicts(verdicts: Verdicts, execute: bool, stream=None) -> list[str]:
    """Move the damaged and out-of-date outputs aside (``<name>.corrupt``, ``<name>.stale``; a
    symbolic link is moved, not what it points to) and say so, one line per reason; in a
    read-only call only name them.  Rendered outputs are named; their jobs are forced by the
    caller.  Returns the lines printed."""
    stream = stream or sys.stderr
    lines = []
    for suffix, found in ((".corrupt", verdicts.corrupt), (".stale", verdicts.stale)):
        for path in found if execute else ():
            os.replace(path, f"{path}{suffix}")
        verb = "moved to <name>" if execute else "a run moves them to <name>"
        for reason, paths in _grouped(found).items():
            lines.append(f"signorini: {_named(paths)}: {reason} ({verb}{suffix}; rebuilt when a job needs them)")
    verb = "rendered anew" if execute else "a run renders them anew"
    for reason, paths in _grouped(verdicts.rerender).items():
        lines.append(f"signorini: {_named(paths)}: {reason} ({verb})")
    for line in lines:
        print(line, file=stream)
    return lines
