"""The cache check (``signorini.pipeline.integrity``), decided in-process on planned outputs as the
workflow builds them from Snakemake's DAG (``planned_outputs``): what it looks at (the plan, and
nothing else), what it distrusts (damaged, foreign, out of date), and that it moves aside and never
deletes; rendered outputs are rendered anew, never moved."""

from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
import pytest
from helpers import ERRORS, PROBLEM

from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    atomic_write_text,
    content_digest,
    load_json,
    recording,
    save_json,
    save_npz,
)
from signorini.pipeline.integrity import Planned, apply_verdicts, artifact_ok, damage, judge

ENV = {"lock": "l", "numpy": "2"}


def _write(path: str, rule: str, inputs=(), wildcards=None, params=None, env=ENV, data=None):
    """An artifact as a job of ``rule`` writes it (its provenance recorded), and its plan entry."""
    wildcards = {"scene": "s", "N": "11"} if wildcards is None else wildcards
    params = params or {"problem": PROBLEM}
    prov = {
        "rule": rule,
        "code": "c",
        "params": params,
        "wildcards": wildcards,
        "inputs": {p: content_digest(p) for p in inputs},
        "environment": env,
    }
    with recording(prov):
        if path.endswith(".npz"):
            save_npz(path, u=np.arange(5.0) if data is None else data)
        elif path.endswith(".json"):
            save_json(path, {"value": 1.0})
        else:
            atomic_write_text(path, ERRORS if data is None else data)
    return Planned(path, rule, "c", params, wildcards, tuple(inputs))


@pytest.fixture
def chain(tmp_path, monkeypatch):
    """A mesh's chain system -> solution -> norm -> errors.csv -> table1.csv, written by its jobs."""
    monkeypatch.chdir(tmp_path)  # the workflow names artifacts relative to its directory
    system = _write("results/s/N11/system.npz", "discretise")
    solution = _write("results/s/N11/solution.npz", "solve", [system.path])
    norm = _write("results/s/N11/norms/L4.json", "norm", [solution.path], {"scene": "s", "N": "11", "norm": "L4"})
    errors = _write("results/s/errors.csv", "errors", [norm.path], {"scene": "s"})
    table = _write("paper_figures/table1.csv", "table1", [errors.path], {})
    return [system, solution, norm, errors, table]


def test_a_plan_written_by_its_jobs_is_trusted(chain):
    assert not judge(chain, ENV)


def test_the_check_looks_only_at_the_planned_outputs(chain, capsys):
    """Artifacts of another scene out of date on disk (a user's scene_defaults changed every scene's
    problem) are not touched by a run whose plan does not hold them."""
    other = _write("results/paper/N101/system.npz", "discretise", wildcards={"scene": "paper", "N": "101"})
    changed = [Planned(o.path, o.rule, o.code, {"problem": {**PROBLEM, "c": 2}}, o.wildcards, o.inputs) for o in chain]
    verdicts = judge(changed[:4], ENV)
    assert set(verdicts.stale) == {o.path for o in chain[:4]} and other.path not in verdicts.stale
    apply_verdicts(verdicts, execute=True)
    assert Path(other.path).exists() and Path("paper_figures/table1.csv").exists()


def test_out_of_date_artifacts_are_moved_aside_not_deleted(chain, capsys):
    """Other parameters (A 10 -> 20) for the system: it and everything computed from it are moved to
    <name>.stale, one line per reason; the rendered table is rendered anew and stays in place."""
    now = {"problem": {**PROBLEM, "A": 20}}
    plan = [Planned(chain[0].path, "discretise", "c", now, chain[0].wildcards), *chain[1:]]
    verdicts = judge(plan, ENV)
    assert list(verdicts.stale) == [o.path for o in chain[:4]] and list(verdicts.rerender) == [chain[4].path]
    assert '"A": 10' in verdicts.stale[chain[0].path] and '"A": 20' in verdicts.stale[chain[0].path]
    lines = apply_verdicts(verdicts, execute=True)
    assert len(lines) == 3 and "moved to <name>.stale" in lines[0]
    assert all(Path(f"{o.path}.stale").exists() and not Path(o.path).exists() for o in chain[:4])
    assert Path(chain[4].path).exists()


def test_a_read_only_call_names_and_moves_nothing(chain):
    plan = [Planned(o.path, o.rule, "new code", o.params, o.wildcards, o.inputs) for o in chain]
    lines = apply_verdicts(judge(plan, ENV), execute=False, stream=io.StringIO())
    assert lines and all("a run" in line for line in lines)
    assert all(Path(o.path).exists() for o in chain) and not list(Path(".").rglob("*.stale"))


def test_other_libraries_make_an_artifact_out_of_date(chain):
    verdicts = judge(chain, {**ENV, "numpy": "3"})
    assert "other libraries (numpy" in verdicts.stale[chain[0].path]


@pytest.mark.parametrize("edit", ["bit", "spreadsheet"])
def test_an_edited_table_fails_its_seal(chain, edit):
    """One flipped bit in errors.csv, or a spreadsheet's round trip (6 digits, CRLF): damaged (its
    seal), moved to .corrupt; the job that reads it would refuse it too."""
    from signorini.pipeline.joblog import check_inputs

    path = Path(chain[3].path)
    if edit == "bit":
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 1
        path.write_bytes(bytes(data))
    else:
        rows = [line.split(",") for line in path.read_text().splitlines()]
        cells = [[c if c[0].isalpha() else f"{float(c):.6g}" for c in row] for row in rows]
        path.write_bytes("\r\n".join(",".join(row) for row in cells).encode())
    verdicts = judge(chain, ENV)
    assert "its bytes differ" in verdicts.corrupt[str(path)]
    assert chain[4].path not in verdicts.stale  # the table was rendered from the true one
    with pytest.raises(CorruptArtifactError, match="bytes differ"):
        check_inputs([str(path)])


