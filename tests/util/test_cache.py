"""Caches that cannot lie (issue 11): the digest covers metadata and shapes; a consistently
rewritten file is refused by the caller's expectations; malformed metadata is a CacheError (the
rebuild signal), never a crash; orphaned temporary files are cleaned."""

import json
import os
import time

import numpy as np
import pytest

from asekit.util.cache import CacheError, _digest, clean_orphans, load_npz, save_npz
from asekit.util.paths import DATA_DIR

MACHS = np.array([0.4, 0.5, 0.6, 0.75])
K = np.array([0.001, 0.1, 1.0])


def _db(tmp_path, **meta):
    rng = np.random.default_rng(0)
    Q = rng.normal(size=(4, 3, 2, 2)) + 1j * rng.normal(size=(4, 3, 2, 2))
    p = save_npz(tmp_path / "db.npz", {"machs": MACHS, "k": K, "Q": Q},
                 {"b_ref": 0.05, "n_rigid": 1, **meta})
    return p, Q


def _rewrite(path, arrays, meta):
    """Write an npz exactly as save_npz's layout but with arbitrary metadata (no new digest)."""
    payload = dict(arrays)
    payload["__metadata__"] = np.frombuffer(json.dumps(meta).encode(), dtype=np.uint8)
    with open(path, "wb") as fh:
        np.savez_compressed(fh, **payload)


def test_round_trip_and_expectations(tmp_path):
    p, Q = _db(tmp_path)
    arrays, meta = load_npz(p, expect_metadata={"b_ref": 0.05, "n_rigid": 1},
                            expect_arrays={"machs": MACHS, "k": K},
                            expect_shapes={"Q": (4, 3, None, None)})
    np.testing.assert_array_equal(arrays["Q"], Q)
    assert meta["b_ref"] == 0.05 and meta["digest_version"] == 2


def test_metadata_tampering_fails_the_digest(tmp_path):
    p, _ = _db(tmp_path)
    arrays, meta = load_npz(p)
    for key, value in (("b_ref", 0.06), ("n_rigid", 0)):
        bad = dict(meta, **{key: value})
        _rewrite(p, arrays, bad)
        with pytest.raises(CacheError, match="checksum"):
            load_npz(p)


def test_consistent_rewrite_refused_by_expectations(tmp_path):
    """Reordered machs with the digest recomputed (the issue's attack: Q_cc 5.61e-4 for 5.83e-4)
    pass any digest; the caller's expected values catch it."""
    p, Q = _db(tmp_path)
    order = [3, 2, 1, 0]
    save_npz(p, {"machs": MACHS[order], "k": K, "Q": Q[order]}, {"b_ref": 0.05, "n_rigid": 1})
    load_npz(p)                                                 # digest is consistent
    with pytest.raises(CacheError, match="'machs'"):
        load_npz(p, expect_arrays={"machs": MACHS})
    save_npz(p, {"machs": MACHS, "k": K, "Q": Q}, {"b_ref": 0.07, "n_rigid": 1})
    with pytest.raises(CacheError, match="'b_ref'"):
        load_npz(p, expect_metadata={"b_ref": 0.05})
    with pytest.raises(CacheError, match="'n_modes' is missing"):
        load_npz(p, expect_metadata={"n_modes": 2})


def test_wrong_shape_refused(tmp_path):
    p, Q = _db(tmp_path)
    save_npz(p, {"machs": MACHS, "k": K, "Q": Q[:, :2]}, {"b_ref": 0.05})
    with pytest.raises(CacheError, match="shape"):
        load_npz(p, expect_shapes={"Q": (4, 3, None, None)})
    with pytest.raises(CacheError, match="shape"):
        load_npz(p, expect_shapes={"Q": (4, 2, 2)})          # wrong number of axes
    with pytest.raises(CacheError, match="'R' is missing"):
        load_npz(p, expect_shapes={"R": (1,)})


