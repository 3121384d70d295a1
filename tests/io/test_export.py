"""Exports: MATLAB .mat state spaces with their signal names, python-control objects of a
case, and OP4 modal / GAF matrices read back by pyNastran's own OP4 reader."""

import os

import control as ct
import numpy as np
import pytest

from asekit.case import load_case
from asekit.case import pipeline as pl
from asekit.io import export
from asekit.io.op4 import read_op4, split_qhhl
from asekit.util.paths import DATA_DIR


@pytest.fixture(scope="module")
def fin():
    return load_case(DATA_DIR / "cases" / "nalci2013_fin.toml")


@pytest.fixture(scope="module")
def systems(fin):
    return export.case_state_spaces(fin)


def test_case_state_spaces_have_named_signals(fin, systems):
    ae = systems["aeroelastic"]
    assert list(ae.input_labels) == ["theta", "theta_dot", "theta_ddot"]
    assert "hinge_moment" in ae.output_labels and "zeta1" in ae.output_labels
    assert {"AEM1", "AEM2"} <= set(systems)
    assert list(systems["AEM1"].input_labels) == ["theta_cmd"]
    # System 3 at M 0.5, sea level is stable (thesis Ch. 5); the PD loop (no integrator)
    # under the de-centering aerodynamic hinge moment tracks a step with a small steady
    # error (1.5 % here), not exactly
    cl = ct.ss(systems["AEM1"])
    i = list(cl.output_labels).index("theta")
    assert np.all(np.linalg.eigvals(cl.A).real < 0)
    assert ct.dcgain(cl)[i] == pytest.approx(1.0, abs=0.05)
    assert ct.dcgain(cl)[i] != pytest.approx(1.0, abs=1e-6)


def test_mat_round_trip_keeps_names_and_matrices(systems, tmp_path):
    p = export.save_mat(tmp_path / "fin.mat", systems, metadata={"case": "nalci2013_fin",
                                                                 "velocity_ms": 170.1})
    back = export.load_mat(p)
    assert back["meta"]["case"] == "nalci2013_fin"
    for name, sys in systems.items():
        s0, s1 = ct.ss(sys), back[name]
        assert list(s1.input_labels) == list(s0.input_labels)
        assert list(s1.output_labels) == list(s0.output_labels)
        assert list(s1.state_labels) == list(s0.state_labels)
        for m in "ABCD":
            np.testing.assert_array_equal(np.asarray(getattr(s1, m)), np.asarray(getattr(s0, m)))
    # scipy's own reader sees a MATLAB struct with cell arrays of char
    import scipy.io
    raw = scipy.io.loadmat(p, squeeze_me=True, struct_as_record=False)
    assert list(raw["aeroelastic"].inputs) == ["theta", "theta_dot", "theta_ddot"]


def test_mat_rejects_bad_names(systems, tmp_path):
    with pytest.raises(ValueError, match="MATLAB identifier"):
        export.save_mat(tmp_path / "x.mat", {"not valid": systems["aeroelastic"]})
    with pytest.raises(TypeError):
        export.save_mat(tmp_path / "x.mat", {"a": np.eye(2)})


def test_op4_modal_and_gaf_read_by_pynastran(fin, tmp_path):
    if not os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):     # set in .ci/run's Nastran environment
        pytest.importorskip("pyNastran")
    from pyNastran.op4.op4 import read_op4 as pyn_read_op4
    model = pl.modal_model(fin)
    db = pl.gaf_database(fin, progress=False)
    p1 = export.write_modal_op4(tmp_path / "modal.op4", model)
    p2 = export.write_gaf_op4(tmp_path / "gaf.op4", db, fin.aero.machs[1])
    theirs = pyn_read_op4(str(p1))
    for name, ref in (("MHH", model.M), ("KHH", model.K), ("BHH", model.C)):
        np.testing.assert_allclose(np.asarray(theirs[name].data), ref, rtol=1e-8,
                                   atol=1e-8 * np.abs(ref).max() + 1e-300)
    q = pyn_read_op4(str(p2))
    qhhl = np.asarray(q["QHHL"].data)
    Q = split_qhhl(qhhl, db.k.size)
    ref = db.Q[1]
    np.testing.assert_allclose(Q, ref, rtol=1e-8, atol=1e-8 * np.abs(ref).max())
    np.testing.assert_allclose(np.asarray(q["KLIST"].data).ravel(), db.k, rtol=1e-9)
    # and asekit's reader agrees with pyNastran's
    ours = read_op4(p2)
    np.testing.assert_allclose(np.asarray(ours["QHHL"].data if hasattr(ours["QHHL"], "data")
                                          else ours["QHHL"]), qhhl, rtol=1e-12)


# ---- issue 22: a damaged .mat file is a named error ---------------------------------------------
def _damage(raw: bytes, kind: str) -> bytes:
    raw = bytearray(raw)
    if kind == "truncated":
        return bytes(raw[:len(raw) * 2 // 3])
    if kind == "flipped":                       # corrupts the zlib stream of the struct
        for i in range(200, len(raw), 7):
            raw[i] ^= 0x5A
        return bytes(raw)
    if kind == "header only":
        return bytes(raw[:128])
    if kind == "empty":
        return b""
    return b"not a MATLAB file\n" * 20


@pytest.mark.parametrize("kind", ["truncated", "flipped", "header only", "empty", "text"])
def test_load_mat_damaged_file_names_the_file(tmp_path, kind):
    """Issue 22's reproducer: load_mat on a damaged file raised scipy's MatReadError, OSError
    ("could not read bytes") or zlib.error; now MatFileError (a ValueError) naming the file."""
    p = export.save_mat(tmp_path / "fin.mat", {"g": ct.ss([[-1.0]], [[1.0]], [[1.0]], [[0.0]])})
    p.write_bytes(_damage(p.read_bytes(), kind))
    with pytest.raises(export.MatFileError, match=r"^fin\.mat "):
        export.load_mat(p)
    assert issubclass(export.MatFileError, ValueError)


def test_load_mat_missing_file_and_directory(tmp_path):
    with pytest.raises(FileNotFoundError, match="no such .mat file"):
        export.load_mat(tmp_path / "none.mat")
    with pytest.raises(export.MatFileError, match="is not a file"):
        export.load_mat(tmp_path)


def test_load_mat_round_trip_still_reads(tmp_path):
    g = ct.ss([[-2.0]], [[1.0]], [[3.0]], [[0.5]], inputs=["u"], outputs=["y"], states=["x"])
    back = export.load_mat(export.save_mat(tmp_path / "g.mat", {"g": g}))["g"]
    np.testing.assert_array_equal(back.A, g.A) and np.testing.assert_array_equal(back.D, g.D)
    assert back.input_labels == ["u"] and back.state_labels == ["x"]
