"""Caches that cannot lie (issues 11, 22): the digest covers metadata and shapes; a consistently
rewritten file is refused by the caller's expectations where it can be (a deliberate consistent
rewrite through save_npz is not detected: documented, and asserted below); legacy array-only
digests are refused unless asked for; malformed metadata is a CacheError (the rebuild signal),
never a crash; orphaned temporary files are cleaned."""

import json
import os
import time

import numpy as np
import pytest

from asekit.util.cache import (
    CacheError,
    _digest,
    clean_orphans,
    load_npz,
    save_npz,
    upgrade_legacy,
)
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
    with pytest.raises(CacheError, match="legacy digest version None .* refused unless "
                                         "allow_legacy=True"):
        load_npz(p)                                                     # issue 22: the default
    assert load_npz(p, allow_legacy=True)[1]["b_ref"] == 0.05           # asked for explicitly
    _rewrite(p, arrays, {"sha256": _digest(arrays), "digest_version": 7})
    with pytest.raises(CacheError, match="digest version 7"):
        load_npz(p, allow_legacy=True)


# ---- issue 22: what the digest does and does not protect against -----------------------------
def _shipped():
    """The arrays and metadata (digest keys dropped) of the shipped data/gaf_fin.npz."""
    path = DATA_DIR / "gaf_fin.npz"
    with np.load(path) as raw:
        arrays = {k: raw[k] for k in ("machs", "k", "Q")}
        meta = json.loads(bytes(raw["__metadata__"]).decode())
    return arrays, {k: v for k, v in meta.items() if k not in ("sha256", "digest_version")}


def test_issue22_legacy_rewrite_of_q_is_refused_by_default(tmp_path):
    """Q x 2 with an array-only (legacy) digest recomputed next to the old metadata: accepted
    before issue 22 (allow_legacy=True was the default), refused now."""
    arrays, meta = _shipped()
    bad = dict(arrays, Q=2 * arrays["Q"])
    p = tmp_path / "gaf.npz"
    _rewrite(p, bad, dict(meta, sha256=_digest(bad)))
    with pytest.raises(CacheError, match="legacy digest"):
        load_npz(p)


def test_issue22_array_digest_with_old_fingerprint_fails_the_checksum(tmp_path):
    """Q x 2, an array-only digest recomputed, the version-2 stamp and the old fingerprint kept:
    the version-2 digest binds the arrays to the metadata, so it fails."""
    arrays, meta = _shipped()
    bad = dict(arrays, Q=2 * arrays["Q"])
    p = tmp_path / "gaf.npz"
    _rewrite(p, bad, dict(meta, sha256=_digest(bad), digest_version=2))
    with pytest.raises(CacheError, match="fails its checksum"):
        load_npz(p)
    _rewrite(p, bad, dict(meta, sha256=_digest(arrays, dict(meta, digest_version=2)),
                          digest_version=2))                   # the original file's digest
    with pytest.raises(CacheError, match="fails its checksum"):
        load_npz(p)


def test_issue22_consistent_rewrite_is_not_detected(tmp_path):
    """The documented limit (module docstring of asekit.util.cache): Q x 2 written again through
    save_npz with the old metadata passes every check. The digest is an integrity check, not an
    authentication; if this ever starts failing, update the documentation with it."""
    arrays, meta = _shipped()
    p = save_npz(tmp_path / "gaf.npz", dict(arrays, Q=2 * arrays["Q"]), meta)
    got, _ = load_npz(p, expect_metadata={"fingerprint": meta["fingerprint"]},
                      expect_arrays={"machs": arrays["machs"], "k": arrays["k"]})
    np.testing.assert_array_equal(got["Q"], 2 * arrays["Q"])


def test_upgrade_legacy_keeps_the_numbers_bit_for_bit(tmp_path):
    arrays, meta = _shipped()
    p = tmp_path / "legacy.npz"
    _rewrite(p, arrays, dict(meta, sha256=_digest(arrays)))
    assert upgrade_legacy(p) == p
    got, m = load_npz(p)
    assert m["digest_version"] == 2 and {k: m[k] for k in meta} == meta
    for k, a in arrays.items():
        assert got[k].dtype == a.dtype and got[k].tobytes() == a.tobytes()
    q = tmp_path / "corrupt.npz"                        # a legacy file failing its own digest
    _rewrite(q, dict(arrays, Q=2 * arrays["Q"]), dict(meta, sha256=_digest(arrays)))
    with pytest.raises(CacheError, match="fails its checksum"):
        upgrade_legacy(q)


def test_shipped_database_still_loads():
    """The committed data/gaf_fin.npz (re-stamped with a version-2 digest in issue 22, its
    arrays and metadata unchanged) is readable without allow_legacy, and left unmodified."""
    path = DATA_DIR / "gaf_fin.npz"
    before = path.stat().st_mtime_ns
    with np.load(path) as raw:
        machs = raw["machs"]
    arrays, meta = load_npz(path, expect_arrays={"machs": machs},
                            expect_shapes={"Q": (machs.size, None, None, None)})
    assert meta["digest_version"] == 2
    assert meta["fingerprint"] == ("f412431191d9e1c4cc7167130b0993aae341f65e15a1efe2695093e6e3057"
                                   "a3c")                         # the fin's, as before issue 22
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
