"""``make check``: did my run reproduce the committed outputs?

    python -m signorini.pipeline.check [--reference REV | --reference-dir DIR] [--rtol R] [FILE ...]

compares the files a run of ``all`` writes under ``paper_figures/`` (default; or the named
``FILE``s) with the committed ones, git's ``HEAD`` version by default, and prints one line per
file: ``identical`` (byte for byte), or for tables (CSV, Markdown, LaTeX) how many of their
numbers differ and the largest relative difference, for figures (PDF, PNG) that their bytes
differ.  A table whose text agrees and whose numbers agree within ``--rtol`` counts as matched.

A file counts as reproduced only if it was rendered on this machine from the current cache: its
seal (``signorini.pipeline.artifacts``, written by the job that rendered it) holds its bytes, and
every input the job read is on disk with the content it had then.  The committed files
themselves, or files rendered from another scene or an older cache, are named as *not rendered
here*.

Exit status: 0 every file matched and was rendered here; 1 a file differs, is missing or was not
rendered here; 2 nothing could be compared (no git repository or revision, nothing rendered here).
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import re
import subprocess
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from signorini.pipeline.paths import FIGURES, TARGETS

# numbers as the tables write them: 5.8746·10⁻⁴ (Markdown), $5.8746 \cdot 10^{-4}$ (LaTeX), 1.9968, 2.0e-05
_SUPERSCRIPT = str.maketrans("⁻⁰¹²³⁴⁵⁶⁷⁸⁹", "-0123456789")
_MD_POWER = re.compile(r"·10([⁻⁰¹²³⁴⁵⁶⁷⁸⁹]+)")
_TEX_POWER = re.compile(r"\s*\\cdot\s*10\^\{(-?\d+)\}")
_NUMBER = re.compile(r"(?<![\w.])[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?(?![\w.])")


class NoReference(RuntimeError):
    """The committed reference cannot be read (no git, not a repository, unknown revision)."""


@dataclass(frozen=True)
class Comparison:
    """One file: ``status`` is ``identical``, ``matched`` (text equal, numbers within rtol),
    ``differs``, ``missing`` (not built), ``not rendered`` (not by a run here from the current
    cache) or ``no reference`` (not committed)."""

    path: str
    status: str
    detail: str = ""
    numbers: int = 0
    differing: int = 0
    max_rel: float = 0.0

    @property
    def ok(self) -> bool:
        return self.status in ("identical", "matched")


def all_outputs() -> list[str]:
    """What ``all`` writes under ``paper_figures/`` and is committed (the run times are not)."""
    return [path for rule in TARGETS["all"] if rule != "runtime" for path in FIGURES[rule].values()]


def git_reference(root: Path, rev: str = "HEAD") -> Callable[[str], bytes | None]:
    """``path -> bytes`` of ``rev``'s version of a file (``None`` when not committed there)."""

    def git(*args: str) -> subprocess.CompletedProcess:
        try:
            return subprocess.run(["git", "-C", str(root), *args], capture_output=True, check=False)
        except FileNotFoundError as err:
            raise NoReference("git is not installed") from err

    top = git("rev-parse", "--show-toplevel")
    if top.returncode != 0:
        raise NoReference(f"{root} is not a git repository (a release archive?)")
    if git("rev-parse", "--verify", "--quiet", f"{rev}^{{commit}}").returncode != 0:
        raise NoReference(f"git knows no revision {rev!r}")
    prefix = Path(top.stdout.decode().strip())

    def read(path: str) -> bytes | None:
        rel = (root / path).resolve().relative_to(prefix.resolve()).as_posix()
        proc = git("show", f"{rev}:{rel}")
        return proc.stdout if proc.returncode == 0 else None

    return read


def dir_reference(directory: Path) -> Callable[[str], bytes | None]:
    """``path -> bytes`` of the same-named file in ``directory`` (a copy of the committed files)."""
    if not directory.is_dir():
        raise NoReference(f"{directory} is not a directory")

    def read(path: str) -> bytes | None:
        candidate = directory / Path(path).name
        return candidate.read_bytes() if candidate.is_file() else None

    return read


def numbers_and_text(text: str) -> tuple[list[float], str]:
    """The numbers of a Markdown/LaTeX/CSV table's text and the text with each number replaced by ``#``."""
    text = _MD_POWER.sub(lambda m: "e" + m.group(1).translate(_SUPERSCRIPT), text)
    text = _TEX_POWER.sub(lambda m: "e" + m.group(1), text)
    values = [float(m.group(0)) for m in _NUMBER.finditer(text)]
    return values, _NUMBER.sub("#", text)


def _csv_cells(text: str) -> tuple[list[float], str]:
    """A CSV's numeric cells in order, and its layout with the numbers replaced by ``#``."""
    values, layout = [], []
    for row in csv.reader(io.StringIO(text)):
        cells = []
        for cell in row:
            try:
                values.append(float(cell))
                cells.append("#")
            except ValueError:
                cells.append(cell)
        layout.append(",".join(cells))
    return values, "\n".join(layout)


def relative_difference(a: float, b: float) -> float:
    """``|a − b| / max(|a|, |b|)``; 0 for equal numbers, ``inf`` when only one is finite."""
    if a == b or (math.isnan(a) and math.isnan(b)):
        return 0.0
    if not (math.isfinite(a) and math.isfinite(b)):
        return math.inf
    return abs(a - b) / max(abs(a), abs(b))


