"""Doublet-lattice method (asekit.aero.dlm): Theodorsen limit, VLM continuity, PanelAero."""

import copy

import numpy as np
import pytest
from panelaero_grid import panelaero_grid
from scipy.special import hankel2

from asekit.aero import dlm
from asekit.aero.boxes import BoxMesh, TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import aic_matrix, normalwash_matrices, normalwash_matrix, pressure_jump
from asekit.aero.vlm import vlm_normalwash_matrix


def theodorsen(k):
    """Theodorsen's function C(k) = H1(k) / (H1(k) + i H0(k)) (Hankel functions, 2nd kind)."""
    return hankel2(1, k) / (hankel2(1, k) + 1j * hankel2(0, k))


def _strip_wing(n_chord=12):
    # chord 1 m (b = 0.5 m), semi-span 400 chords with a wall at the root: the root strip is
    # two-dimensional to within about 0.2 % in lift
    return mesh_surfaces([
        TrapezoidSurface((0, 0, 0), 1.0, (0, 2, 0), 1.0, n_chord, 16, "inner"),
        TrapezoidSurface((0, 2, 0), 1.0, (0, 20, 0), 1.0, n_chord, 18, "mid"),
        TrapezoidSurface((0, 20, 0), 1.0, (0, 400, 0), 1.0, n_chord, 19, "outer")])


def test_two_dimensional_limit_is_theodorsen():
    # Theodorsen (NACA Rep. 496, 1935): with h up and alpha nose-up about mid-chord,
    # c_l/(h/b) = pi k^2 - 2 pi i k C(k); c_l/alpha = pi i k + 2 pi C(k) (1 + i k/2);
    # c_m,mid/alpha = pi/2 (-i k/2 + k^2/8) + pi/2 C(k) (1 + i k/2)   (moment over q (2b)^2)
    b = 0.5
    m = _strip_wing()
    ks = np.array([0.05, 0.1, 0.2, 0.5, 1.0])
    d = normalwash_matrices(m, 0.0, ks, b, symmetric=True)
    x, xl = m.control_point[:, 0], m.load_point[:, 0]
    root = m.strip == 0
    for ik, k in enumerate(ks):
        c = theodorsen(k)
        cp_h = np.linalg.solve(d[ik], 1j * k * np.ones(m.n))              # h = b
        cp_a = np.linalg.solve(d[ik], -1.0 + 1j * k * (-(x - 0.5)) / b)  # alpha = 1
        cl_h = np.sum(cp_h[root] * m.chord[root])
        cl_a = np.sum(cp_a[root] * m.chord[root])
        cm_a = np.sum(-(xl[root] - 0.5) * cp_a[root] * m.chord[root])
        ref = (np.pi * k**2 - 2j * np.pi * k * c, 1j * np.pi * k + 2 * np.pi * c * (1 + 0.5j * k),
               np.pi / 2 * (-0.5j * k + k**2 / 8) + np.pi / 2 * c * (1 + 0.5j * k))
        tol = (0.03, 0.03, 0.05) if k > 0.5 else (0.01, 0.01, 0.015)
        for got, want, t in zip((cl_h, cl_a, cm_a), ref, tol):
            assert abs(got) == pytest.approx(abs(want), rel=t), (k, got, want)
            assert abs(np.degrees(np.angle(got / want))) < 1.5, (k, got, want)


def test_theodorsen_error_shrinks_with_chordwise_boxes():
    # pitch lift at k = 1: the error against Theodorsen falls steadily with chordwise refinement
    b, k = 0.5, 1.0
    errs = []
    for nc in (4, 8, 16):
        m = _strip_wing(nc)
        cp = pressure_jump(m, 0.0, k, b, -1.0 + 1j * k * (-(m.control_point[:, 0] - 0.5)) / b,
                           symmetric=True)
        root = m.strip == 0
        cl = np.sum(cp[root] * m.chord[root])
        errs.append(abs(cl / (1j * np.pi * k + 2 * np.pi * theodorsen(k) * (1 + 0.5j * k)) - 1))
    assert errs[2] < 0.6 * errs[1] < 0.6 * 0.6 * errs[0]
    assert errs[2] < 0.025


