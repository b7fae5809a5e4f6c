"""The code a workflow job runs, derived from the imports.

``code_inputs(script, src)`` is the static import closure of a rule's script within the
package under ``src``: every ``import``/``from … import`` of a ``signorini`` module (at module
level or inside a function, where the heavy imports live; not under ``if TYPE_CHECKING:``,
which never runs), followed recursively, plus the ``__init__.py`` of every package on the way
(Python runs them on import).  The Snakefile lists the result as the rule's ``code`` input, so
editing any module a job can run re-runs that job, and nothing else.

Every Snakemake process parses the Snakefile, including each job a cluster runs; ``ImportCache``
keeps each file's direct imports on disk, keyed by the digest of its content, so that a process
parses only the files that changed (reading and hashing a file costs a fraction of parsing it:
docs/evidence/design-measurements.md#import-cache).
"""

from __future__ import annotations

import ast
import hashlib
import json
import os
import tempfile
from collections.abc import Iterator
from functools import cache
from pathlib import Path

PACKAGE = "signorini"


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, module: str, is_package: bool) -> Iterator[str]:
    """Dotted names a module imports (absolute; ``from x import y`` also yields ``x.y``,
    which is a module if ``y`` is one)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            stack.extend(node.orelse)
            continue
        if isinstance(node, ast.Import):
            yield from (alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:  # relative: resolve against this module's package
                parts = module.split(".")
                anchor = parts if is_package else parts[:-1]
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join([*anchor, base] if base else anchor)
            yield base
            yield from (f"{base}.{alias.name}" for alias in node.names if alias.name != "*")
        stack.extend(ast.iter_child_nodes(node))


def _module_file(name: str, src: Path) -> Path | None:
    """The file of a package module under ``src`` (``a/b.py`` or ``a/b/__init__.py``), or None."""
    if name != PACKAGE and not name.startswith(PACKAGE + "."):
        return None
    base = src.joinpath(*name.split("."))
    for path in (base.with_suffix(".py"), base / "__init__.py"):
        if path.is_file():
            return path
    return None


def _module_name(path: Path, src: Path) -> str:
    rel = path.relative_to(src).with_suffix("")
    parts = list(rel.parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@cache
def _imported_names(path: Path, src: Path, digest: str) -> tuple[str, ...]:
    """The dotted names one file imports, with the packages on the way (Python runs their
    ``__init__.py``); ``digest``, of the file's content, keys the memo."""
    module = _module_name(path, src) if path.is_relative_to(src) else "__main__"
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    names: set[str] = set()
    for name in _imports(tree, module, path.name == "__init__.py"):
        parts = name.split(".")
        names.update(".".join(parts[:k]) for k in range(1, len(parts) + 1))
    return tuple(sorted(n for n in names if n == PACKAGE or n.startswith(PACKAGE + ".")))


def _resolve(path: Path, names: tuple[str, ...] | list[str], src: Path) -> frozenset[Path]:
    """The package files of ``names`` as they are now: a module written after its importer was
    read is found, one that was deleted is not."""
    found = {target for name in names if (target := _module_file(name, src)) is not None}
    found.discard(path)
    return frozenset(found)


def _direct(path: Path, src: Path, digest: str) -> frozenset[Path]:
    """Package files one file imports directly (with the ``__init__.py`` of their packages)."""
    return _resolve(path, _imported_names(path, src, digest), src)


class ImportCache:
    """The direct imports of files, kept in a JSON file between processes: an entry holds only
    while the file's content has the recorded digest.  A missing or damaged cache file is an empty
    cache; ``save`` replaces it atomically (concurrent processes: the last one wins, each with
    valid entries)."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        try:
            entries = json.loads(self.path.read_text(encoding="utf-8"))
            self._entries = entries if isinstance(entries, dict) else {}
        except (OSError, ValueError):
            self._entries = {}
        self._changed = False
        # one parse of the Snakefile asks for the same files' imports for every rule: answered once
        self._known: dict[tuple[Path, Path], frozenset[Path]] = {}

    def direct(self, path: Path, src: Path) -> frozenset[Path]:
        """``path``'s direct package imports under ``src``: the imported names from the cache when
        the file is unchanged, resolved to files as they are now (the cache holds names, not files,
        so that a module created, moved or deleted after its importer was read is seen; within the
        life of this cache, which one parse of the Snakefile creates, a file is read once)."""
        if (path, src) not in self._known:
            self._known[path, src] = self._direct(path, src)
        return self._known[path, src]

    def _direct(self, path: Path, src: Path) -> frozenset[Path]:
        key, digest = f"names::{src}::{path}", _digest(path)
        entry = self._entries.get(key)
        if isinstance(entry, list) and len(entry) == 2 and entry[0] == digest:
            return _resolve(path, entry[1], src)
        names = _imported_names(path, src, digest)
        self._entries[key] = [digest, list(names)]
        self._changed = True
        return _resolve(path, names, src)

    def save(self) -> None:
        """Write the cache if it gained entries (best effort: a read-only directory keeps none)."""
        if not self._changed:
            return
        tmp = None
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            fd, tmp = tempfile.mkstemp(dir=self.path.parent, prefix=f".{self.path.name}.", suffix=".tmp")
            with os.fdopen(fd, "w", encoding="utf-8") as fh:
                json.dump(self._entries, fh)
            os.replace(tmp, self.path)
            self._changed = False
        except OSError:
            if tmp is not None and os.path.exists(tmp):
                os.remove(tmp)


def import_closure(
    path: str | os.PathLike, src: str | os.PathLike, cache: ImportCache | None = None
) -> list[Path]:
    """Every package file under ``src`` that ``path`` imports, directly or indirectly (sorted;
    ``path`` itself is included when it lies under ``src``); ``cache`` keeps the direct imports
    of unchanged files between processes."""
    path, src = Path(path).resolve(), Path(src).resolve()
    seen: set[Path] = {path} if path.is_relative_to(src) else set()
    todo = [path]
    while todo:
        current = todo.pop()
        direct = cache.direct(current, src) if cache else _direct(current, src, _digest(current))
        for target in direct:
            if target not in seen:
                seen.add(target)
                todo.append(target)
    return sorted(seen)


def code_inputs(
    script: str | os.PathLike,
    src: str | os.PathLike,
    relative_to: str | os.PathLike,
    cache: ImportCache | None = None,
) -> list[str]:
    """The rule's code inputs: its script and the package files it runs, as paths relative to
    ``relative_to`` (the workflow's working directory)."""
    base = Path(relative_to).resolve()
    files = [Path(script).resolve(), *import_closure(script, src, cache)]
    return [os.path.relpath(f, base) for f in dict.fromkeys(files)]