def compare_file(path: str, ours: bytes | None, reference: bytes | None, rtol: float = 0.0) -> Comparison:
    """One file of our run against its committed version."""
    if ours is None:
        return Comparison(path, "missing", "not built: run `make all`")
    if reference is None:
        return Comparison(path, "no reference", "not in the committed reference")
    if ours == reference:
        return Comparison(path, "identical")
    suffix = Path(path).suffix
    if suffix not in (".csv", ".md", ".tex"):
        return Comparison(path, "differs", "bytes differ (a figure: no numbers to compare)")
    parse = _csv_cells if suffix == ".csv" else numbers_and_text
    (a, layout_a), (b, layout_b) = parse(ours.decode("utf-8")), parse(reference.decode("utf-8"))
    if layout_a != layout_b or len(a) != len(b):
        return Comparison(path, "differs", "the text or the layout differs, not only numbers")
    diffs = [relative_difference(x, y) for x, y in zip(a, b, strict=True)]
    worst, differing = max(diffs, default=0.0), sum(d > 0.0 for d in diffs)
    status = "matched" if worst <= rtol else "differs"
    detail = f"{differing} of {len(a)} numbers differ, largest relative difference {worst:.1e}"
    return Comparison(path, status, detail, len(a), differing, worst)


def compare(
    root: Path, files: Sequence[str], reference: Callable[[str], bytes | None], rtol: float = 0.0
) -> list[Comparison]:
    """Every file of ``files`` (relative to ``root``) against ``reference``."""
    out = []
    for path in files:
        mine = root / path
        out.append(compare_file(path, mine.read_bytes() if mine.is_file() else None, reference(path), rtol))
    return out


def report(results: Sequence[Comparison], source: str) -> str:
    """The lines ``main`` prints."""
    width = max((len(r.path) for r in results), default=0)
    lines = [f"Comparing with {source}:"]
    lines += [f"  {r.path:<{width}}  {r.status:<12}  {r.detail}".rstrip() for r in results]
    good = sum(r.ok for r in results)
    verdict = "reproduced" if good == len(results) else "NOT reproduced"
    lines.append(f"{verdict}: {good} of {len(results)} files were rendered here and match the committed ones")
    return "\n".join(lines)


MAKE_ALL = "run `make all`"


def not_rendered_here(root: Path, path: str) -> tuple[str, str] | None:
    """Why ``path`` (relative to ``root``) was not rendered on this machine from the current cache,
    and what renders it (None when it was): no seal, other bytes than its job wrote, or an input now
    on disk with other content than the job read (another scene, a rebuilt cache) or gone.  A gone
    input (a damaged one that a run moved aside) is rebuilt only when requested: a run of ``all``
    keeps the rendered file, which was computed from the intact input."""
    from signorini.pipeline.artifacts import CorruptArtifactError, content_digest, seal_broken, seal_of, seal_path

    if not (root / path).is_file():
        return None  # a missing file is reported as missing
    if not seal_path(path, root).is_file():
        return "not rendered by a run here (the committed file?)", MAKE_ALL
    if reason := seal_broken(path, root):
        return reason, MAKE_ALL
    inputs = ((seal_of(path, root) or {}).get("_provenance") or {}).get("inputs") or {}
    for source, recorded in inputs.items():
        try:
            if content_digest(root / source) != recorded:
                return f"rendered from another {source} than the cache holds now", MAKE_ALL
        except (CorruptArtifactError, FileNotFoundError):
            why = f"rendered from {source}, which the cache no longer holds intact"
            return why, f"rebuild it: `.venv/bin/snakemake -c2 {source}`"
    return None


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m signorini.pipeline.check", description=__doc__.split("\n\n")[0])
    parser.add_argument("files", nargs="*", help="files to compare (default: what `all` writes in paper_figures/)")
    parser.add_argument("--reference", default="HEAD", help="the git revision to compare with (default HEAD)")
    parser.add_argument("--reference-dir", type=Path, help="compare with the files of this directory instead of git")
    parser.add_argument("--rtol", type=float, default=0.0, help="accept tables whose numbers differ by at most this")
    parser.add_argument("--root", type=Path, default=Path("."), help="the repository checkout (default .)")
    args = parser.parse_args(argv)
    root = args.root
    try:
        if args.reference_dir is not None:
            reference, source = dir_reference(args.reference_dir), str(args.reference_dir)
        else:
            reference, source = git_reference(root, args.reference), f"git {args.reference}"
    except NoReference as err:
        print(f"check: cannot read the committed files: {err}; pass --reference-dir DIR with a copy", file=sys.stderr)
        return 2
    files = args.files or all_outputs()
    elsewhere = {path: why for path in files if (why := not_rendered_here(root, path))}
    if len(elsewhere) == len(files) and {remedy for _, remedy in elsewhere.values()} == {MAKE_ALL}:
        print(
            "check: nothing in paper_figures/ was rendered on this machine from the current cache (it holds the "
            "committed files): run `make all` first",
            file=sys.stderr,
        )
        return 2
    results = compare(root, files, reference, args.rtol)
    results = [
        Comparison(r.path, "not rendered", "; ".join(elsewhere[r.path])) if r.path in elsewhere else r for r in results
    ]
    print(report(results, source))
    if len(elsewhere) == len(files):
        return 2  # nothing was compared that was rendered here
    return 0 if all(r.ok for r in results) else 1


if __name__ == "__main__":
    sys.exit(main())
