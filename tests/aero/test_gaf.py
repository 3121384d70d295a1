"""Splines, generalised aerodynamic forces and the fin's GAF database (asekit.aero.spline/gaf)."""

import math
import shutil

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import (
    GAF_FILE,
    cached_gaf_database,
    gaf_from_box_modes,
    gaf_matrix,
    steady_hinge_coefficient,
)
from asekit.aero.spline import InfinitePlateSpline, analytic_modes, fe_spline, normalwash
from asekit.case import pipeline

B = 0.078          # reference semi-chord of the fin (root semi-chord), m
X_AXIS = 0.078     # shaft axis, m


@pytest.fixture(scope="module")
def fin_db(fin_gafs, fin_modal):
    """(GafDatabase, ModalModel) of the fin (tests/conftest.py, via the case pipeline)."""
    return fin_gafs, fin_modal


def _plunge_pitch(mesh):
    return analytic_modes(mesh, [lambda x, y: (np.ones_like(x), np.zeros_like(x)),
                                 lambda x, y: (-(x - X_AXIS), -np.ones_like(x))])


def test_quasi_steady_plunge_equals_pitch_lift(boxes_of):
    # a slow plunge h = 1 is an incidence -i k / b: its lift is -(i k / b) times the pitch lift
    m = boxes_of(8, 6)
    lift_mode = analytic_modes(m, [lambda x, y: (np.ones_like(x), np.zeros_like(x))])
    modes = _plunge_pitch(m)
    k = 1e-4
    q = gaf_from_box_modes(modes, m, 0.6, [k], B)[0]
    # row 0 (generalised force on the plunge mode) is the lift
    assert q[0, 0] / (1j * k / B) == pytest.approx(-q[0, 1].real, rel=1e-3)
    assert q[0, 1].real > 0                       # nose-up pitch: upward lift
    assert lift_mode.h_lp.shape == (m.n, 1)


def test_fe_rigid_mode_equals_analytic_pitch(fin_db, fin_box_mesh):
    db, model = fin_db
    m = fin_box_mesh
    fe = fe_spline(model, m)
    an = _plunge_pitch(m)
    assert np.allclose(fe.h_cp[:, 0], an.h_cp[:, 1], atol=1e-12)
    assert np.allclose(fe.dhdx_cp[:, 0], -1.0, atol=1e-12)
    q_fe = gaf_matrix(model, m, 0.6, 0.001, B)
    q_an = gaf_from_box_modes(an, m, 0.6, [0.001], B)[0]
    assert q_fe[0, 0] == pytest.approx(q_an[1, 1], rel=1e-10)


def test_database_contract(fin_db, fin_case):
    db, model = fin_db
    a = fin_case.aero
    k_max = 2 * math.pi * a.f_max * a.reference_semichord / a.u_min      # 2 pi f_max b / U_min
    assert db.machs.tolist() == [0.4, 0.5, 0.6, 0.75]
    assert db.k[0] == pytest.approx(0.001) and db.k.size >= 12 and np.all(np.diff(db.k) > 0)
    assert db.k[-1] == pytest.approx(k_max) and db.k[-1] == pytest.approx(2.7227, abs=1e-3)
    assert db.Q.shape == (4, db.k.size, model.M.shape[0], model.M.shape[0])
    assert db.Q.dtype == complex and np.all(np.isfinite(db.Q))
    assert db.b_ref == B and db.n_rigid == model.n_rigid == 1
    for key in ("fingerprint", "asekit_version", "symmetric", "boxes", "method", "mode_set"):
        assert key in db.metadata
    assert db.metadata["symmetric"] is False


def test_database_matches_a_fresh_computation(fin_db, fin_box_mesh):
    db, model = fin_db
    m = fin_box_mesh
    for im, ik in ((0, 0), (3, 9), (2, db.k.size - 1)):
        q = gaf_matrix(model, m, db.machs[im], db.k[ik], db.b_ref)
        assert np.allclose(q, db.Q[im, ik], rtol=1e-9, atol=1e-12 * np.abs(q).max())