def _planar():
    return mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0.5, 2, 0.0), 0.6, 6, 8))


def _nonplanar():
    return mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.3, 1, 0.0), 0.8, 5, 4, "wing"),
                          TrapezoidSurface((0.3, 1, 0), 0.8, (0.6, 1.5, 0.5), 0.5, 5, 3, "winglet"),
                          TrapezoidSurface((2.0, 0, 0.3), 0.5, (2.2, 0.8, 0.3), 0.4, 4, 4, "tail")])


@pytest.mark.parametrize("method", ["parabolic", "quartic"])
@pytest.mark.parametrize("mach,k", [(0.0, 0.1), (0.5, 0.5), (0.8, 2.0)])
@pytest.mark.parametrize("geom", ["planar", "nonplanar"])
def test_same_matrix_as_panelaero(method, mach, k, geom):
    # PanelAero (DLR) implements the same [R71]/[R98] kernels independently; on identical boxes
    # the normalwash matrices agree to round-off. PanelAero's k is omega/U (1/m) and its
    # matrices carry the opposite sign (Qjj = -inv(D)).
    from panelaero import DLM, VLM
    b = 0.5
    m = _planar() if geom == "planar" else _nonplanar()
    g = panelaero_grid(m)
    d_pa = VLM.calc_Ajj(copy.deepcopy(g), mach)[0] + DLM.calc_Ajj(copy.deepcopy(g), mach, k / b,
                                                                   method=method)
    d = normalwash_matrix(m, mach, k, b, method)
    assert np.abs(d - d_pa).max() < 1e-11 * np.abs(d).max()


def test_k_to_zero_is_vlm():
    m = _nonplanar()
    d0 = vlm_normalwash_matrix(m, 0.6)
    dk = normalwash_matrices(m, 0.6, [0.0, 1e-6, 1e-3], 0.5)
    assert np.array_equal(dk[0], d0)
    assert np.abs(dk[1] - d0).max() < 1e-5 * np.abs(d0).max()
    assert np.abs(dk[2] - d0).max() < 1e-2 * np.abs(d0).max()
    # and the quasi-steady limit is smooth: the imaginary part grows linearly in k
    ratio = np.abs(dk[2].imag).max() / np.abs(dk[1].imag).max()
    assert ratio == pytest.approx(1e3, rel=0.05)


def test_sweep_equals_single_calls_and_chunking(monkeypatch):
    m = _nonplanar()
    ks = [0.05, 0.7, 2.0]
    sweep = normalwash_matrices(m, 0.7, ks, 0.3, symmetric=True)
    monkeypatch.setattr(dlm, "PAIRS_PER_CHUNK", 37)   # many tiny chunks
    for ik, k in enumerate(ks):
        assert np.allclose(normalwash_matrix(m, 0.7, k, 0.3, symmetric=True), sweep[ik],
                           rtol=0, atol=1e-14 * np.abs(sweep[ik]).max())


@pytest.mark.parametrize("method", ["parabolic", "quartic"])
@pytest.mark.parametrize("case", ["wing", "fin_symmetric", "tiny_chunks_no_table"])
def test_planar_path_equals_pairwise_path(monkeypatch, method, case, boxes_of):
    """All-planar meshes take a faster path (kernel once per distinct station point, weights
    per strip group, Re I1(0) per (y, z) group); it must give the pairwise path's matrix to
    rounding (the 1e-13 bound is ~100x the differences seen)."""
    m = boxes_of(6, 5) if case == "fin_symmetric" else _planar()
    sym = case == "fin_symmetric"
    ks = [0.001, 0.4, 2.5]
    if case == "tiny_chunks_no_table":
        monkeypatch.setattr(dlm, "PLANAR_POINTS_PER_CHUNK", 50)
        monkeypatch.setattr(dlm, "PAIRS_PER_CHUNK", 37)
        monkeypatch.setattr(dlm, "PLANAR_WEIGHT_TABLE_BYTES", 0)
    fast = normalwash_matrices(m, 0.6, ks, 0.5, method, symmetric=sym)
    with monkeypatch.context() as mp:
        mp.setattr(dlm, "_all_planar", lambda *args: False)
        slow = normalwash_matrices(m, 0.6, ks, 0.5, method, symmetric=sym)
    for k, f, s in zip(ks, fast, slow):
        assert np.abs(f - s).max() <= 1e-13 * np.abs(s).max()
        if k > 0.1:      # also relative to the oscillatory increment (tiny at k = 0.001)
            assert np.abs(f - s).max() <= 1e-12 * np.abs(s - slow[0].real).max()


