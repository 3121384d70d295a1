"""Supersonic lifting-surface method (asekit.aero.supersonic).

Sources of the reference values:
- Ackeret's 2-D lift slope 4 / sqrt(M^2 - 1) (J. Ackeret, "Luftkraefte auf Fluegel, die mit
  groesserer als Schallgeschwindigkeit bewegt werden", ZFM 16, 1925); the region of a wing
  outside the Mach cones of its tips is exactly two-dimensional in linear theory.
- Rectangular wing, both tips free: C_L,alpha = (4/beta) (1 - 1 / (2 beta A)) for beta A >= 1
  (each tip Mach cone carries half the 2-D loading on average; e.g. Jones & Cohen, *High Speed
  Wing Theory*, Princeton 1960, rectangular wings; Bisplinghoff, Ashley & Halfman,
  *Aeroelasticity*, 1955, Section 7-4).
- Delta wing with supersonic leading edges (beta cot Lambda >= 1): C_L,alpha = 4 / beta
  (Puckett 1946, J. Aeronaut. Sci. 13(9); Jones & Cohen 1960).
- Unsteady 2-D: the exact solution of the oscillating supersonic airfoil in the integral form
  of Garrick & Rubinow (NACA Report 872, 1946), phi(x) = -(1/beta) int_0^x w(xi)
  exp(-i lambda (x - xi)) J0(kappa (x - xi)) d xi, evaluated here independently of the 3-D grid
  by Gauss-Legendre quadrature (the published tables were not at hand: this is the "exact 2-D
  solution computed independently" alternative).
- Piston theory as the high-Mach / high-frequency limit: Lighthill 1953; Ashley & Zartarian 1956.
"""

import math
import warnings

import numpy as np
import pytest
from scipy.special import j0

from asekit.aero.boxes import MeshRuleWarning, TrapezoidSurface, mesh_surfaces
from asekit.aero.piston import piston_pressure_matrices
from asekit.aero.supersonic import (
    cell_potential_integral,
    supersonic_pressure_matrices,
    supersonic_pressure_matrix,
    supersonic_pressures,
)


def _rect(chord, span, n_chord, n_span):
    return mesh_surfaces([TrapezoidSurface((0, 0), chord, (0, span), chord, n_chord, n_span)])


def _lift(mesh, cp, rows=None):
    rows = np.ones(mesh.n, bool) if rows is None else rows
    return np.sum(cp[rows] * mesh.area[rows]) / np.sum(mesh.area[rows])


# ---- the exact steady cell integral -----------------------------------------------------------
def _g(x, a):
    """Antiderivative in X of asin(clip(a / X)) (the steady integral of 1/R over t, times beta),
    continuous at X = |a| (derived by hand: d/dX [X asin(a/X) + a ln(X + sqrt(X^2 - a^2))])."""
    if a == 0:
        return 0.0
    if x <= abs(a):
        return math.copysign(math.pi / 2, a) * x
    return x * math.asin(a / x) + a * math.log((x + math.sqrt(x * x - a * a)) / abs(a))


@pytest.mark.parametrize("xa, xb, t1, t2", [(0.1, 0.3, -0.05, 0.02), (-0.1, 0.2, 0.05, 0.1),
                                            (0.2, 0.5, -0.3, -0.1), (0.0, 0.05, -1.0, 1.0)])
def test_steady_cell_integral_closed_form(xa, xb, t1, t2):
    beta = 1.3
    x0 = max(xa, 0.0)
    exact = (_g(xb, beta * t2) - _g(x0, beta * t2) - _g(xb, beta * t1) + _g(x0, beta * t1)) / beta
    assert cell_potential_integral(xa, xb, t1, t2, beta, 0.0, 0.0).real == pytest.approx(
        exact, rel=1e-10, abs=1e-14)


# ---- 2-D limits -----------------------------------------------------------------------------
@pytest.mark.parametrize("mach", [1.3, 2.0, 3.0])
def test_ackeret_two_dimensional_region(mach):
    """Boxes of a wide rectangular wing outside the tip Mach cones: DeltaCp = 4 alpha / beta
    (to rounding, except the first and the last two boxes, where the force transfer to the
    quarter-chord load points redistributes but conserves the load), and the strip
    lift slope equals 4/beta."""
    beta = math.sqrt(mach**2 - 1)
    chord = 1.0
    span = 2 * chord / beta + 0.8
    n_span = int(round(span / 0.2))
    mesh = _rect(chord, span, 10, n_span)
    cp = supersonic_pressure_matrix(mesh, mach, 0.0, 0.5) @ -np.ones(mesh.n)
    mid = mesh.strip == n_span // 2
    np.testing.assert_allclose(cp[mid][1:-2].real, 4 / beta, rtol=1e-9)
    assert _lift(mesh, cp, mid).real == pytest.approx(4 / beta, rel=1e-9)
    assert np.max(np.abs(cp.imag)) < 1e-12


