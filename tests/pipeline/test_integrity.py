"""The cache check (``signorini.pipeline.integrity``): damaged, stale and out-of-date artifacts and
tables are found, named as what they are, and moved aside or removed; leftover temporaries."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from helpers import ERRORS, PROBLEM

from signorini.pipeline.artifacts import CorruptArtifactError, load_json, save_json, save_npz
from signorini.pipeline.integrity import artifact_ok, cached_artifacts, corrupt_artifacts, quarantine_corrupt

EOC = "N,h,L4\n21,0.0476,1.8\n41,0.0244,1.9\nregression,,1.85\n"


@pytest.mark.parametrize("table, text", [("errors.csv", ERRORS), ("eoc.csv", EOC)])
def test_a_table_that_lost_a_row_is_out_of_date(tmp_path, table, text, capsys):
    """A complete table without one of the scene's N (``sed -i '3d'``, or the N list changed) is a
    valid file of another state: removed and rebuilt, and called out of date, not corrupt."""
    from signorini.pipeline.integrity import remove_stale

    scene = {"N": [11, 21, 41], "norms": ["L4"]}
    path = tmp_path / "s" / table
    path.parent.mkdir()
    path.write_text(text)
    assert not remove_stale(cached_artifacts(tmp_path, {"s": scene}), str, execute=True)
    lines = text.splitlines(keepends=True)
    path.write_text("".join(lines[:2] + lines[3:]))  # a complete-looking table without one N
    assert artifact_ok(path) and not corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene}))
    assert remove_stale(cached_artifacts(tmp_path, {"s": scene}), str, execute=True) == [str(path)]
    err = capsys.readouterr().err
    assert "out of date" in err and "the scene asks for" in err and "corrupt" not in err
    assert not path.exists() and not (tmp_path / "s" / f"{table}.corrupt").exists()


@pytest.mark.parametrize("value", ["nan", "inf", "-0.5"])
def test_a_table_with_a_non_finite_or_negative_error_is_caught(tmp_path, value):
    path = tmp_path / "errors.csv"
    path.write_text(ERRORS.replace("0.012", value))
    assert not artifact_ok(path)


def test_temporaries_left_by_a_killed_job_are_removed(tmp_path, monkeypatch):
    """``kill -9`` during an atomic write leaves ``.<name>.<random>.tmp``; the next run that
    executes jobs deletes it, unless another run holds the directory's lock (its jobs may be
    writing) or the file is fresh (a run with ``--nolock``)."""
    from signorini.pipeline.integrity import leftover_temporaries, remove_leftover_temporaries

    monkeypatch.chdir(tmp_path)
    old = tmp_path / "results/smoke/N11/.solution.npz.x1y2.tmp"
    fresh = tmp_path / "results/smoke/N21/.solution.npz.a3b4.tmp"
    for path in (old, fresh):
        path.parent.mkdir(parents=True)
        path.write_bytes(b"PK\x03\x04 half an archive")
    os.utime(old, (1e9, 1e9))
    lock = tmp_path / ".snakemake/locks/0.input.lock"
    lock.parent.mkdir(parents=True)
    lock.write_text("")
    assert leftover_temporaries(["results"]) == []  # another run is active
    lock.unlink()
    assert remove_leftover_temporaries(["results"], execute=False) == [] and old.exists()  # read-only
    assert remove_leftover_temporaries(["results"], execute=True) == [old.relative_to(tmp_path)]
    assert not old.exists() and fresh.exists()


def test_the_damage_check_covers_every_kind_of_artifact(tmp_path):
    """The theory, work-precision and atlas artifacts and the benchmark files are checked like
    the chain's: each damaged one is found, an intact one is not."""
    kinds = [
        "N11/theory.json",
        "N11/work_precision/osqp.json",
        "atlas/A_1.json",
        "N11/norms/L4.json",
        "N11/solution.json",
    ]
    for name in kinds:
        save_json(tmp_path / "s" / name, {"value": 1.0})
    tsv = tmp_path / "s/benchmarks/N11/solve.tsv"
    tsv.parent.mkdir(parents=True)
    tsv.write_text("s\th:m:s\tmax_rss\n0.5\t0:00:00\t100.0\n")
    scene = {"N": [11], "atlas": {}}
    assert corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene})) == []
    for name in kinds:
        (tmp_path / "s" / name).write_text((tmp_path / "s" / name).read_text().replace("1.0", "2.0"))
    tsv.write_text("s\th:m:s\tmax_rss\n")
    damaged = corrupt_artifacts(cached_artifacts(tmp_path, {"s": scene}))
    assert sorted(damaged) == sorted(str(tmp_path / "s" / name) for name in [*kinds, "benchmarks/N11/solve.tsv"])


# --- provenance includes the parameters; words match the state --------------------------------


