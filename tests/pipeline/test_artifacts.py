"""Atomic, checked artifacts: round trips, corruption detection, no temporary files left."""

from __future__ import annotations

import json
import os
import stat

import numpy as np
import pytest

from signorini.pipeline import artifacts
from signorini.pipeline.artifacts import (
    CorruptArtifactError,
    atomic_write_text,
    load_json,
    load_npz,
    save_json,
    save_npz,
)
from signorini.pipeline.integrity import artifact_ok
from signorini.studies.scene.norm import norm_stage


def leftovers(directory) -> list[str]:
    return sorted(p.name for p in directory.iterdir() if p.name.startswith(".") or p.suffix == ".tmp")


ARRAYS = {
    "u": np.linspace(-1.0, 1.0, 1001),
    "active": np.array([3, 5, 8], dtype=np.int64),
    "mask": np.array([True, False, True]),
    "matrix": np.arange(12, dtype=np.float32).reshape(3, 4),
    "scalar": np.array(2.5),
    "empty": np.zeros(0),
}


def test_npz_roundtrip(tmp_path):
    path = tmp_path / "sub" / "dir" / "u.npz"  # parents are created
    save_npz(path, **ARRAYS)
    loaded = load_npz(path)
    assert set(loaded) == set(ARRAYS)
    for key, value in ARRAYS.items():
        assert loaded[key].dtype == value.dtype and loaded[key].shape == value.shape
        np.testing.assert_array_equal(loaded[key], value)
    assert leftovers(path.parent) == []


def test_npz_members_read_as_numpy_reads_them(tmp_path):
    """Members read from the file straight into their arrays are numpy's, dtype, shape, order and
    bytes (a column-ordered matrix, a 0-d array, an empty one); a compressed archive, which no
    ``save_npz`` writes, is read through numpy's reader and verified alike."""
    arrays = ARRAYS | {"columns": np.asfortranarray(np.arange(20.0).reshape(4, 5))}
    for name, write in (("stored.npz", np.savez), ("compressed.npz", np.savez_compressed)):
        path = tmp_path / name
        checksum = np.frombuffer(artifacts._digest(arrays).encode(), dtype=np.uint8)
        write(path, _checksum=checksum, **arrays)
        loaded = load_npz(path)
        with np.load(path) as reference:
            for key in arrays:
                assert loaded[key].dtype == reference[key].dtype and loaded[key].shape == reference[key].shape
                assert loaded[key].flags.f_contiguous == reference[key].flags.f_contiguous
                assert loaded[key].tobytes(order="A") == reference[key].tobytes(order="A")


def test_npz_overwrite_replaces_the_file(tmp_path):
    path = tmp_path / "u.npz"
    save_npz(path, u=np.zeros(3))
    save_npz(path, u=np.ones(4))
    np.testing.assert_array_equal(load_npz(path)["u"], np.ones(4))
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("keep", [0.0, 0.3, 0.6, 0.9])
def test_truncated_npz_raises(tmp_path, keep):
    path = tmp_path / "u.npz"
    save_npz(path, **ARRAYS)
    data = path.read_bytes()
    path.write_bytes(data[: int(keep * len(data))])
    with pytest.raises(CorruptArtifactError):
        load_npz(path)


def test_tampered_npz_raises(tmp_path):
    path = tmp_path / "u.npz"
    save_npz(path, u=np.arange(5.0))
    with np.load(path) as data:
        checksum = data["_checksum"]
    np.savez(path, _checksum=checksum, u=np.arange(5.0) + 1e-12)  # valid archive, wrong content
    with pytest.raises(CorruptArtifactError, match="checksum"):
        load_npz(path)
    np.savez(path, u=np.arange(5.0))  # no checksum at all (e.g. written by plain numpy)
    with pytest.raises(CorruptArtifactError):
        load_npz(path)


def test_missing_npz_raises(tmp_path):
    with pytest.raises(CorruptArtifactError):
        load_npz(tmp_path / "nope.npz")