def _exact_2d(mach, k, b, x_axis):
    """Lift / (q c) and nose-up moment about x_axis / (q c^2) of plunge (h = 1 m) and pitch
    (1 rad) of a 2-D flat plate of chord 2b in supersonic flow, from the Garrick-Rubinow
    integral (module docstring) by nested 200-point Gauss-Legendre quadrature."""
    beta = math.sqrt(mach**2 - 1)
    kb = k / b
    lam, kap = kb * mach**2 / beta**2, kb * mach / beta**2
    c = 2 * b
    g, w = np.polynomial.legendre.leggauss(200)
    x, wx = 0.5 * c * (g + 1), 0.5 * c * w
    xx = x[:, None] * 0.5 * (g[None] + 1)
    ww = x[:, None] * 0.5 * w[None]
    kern = np.exp(-1j * lam * xx) * j0(kap * xx)
    g0, g1 = (kern * ww).sum(1), (kern * xx * ww).sum(1)
    gx = np.exp(-1j * lam * x) * j0(kap * x)
    out = {}
    for name, (w0, w1) in {"h": (1j * kb, 0.0), "a": (-1.0 + 1j * kb * x_axis, -1j * kb)}.items():
        phi = -(w0 * g0 + w1 * (x * g0 - g1)) / beta
        phi_x = -(w0 * gx + w1 * g0) / beta
        cp = 4 * (1j * kb * phi + phi_x)
        out["L" + name] = np.sum(cp * wx) / c
        out["M" + name] = np.sum(cp * -(x - x_axis) * wx) / c**2
    return out


@pytest.mark.parametrize("mach", [1.5, 2.0])
def test_unsteady_two_dimensional_strip(mach):
    """Mid-span strip of a wide wing (outside the tip Mach cones, hence exactly 2-D) against the
    exact 2-D solution: lift and moment of plunge and pitch about the quarter chord at
    k = 0.1, 0.5, 1.0 within 2 % of the largest coefficient of each kind."""
    beta = math.sqrt(mach**2 - 1)
    chord, b = 1.0, 0.5
    span = 2 * chord / beta + 0.4
    n_span = int(round(span / 0.2))
    mesh = _rect(chord, span, 12, n_span)
    ks = [0.1, 0.5, 1.0]
    a = supersonic_pressure_matrices(mesh, mach, ks, b)
    mid = mesh.strip == n_span // 2
    xa = 0.25 * chord
    xc, xl = mesh.control_point[:, 0], mesh.load_point[:, 0]
    ar = mesh.area[mid]
    for ik, k in enumerate(ks):
        kb = k / b
        ex = _exact_2d(mach, k, b, xa)
        got = {}
        for name, w in {"h": 1j * kb * np.ones(mesh.n), "a": -1 - 1j * kb * (xc - xa)}.items():
            cp = a[ik] @ w
            got["L" + name] = np.sum(cp[mid] * ar) / ar.sum()
            got["M" + name] = np.sum(cp[mid] * ar * -(xl[mid] - xa)) / ar.sum() / chord
        for key in ex:
            scale = max(abs(ex["L" + key[1]]), abs(ex["M" + key[1]]))
            assert abs(got[key] - ex[key]) < 0.02 * scale, (mach, k, key, got[key], ex[key])


# ---- 3-D steady -----------------------------------------------------------------------------
@pytest.mark.parametrize("mach, aspect", [(1.5, 3.0), (2.0, 2.0), (3.0, 1.0)])
def test_rectangular_wing_tip_mach_cones(mach, aspect):
    beta = math.sqrt(mach**2 - 1)
    assert beta * aspect >= 1
    mesh = _rect(1.0, aspect, 10, int(round(aspect / 0.125)))
    cla = _lift(mesh, supersonic_pressure_matrix(mesh, mach, 0.0, 0.5) @ -np.ones(mesh.n)).real
    exact = 4 / beta * (1 - 1 / (2 * beta * aspect))
    assert cla == pytest.approx(exact, rel=0.02)


def _half_delta(chord, semispan, n):
    # tip chord 1e-3 c: a delta with a sliver tip (its boxes hold less than 2 % of the area)
    return mesh_surfaces([TrapezoidSurface((0, 0), chord, (chord * (1 - 1e-3), semispan),
                                           chord * 1e-3, n, n)])


def test_delta_wing_supersonic_leading_edges():
    mach, semispan = 2.0, 1.0                 # beta cot(Lambda) = 1.73 >= 1
    mesh = _half_delta(1.0, semispan, 12)
    a = supersonic_pressure_matrix(mesh, mach, 0.0, 0.5, symmetric=True)
    assert _lift(mesh, a @ -np.ones(mesh.n)).real == pytest.approx(4 / math.sqrt(3), rel=0.02)


def test_delta_wing_subsonic_leading_edges_known_error():
    """Diaphragm ahead of a subsonic leading edge (m = beta cot Lambda = 0.56): the lift slope
    against Stewart's conical-flow result 2 pi tan(eps) / E(sqrt(1 - m^2)) (Stewart 1946,
    Q. Appl. Math. 4; E the complete elliptic integral of the second kind). The Mach-box method
    is known to be least accurate at subsonic leading edges; asekit measures +4 % here, and the
    test holds it below 6 % (documented limitation, not the 2 % of supersonic edges)."""
    from scipy.special import ellipe
    mach, semispan = 1.5, 0.5
    m = math.sqrt(mach**2 - 1) * semispan
    mesh = _half_delta(1.0, semispan, 12)
    cp = supersonic_pressures(mesh, mach, [0.0], 0.5, -np.ones((1, mesh.n, 1)), symmetric=True)
    exact = 2 * math.pi * semispan / ellipe(1 - m * m)      # scipy's ellipe takes k^2
    assert abs(_lift(mesh, cp[0, :, 0]).real / exact - 1) < 0.06