def test_an_artifact_computed_with_other_parameters_is_out_of_date(tmp_path, capsys, monkeypatch):
    """Its recorded code and inputs are current, only the parameters a job would get now differ
    (A 10 -> 20): out of date, and so is everything computed from it and the scene's tables."""
    from signorini.pipeline.artifacts import content_digest, recording
    from signorini.pipeline.integrity import remove_stale, stale_artifacts

    monkeypatch.chdir(tmp_path)  # the workflow names artifacts relative to its directory
    scene = Path("results/s")
    system, norm = scene / "N11/system.json", scene / "N11/norms/L4.json"
    with recording({"rule": "discretise", "code": "c", "params": {"problem": PROBLEM}, "inputs": {}}):
        save_json(system, {"n": 1})
    inputs = {str(system): content_digest(system)}
    with recording({"rule": "norm", "code": "c", "params": {"problem": PROBLEM}, "inputs": inputs}):
        save_json(norm, {"value": 1.0})
    (scene / "errors.csv").write_text(ERRORS)

    def cached():
        return cached_artifacts("results", {"s": {"N": [11, 21, 41], "norms": ["L4"]}})

    def code(rule):
        return "c"

    assert stale_artifacts(cached(), code, lambda path, prov: {"problem": PROBLEM}) == []
    now = {"problem": {**PROBLEM, "A": 20}}
    stale = dict(stale_artifacts(cached(), code, lambda path, prov: now))
    assert set(stale) == {str(system), str(norm)}
    assert '"A": 10' in stale[str(system)] and '"A": 20' in stale[str(system)]
    removed = remove_stale(cached(), code, False, lambda path, prov: now)
    assert set(removed) == {str(system), str(norm), str(scene / "errors.csv")} and system.exists()  # read-only
    assert "out of date" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("block", "reason"),
    [
        ({"N": [11, 21], "norms": ["L4"]}, "holds the rows N = 11, 21, 41, the scene asks for 11, 21"),
        ({"N": [11, 21, 41, 81], "norms": ["L4"]}, "the scene asks for 11, 21, 41, 81"),
        ({"N": [11, 21, 41], "norms": ["L4", "H12"]}, "has the norms L4, the scene asks for L4, H12"),
        ({"N": [11, 21, 41], "norms": []}, "has the norms L4, the scene asks for none"),
    ],
)
def test_a_table_of_other_meshes_or_norms_is_out_of_date_not_corrupt(tmp_path, capsys, block, reason):
    from signorini.pipeline.integrity import quarantine_corrupt, remove_stale

    (tmp_path / "s").mkdir()
    (tmp_path / "s/errors.csv").write_text(ERRORS)
    assert quarantine_corrupt(cached_artifacts(tmp_path, {"s": block})) == []
    assert remove_stale(cached_artifacts(tmp_path, {"s": block}), str, execute=True) == [str(tmp_path / "s/errors.csv")]
    err = capsys.readouterr().err
    assert reason in err and "out of date" in err and "corrupt" not in err
    assert not list(tmp_path.rglob("*.corrupt"))


# --- integrity checks are not optional ----------------------------------------------------------


@pytest.mark.parametrize("kind", ["json", "npz", "large_npz"])
def test_a_checksummed_artifact_without_its_checksum_is_damaged(tmp_path, monkeypatch, kind):
    """A norm JSON edited by hand with its ``_checksum`` removed, an archive rewritten without it:
    both fail their check (the checksum is part of the format, not optional)."""
    import json

    import signorini.pipeline.integrity as cache
    from signorini.pipeline.artifacts import load_npz, save_npz

    if kind == "json":
        path = tmp_path / "L4.json"
        save_json(path, {"value": 0.04})
        data = json.loads(path.read_text())
        del data["_checksum"]
        path.write_text(json.dumps({**data, "value": 0.004}))
        with pytest.raises(CorruptArtifactError, match="no checksum"):
            load_json(path)
    else:
        path = tmp_path / "solution.npz"
        save_npz(path, u=np.arange(4.0))
        np.savez(path, **{k: v for k, v in np.load(path).items() if k != "_checksum"})
        with pytest.raises(CorruptArtifactError, match="no checksum"):
            load_npz(path)
        if kind == "large_npz":  # checked structurally, by its zip directory
            monkeypatch.setattr(cache, "CHECKSUM_MAX_BYTES", 0)
    assert not artifact_ok(path)
    assert corrupt_artifacts([path]) == [str(path)]


def test_rendered_tables_of_other_meshes_are_named(tmp_path):
    from signorini.pipeline.integrity import rendered_mismatch

    t1, t2 = tmp_path / "table1.csv", tmp_path / "table2.csv"
    t1.write_text("h,L4\n1/11,1e-3\n1/21,3e-4\n", encoding="utf-8")
    t2.write_text("h,L4\n1/21,1.9\nregr.,1.9\ntheo.,2.0\n", encoding="utf-8")
    tables = {"table1": t1, "table2": t2}
    assert rendered_mismatch(tables, [11, 21]) is None
    assert "holds the rows h = 1/11, 1/21" in rendered_mismatch(tables, [11, 21, 41])
    assert rendered_mismatch({"table1": tmp_path / "absent.csv"}, [11]) is None


def test_quarantine_moves_only_corrupt_artifacts(tmp_path):
    good, bad_json, bad_npz = tmp_path / "good.json", tmp_path / "bad.json", tmp_path / "bad.npz"
    save_json(good, {"value": 1.0})
    save_json(bad_json, {"value": 1.0})
    bad_json.write_text(bad_json.read_text()[:10])
    save_npz(bad_npz, u=np.arange(100.0))
    bad_npz.write_bytes(bad_npz.read_bytes()[:-40])
    moved = quarantine_corrupt([good, bad_json, bad_npz, tmp_path / "missing.npz"])
    assert sorted(moved) == sorted([str(bad_json), str(bad_npz)])
    assert good.exists() and not bad_json.exists() and not bad_npz.exists()
    assert (tmp_path / "bad.npz.corrupt").exists()


def test_csv_check_detects_truncation(tmp_path):
    good = "N,h,L4\n11,0.09,0.04\n21,0.047,0.01\n"
    (tmp_path / "errors.csv").write_text(good)
    assert artifact_ok(tmp_path / "errors.csv")
    for bad in (good[:-1], good[:-8], "N,h,L4\n11,0.09,\n"):
        (tmp_path / "errors.csv").write_text(bad)
        assert not artifact_ok(tmp_path / "errors.csv"), bad
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\nregression,,1.9\n")
    assert artifact_ok(tmp_path / "eoc.csv")
    (tmp_path / "eoc.csv").write_text("N,h,L4\n21,0.047,1.9\n")
    assert not artifact_ok(tmp_path / "eoc.csv")
