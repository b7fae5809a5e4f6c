"""Atomic writes and checked reads of the cached artifacts.

Every file is written to a temporary sibling and renamed into place, so a
killed job never leaves a half-written file under the final name.  ``.npz``
archives carry a ``_checksum`` of their arrays, and JSON files a ``"_checksum"`` of their content
and a ``"_complete"`` marker; a truncated, edited or tampered file raises ``CorruptArtifactError``
on load.

Inside a workflow job (``signorini.pipeline.joblog.job_log``) every artifact also records its
provenance (``_provenance``): the digest of the code the job ran (its script and the package
modules it imports, read at job start), the parameters that define it and the content digest
(``content_digest``) of every input artifact it read.  The workflow compares the code digest with
the current code, and the input digests with the current inputs, before planning
(``signorini.pipeline.integrity``); a job refuses an input computed from other inputs than the ones
now on disk (``signorini.pipeline.joblog``).

Files that cannot carry a checksum of their own (tables, Markdown, figures) get a *seal* when a
workflow job writes them: a checksummed JSON record under ``results/.seals/`` holding the SHA-256
of the file's bytes and the job's provenance (``seal_of``, ``verify_seal``).  An edited table (a
flipped bit, a spreadsheet's round trip) then fails its seal instead of being read as data, and a
rendered output says what it was rendered from.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import struct
import tempfile
import zipfile
from collections.abc import Callable, Iterable, Iterator, Mapping
from functools import partial
from pathlib import Path

import numpy as np

from signorini.pipeline.paths import FIGDIR, RESULTS, SEALS


class CorruptArtifactError(RuntimeError):
    """A cached artifact is unreadable, truncated or fails its checksum."""


# what reading a damaged zip archive raises (a flipped bit in a header can name an unknown compression)
_ARCHIVE_ERRORS = (OSError, ValueError, zipfile.BadZipFile, EOFError, UnicodeDecodeError, NotImplementedError)
_PROVENANCE: dict | None = None  # of the running job, recorded in every artifact it writes


def code_digest(files: Iterable[str | os.PathLike]) -> str:
    """SHA-256 over the names and contents of ``files`` (in sorted order): what a job's code was."""
    h = hashlib.sha256()
    for name in sorted(str(f) for f in files):
        h.update(name.encode())
        h.update(Path(name).read_bytes())
    return h.hexdigest()


@contextlib.contextmanager
def recording(provenance: Mapping) -> Iterator[None]:
    """Record ``provenance`` (JSON-ready) in every artifact written inside the block."""
    global _PROVENANCE
    old, _PROVENANCE = _PROVENANCE, dict(provenance)
    try:
        yield
    finally:
        _PROVENANCE = old


def npz_provenance(arrays: Mapping[str, np.ndarray]) -> dict | None:
    """The provenance recorded in the arrays of a loaded archive (``load_npz``), or None."""
    raw = arrays.get("_provenance")
    return None if raw is None else json.loads(raw.tobytes().decode())


def provenance_of(path: str | os.PathLike) -> dict | None:
    """The provenance an artifact records (None for one written outside a workflow job): an
    archive's or JSON record's own, any other file's in its seal."""
    path = Path(path)
    if needs_seal(path):
        return (seal_of(path) or {}).get("_provenance")
    if path.suffix == ".npz":
        try:  # only this member is read: the arrays may be large
            with np.load(path, allow_pickle=False) as data:
                return npz_provenance({"_provenance": data["_provenance"]} if "_provenance" in data.files else {})
        except (OSError, ValueError, zipfile.BadZipFile, EOFError) as err:
            raise CorruptArtifactError(f"{path}: unreadable archive ({err})") from err
    return load_json(path).get("_provenance")