def test_symmetric_equals_explicit_image():
    """A wall at y = 0 (symmetric=True) equals meshing the image explicitly."""
    s = TrapezoidSurface((0, 0), 1.0, (0.3, 1.0), 0.6, 6, 5)
    mesh = mesh_surfaces([s])
    img = mesh.mirrored()
    both = mesh_surfaces([s, TrapezoidSurface((0.3, -1.0), 0.6, (0, 0), 1.0, 6, 5)])
    a_sym = supersonic_pressure_matrix(mesh, 2.0, 0.3, 0.5, symmetric=True)
    a_both = supersonic_pressure_matrix(both, 2.0, 0.3, 0.5)
    w = -1 - 0.3j * mesh.control_point[:, 0] / 0.5
    wb = -1 - 0.3j * both.control_point[:, 0] / 0.5
    cp_sym = a_sym @ w
    cp_both = (a_both @ wb)[: mesh.n]
    assert img.n == mesh.n
    np.testing.assert_allclose(_lift(mesh, cp_sym), _lift(mesh, cp_both), rtol=0.02)


# ---- the fin: stability over Mach and the piston limit ------------------------------------------
def test_fin_smooth_over_mach_and_tends_to_piston(fin_box_mesh):
    """On the fin: lift of the rigid pitch mode finite and smooth over M 1.15-5 (the diaphragm
    march stays stable), and the ratio to first-order piston theory tends to 1 as M grows at
    M 2, 3, 5 (steady and k = 0.5): |ratio - 1| falls monotonically, below 8 % at M 5."""
    mesh = fin_box_mesh
    b, xa = 0.078, 0.078
    x = mesh.control_point[:, 0]

    def pitch(k):
        return (-1 - 1j * k * (x - xa) / b)[:, None]

    err = {0.0: [], 0.5: []}
    for mach in (2.0, 3.0, 5.0):
        ks = [0.0, 0.5]
        cp = supersonic_pressures(mesh, mach, ks, b, pitch)
        p = piston_pressure_matrices(mesh, mach, ks, b, warn=False)
        for ik, k in enumerate(ks):
            ratio = np.sum(cp[ik, :, 0] * mesh.area) / np.sum((p[ik] @ pitch(k))[:, 0] * mesh.area)
            err[k].append(abs(ratio - 1))
    for k, e in err.items():
        assert e[0] > e[1] > e[2], (k, e)
        assert e[2] < 0.08
    lifts = []
    for mach in (1.15, 1.3, 1.6, 2.2, 3.0, 4.0):
        cp = supersonic_pressures(mesh, mach, [0.3], b, pitch)[0, :, 0]
        assert np.all(np.isfinite(cp))
        lifts.append(abs(_lift(mesh, cp)))
    assert np.all(np.diff(lifts) < 0)               # lift slope falls with M above M 1.15
    assert max(lifts) < 4 / math.sqrt(1.15**2 - 1)  # below the 2-D value