def test_a_file_copied_from_another_mesh_is_foreign_and_its_consumers_are_kept(chain):
    """system.npz of N = 21 copied over N = 11: foreign (its record names N = 21), moved aside; the
    solution computed from the true one is not judged by the intruder."""
    other = _write("results/s/N21/system.npz", "discretise", wildcards={"scene": "s", "N": "21"}, data=np.ones(3))
    Path(chain[0].path).write_bytes(Path(other.path).read_bytes())
    verdicts = judge(chain, ENV)
    assert list(verdicts.stale) == [chain[0].path] and "other wildcards" in verdicts.stale[chain[0].path]
    assert not verdicts.corrupt and not verdicts.rerender


def test_a_file_written_outside_the_workflow_is_not_trusted(chain):
    """A cached table without a seal is moved aside; a rendered one (a committed file) rendered anew."""
    from signorini.pipeline.artifacts import seal_path

    for planned in chain[3:]:
        seal_path(planned.path).unlink()
    verdicts = judge(chain, ENV)
    assert "no record" in verdicts.stale[chain[3].path] and "no record" in verdicts.rerender[chain[4].path]


def test_a_committed_output_is_rendered_anew_only_from_the_cache_at_hand(chain):
    """A committed file (no record of a run here) whose inputs are all cached is rendered anew (it
    costs a rendering job); one whose inputs are not is kept: rendering it would recompute them."""
    from signorini.pipeline.artifacts import seal_path

    seal_path(chain[4].path).unlink()
    assert "no record" in judge(chain, ENV).rerender[chain[4].path]
    Path(chain[3].path).rename("errors.csv.elsewhere")
    assert chain[4].path not in judge(chain, ENV).rerender


def test_a_rendered_output_of_another_scene_is_rendered_anew(chain):
    """figures_scene switched back: the table's job now reads another scene's errors.csv."""
    _write("results/s2/errors.csv", "errors", wildcards={"scene": "s2"})
    plan = [*chain[:4], Planned(chain[4].path, "table1", "c", chain[4].params, {}, ("results/s2/errors.csv",))]
    assert "was not computed from results/s2/errors.csv" in judge(plan, ENV).rerender[chain[4].path]


def test_an_archive_read_by_the_run_is_verified_in_full(chain):
    """A flipped data bit in a large archive: found when a job of this run reads it (streamed
    checksum), not when it is only listed; either way it is never deleted."""
    path = Path(chain[1].path)
    data = bytearray(path.read_bytes())
    data[data.index(b"\x00\x00\x00\x00\x00\x00\xf0?")] ^= 1  # a byte of u = 1.0
    path.write_bytes(bytes(data))
    assert damage(path, read=False) is None and damage(path, read=True)  # the zip's CRC or the checksum
    plan = [*chain[:1], Planned(**{**chain[1].__dict__, "read": True}), *chain[2:]]
    verdicts = judge(plan, ENV)
    assert list(verdicts.corrupt) == [str(path)]
    apply_verdicts(verdicts, execute=True)
    assert Path(f"{path}.corrupt").exists()


def test_a_symbolic_link_is_moved_not_what_it_points_to(chain, tmp_path):
    target = tmp_path / "elsewhere.json"
    target.write_text("{}")
    Path(chain[2].path).unlink()
    Path(chain[2].path).symlink_to(target)
    verdicts = judge(chain, ENV)
    assert chain[2].path in verdicts.corrupt
    apply_verdicts(verdicts, execute=True)
    assert Path(f"{chain[2].path}.corrupt").is_symlink() and target.read_text() == "{}"


def test_damage_covers_every_kind_of_artifact(tmp_path):
    """Theory, work-precision and atlas records and benchmark files are checked like the chain's."""
    kinds = ["N11/theory.json", "N11/work_precision/osqp.json", "atlas/A_1.json", "N11/solution.json"]
    for name in kinds:
        save_json(tmp_path / name, {"value": 1.0})
    tsv = tmp_path / "benchmarks/N11/solve.tsv"
    tsv.parent.mkdir(parents=True)
    tsv.write_text("s\th:m:s\tmax_rss\n0.5\t0:00:00\t100.0\n")
    assert all(damage(tmp_path / n, read=True) is None for n in [*kinds, "benchmarks/N11/solve.tsv"])
    for name in kinds:
        (tmp_path / name).write_text((tmp_path / name).read_text().replace("1.0", "2.0"))
    tsv.write_text("s\th:m:s\tmax_rss\n")
    assert all(damage(tmp_path / n, read=True) for n in [*kinds, "benchmarks/N11/solve.tsv"])


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


# --- integrity checks are not optional ----------------------------------------------------------


@pytest.mark.parametrize("kind", ["json", "npz", "unread_npz"])
def test_a_checksummed_artifact_without_its_checksum_is_damaged(tmp_path, kind):
    """A norm JSON edited by hand with its ``_checksum`` removed, an archive rewritten without it:
    both fail their check (the checksum is part of the format, not optional)."""
    import json

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
    assert not artifact_ok(path)
    assert damage(path, read=kind == "npz") is not None  # read or not: the archive lists no checksum


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