def content_digest(path: str | os.PathLike) -> str:
    """What identifies an artifact's content: the checksum it stores (``.npz``: only that member is
    read; ``.json``), else the SHA-256 of its bytes (tables, benchmark files)."""
    path = Path(path)
    try:
        if path.suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                if "_checksum" in data.files:
                    return data["_checksum"].tobytes().decode()
        elif path.suffix == ".json":
            stored = json.loads(path.read_text(encoding="utf-8")).get("_checksum")
            if isinstance(stored, str):
                return stored
        return file_digest(path)
    except (OSError, ValueError, AttributeError, zipfile.BadZipFile, EOFError) as err:
        raise CorruptArtifactError(f"{path}: unreadable ({err})") from err


def changed_input(provenance: dict | None, digest: Callable[[str], str] | None = None) -> str | None:
    """The first input recorded in ``provenance`` whose current content differs from the recorded
    digest (None when all agree; a missing or unreadable input is left to the workflow).
    ``digest``: ``content_digest`` or a memoised one (many artifacts share an input)."""
    digest = digest or content_digest
    for path, recorded in ((provenance or {}).get("inputs") or {}).items():
        if not Path(path).is_file():
            continue
        try:
            if digest(path) != recorded:
                return path
        except CorruptArtifactError:
            continue
    return None


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_SEALED_SUFFIXES = (".npz", ".json")  # these carry their checksum and provenance themselves
_UNSEALED_SUFFIXES = (".tsv", ".log")  # written by Snakemake itself: benchmark files, logs


def seal_path(path: str | os.PathLike, root: str | os.PathLike = ".") -> Path:
    """Where the seal of ``path`` lives: ``<root>/results/.seals/<path relative to root>.json``
    (``root``: the directory the workflow runs in; a path outside it is named by the SHA-256 of its
    absolute path)."""
    where = os.path.abspath(os.path.join(root, path))
    rel = os.path.relpath(where, os.path.abspath(root))
    if rel.startswith(os.pardir):
        rel = hashlib.sha256(where.encode()).hexdigest()
    return Path(root) / SEALS / f"{rel}.json"


def file_digest(path: str | os.PathLike, chunk: int = 1 << 20) -> str:
    """SHA-256 of a file's bytes, read in chunks (any size in constant memory)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(partial(fh.read, chunk), b""):
            h.update(block)
    return h.hexdigest()


def needs_seal(path: str | os.PathLike) -> bool:
    """Whether ``path`` is a file kind that needs a seal to be vouched for (not ``.npz``/``.json``)."""
    return Path(path).suffix not in _SEALED_SUFFIXES


def is_sealed_kind(path: str | os.PathLike) -> bool:
    """Whether a job's output at ``path`` is sealed when written: a file of the cache or a rendered
    output (``results/``, ``paper_figures/``) that carries no checksum of its own."""
    where = Path(os.path.abspath(path))
    if not needs_seal(path) or where.suffix in _UNSEALED_SUFFIXES:
        return False
    return any(where.is_relative_to(Path(os.path.abspath(d))) for d in (RESULTS, FIGDIR))


def seal_of(path: str | os.PathLike, root: str | os.PathLike = ".") -> dict | None:
    """The seal of ``path`` (``{"sha256": ..., "_provenance": ...}``), None when it has none; a
    damaged seal raises ``CorruptArtifactError``."""
    where = seal_path(path, root)
    return load_json(where) if where.is_file() else None


def seal_broken(path: str | os.PathLike, root: str | os.PathLike = ".") -> str | None:
    """Why ``path`` is not what its job wrote, if it has a seal: a damaged seal, or other bytes
    (edited after it was written); None when it has none or its bytes match."""
    try:
        seal = seal_of(path, root)
    except CorruptArtifactError as err:
        return f"its seal is damaged ({err})"
    if seal is not None and seal.get("sha256") != file_digest(Path(root) / path):
        return "its bytes differ from what its job wrote (edited by hand, or damaged)"
    return None


def verify_seal(path: str | os.PathLike, root: str | os.PathLike = ".") -> str | None:
    """Why ``path`` is not vouched for by a seal (None when its bytes match its seal): no seal, or
    ``seal_broken``."""
    if not seal_path(path, root).is_file():
        return "no record of the job that wrote it"
    return seal_broken(path, root)


def _write_seal(path: Path) -> None:
    if _PROVENANCE is not None and is_sealed_kind(path):
        save_json(seal_path(path), {"path": str(path), "sha256": file_digest(path)})


def _atomic_write(path: str | os.PathLike, write) -> None:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; a plain open() would follow the umask
        with os.fdopen(fd, "wb") as fh:
            write(fh)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    _write_seal(path)


def _digest(arrays: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for key in sorted(arrays):
        a = np.ascontiguousarray(arrays[key])
        h.update(key.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.reshape(-1).view(np.uint8))  # the array's bytes, without copying them
    return h.hexdigest()


def save_npz(path: str | os.PathLike, **arrays: np.ndarray) -> None:
    """Write arrays atomically with a SHA-256 checksum."""
    arrays = {k: np.asarray(v) for k, v in arrays.items()}
    if _PROVENANCE is not None:
        arrays["_provenance"] = np.frombuffer(json.dumps(_PROVENANCE, sort_keys=True).encode(), dtype=np.uint8)
    checksum = np.frombuffer(_digest(arrays).encode(), dtype=np.uint8)
    _atomic_write(path, lambda fh: np.savez(fh, _checksum=checksum, **arrays))


def _npy_header(fh) -> tuple[tuple[int, ...], bool, np.dtype]:
    """``(shape, fortran_order, dtype)`` of the ``.npy`` data starting at ``fh``'s position, which is
    left at the array's first byte."""
    fmt = np.lib.format
    major = fmt.read_magic(fh)[0]
    return (fmt.read_array_header_1_0 if major == 1 else fmt.read_array_header_2_0)(fh)