def test_matrix_and_column_paths_agree():
    mesh = _rect(1.0, 0.8, 6, 4)
    w = np.random.default_rng(1).standard_normal((mesh.n, 2))
    a = supersonic_pressure_matrices(mesh, 1.8, [0.0, 0.7], 0.5)
    cp = supersonic_pressures(mesh, 1.8, [0.0, 0.7], 0.5, lambda k: w)
    for ik in range(2):
        np.testing.assert_allclose(cp[ik], a[ik] @ w, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("mach, symmetric", [(1.2, False), (2.0, False), (3.0, False),
                                             (1.5, True)])
def test_direct_matrix_equals_fft_columns(mach, symmetric, fin_box_mesh):
    """The full matrix (direct summation over the gathered Mach-cone kernel tables, sparse
    transfers) equals the FFT-convolution path applied to the unit columns (the method's
    original implementation) to 1e-12 of the largest entry, at each k: a vectorisation, not a
    change of the result."""
    mesh = fin_box_mesh
    ks = [0.0, 0.5, 1.2]
    a = supersonic_pressure_matrices(mesh, mach, ks, 0.078, symmetric=symmetric, warn=False)
    cols = supersonic_pressures(mesh, mach, ks, 0.078, np.eye(mesh.n)[None].repeat(3, 0),
                                symmetric=symmetric, warn=False)
    for ik in range(len(ks)):
        scale = np.abs(cols[ik]).max()
        assert np.abs(a[ik] - cols[ik]).max() < 1e-12 * scale, (mach, ks[ik])


def test_direct_matrix_equals_fft_columns_with_wake():
    """The same with wake cells (subsonic trailing edge, tan 0.6 > beta 0.5)."""
    mesh = mesh_surfaces([TrapezoidSurface((0, 0), 1.0, (0, 1.0), 1.6, 8, 8)])
    ks = [0.0, 0.4]
    a = supersonic_pressure_matrices(mesh, 1.118, ks, 0.5, symmetric=True, warn=False)
    cols = supersonic_pressures(mesh, 1.118, ks, 0.5, np.eye(mesh.n)[None].repeat(2, 0),
                                symmetric=True, warn=False)
    for ik in range(len(ks)):
        assert np.abs(a[ik] - cols[ik]).max() < 1e-12 * np.abs(cols[ik]).max()


def test_grid_location_equals_brute_force(fin_box_mesh):
    """The grid builder locates cell centres box by box (candidates in each box's bounding
    rectangle); the brute-force test of every centre against every box gives the same owner."""
    from asekit.aero.supersonic import _locate, _locate_grid, mach_grid
    for mesh, sym in ((fin_box_mesh, False), (_half_delta(1.0, 0.5, 12), True)):
        for mach in (1.2, 3.0):
            g = mach_grid(mesh, mach, 0.5, 0.078, sym, max_cells=20000)
            corners = np.concatenate([mesh.corners, mesh.mirrored().corners]) if sym else \
                mesh.corners
            ii, jj = np.meshgrid(np.arange(g.nx), np.arange(g.ny), indexing="ij")
            cen = np.column_stack([g.x0 + (ii.ravel() + 0.5) * g.dx,
                                   g.y0 + (jj.ravel() + 0.5) * g.dy])
            np.testing.assert_array_equal(_locate_grid(corners, g.x0, g.y0, g.dx, g.dy, g.nx,
                                                       g.ny), _locate(corners, cen))


def test_grid_converges_on_the_fin(fin_box_mesh):
    """Re Q_cc of the fin's rigid pitch at M 2 (steady): default grid within 2 % of a grid with
    twice as many cells per box chord (diaphragm march stable as the grid is refined)."""
    mesh = fin_box_mesh
    b = xa = 0.078
    xl = mesh.load_point[:, 0]
    qcc = []
    for cpb in (1.5, 3.0):
        cp = supersonic_pressures(mesh, 2.0, [0.0], b, -np.ones((1, mesh.n, 1)),
                                  cells_per_box=cpb, max_cells=20000)[0, :, 0]
        qcc.append(float(np.sum(-(xl - xa) * cp * mesh.area).real))
    assert qcc[0] < 0 and qcc[0] == pytest.approx(qcc[1], rel=0.02)


# ---- bad input --------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, match", [
    ({"mach": 1.0}, "mach"), ({"mach": 0.7}, "mach"), ({"mach": float("inf")}, "mach"),
    ({"mach": float("nan")}, "mach"), ({"k": [0.1, -0.1]}, "k must"),
    ({"k": -0.5}, "k must"), ({"k": float("nan")}, "k must"), ({"b_ref": -1.0}, "b_ref"),
])
def test_bad_arguments(kwargs, match):
    args = {"mach": 2.0, "k": 0.1, "b_ref": 0.5}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        supersonic_pressure_matrices(_rect(1.0, 1.0, 4, 4), **args)


@pytest.mark.parametrize("mach", [1.077, 1.118])
def test_subsonic_trailing_edge_flow_reversal(mach):
    """Subsonic trailing edge (wake cells with DeltaCp = 0). The flow-reversal theorem of
    linearised supersonic flow (Ursell & Ward 1950, Q. J. Mech. Appl. Math. 3; Brown 1950,
    NACA TN 1944; Jones & Cohen 1960): a flat wing at incidence has the same lift in forward
    and in reversed flow. Wing A: unswept (supersonic) leading edge, trailing edge swept back
    with tan 0.6 > beta (subsonic; beta = 0.40 and 0.50); wing B, A reversed: a forward-swept
    subsonic leading edge (diaphragm) and an unswept trailing edge. Wall at the root, 20 x 20
    boxes. asekit: 2.2 % (M 1.077) and 1.2 % (M 1.118) apart, within 3 %; leaving the wake
    out (the method before the wake condition) gives A 19 % and 10 % below B."""
    a = mesh_surfaces([TrapezoidSurface((0, 0), 1.0, (0, 1.0), 1.6, 20, 20)])
    b = mesh_surfaces([TrapezoidSurface((0.6, 0), 1.0, (0, 1.0), 1.6, 20, 20)])
    from asekit.aero.supersonic import has_subsonic_trailing_edge
    assert has_subsonic_trailing_edge(a, mach) and not has_subsonic_trailing_edge(b, mach)
    lifts = []
    for mesh in (a, b):
        cp = supersonic_pressures(mesh, mach, [0.0], 0.5, -np.ones((1, mesh.n, 1)),
                                  symmetric=True, warn=False, max_cells=40000)[0, :, 0]
        lifts.append(_lift(mesh, cp).real)
    assert lifts[0] == pytest.approx(lifts[1], rel=0.03)