def test_json_roundtrip(tmp_path):
    data = {"N": 101, "norms": {"L4": 5.87e-4, "W14": 0.13}, "ok": True, "names": ["L4", "W14"], "x": None}
    path = tmp_path / "r" / "result.json"
    save_json(path, data)
    assert load_json(path) == data
    assert json.loads(path.read_text())["_complete"] is True
    assert leftovers(path.parent) == []


def test_json_accepts_numpy_scalars(tmp_path):
    path = tmp_path / "r.json"
    save_json(path, {"e": np.float64(1.5), "f": np.float32(0.25)})
    assert load_json(path) == {"e": 1.5, "f": 0.25}


@pytest.mark.parametrize("keep", [0, 1, 10, -2])
def test_truncated_json_raises(tmp_path, keep):
    path = tmp_path / "r.json"
    save_json(path, {"a": 1.0, "b": [1, 2, 3]})
    text = path.read_text()
    path.write_text(text[:keep])
    with pytest.raises(CorruptArtifactError):
        load_json(path)


@pytest.mark.parametrize("content", ['{"a": 1}', '{"a": 1, "_complete": false}', "[1, 2]", '"text"', "null"])
def test_incomplete_json_raises(tmp_path, content):
    path = tmp_path / "r.json"
    path.write_text(content)
    with pytest.raises(CorruptArtifactError):
        load_json(path)


def test_missing_json_raises(tmp_path):
    with pytest.raises(CorruptArtifactError):
        load_json(tmp_path / "nope.json")


def test_atomic_write_text(tmp_path):
    path = tmp_path / "t" / "table.md"
    atomic_write_text(path, "| a |\n|---|\n| ü |\n")
    assert path.read_text() == "| a |\n|---|\n| ü |\n"
    assert leftovers(path.parent) == []


def test_failed_write_keeps_the_old_file_and_leaves_no_temporary(tmp_path, monkeypatch):
    path = tmp_path / "u.npz"
    save_npz(path, u=np.zeros(3))
    before = path.read_bytes()

    def broken_savez(fh, **arrays):
        fh.write(b"PK\x03\x04 partial")  # a few bytes, then the job dies
        raise KeyboardInterrupt

    monkeypatch.setattr(artifacts.np, "savez", broken_savez)
    with pytest.raises(KeyboardInterrupt):
        save_npz(path, u=np.ones(3))
    monkeypatch.undo()
    assert path.read_bytes() == before
    np.testing.assert_array_equal(load_npz(path)["u"], np.zeros(3))
    assert leftovers(tmp_path) == []
    assert sorted(os.listdir(tmp_path)) == ["u.npz"]


def test_unserialisable_json_leaves_nothing(tmp_path):
    path = tmp_path / "r.json"
    with pytest.raises(TypeError):
        save_json(path, {"bad": object()})
    assert list(tmp_path.iterdir()) == []


def test_artifacts_follow_the_umask(tmp_path):
    old = os.umask(0o022)
    try:
        save_json(tmp_path / "a.json", {"x": 1})
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.json").stat().st_mode) == 0o644


def test_a_hand_edited_norm_value_is_caught(solved, tmp_path):
    d, at = solved
    path = tmp_path / "L4.json"
    norm_stage(at, d / "solution.npz", "L4", path, {})
    value = load_json(path)["value"]
    path.write_text(path.read_text().replace(repr(value), repr(2 * value)))  # a well-formed edit
    with pytest.raises(CorruptArtifactError, match="checksum mismatch"):
        load_json(path)
    assert not artifact_ok(path)


def test_interrupted_write_leaves_no_file(tmp_path):
    from signorini.pipeline.artifacts import _atomic_write

    def killed(fh):
        fh.write(b"partial")
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        _atomic_write(tmp_path / "x.npz", killed)
    assert list(tmp_path.iterdir()) == []
