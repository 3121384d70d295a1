"""Atomic, checked storage of computed arrays (``.npz`` plus a JSON metadata record).

A cache file is written to a temporary name in the same directory and renamed into place, so an
interrupted write never leaves a half-written file. The metadata stores a SHA-256 of every array;
``load_npz`` recomputes it and refuses a file whose contents do not match.
"""

from __future__ import annotations

import hashlib
import json
import os
import tempfile
from pathlib import Path

import numpy as np


class CacheError(RuntimeError):
    """A cache file is missing, corrupt or does not match the requested metadata."""


def _digest(arrays: dict[str, np.ndarray]) -> str:
    h = hashlib.sha256()
    for name in sorted(arrays):
        a = np.ascontiguousarray(arrays[name])
        h.update(name.encode())
        h.update(str(a.dtype).encode())
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    return h.hexdigest()


def save_npz(path: str | Path, arrays: dict[str, np.ndarray], metadata: dict) -> Path:
    """Write ``arrays`` and ``metadata`` (JSON-serialisable) atomically to ``path`` (.npz).

    The digest of the arrays is added to the metadata under ``"sha256"``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    meta = dict(metadata)
    meta["sha256"] = _digest(arrays)
    payload = dict(arrays)
    payload["__metadata__"] = np.frombuffer(json.dumps(meta, sort_keys=True).encode(), dtype=np.uint8)
    fd, tmp = tempfile.mkstemp(prefix=path.name + ".", suffix=".tmp", dir=path.parent)
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
    return path


def load_npz(path: str | Path) -> tuple[dict[str, np.ndarray], dict]:
    """Read a file written by :func:`save_npz` and verify its digest.

    Raises
    ------
    CacheError
        If the file is missing, unreadable or its arrays do not match the stored digest.
    """
    path = Path(path)
    if not path.exists():
        raise CacheError(f"cache file {path} does not exist")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files if k != "__metadata__"}
            meta = json.loads(bytes(data["__metadata__"]).decode())
    except Exception as exc:  # corrupt zip, bad JSON, missing metadata
        raise CacheError(f"cache file {path} is unreadable: {exc}") from exc
    if meta.get("sha256") != _digest(arrays):
        raise CacheError(f"cache file {path} fails its checksum")
    return arrays, meta