@pytest.mark.parametrize("method", ["parabolic", "quartic"])
@pytest.mark.parametrize("symmetric", [False, True])
def test_plane_blocks_equal_pairwise_path(monkeypatch, method, symmetric):
    """Surfaces in several planes: blocks of coplanar receivers and senders take the planar
    path, the rest the pairwise one; the matrix must be the all-pairwise one to rounding. The
    second surface is a vertical fin; with the symmetry plane the wing and its image share the
    plane z = 0 (separate columns of one block). The symmetric case moves the fin off y = 0 (to
    y = 0.3): a fin in the plane y = 0 coincides with its own image (D singular, cond ~ 1e18)
    and is refused by BoxMesh.mirrored."""
    y_fin = 0.3 if symmetric else 0.0
    m = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0.3, 1.2, 0.0), 0.7, 5, 6, "wing"),
                       TrapezoidSurface((1.3, y_fin, 0.05), 0.8, (1.6, y_fin, 0.9), 0.5, 4, 4,
                                        "fin")])
    # receivers {wing, fin} x sender planes {z = 0, y = y_fin (, y = -y_fin with the image)}
    assert len(dlm._plane_blocks(m, dlm._Senders(m, symmetric))) == (6 if symmetric else 4)
    ks = [0.001, 0.4, 2.5]
    fast = normalwash_matrices(m, 0.6, ks, 0.5, method, symmetric=symmetric)
    with monkeypatch.context() as mp:
        mp.setattr(dlm, "_plane_blocks", lambda *args: None)
        slow = normalwash_matrices(m, 0.6, ks, 0.5, method, symmetric=symmetric)
    for f, s in zip(fast, slow):
        assert np.abs(f - s).max() <= 1e-13 * np.abs(s).max()


@pytest.mark.parametrize("geom", ["planar", "nonplanar"])
def test_symmetry_plane_equals_explicit_image(geom):
    m = _planar() if geom == "planar" else _nonplanar()
    im = m.mirrored()
    full = BoxMesh(np.concatenate([m.corners, im.corners]), np.r_[m.strip, m.strip + 100],
                   np.r_[m.surface, m.surface])
    k, b = 0.8, 0.5
    h = -(m.control_point[:, 0] - 0.3) * m.normal[:, 2]
    w = -m.normal[:, 2] + 1j * k * h / b
    cp_sym = pressure_jump(m, 0.6, k, b, w, symmetric=True)
    cp_full = pressure_jump(full, 0.6, k, b, np.r_[w, w])
    assert np.allclose(cp_sym, cp_full[:m.n], rtol=1e-10, atol=1e-12)


def test_fin_pitch_signs_and_lag(fin_box_mesh):
    # nose-up pitch about the shaft gives upward load; unsteady lift lags (Theodorsen-like)
    m = fin_box_mesh
    x = m.control_point[:, 0]
    b = 0.078
    lifts = []
    for k in (0.001, 0.5):
        cp = pressure_jump(m, 0.6, k, b, -1.0 + 1j * k * (-(x - 0.078)) / b)
        lifts.append(np.sum(cp * m.area))
    assert lifts[0].real > 0 and abs(lifts[0].imag) < 1e-2 * lifts[0].real
    assert abs(lifts[1]) < 2 * abs(lifts[0])