@pytest.mark.parametrize("raw", [b"[1, 2, 3]", b"\xff\xfe", b"{not json", b'{"b_ref": 1}',
                                 b'{"sha256": 5}', b'"text"'])
def test_malformed_metadata_is_a_cache_error(tmp_path, raw):
    p = tmp_path / "bad.npz"
    with open(p, "wb") as fh:
        np.savez(fh, machs=MACHS, __metadata__=np.frombuffer(raw, dtype=np.uint8))
    with pytest.raises(CacheError):
        load_npz(p)


def test_metadata_with_wrong_dtype_or_missing(tmp_path):
    p = tmp_path / "bad.npz"
    with open(p, "wb") as fh:
        np.savez(fh, machs=MACHS, __metadata__=np.arange(5.0))
    with pytest.raises(CacheError):
        load_npz(p)
    with open(p, "wb") as fh:
        np.savez(fh, machs=MACHS)
    with pytest.raises(CacheError, match="unreadable"):
        load_npz(p)
    p.write_bytes(b"PK\x03\x04 truncated")
    with pytest.raises(CacheError, match="unreadable"):
        load_npz(p)


def test_unknown_digest_version_and_legacy(tmp_path):
    p = tmp_path / "legacy.npz"
    arrays = {"machs": MACHS}
    _rewrite(p, arrays, {"b_ref": 0.05, "sha256": _digest(arrays)})      # pre-v2 file
    assert load_npz(p)[1]["b_ref"] == 0.05
    with pytest.raises(CacheError, match="digest version"):
        load_npz(p, allow_legacy=False)
    _rewrite(p, arrays, {"sha256": _digest(arrays), "digest_version": 7})
    with pytest.raises(CacheError, match="digest version"):
        load_npz(p)


def test_shipped_database_still_loads():
    """The committed data/gaf_fin.npz (array-only digest) stays readable, unmodified."""
    path = DATA_DIR / "gaf_fin.npz"
    if not path.exists():
        pytest.skip("no shipped database")
    before = path.stat().st_mtime_ns
    with np.load(path) as raw:
        machs = raw["machs"]
    arrays, meta = load_npz(path, expect_arrays={"machs": machs},
                            expect_shapes={"Q": (machs.size, None, None, None)})
    assert arrays["Q"].shape[2] == arrays["Q"].shape[3] == len(meta["frequencies_hz"])
    assert path.stat().st_mtime_ns == before


def test_orphaned_tmp_files_are_cleaned(tmp_path):
    target = tmp_path / "db.npz"
    dead = tmp_path / "db.npz.999999999.abcd.tmp"             # no such pid
    old = tmp_path / "db.npz.oldstyle.tmp"
    live = tmp_path / f"db.npz.{os.getpid()}.live.tmp"       # a writer still running
    other = tmp_path / "other.npz.999999999.x.tmp"            # another cache's: left alone
    for f in (dead, old, live, other):
        f.write_bytes(b"partial")
    t = time.time() - 7200
    os.utime(old, (t, t))
    _db(tmp_path)
    assert not dead.exists() and not old.exists()
    assert live.exists() and other.exists()
    assert clean_orphans(tmp_path / "missing_dir" / "x.npz") == []
    live.unlink()
    assert load_npz(target)[0]["machs"].size == 4
    assert [f.name for f in tmp_path.glob("db.npz.*.tmp")] == []


def test_save_refuses_unstorable(tmp_path):
    with pytest.raises(ValueError, match="arrays"):
        save_npz(tmp_path / "x.npz", {}, {})
    with pytest.raises(TypeError, match="metadata"):
        save_npz(tmp_path / "x.npz", {"a": np.ones(2)}, [1])
    with pytest.raises(ValueError, match="metadata"):
        save_npz(tmp_path / "x.npz", {"a": np.ones(2)}, {"x": float("nan")})
    with pytest.raises(TypeError, match="object"):
        save_npz(tmp_path / "x.npz", {"a": np.array([None, 1], dtype=object)}, {})
    assert not list(tmp_path.glob("*.tmp"))
