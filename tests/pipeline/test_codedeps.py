"""The rules' code inputs (``signorini.pipeline.codedeps``): the import closure of a script and the
cache of direct imports."""

from __future__ import annotations

import json
import os

from signorini.pipeline.codedeps import ImportCache, import_closure

# --- the import closure --------------------------------------------------------------------------


def test_import_closure_follows_every_kind_of_import(tmp_path):
    src = tmp_path / "src"
    files = {
        "signorini/__init__.py": "",
        "signorini/a/__init__.py": "",
        "signorini/a/top.py": "from signorini.a import lazy_user\nimport signorini.b.deep as d\n",
        "signorini/a/lazy_user.py": "def f():\n    from . import sibling\n",
        "signorini/a/sibling.py": "from ..c import thing\n",
        "signorini/b/__init__.py": "",
        "signorini/b/deep.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    import signorini.never\n",
        "signorini/c.py": "thing = 1\n",
        "signorini/never.py": "",
        "signorini/unused.py": "",
    }
    for rel, text in files.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(text)
    script = tmp_path / "script.py"
    script.write_text("import numpy\nfrom signorini.a.top import x\n")
    found = {p.relative_to(src).as_posix() for p in import_closure(script, src)}
    assert found == {
        "signorini/__init__.py",
        "signorini/a/__init__.py",
        "signorini/a/top.py",
        "signorini/a/lazy_user.py",  # ``from package import module``
        "signorini/a/sibling.py",  # relative import inside a function
        "signorini/b/__init__.py",
        "signorini/b/deep.py",  # ``import a.b as c``
        "signorini/c.py",  # ``from ..c import name``
    }


def test_the_import_cache_holds_only_while_a_file_is_unchanged(tmp_path):
    """Direct imports come from the cache file in another process, until the file's content changes
    (even with its size and modification time kept)."""
    src = tmp_path / "src"
    (src / "signorini").mkdir(parents=True)
    for name, text in {"__init__.py": "", "a.py": "", "b.py": "", "c.py": ""}.items():
        (src / "signorini" / name).write_text(text)
    script, cache_file = tmp_path / "script.py", tmp_path / "cache/imports.json"
    script.write_text("from signorini import a\n")

    def closure() -> set[str]:
        cache = ImportCache(cache_file)  # a new process
        found = {p.name for p in import_closure(script, src, cache)}
        cache.save()
        assert found == {p.name for p in import_closure(script, src)}  # the same as without a cache
        return found

    assert closure() == {"__init__.py", "a.py"}
    entries = json.loads(cache_file.read_text())
    assert len(entries) == 3  # the script, signorini/__init__.py, a.py
    (src / "signorini/a.py").write_text("from signorini import b\n")  # a new import, new size
    assert closure() == {"__init__.py", "a.py", "b.py"}
    stat = (src / "signorini/a.py").stat()
    (src / "signorini/a.py").write_text("from signorini import c\n")  # same size, same time
    os.utime(src / "signorini/a.py", ns=(stat.st_atime_ns, stat.st_mtime_ns))
    assert closure() == {"__init__.py", "a.py", "c.py"}
    cache_file.write_text("{truncated")  # a damaged cache is an empty one
    assert closure() == {"__init__.py", "a.py", "c.py"}
    assert json.loads(cache_file.read_text())


def test_a_module_written_after_its_importer_was_cached_is_found(tmp_path):
    """The cache keeps the names a file imports, not the files they were then: a module created
    after its importer entered the cache (a stage written after the rule's script), moved to a
    package or deleted, is seen by the next process without the importer changing."""
    src = tmp_path / "src"
    (src / "signorini").mkdir(parents=True)
    (src / "signorini/__init__.py").write_text("")
    script, cache_file = tmp_path / "script.py", tmp_path / "imports.json"
    script.write_text("from signorini.stage import run\n")

    def closure() -> set[str]:
        cache = ImportCache(cache_file)  # a new process
        found = {p.relative_to(src).as_posix() for p in import_closure(script, src, cache)}
        cache.save()
        return found

    assert closure() == {"signorini/__init__.py"}  # the stage is not written yet
    (src / "signorini/stage.py").write_text("")
    assert closure() == {"signorini/__init__.py", "signorini/stage.py"}
    (src / "signorini/stage.py").unlink()
    (src / "signorini/stage").mkdir()
    (src / "signorini/stage/__init__.py").write_text("")
    assert closure() == {"signorini/__init__.py", "signorini/stage/__init__.py"}


def test_one_cache_reads_each_file_once(tmp_path, monkeypatch):
    """The Snakefile asks one cache for the closures of every rule's script: files the closures share
    are read and hashed once, and the closures are the ones computed without a cache."""
    import signorini.pipeline.codedeps as codedeps

    src = tmp_path / "src"
    (src / "signorini").mkdir(parents=True)
    for name, text in {"__init__.py": "", "a.py": "from signorini import b\n", "b.py": ""}.items():
        (src / "signorini" / name).write_text(text)
    scripts = [tmp_path / "one.py", tmp_path / "two.py"]
    for script in scripts:
        script.write_text("from signorini import a\n")
    read = []
    digest = codedeps._digest
    monkeypatch.setattr(codedeps, "_digest", lambda path: read.append(path.name) or digest(path))
    cache = ImportCache(tmp_path / "imports.json")
    closures = [import_closure(script, src, cache) for script in scripts]
    assert sorted(read) == ["__init__.py", "a.py", "b.py", "one.py", "two.py"]
    assert closures == [import_closure(script, src) for script in scripts]