def test_bad_meshes():
    tilted = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 1.0, 0.5), 1.0, 4, 4)])
    with pytest.raises(ValueError, match="planar"):
        supersonic_pressure_matrix(tilted, 2.0, 0.0, 0.5)
    with pytest.raises(ValueError, match="max_cells"):
        supersonic_pressure_matrix(_rect(1.0, 1.0, 4, 4), 2.0, 0.0, 0.5, cells_per_box=40,
                                   max_cells=500)


def test_grid_too_coarse_for_small_boxes():
    """Strips of unequal width, some much narrower than a Mach box (dy = dx / beta): after
    refining the grid 1.5x three times the narrow boxes still hold no cell centre, and the
    error names cells_per_box (no silent loss of their area)."""
    from asekit.aero.supersonic import GridTooCoarseError
    mesh = mesh_surfaces([TrapezoidSurface((0, 0), 1.0, (0, 1.0), 1.0, 4, 2),
                          TrapezoidSurface((0, 1.0), 1.0, (0, 1.08), 1.0, 4, 8)])
    with pytest.raises(GridTooCoarseError, match="cells_per_box"):
        supersonic_pressure_matrix(mesh, 2.0, 0.0, 0.5)


def test_bad_normalwash():
    mesh = _rect(1.0, 1.0, 4, 4)
    with pytest.raises(ValueError, match="normalwash"):
        supersonic_pressures(mesh, 2.0, [0.1], 0.5, np.ones((1, mesh.n + 1, 1)))
    with pytest.raises(ValueError, match="normalwash"):
        supersonic_pressures(mesh, 2.0, [0.1], 0.5, np.full((1, mesh.n, 1), np.nan))