def test_corrupt_cache_is_rebuilt(tmp_path, fin_db, fin_case, fin_box_mesh):
    db, model = fin_db
    p = tmp_path / "gaf.npz"
    shutil.copy(GAF_FILE, p)
    raw = bytearray(p.read_bytes())
    raw[len(raw) // 2] ^= 0xFF
    p.write_bytes(bytes(raw))
    a = fin_case.aero
    args = (model, fin_box_mesh, a.machs, pipeline.reduced_frequencies(fin_case),
            a.reference_semichord)
    db2 = cached_gaf_database(*args, path=p, progress=False)
    assert np.allclose(db2.Q, db.Q, rtol=1e-9, atol=1e-15)
    db3 = cached_gaf_database(*args, path=p, progress=False)  # now valid: loaded, not rebuilt
    assert db3.metadata["sha256"] == db2.metadata["sha256"]


def test_hinge_moment_physics(fin_db, thesis_table):
    db, _ = fin_db
    qcc = [steady_hinge_coefficient(db, m) for m in db.machs]
    # de-centering (centre of pressure ahead of the mid-root-chord shaft), grows with Mach
    assert all(q > 0 for q in qcc) and np.all(np.diff(qcc) > 0)
    assert abs(db.Q[2, 0, 0, 0].imag) < 0.01 * db.Q[2, 0, 0, 0].real
    # thesis Eq. 4.11: 5.825e-4 m^3 (MSC FlightLoads DLM, mesh not given); our rule-based
    # 140-box mesh gives a value within a few per cent (it converges to about 5.6e-4)
    assert qcc[2] == pytest.approx(thesis_table["aero.Qcc_steady_m3"]["value"], rel=0.05)
    with pytest.raises(ValueError, match="mach"):
        steady_hinge_coefficient(db, 0.55)


def test_wall_at_root_raises_hinge_moment(fin_db, boxes_of):
    _, model = fin_db
    m = boxes_of(8, 6)
    iso = gaf_matrix(model, m, 0.6, 0.001, B)[0, 0].real
    wall = gaf_matrix(model, m, 0.6, 0.001, B, symmetric=True)[0, 0].real
    assert wall > 1.2 * iso


def test_infinite_plate_spline_reproduces_planes_and_conserves_loads(boxes_of):
    rng = np.random.default_rng(1)
    nodes = rng.uniform([0, 0], [0.156, 0.15], size=(30, 2))
    ips = InfinitePlateSpline(nodes)
    m = boxes_of(6, 5)
    g, gx = ips.matrices(m.control_point)
    plane = 0.3 + 2.0 * nodes[:, 0] - 0.7 * nodes[:, 1]
    assert np.allclose(g @ plane, 0.3 + 2.0 * m.control_point[:, 0] - 0.7 * m.control_point[:, 1])
    assert np.allclose(gx @ plane, 2.0)
    # interpolation at the nodes is exact
    g_n, _ = ips.matrices(nodes)
    assert np.allclose(g_n, np.eye(30), atol=1e-8)
    # transposed forces conserve total force and moments (the spline reproduces 1, x, y)
    f = rng.normal(size=m.n)
    gl, _ = ips.matrices(m.load_point)
    fn = gl.T @ f
    assert fn.sum() == pytest.approx(f.sum())
    assert fn @ nodes[:, 0] == pytest.approx(f @ m.load_point[:, 0])
    # the fin's pitch mode through the spline gives the analytic Q_cc
    h = -(nodes[:, 0] - X_AXIS)
    q_ips = gaf_from_box_modes(ips.box_modes(m, h), m, 0.6, [0.001], B)[0, 0, 0]
    q_an = gaf_from_box_modes(_plunge_pitch(m), m, 0.6, [0.001], B)[0, 1, 1]
    assert q_ips == pytest.approx(q_an, rel=1e-8)


def test_bad_input(fin_db, fin_case, boxes_of):
    _, model = fin_db
    m = boxes_of(4, 4)
    with pytest.raises(ValueError, match="k"):
        gaf_matrix(model, m, 0.6, [0.1, 0.2], B)
    with pytest.raises(ValueError, match="k"):
        normalwash(np.ones(3), np.zeros(3), -1.0, B)
    with pytest.raises(ValueError, match="b_ref"):
        normalwash(np.ones(3), np.zeros(3), 0.1, 0.0)
    lifted = mesh_surfaces(TrapezoidSurface((0, 0, 0.01), 0.156, (0.078, 0.15, 0.01), 0.078, 4, 4))
    with pytest.raises(ValueError, match="plane"):
        fe_spline(model, lifted)
    with pytest.raises(ValueError, match="line"):
        InfinitePlateSpline(np.array([[0, 0], [1, 0], [2, 0.0]]))
    assert pipeline.reduced_frequencies(fin_case)[0] == 0.001


# ---- issue 22: TabulatedGaf refuses non-finite and loosely typed tables -----------------------
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf, complex(0, math.inf),
                                 complex(math.nan, 0)])