def test_compressibility_raises_steady_lift(boxes_of):
    m = boxes_of(6, 6)
    cl = [np.sum(pressure_jump(m, M, 0.001, 0.078, -np.ones(m.n)) * m.area).real
          for M in (0.0, 0.4, 0.75)]
    assert cl[0] < cl[1] < cl[2]


def test_aic_is_inverse():
    m = _planar()
    a = aic_matrix(m, 0.5, 0.3, 0.5)
    d = normalwash_matrix(m, 0.5, 0.3, 0.5)
    assert np.allclose(a @ d, np.eye(m.n), atol=1e-10)


@pytest.mark.parametrize("kw", [dict(k=-0.1), dict(k=float("nan")), dict(k=float("inf")),
                                dict(mach=1.0), dict(mach=-0.2), dict(b_ref=0.0),
                                dict(method="cubic")])
def test_bad_input(kw):
    args = dict(mach=0.5, k=0.5, b_ref=0.5, method="quartic")
    args.update(kw)
    name = next(iter(kw))
    with pytest.raises(ValueError, match=name):
        normalwash_matrix(_planar(), **args)


def _fin_qcc(mesh, scale, d=None):
    b, k, xa = 0.078 * scale, 0.001, 0.078 * scale
    x, xl = mesh.control_point[:, 0], mesh.load_point[:, 0]
    w = -1.0 + 1j * k * (-(x - xa)) / b
    cp = np.linalg.solve(normalwash_matrix(mesh, 0.6, k, b) if d is None else d, w)
    return np.sum(-(xl - xa) * cp * mesh.area).real


def test_fin_hinge_moment_panelaero_and_scale_invariance():
    # Q_cc of the fin (M 0.6, k 0.001) on the same boxes by PanelAero; and our result is
    # invariant under a change of length unit (Q_cc scales with length^3). PanelAero is compared
    # on the 140-box mesh only: its VLM drops bound vortices whose |r1 x r2| < 1e-5 (an absolute
    # tolerance in m^2), which corrupts meshes of millimetre boxes (e.g. 780 fin boxes: 6.38e-4
    # instead of 5.65e-4 m^3).
    from panelaero import DLM, VLM
    s = lambda f: TrapezoidSurface((0, 0, 0), 0.156 * f, (0.078 * f, 0.15 * f, 0), 0.078 * f,  # noqa
                                   14, 10)
    m1, m10 = mesh_surfaces(s(1.0)), mesh_surfaces(s(10.0))
    q1 = _fin_qcc(m1, 1.0)
    assert _fin_qcc(m10, 10.0) / 1000 == pytest.approx(q1, rel=1e-10)
    g = panelaero_grid(m1)
    d_pa = VLM.calc_Ajj(copy.deepcopy(g), 0.6)[0] + DLM.calc_Ajj(copy.deepcopy(g), 0.6, 0.001 / 0.078,
                                                                  method="quartic")
    assert _fin_qcc(m1, 1.0, d_pa) == pytest.approx(q1, rel=1e-9)


def test_quartic_kernel_better_for_long_boxes_at_high_k():
    # Rodden, Taylor & McIntosh (1998) introduced the quartic numerator because the parabola
    # fails for boxes much wider than long at high k: boxes of aspect ratio 8 (3 strips on a
    # semi-span of 3 chords, 8 boxes per chord), k = 2 and 3, against a 48-strip reference.
    b = 0.5

    def lift(ns, method, k):
        m = mesh_surfaces(TrapezoidSurface((0, 0, 0), 1.0, (0, 3, 0), 1.0, 8, ns))
        x = m.control_point[:, 0]
        cp = pressure_jump(m, 0.5, k, b, -1 + 1j * k * (-(x - 0.25)) / b, method=method,
                           symmetric=True)
        return np.sum(cp * m.area)

    for k in (2.0, 3.0):
        ref = lift(48, "quartic", k)
        err_p = abs(lift(3, "parabolic", k) / ref - 1)
        err_q = abs(lift(3, "quartic", k) / ref - 1)
        assert err_q < 0.5 * err_p