def test_coarse_mesh_warning():
    """Boxes per kernel wavelength 2 pi b (M-1)/(k M): warn naming Mach and k."""
    mesh = _rect(1.0, 1.0, 4, 4)
    with pytest.warns(MeshRuleWarning, match=r"mach=1\.2, k=2.*use box chords below [0-9.]+ m "
                                             r"\(a case file: more chordwise boxes in aero\.boxes"):
        supersonic_pressure_matrices(mesh, 1.2, [0.0, 2.0], 0.5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        supersonic_pressure_matrices(mesh, 2.0, [0.0, 0.2], 0.5)


# ---- method dispatch and the GAF hook ---------------------------------------------------------
def test_dispatcher_and_transonic_gap():
    from asekit.aero.methods import TransonicGapError, TransonicWarning, resolve_method
    assert resolve_method("auto", 0.6) == "dlm"
    assert resolve_method("auto", 0.9) == "dlm"
    assert resolve_method("auto", 1.15) == "supersonic"
    assert resolve_method("quartic", 0.5) == "dlm"
    for m in (0.95, 1.0, 1.1):
        with pytest.raises(TransonicGapError, match="transonic gap.*linear potential theory"):
            resolve_method("auto", m)
    with pytest.raises(ValueError, match="mach must be < 1 for the DLM"):
        resolve_method("dlm", 1.2)
    with pytest.raises(ValueError, match="mach must be > 1"):
        resolve_method("supersonic", 0.8)
    with pytest.raises(ValueError, match="mach must be > 1"):
        resolve_method("piston", 1.0)
    with pytest.raises(ValueError, match="method must be one of"):
        resolve_method("zona51", 2.0)
    with pytest.warns(TransonicWarning, match="mach=1.1.*overpredicts the flutter speed"):
        resolve_method("supersonic", 1.1)
    with pytest.warns(TransonicWarning, match="mach=1.141"):
        resolve_method("piston", 1.141)
    with pytest.raises(TransonicGapError, match="mach=1.072"):
        resolve_method("auto", 1.072)


def test_gaf_hook_any_method():
    """The GAF builder takes method=: 'dlm' equals the default DLM, 'auto' at M 2 equals the
    supersonic matrices projected by hand, and 'auto' across the gap is refused."""
    from asekit.aero.gaf import build_gaf_database, gaf_from_box_modes
    from asekit.aero.methods import TransonicGapError
    from asekit.aero.spline import analytic_modes
    mesh = _rect(0.2, 0.3, 6, 4)
    modes = analytic_modes(mesh, [lambda x, y: (1 + 0 * x, 0 * x),
                                  lambda x, y: (-(x - 0.05), -1 + 0 * x)])
    ks, b = [0.01, 0.3], 0.1
    np.testing.assert_allclose(gaf_from_box_modes(modes, mesh, 0.6, ks, b, method="dlm"),
                               gaf_from_box_modes(modes, mesh, 0.6, ks, b), rtol=1e-12)
    q = gaf_from_box_modes(modes, mesh, 2.0, ks, b, method="auto")
    a = supersonic_pressure_matrices(mesh, 2.0, ks, b)
    for ik, k in enumerate(ks):
        cp = a[ik] @ modes.normalwash(k, b)
        np.testing.assert_allclose(q[ik], modes.h_lp.T @ (mesh.area[:, None] * cp), rtol=1e-12)
    assert q[0, 1, 1].real < 0          # pitch about the quarter chord: nose-down moment at M 2
    db = build_gaf_database(modes, mesh, [0.6, 2.0], ks, b, 1, method="auto", progress=False)
    assert db.Q.shape == (2, 2, 2, 2) and np.all(np.isfinite(db.Q))
    with pytest.raises(TransonicGapError):
        build_gaf_database(modes, mesh, [0.6, 1.0], ks, b, 1, method="auto", progress=False)


# ---- AGARD 445.6 weakened wing 3 at its supersonic test Mach numbers ----------------------------
# Yates (1987), AGARD R-765 / NASA TM-100492. The wing and the M 0.499 mass ratio and density
# (mu 33.465 at 0.4278 kg/m^3, so m / V = 14.316 kg/m^3 in Yates's mu = m / (rho V)) are those
# of data/cases/agard445_6.toml and tests/case/test_case.py. The experimental flutter speed indices
# and frequency ratios of the M 1.072 and M 1.141 points (and their test densities) could NOT
# be retrieved and verified from a source when these tests were written, so no test compares
# with them: the tests below check what the comparison rests on (the method refuses / warns as
# it should, the result is insensitive to the unknown test density at M 1.141, the Mach-box
# grid is converged, piston theory is out of its range); the numbers are in the notebook
# bring_your_own_surface.ipynb and the branch report.
AGARD_SS = None


def _agard_mu(rho):
    return 33.465 * 0.4278 / rho          # Yates's mass ratio at density rho (header above)


def _agard_fsi(result):
    """(FSI, omega_f / omega_alpha) of a p-k result of the AGARD case: b_s 0.2789 m,
    f_alpha 38.10 Hz (the measured first torsion, Yates 1987)."""
    f = result.flutter
    w_a = 2 * math.pi * 38.10
    return (f.speed / (0.2789 * w_a * math.sqrt(_agard_mu(result.condition.density))),
            f.frequency_hz / 38.10)


@pytest.fixture(scope="module")
def agard_supersonic():
    from asekit.aero.methods import TransonicWarning
    from asekit.case import load_case
    from asekit.case import pipeline as P
    from asekit.util.paths import CASES_DIR
    with pytest.warns(TransonicWarning, match="overpredicts the flutter speed"):
        case = load_case(CASES_DIR / "agard445_6_supersonic.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", TransonicWarning)
        fa = P.flutter(case, db=P.gaf_database(case, progress=False, cache=False))
    return case, fa


def test_agard445_6_supersonic_method_choice():
    """"auto" refuses M 1.072 and 1.141 (transonic gap) with the reason; the case file chooses
    the Mach boxes explicitly and gets a warning; the wing's leading and trailing edges are
    subsonic at both Mach numbers (so diaphragm and wake are solved)."""
    import tomllib

    from asekit.aero.supersonic import has_subsonic_trailing_edge
    from asekit.case import CaseError, case_from_dict
    from asekit.case import pipeline as P
    from asekit.util.paths import CASES_DIR
    d = tomllib.loads((CASES_DIR / "agard445_6_supersonic.toml").read_text())
    d["aero"]["method"] = "auto"
    with pytest.raises(CaseError, match=r"aero\.machs\[0\] = 1\.072.*transonic gap"):
        case_from_dict(d)
    d["aero"]["method"] = "supersonic"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        mesh = P.box_mesh(case_from_dict(d))
    tan_le = 0.8094 / 0.762
    for mach in (1.072, 1.141):
        beta = math.sqrt(mach**2 - 1)
        assert beta / tan_le < 1                                  # subsonic leading edge
        assert has_subsonic_trailing_edge(mesh, mach)             # and trailing edge


def test_agard445_6_supersonic_flutter(agard_supersonic):
    """p-k with the Mach-box GAFs at M 1.072 and 1.141, densities 0.05-0.2 kg/m^3 (mu 286-72):
    bending-torsion flutter (first mode) everywhere, none at the first point of the sweep; at
    M 1.141 the flutter speed index varies by less than 5 % over the densities (asekit 2.9 %),
    so the comparison with the test is insensitive to the test density; at M 1.072, nearer the
    gap, by 10 %. Linear theory gives the lower index at M 1.072 (0.33-0.37) than at M 1.141
    (0.45-0.46)."""
    case, fa = agard_supersonic
    fsi = {1.072: [], 1.141: []}
    for r in fa.results:
        assert r.flutter is not None and r.flutter.mode == 0 and not r.unstable_at_start
        fsi[r.mach].append(_agard_fsi(r))
    f1141 = np.array(fsi[1.141])
    assert np.ptp(f1141[:, 0]) < 0.05 * f1141[:, 0].mean()
    assert np.ptp(f1141[:, 1]) < 0.05 * f1141[:, 1].mean()
    assert max(v[0] for v in fsi[1.072]) < f1141[:, 0].min()


def test_agard445_6_supersonic_against_the_experiment(agard_supersonic):
    """The two supersonic test points of the weakened wing against the experiment.

    Reference: E. C. Yates Jr., "AGARD standard aeroelastic configurations for dynamic response
    I - wing 445.6", NASA TM-100492 (1987), appendix = NASA TN D-1616, Table II "Flutter data
    measured in air", p. 49, 2.5-ft weakened model 3 (read from the scanned table; the report's
    PDF is in the public GitHub repository eem2314/bib, flutter/yates1987agard.pdf):
      M 1.072: rho 0.000107 slug/ft^3, mu 259.590, omega 86.7 rad/s, omega_alpha 239.3 rad/s,
               V 1131.0 ft/s, V / (b_s omega_alpha sqrt(mu)) = 0.3201;
      M 1.141: rho 0.000152 slug/ft^3, mu 182.740, omega 109.9 rad/s, V 1195.3 ft/s, 0.4031.
    (The same table gives M 0.499: 0.000830 slug/ft^3, mu 33.465, 0.4459, the values of
    agard445_6.toml.) asekit, Mach boxes, default grid, at the test densities: M 1.141 index
    +11.6 %, frequency ratio +9.7 % (the grid study adds about 2 %: linear theory over-predicts
    this point by 12-14 %, the issue expected about 10 %); M 1.072 index +3.7 % but frequency
    ratio +11.5 %, and that index moves 2-7 % with the grid (transonic: K = 1.2)."""
    slug_ft3 = 515.3788                                   # kg/m^3 per slug/ft^3
    yates = {1.072: (0.000107 * slug_ft3, 259.590, 0.3201, 86.7 / 239.3),
             1.141: (0.000152 * slug_ft3, 182.740, 0.4031, 109.9 / 239.3)}
    case, fa = agard_supersonic
    err = {}
    for mach, (rho, mu, fsi_t, ratio_t) in yates.items():
        assert _agard_mu(rho) == pytest.approx(mu, rel=2e-4)   # the table's own mass ratio
        (r,) = [r for r in fa.results if r.mach == mach and abs(r.condition.density - rho) < 1e-5]
        fsi, ratio = _agard_fsi(r)
        err[mach] = (fsi / fsi_t - 1, ratio / ratio_t - 1)
    # linear theory over-predicts both the speed and the frequency at M 1.141
    assert 0.0 < err[1.141][0] < 0.15 and 0.0 < err[1.141][1] < 0.15, err
    # M 1.072 (transonic): the index lands close, the frequency ratio does not
    assert abs(err[1.072][0]) < 0.08 and 0.0 < err[1.072][1] < 0.15, err


@pytest.mark.slow
def test_agard445_6_supersonic_mach_box_convergence():
    """Mach-box grid at M 1.141 (density 0.1 kg/m^3): the default grid (1.5 cells per box
    chord, Mach boxes dx = beta dy, box mesh 16 x 16) against 2.25 cells per box chord and a
    24 x 24 box mesh: flutter speed index within 2 % of both (asekit: 1.0 % and 1.1 %; the
    finest grids run, 24 x 24 boxes at 3 cells per box chord and 32 x 32 at 1.5, give 1.9 % and
    2.2 % above the default: FSI 0.452 -> 0.462); the frequency ratio within 1 %. At M 1.072
    the same refinements move the index by 1.7-7 % (0.344 -> 0.350-0.369): not asserted, that
    point lies in the transonic range anyway."""
    import tomllib
    from dataclasses import replace

    from asekit.aero.gaf import build_gaf_database
    from asekit.aero.spline import fe_spline
    from asekit.case import case_from_dict
    from asekit.case import pipeline as P
    from asekit.util.paths import CASES_DIR
    d = tomllib.loads((CASES_DIR / "agard445_6_supersonic.toml").read_text())
    d["aero"]["machs"] = [1.141]
    d["flight"]["densities"] = [0.1]
    out = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        base = case_from_dict(d)
        for boxes, cpb in ((16, 1.5), (16, 2.25), (24, 1.5)):
            # 24 x 24 boxes need more cells than a case file's grid allows (the loader refuses
            # it, naming aero.boxes): the case is built at 16 x 16 and its boxes replaced, the
            # grid's limit raised below (max_cells)
            case = replace(base, aero=replace(base.aero, boxes=((boxes, boxes),)))
            model, mesh = P.modal_model(case), P.box_mesh(case)
            db = build_gaf_database(fe_spline(model, mesh), mesh, [1.141],
                                    case.aero.reduced_frequencies, 0.2789, model.n_rigid,
                                    symmetric=True, method="supersonic", progress=False,
                                    aero_options={"cells_per_box": cpb, "max_cells": 40000})
            out.append(_agard_fsi(P.flutter(case, db=db).results[0]))
    out = np.array(out)
    assert np.all(np.abs(out[1:, 0] / out[0, 0] - 1) < 0.02), out
    assert np.all(np.abs(out[1:, 1] / out[0, 1] - 1) < 0.01), out


def test_agard445_6_piston_theory_out_of_range():
    """Piston theory at M 1.141 is outside its bound (M >= 2 or M k >= 2; here M k ~ 0.1) and
    says so naming Mach and k; its 2-D load 4/M per unit w/U is beta/M = 0.48 of Ackeret's
    4/beta, so it puts the flutter speed far too high: above 1.4x the Mach-box value."""
    import tomllib

    from asekit.aero.methods import TransonicWarning
    from asekit.aero.piston import PistonValidityWarning
    from asekit.case import case_from_dict
    from asekit.case import pipeline as P
    from asekit.util.paths import CASES_DIR
    d = tomllib.loads((CASES_DIR / "agard445_6_supersonic.toml").read_text())
    d["aero"]["machs"] = [1.141]
    d["flight"]["densities"] = [0.1]
    d["flight"]["velocities"] = {"min": 50.0, "max": 2000.0, "step": 5.0}
    res = {}
    for method in ("supersonic", "piston"):
        d["aero"]["method"] = method
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            case = case_from_dict(d)
        if method == "piston":
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", TransonicWarning)
                with pytest.warns(PistonValidityWarning, match=r"mach=1\.141"):
                    db = P.gaf_database(case, progress=False, cache=False)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                db = P.gaf_database(case, progress=False, cache=False)
        r = P.flutter(case, db=db).results[0]
        res[method] = None if r.flutter is None else r.flutter.speed
    assert res["supersonic"] is not None
    assert res["piston"] is None or res["piston"] > 1.4 * res["supersonic"]


def test_aero_method_registry_is_the_one_mach_check():
    """AERO_METHODS holds every method's Mach range; the kernels' own guards (vlm / dlm,
    piston / supersonic), the front door (check_mach, resolve_method), the case schema and the
    GAF builder all give the same range and message; an unknown method lists the known ones."""
    import math

    from asekit.aero import methods as M
    from asekit.aero import validity as V
    from asekit.aero.dlm import check_k as dlm_check_k
    from asekit.aero.piston import check_supersonic_mach
    from asekit.aero.vlm import check_mach as vlm_check_mach
    assert set(M.AERO_METHODS) == {"auto", "dlm", "supersonic", "piston", "tsd"} \
        == set(M.METHODS)
    assert M.AERO_METHODS["dlm"].mach_range is V.SUBSONIC
    assert M.AERO_METHODS["supersonic"].mach_range is M.AERO_METHODS["piston"].mach_range \
        is V.SUPERSONIC
    # the TSD's operator needs its section (a case option): not shared by the sweep
    assert all(s.structure_independent for n, s in M.AERO_METHODS.items() if n != "tsd")
    assert V.SUBSONIC.contains(0.0) and not V.SUBSONIC.contains(1.0)
    assert V.SUPERSONIC.contains(1.0 + 1e-12) and not V.SUPERSONIC.contains(1.0)
    assert not V.SUPERSONIC.contains(math.nan)
    for fn, arg in ((vlm_check_mach, 1.0), (lambda m: M.check_mach(m, "dlm"), 1.0)):
        with pytest.raises(ValueError, match=r"mach must be < 1 for .*\(subsonic: 0 <= M < 1\), "
                                             r"got 1.0"):
            fn(arg)
    with pytest.raises(ValueError, match=r"mach must be >= 0 .*got -0.1"):
        vlm_check_mach(-0.1)
    for fn in (check_supersonic_mach, lambda m: M.check_mach(m, "piston")):
        with pytest.raises(ValueError, match=r"mach must be > 1 for .*\(supersonic: M > 1\)"):
            fn(0.99)
    with pytest.raises(ValueError, match=r"aero.machs\[2\] must be > 1 for method='supersonic'"):
        M.check_mach(0.5, "supersonic", "aero.machs[2]")
    with pytest.raises(ValueError, match=r"method must be one of \['auto', 'dlm', 'supersonic', "
                                         r"'piston', 'tsd', 'quartic', 'parabolic'\], got 'mach_box'"):
        M.check_mach(2.0, "mach_box")
    assert M.check_mach(1.1, "supersonic") == 1.1           # in the gap: no warning at the door
    assert M.method_spec("auto", 0.5).name == "dlm" and M.method_spec("quartic").name == "dlm"
    for bad in (-0.1, math.inf, [[0.1]]):
        with pytest.raises(ValueError, match="k must be finite reduced frequencies >= 0"):
            V.check_k(bad)
    assert dlm_check_k is V.check_k
    np.testing.assert_array_equal(V.check_k(0.5), [0.5])
    from asekit.aero.gaf import build_gaf_database
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 0.2, (0, 0.2, 0), 0.2, 2, 2)])
    with pytest.raises(ValueError, match=r"machs\[1\] must be < 1 for the DLM"):
        build_gaf_database(None, mesh, [0.5, 1.2], [0.0, 0.1], 0.1, 0, progress=False)


# ---- issue 22: an absurd Mach number is refused, not an OverflowError ---------------------------
@pytest.mark.parametrize("mach", [1e300, 1e20])
def test_huge_mach_is_refused_by_the_cell_count(mach):
    """Issue 22: Mach 1e300 raised OverflowError ("cannot convert float infinity to integer")
    in the grid; beta = sqrt(M^2 - 1) makes the Mach boxes ~1/beta wide, so the grid is refused
    by its cell count, naming mach."""
    from asekit.aero.supersonic import supersonic_pressure_matrices
    mesh = _rect(1.0, 1.0, 2, 2)
    with pytest.raises(ValueError, match=r"supersonic grid would need more than .* cells .* "
                                         r"mach must be a physical Mach number"):
        supersonic_pressure_matrices(mesh, mach, [0.1], 0.5)