def test_tabulated_gaf_refuses_non_finite_q_naming_the_entry(bad):
    """Issue 22's reproducer: a NaN/inf in Q was accepted (p-k then ignored it or raised a bare
    LinAlgError). Now refused at construction, naming Q, the entry, its k and its modes."""
    from asekit.aero.gaf import TabulatedGaf
    Q = np.ones((3, 2, 2), complex)
    Q[1, 0, 1] = bad
    with pytest.raises(ValueError, match=r"Q must be finite: Q\[1, 0, 1\] = .* at k = 0\.5, "
                                         r"modes \(0, 1\)"):
        TabulatedGaf(np.array([0.0, 0.5, 1.0]), Q, 1.0)


@pytest.mark.parametrize("kw, word, error", [
    ({"b_ref": "1.0"}, "b_ref must be a real number", ValueError),
    ({"b_ref": math.nan}, "b_ref must be a finite number > 0", ValueError),
    ({"k": np.array([0.0, 0.5, 1.0 + 0.5j])}, r"k must be real numbers.*k\[2\]", TypeError),
    ({"k": ["0", "0.5", "1"]}, "k must be real numbers", ValueError),
    ({"k": np.array([0.0, math.nan, 1.0])}, r"k must be finite, got k\[1\] = nan", ValueError),
    ({"mach": "0.5"}, "mach must be a real number", ValueError),
])
def test_tabulated_gaf_strict_types(kw, word, error):
    from asekit.aero.gaf import TabulatedGaf
    a = {"k": np.array([0.0, 0.5, 1.0]), "Q": np.ones((3, 2, 2), complex), "b_ref": 1.0} | kw
    with pytest.raises(error, match=word):
        TabulatedGaf(**a)


def test_tabulated_gaf_accepts_numpy_reals():
    from asekit.aero.gaf import TabulatedGaf
    g = TabulatedGaf([0, 1], np.ones((2, 1, 1)), np.float32(0.5), mach=np.float64(0.7))
    assert g.b_ref == 0.5 and g.mach == 0.7 and g.Q.dtype == complex and g.k.dtype == float


def test_pk_with_a_nan_gaf_no_longer_reaches_the_solver():
    """Before issue 22, pk_flutter on such a table raised LinAlgError("Array must not contain
    infs or NaNs"); the table is now refused before any flutter computation."""
    from asekit.aero.gaf import TabulatedGaf
    Q = np.ones((3, 2, 2), complex)
    Q[2, 1, 1] = math.nan
    with pytest.raises(ValueError, match=r"Q\[2, 1, 1\]"):
        TabulatedGaf(np.array([0.0, 1.0, 10.0]), Q, 1.0)