def _read_member(fh, archive: zipfile.ZipFile, info: zipfile.ZipInfo) -> np.ndarray:
    """One ``.npy`` member: an uncompressed one (``np.savez``) read from the file straight into its
    array, without the copies of ``np.load``'s zip reader (docs/evidence/design-measurements.md#archive-reading);
    any other through ``np.load``'s reader.  The checksum of ``load_npz`` vouches for the bytes
    either way."""
    if info.compress_type != zipfile.ZIP_STORED or info.flag_bits & 0x1:
        return np.lib.format.read_array(archive.open(info), allow_pickle=False)
    fh.seek(info.header_offset)
    local = fh.read(30)  # the local file header: its name and extra field may differ from the directory's
    if len(local) < 30 or local[:4] != b"PK\x03\x04":
        raise zipfile.BadZipFile(f"bad local header of {info.filename}")
    name_len, extra_len = struct.unpack("<HH", local[26:30])
    fh.seek(info.header_offset + 30 + name_len + extra_len)
    shape, fortran, dtype = _npy_header(fh)
    if dtype.hasobject:
        raise ValueError(f"{info.filename}: object arrays are not read")
    array = np.empty(shape, dtype=dtype, order="F" if fortran else "C")
    target = array.reshape(-1, order="A").view(np.uint8)
    if fh.readinto(target) != target.size:
        raise EOFError(f"{info.filename}: truncated")
    return array


