"""Atomic, checked storage of computed arrays (``.npz`` plus a JSON metadata record).

A cache file is written to a temporary name in the same directory and renamed into place, so an
interrupted write never leaves a half-written file; temporary files orphaned by a killed writer
(``<name>.<pid>.*.tmp`` whose process is gone, or any ``<name>.*.tmp`` older than an hour) are
removed by the next :func:`save_npz` / :func:`load_npz` of that path.

The metadata stores a SHA-256 (``"sha256"``, ``"digest_version": 2``) over every array's name,
dtype, shape and bytes *and* over the metadata itself (the caller's fingerprint of the inputs
included), so editing ``b_ref`` or ``n_rigid`` in the metadata, or changing a shape, fails the
check. ``load_npz`` recomputes it and raises :class:`CacheError` -- the signal to rebuild -- for
a missing, unreadable, malformed or mismatching file.

What the digest protects against, and what it does not
------------------------------------------------------
It is an integrity check, not an authentication (there is no secret: anyone who can write the
cache folder can run :func:`save_npz`). It catches

* accidental corruption: a flipped bit, a truncated or half-copied file, a zip member lost;
* an edit by any tool that does not recompute the version-2 digest: an array changed alone
  (``Q`` doubled, ``machs`` reordered), a metadata value changed alone, or an array changed with
  an *array-only* digest recomputed next to the old metadata (version 2 covers both, so the old
  fingerprint no longer matches the new arrays);
* a legacy file (digest version 1: arrays only, the metadata unprotected), refused unless the
  caller asks for it (``allow_legacy=True``; :func:`upgrade_legacy` re-stamps one explicitly);
* together with the caller's checks, a stale cache from other inputs: the caller stores a
  fingerprint of its inputs in the metadata and passes what it expects (``expect_metadata``,
  ``expect_arrays``, ``expect_shapes``); every mismatch is a CacheError.

It does **not** protect against a deliberate, consistent rewrite: arrays changed (``Q`` x 2)
and the file written again through :func:`save_npz` (or the digest recomputed by hand) with the
old fingerprint passes every check and is used as is. Guarding that needs a secret the writer
does not have, which a local cache cannot keep from its own user; the remedy is not to trust a
cache folder others can write, and to rebuild (``pipeline.gaf_database(case, cache=False)``, or
delete the file) when in doubt.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import tempfile
import time
from pathlib import Path

import numpy as np

_log = logging.getLogger(__name__)

DIGEST_VERSION = 2
#: temporary files of a cache path older than this (s) are orphans whatever their pid
ORPHAN_AGE = 3600.0
_DIGEST_KEYS = ("sha256", "digest_version")


class CacheError(RuntimeError):
    """A cache file is missing, corrupt or does not match the requested metadata."""


def _array_digest(h, arrays: dict[str, np.ndarray]) -> None:
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(name.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())


def _digest(arrays: dict[str, np.ndarray], metadata: dict | None = None) -> str:
    """SHA-256 of the arrays (name, dtype, shape, bytes); with ``metadata`` (version 2) also of
    its canonical JSON without the digest keys."""
    h = hashlib.sha256()
    _array_digest(h, arrays)
    if metadata is not None:
        body = {k: v for k, v in metadata.items() if k not in _DIGEST_KEYS}
        h.update(b"\0metadata\0")
        h.update(json.dumps(body, sort_keys=True).encode())
    return h.hexdigest()


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OSError):
        return True
    return True


def clean_orphans(path: str | Path, max_age: float = ORPHAN_AGE) -> list[Path]:
    """Remove temporary files left next to ``path`` by an interrupted :func:`save_npz`:
    ``<name>.<pid>.*.tmp`` whose process no longer exists, and any ``<name>.*.tmp`` older than
    ``max_age`` seconds. Returns the removed paths (unremovable ones are skipped)."""
    path = Path(path)
    removed = []
    if not path.parent.is_dir():
        return removed
    now = time.time()
    for tmp in path.parent.glob(path.name + ".*.tmp"):
        parts = tmp.name[len(path.name) + 1:].split(".")
        try:
            old = now - tmp.stat().st_mtime > max_age
        except OSError:
            continue
        dead = parts[0].isdigit() and not _pid_alive(int(parts[0]))
        if old or dead:
            try:
                tmp.unlink()
                removed.append(tmp)
            except OSError:
                pass
    return removed


def _jsonable(name: str, metadata) -> dict:
    if not isinstance(metadata, dict):
        raise TypeError(f"metadata must be a dict, got {type(metadata).__name__}")
    try:
        text = json.dumps(metadata, sort_keys=True, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"{name} must be JSON-serialisable with finite numbers: {exc}") from exc
    return json.loads(text)


def save_npz(path: str | Path, arrays: dict[str, np.ndarray], metadata: dict) -> Path:
    """Write ``arrays`` and ``metadata`` (JSON-serialisable) atomically to ``path`` (.npz).

    The digest of the arrays and the metadata is added to the metadata under ``"sha256"``
    (with ``"digest_version": 2``). Orphaned temporary files of ``path`` are removed first.
    """
    path = Path(path)
    if not isinstance(arrays, dict) or not arrays:
        raise ValueError("arrays must be a non-empty dict of name -> array")
    if "__metadata__" in arrays:
        raise ValueError("arrays must not contain the reserved name '__metadata__'")
    arrays = {str(k): np.asarray(v) for k, v in arrays.items()}
    for k, v in arrays.items():
        if v.dtype == object:
            raise TypeError(f"arrays[{k!r}] has dtype object: not storable without pickle")
    meta = _jsonable("metadata", metadata)
    for key in _DIGEST_KEYS:
        meta.pop(key, None)
    meta["digest_version"] = DIGEST_VERSION
    meta["sha256"] = _digest(arrays, meta)
    path.parent.mkdir(parents=True, exist_ok=True)
    clean_orphans(path)
    payload = dict(arrays)
    payload["__metadata__"] = np.frombuffer(json.dumps(meta, sort_keys=True).encode(),
                                            dtype=np.uint8)
    fd, tmp = tempfile.mkstemp(prefix=f"{path.name}.{os.getpid()}.", suffix=".tmp",
                               dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as fh:
            np.savez_compressed(fh, **payload)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
    _log.debug("cache written: %s", path)
    return path


def _same(a, b) -> bool:
    """Metadata value equality through JSON (floats compared to 1e-12 relative)."""
    if isinstance(a, bool) or isinstance(b, bool):
        return a is b or a == b and type(a) is type(b)
    if isinstance(a, (int, float)) and isinstance(b, (int, float)):
        return math.isclose(float(a), float(b), rel_tol=1e-12, abs_tol=0.0)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return a == b


def _check_digest(path: Path, arrays: dict, meta: dict, stored: str, allow_legacy: bool) -> None:
    """Raise CacheError unless ``stored`` is the digest of the arrays and metadata (version
    2), or of the arrays alone for a legacy file when ``allow_legacy``."""
    version = meta.get("digest_version")
    if version == DIGEST_VERSION:
        ok = stored == _digest(arrays, meta)
    elif version is None and allow_legacy:
        ok = stored == _digest(arrays)
    elif version is None:
        raise CacheError(f"cache file {path} has a legacy digest version None (arrays only, its "
                         f"metadata unprotected), expected {DIGEST_VERSION}: refused unless "
                         f"allow_legacy=True; rebuild it or re-stamp it with "
                         f"asekit.util.cache.upgrade_legacy")
    else:
        raise CacheError(f"cache file {path} has digest version {version!r}, expected "
                         f"{DIGEST_VERSION}")
    if not ok:
        raise CacheError(f"cache file {path} fails its checksum")


def load_npz(path: str | Path, expect_metadata: dict | None = None,
             expect_arrays: dict | None = None, expect_shapes: dict | None = None,
             allow_legacy: bool = False) -> tuple[dict[str, np.ndarray], dict]:
    """Read a file written by :func:`save_npz`, verify its digest and the caller's expectations.

    Parameters
    ----------
    path : the .npz file.
    expect_metadata : metadata keys whose stored values must equal these (JSON values; floats to
        1e-12 relative), e.g. the fingerprinted settings ``{"b_ref": 0.05, "n_rigid": 1}``.
    expect_arrays : arrays that must be stored with exactly these values (same shape, equal to
        1e-12 relative), e.g. ``{"machs": [0.4, 0.5, 0.6, 0.75], "k": ks}``.
    expect_shapes : ``name -> shape`` with ``None`` for a free axis, e.g.
        ``{"Q": (4, 15, None, None)}``; the array must exist with that number of axes.
    allow_legacy : accept a file with an array-only digest (digest version 1, written before
        version 2, its metadata unprotected). Default False: such a file is a CacheError (the
        rebuild signal) unless the caller asks for it explicitly; :func:`upgrade_legacy`
        re-stamps one with a version-2 digest.

    Raises
    ------
    CacheError
        If the file is missing, unreadable, its metadata malformed, its digest does not match
        (or is a legacy digest and ``allow_legacy`` is False), or an expectation fails (the
        message names the key). What the digest does and does not protect against: the module
        docstring (a consistent rewrite through :func:`save_npz` is *not* detected).
    """
    path = Path(path)
    clean_orphans(path)
    if not path.exists():
        raise CacheError(f"cache file {path} does not exist")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files if k != "__metadata__"}
            raw = data["__metadata__"]
            if raw.dtype != np.uint8 or raw.ndim != 1:
                raise ValueError(f"metadata record has dtype {raw.dtype}, shape {raw.shape}")
            meta = json.loads(bytes(raw).decode())
    except Exception as exc:  # corrupt zip, bad JSON, missing metadata, pickled arrays
        raise CacheError(f"cache file {path} is unreadable: {exc}") from exc
    if not isinstance(meta, dict):
        raise CacheError(f"cache file {path} has malformed metadata (a {type(meta).__name__}, "
                         "not a JSON object)")
    stored = meta.get("sha256")
    if not isinstance(stored, str):
        raise CacheError(f"cache file {path} has no digest in its metadata")
    _check_digest(path, arrays, meta, stored, allow_legacy)
    for key, want in (expect_metadata or {}).items():
        if key not in meta:
            raise CacheError(f"cache file {path}: metadata {key!r} is missing")
        want = json.loads(json.dumps(want))
        if not _same(meta[key], want):
            raise CacheError(f"cache file {path}: metadata {key!r} is {meta[key]!r}, "
                             f"expected {want!r}")
    for key, want in (expect_arrays or {}).items():
        want = np.asarray(want)
        got = arrays.get(key)
        if got is None:
            raise CacheError(f"cache file {path}: array {key!r} is missing")
        if got.shape != want.shape or not np.allclose(got, want, rtol=1e-12, atol=0.0):
            raise CacheError(f"cache file {path}: array {key!r} does not hold the expected "
                             f"values (shape {got.shape}, expected {want.shape})")
    for key, shape in (expect_shapes or {}).items():
        got = arrays.get(key)
        if got is None:
            raise CacheError(f"cache file {path}: array {key!r} is missing")
        if got.ndim != len(shape) or any(s is not None and s != g
                                         for s, g in zip(shape, got.shape)):
            raise CacheError(f"cache file {path}: array {key!r} has shape {got.shape}, "
                             f"expected {tuple(shape)}")
    _log.debug("cache read and verified: %s", path)
    return arrays, meta


def upgrade_legacy(path: str | Path, target: str | Path | None = None) -> Path:
    """Re-stamp a legacy cache file (array-only digest) with a version-2 digest.

    The legacy digest is verified first (a corrupt file is a CacheError), then the same arrays,
    bit for bit, and the same metadata are written through :func:`save_npz` to ``target``
    (default: ``path`` itself, replaced atomically). This is the explicit "I trust this legacy
    file" step: from then on its metadata is covered by the digest too. A file that already has
    a version-2 digest is verified and rewritten unchanged in content.

    Parameters
    ----------
    path : the legacy ``.npz``.
    target : where to write the re-stamped file (default ``path``).

    Returns
    -------
    Path
        The re-stamped file.
    """
    arrays, meta = load_npz(path, allow_legacy=True)
    body = {k: v for k, v in meta.items() if k not in _DIGEST_KEYS}
    return save_npz(Path(path) if target is None else Path(target), arrays, body)
