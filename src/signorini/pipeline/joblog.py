"""The log of one workflow job."""

from __future__ import annotations

import contextlib
import json
import logging
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    changed_input,
    code_digest,
    content_digest,
    file_digest,
    is_sealed_kind,
    provenance_of,
    recording,
    verify_seal,
)

log = logging.getLogger("signorini.job")
MODULES_LINE = "modules run: %s"  # the last line of a job's log file
INTERRUPTED = 130  # a job's exit status after Ctrl-C (128 + SIGINT; signorini/__init__.py)


def loaded_modules() -> list[str]:
    """The package's modules loaded in this interpreter (sorted), as logged at the end of a job."""
    return sorted(m for m in sys.modules if m == "signorini" or m.startswith("signorini."))


class StaleInputError(RuntimeError):
    """An input artifact was computed from other inputs than the ones now on disk."""


# the checkout's environment lock, whose digest every artifact records (the Snakefile sets it)
LOCK_VARIABLE = "SIGNORINI_ENVIRONMENT_LOCK"
# the libraries whose installed versions every artifact records beside the lock's digest
RECORDED_LIBRARIES = ("numpy", "scipy", "scikit-fem")


def environment() -> dict[str, str | None]:
    """What an artifact records of the software it was computed with: the SHA-256 of the
    environment lock (None without one) and the installed versions of ``RECORDED_LIBRARIES``."""
    from importlib.metadata import PackageNotFoundError, version

    lock = os.environ.get(LOCK_VARIABLE)
    record: dict[str, str | None] = {"lock": file_digest(lock) if lock and Path(lock).is_file() else None}
    for name in RECORDED_LIBRARIES:
        try:
            record[name] = version(name)
        except PackageNotFoundError:
            record[name] = None
    return record


def check_inputs(paths: list[str]) -> None:
    """Vouch for every input before a job reads it: a sealed file's bytes (a table, a Markdown page:
    ``CorruptArtifactError`` if edited), and that no input was computed from other inputs than the
    ones now on disk (say a ``system.npz`` replaced under a ``solution.npz`` computed from the old
    one: ``StaleInputError``).  Archives and JSON records verify their own checksum when the stage
    loads them (``load_npz``, ``load_json``): not read a second time here."""
    for path in paths:
        if not Path(path).is_file():
            continue
        if is_sealed_kind(path):
            if reason := verify_seal(path):
                raise CorruptArtifactError(f"{path}: {reason}; rebuild it")
        changed = changed_input(provenance_of(path))
        if changed:
            raise StaleInputError(f"{path} was computed from another {changed} than the one now on disk; rebuild it")


def plain(items: Any) -> dict:
    """Snakemake's params or wildcards (name, value pairs) as the JSON values an artifact records;
    the cache check normalises the params a job would get now the same way."""
    return json.loads(json.dumps(dict(items), default=str))


def job_provenance(job: Any) -> dict:
    """What a Snakemake job's artifacts record: its rule, the digest of its code inputs (script and
    package modules, read now, at job start), its parameters and wildcards, and the content digest
    of each of its other inputs."""
    code = list(getattr(job.input, "code", []))
    data = [str(path) for path in job.input if str(path) not in set(code) and Path(path).is_file()]
    return {
        "rule": job.rule,
        "code": code_digest(code),
        "params": plain(job.params.items()),
        "wildcards": plain(job.wildcards.items()),
        "inputs": {path: content_digest(path) for path in data},
        "environment": environment(),
    }


@contextlib.contextmanager
def job_log(job: Any) -> Iterator[logging.Logger]:
    """Log to the job's log file (and its warnings to stderr; everything there without a file); an
    exception is logged with its traceback, then re-raised (Ctrl-C: one line, in the file only).
    ``job``: the Snakemake job object of a script (its log file, and the provenance every artifact
    it writes records: ``job_provenance``), or just a log path (or None).  The log
    file's last line names the package modules the job ran (``loaded_modules``), which the tests
    compare with the rule's code inputs."""
    path, provenance = (
        (job, None) if job is None or isinstance(job, (str, os.PathLike)) else (job.log[0], job_provenance(job))
    )
    if provenance is not None:
        check_inputs(list(provenance["inputs"]))
    root = logging.getLogger()
    console = logging.StreamHandler(sys.stderr)
    handlers: list[logging.Handler] = [console]
    if path:
        # with a log file the console gets the warnings only: a run prints a line per job, not its steps
        console.setLevel(logging.WARNING)
        Path(path).parent.mkdir(parents=True, exist_ok=True)
        handlers.append(logging.FileHandler(path, mode="w", encoding="utf-8"))
    file_handlers = handlers[1:]
    fmt = logging.Formatter("%(asctime)s %(levelname)s %(name)s: %(message)s")
    for handler in handlers:
        handler.setFormatter(fmt)
        root.addHandler(handler)
    pkg = logging.getLogger("signorini")
    old_level = pkg.level
    pkg.setLevel(logging.INFO)  # the package's messages; other libraries stay at WARNING
    try:
        with recording(provenance) if provenance is not None else contextlib.nullcontext():
            yield log
        record = log.makeRecord(log.name, logging.INFO, __file__, 0, MODULES_LINE, (" ".join(loaded_modules()),), None)
        for handler in file_handlers:  # the log file only: the console stays short
            handler.handle(record)
    except BaseException as err:
        if isinstance(err, KeyboardInterrupt) or (isinstance(err, SystemExit) and err.code == INTERRUPTED):
            console.setLevel(logging.CRITICAL + 1)  # Ctrl-C: said in the log file, not on the console
            log.warning("job interrupted")
        else:
            log.exception("job failed")
        raise
    finally:
        for handler in handlers:
            root.removeHandler(handler)
            handler.close()
        pkg.setLevel(old_level)