def load_npz(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read an archive written by ``save_npz`` and verify its checksum."""
    try:
        with open(path, "rb") as fh, zipfile.ZipFile(fh) as archive:
            arrays = {
                info.filename.removesuffix(".npy"): _read_member(fh, archive, info)
                for info in archive.infolist()
                if info.filename.endswith(".npy")
            }
    except _ARCHIVE_ERRORS as err:
        raise CorruptArtifactError(f"{path}: unreadable archive ({err})") from err
    stored = arrays.pop("_checksum", None)
    if stored is None:
        raise CorruptArtifactError(f"{path}: no checksum (edited or damaged)")
    if stored.tobytes().decode() != _digest(arrays):
        raise CorruptArtifactError(f"{path}: checksum mismatch (truncated or modified)")
    return arrays


def _stream_member(h, archive: zipfile.ZipFile, name: str, chunk: int) -> None:
    """Hash one ``.npy`` member of an archive as ``_digest`` hashes its array, streaming its data."""
    with archive.open(name) as fh:
        shape, fortran, dtype = _npy_header(fh)
        h.update(name[: -len(".npy")].encode())
        h.update(str(dtype).encode())
        h.update(str(shape or (1,)).encode())  # np.ascontiguousarray makes a 0-d array 1-d
        if fortran and len(shape) > 1:  # stored in column order: the digest is of the row-order bytes
            h.update(np.ascontiguousarray(np.lib.format.read_array(archive.open(name))).tobytes())
            return
        for block in iter(partial(fh.read, chunk), b""):
            h.update(block)


def verify_npz(path: str | os.PathLike, chunk: int = 1 << 22) -> None:
    """Verify an archive's checksum reading its arrays in chunks (memory independent of its size);
    raises ``CorruptArtifactError`` as ``load_npz`` does."""
    try:
        with zipfile.ZipFile(path) as archive:
            names = sorted(n for n in archive.namelist() if n.endswith(".npy"))
            if "_checksum.npy" not in names:
                raise CorruptArtifactError(f"{path}: no checksum (edited or damaged)")
            stored = np.lib.format.read_array(archive.open("_checksum.npy")).tobytes().decode()
            h = hashlib.sha256()
            for name in (n for n in names if n != "_checksum.npy"):
                _stream_member(h, archive, name, chunk)
    except _ARCHIVE_ERRORS as err:
        raise CorruptArtifactError(f"{path}: unreadable archive ({err})") from err
    if stored != h.hexdigest():
        raise CorruptArtifactError(f"{path}: checksum mismatch (truncated or modified)")


def _json_digest(data: dict) -> str:
    return hashlib.sha256(json.dumps(data, sort_keys=True, default=float).encode()).hexdigest()


def save_json(path: str | os.PathLike, data: dict) -> None:
    """Write a JSON object atomically with a SHA-256 checksum of its content and a completeness marker."""
    payload = json.loads(json.dumps({**data, **({"_provenance": _PROVENANCE} if _PROVENANCE else {})}, default=float))
    text = json.dumps(
        {**payload, "_checksum": _json_digest(payload), "_complete": True}, indent=2, sort_keys=True, default=float
    )
    _atomic_write(path, lambda fh: fh.write(text.encode()))


def load_json(path: str | os.PathLike) -> dict:
    """Read a JSON object written by ``save_json``."""
    try:
        data = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError) as err:
        raise CorruptArtifactError(f"{path}: unreadable JSON ({err})") from err
    if not isinstance(data, dict) or data.pop("_complete", None) is not True:
        raise CorruptArtifactError(f"{path}: incomplete JSON artifact")
    checksum = data.pop("_checksum", None)
    if checksum is None:  # save_json always writes one: its absence is damage, not an old format
        raise CorruptArtifactError(f"{path}: no checksum (edited or damaged)")
    if checksum != _json_digest(data):
        raise CorruptArtifactError(f"{path}: checksum mismatch (edited or damaged)")
    return data


def atomic_write_text(path: str | os.PathLike, text: str) -> None:
    """Write a text file (tables, markdown) atomically."""
    _atomic_write(path, lambda fh: fh.write(text.encode()))


def atomic_write_bytes(path: str | os.PathLike, data: bytes) -> None:
    """Write a binary file (figures) atomically."""
    _atomic_write(path, lambda fh: fh.write(data))


def atomic_write_csv(frame, path: str | os.PathLike) -> None:
    """Write a DataFrame as CSV atomically (no index; floats round-trip, shortest repr)."""
    atomic_write_text(path, frame.to_csv(index=False, lineterminator="\n"))
