"""The cross-flow terms of swept wings in the 3-D TSD solver (asekit.aero.tsd3d; issue 29,
tsdswept): the modified TSD equation of Batina (1989, J. Aircraft 26(6) 531-538, Eq. 1) with
G = (gamma - 3) M^2 / 2, H = -(gamma - 1) M^2 (Ballhaus, Bailey & Frick 1977)."""

import numpy as np
import pytest

from asekit.aero.tsd3d import (
    Tsd3dGrid,
    TsdPlanform,
    _Operator,
    biconvex_thickness,
    cross_flow_coefficients,
    harmonic_tsd3d,
    steady_tsd3d,
    tsd3d_grid,
)


def _yawed_residual_error(n: int, cross_flow: bool) -> float:
    """Max |R / V - exact| / max |exact| of the discrete operator (residual per cell volume R /
    V) applied to the potential of an infinite yawed wing, phi = f(x - y tan Lambda), f =
    eps sin(a s), against simple sweep theory: in the TSD approximation the flow is that of the
    normal Mach number M cos Lambda, i.e. for phi = f(x - t y), t = tan Lambda,

        sec^2 Lambda [(1 - M^2 cos^2 Lambda) f'' - (gamma + 1) M^2 f' f''] = 0

    (derived from the full-potential expansion; Ballhaus, Bailey & Frick 1977 introduced the
    cross-flow terms so that the TSD equation keeps this property). Without the terms the
    nonlinear part is -(gamma + 1) M^2 f' f'' instead of -(gamma + 1) M^2 sec^2 Lambda f' f'':
    short by the factor cos^2 Lambda (half at 45 deg).
    Interior nodes of a uniform (n x n x 4)-cell grid, M 0.8, Lambda 45 deg, eps 0.05, a = 2
    (subsonic everywhere: A >= 0.2)."""
    mach, gamma, lam = 0.8, 1.4, np.radians(45.0)
    t = np.tan(lam)
    x, y = np.linspace(-2.0, 2.0, n + 1), np.linspace(0.0, 4.0, n + 1)
    grid = Tsd3dGrid(x, y, np.linspace(0.0, 1.0, 5))
    X, Y, _ = np.meshgrid(grid.x, grid.y, grid.z, indexing="ij")
    s, eps, a = X - t * Y, 0.05, 2.0
    phi = eps * np.sin(a * s)
    f1, f2 = eps * a * np.cos(a * s), -eps * a * a * np.sin(a * s)
    exact = (1 + t * t) * ((1 - mach ** 2 * np.cos(lam) ** 2) * f2
                           - (gamma + 1) * mach ** 2 * f1 * f2)
    op = _Operator(grid, mach, gamma, cross_flow)
    mu = op.switches(phi)
    assert mu.sum() == 0
    r = np.zeros(op.shape).ravel()
    r[op.idx] = op.residual(phi, mu, np.zeros(op.shape))
    r = r.reshape(op.shape) / np.where(op.vol > 0, op.vol, 1.0)
    inner = (slice(5, -5), slice(5, -5), slice(1, 3))
    return float(np.max(np.abs(r[inner] - exact[inner])) / np.max(np.abs(exact[inner])))


def test_cross_flow_terms_give_simple_sweep_theory_on_a_yawed_wing():
    """Measured: with the cross-flow terms 0.46 % (n = 40) and 0.11 % (n = 80: second order in
    the cell size); without them 5.8 % and 5.6 % (the equation itself is off, not its
    discretisation). n = 40 and 20 here (a fraction of a second)."""
    with_terms = [_yawed_residual_error(n, True) for n in (20, 40)]
    without = _yawed_residual_error(40, False)
    assert with_terms[1] < 0.006
    assert with_terms[1] < 0.3 * with_terms[0]               # second order: 4x per halving
    assert without > 0.04                                    # the plain TSD misses the sweep


def test_cross_flow_coefficients_and_their_jacobian():
    """G, H as Batina (1989) Eq. 1 with the Ballhaus-Bailey-Frick choice, and the Newton /
    time-linearised Jacobian of the terms against finite differences of the residual (a
    45-deg swept tapered wing's grid, random potential, M 0.9: relative error below 1e-4 at a
    step of 1e-7; measured 2.7e-6)."""
    g, h = cross_flow_coefficients(0.8, 1.4)
    assert g == pytest.approx(-0.8 * 0.64) and h == pytest.approx(-0.4 * 0.64)
    wing = TsdPlanform(np.array([0.0, 1.0]), np.array([0.0, 1.0]), np.array([1.0, 0.7]))
    grid = tsd3d_grid(wing, 8, 4, far=3.0, ratio=1.5, edges="faces")
    op = _Operator(grid, 0.9, 1.4, True)
    rng = np.random.default_rng(0)
    phi = 0.05 * rng.standard_normal(grid.shape)
    mu = op.switches(phi)
    src = np.zeros(grid.shape)
    step = 1e-7 * rng.standard_normal(op.idx.size)
    moved = phi.ravel().copy()
    moved[op.idx] += step
    fd = op.residual(moved.reshape(grid.shape), mu, src) - op.residual(phi, mu, src)
    jac = op.jacobian(phi, mu) @ step
    assert np.max(np.abs(fd - jac)) < 1e-4 * np.max(np.abs(fd))


def test_cross_flow_terms_leave_the_linear_limit_and_an_unswept_mid_span_unchanged():
    """The terms are quadratic in the perturbation: about a zero-thickness background the
    time-linearised problem is exactly the linear one (GAFs equal to round-off, with or
    without the terms); at the mid-span (root plane) of an unswept rectangular wing (6 %
    biconvex, M 0.85, a supersonic pocket) phi_y = 0 on the root and is small nearby, so the
    root Cp barely moves. Measured, max |Cp change| over the peak |Cp|: 0.041 % (semi-span 2
    chords, 12 x 4 cells, 2 supersonic nodes), 0.0069 % (semi-span 4, 12 x 8 cells, 16)."""
    wing = TsdPlanform.rectangular(1.0, 1.0)
    grid = tsd3d_grid(wing, 8, 4, far=4.0, ratio=1.5, edges="faces")
    pitch = [lambda x, y: (-(x - 0.5), -1.0 + 0 * x)]
    phi = [harmonic_tsd3d(steady_tsd3d(wing, biconvex_thickness(0.0), 0.8, grid,
                                       cross_flow=cf), pitch, 0.6).phi for cf in (False, True)]
    assert np.max(np.abs(phi[1] - phi[0])) < 1e-12 * np.max(np.abs(phi[0]))
    long = TsdPlanform.rectangular(1.0, 2.0)
    grid = tsd3d_grid(long, 12, 4, far=6.0, ratio=1.3)
    cp = []
    for cf in (False, True):
        sol = steady_tsd3d(long, biconvex_thickness(0.06), 0.85, grid, cross_flow=cf)
        assert sol.converged and sol.cross_flow == cf and sol.supersonic_points > 0
        cp.append(sol.section_cp(0.0)[1])
    assert np.max(np.abs(cp[1] - cp[0])) < 0.002 * np.max(np.abs(cp[0]))


# --- the swept wing's linear limit against the DLM -------------------------------------------
_CR = 0.5578                                  # m, AGARD 445.6 root chord (Yates 1987)
_SEMI, _XT, _CT = 0.762 / _CR, 0.8094 / _CR, 0.3682 / _CR      # in root chords
_SWEPT_MODES = [lambda x, y: (y * y + 0 * x, 0 * x),                   # bending-like
                lambda x, y: (-(x - (0.25 + y)) * y, -y + 0 * x)]       # torsion-like


def _swept_lift_error(n_chord: int, n_span: int, dlm) -> float:
    from asekit.aero.tsd3d import tsd_gaf

    wing = TsdPlanform(np.array([0.0, _SEMI]), np.array([0.0, _XT]), np.array([1.0, _CT]))
    grid = tsd3d_grid(wing, n_chord, n_span, far=6.0, ratio=1.3, edges="faces")
    bg = steady_tsd3d(wing, biconvex_thickness(0.0), 0.8, grid, cross_flow=True)
    mesh, d = dlm
    q = tsd_gaf(bg, mesh, _SWEPT_MODES, [0.0], 0.5)
    return float(q[0, 0, 1].real / d[0, 0, 1].real - 1.0)


def test_swept_wing_linear_limit_approaches_the_dlm():
    """The AGARD 445.6 planform (45 deg quarter-chord sweep, taper 0.66, root chord 1), zero
    thickness (the cross-flow terms are then inactive), M 0.8, k = 0, a bending-like and a
    torsion-like mode: Q_bending,torsion against the DLM on 12 x 12 boxes (1.5192; 20 x 20:
    1.4728). Measured TSD errors: +30.0 %, +7.1 %, +1.9 % on 8 x 4, 12 x 6, 16 x 8 cells
    (12 x 12: -2.5 %). Before the projection fix of box_pressures (each grid row sampled at
    its own leading- and trailing-edge nodes: the box GAFs now equal the solver's
    circulation, 4 int phi_TE dy, exactly) they were -62.9 %, -34.3 %, -28.5 % (12 x 12:
    -38.6 %): the old projection took the boxes' edges at the boxes' own abscissae, which on
    a swept row fall inside the chord on half the band, and dropped half an edge cell.
    About 4 s."""
    from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
    from asekit.aero.gaf import gaf_from_box_modes
    from asekit.aero.spline import analytic_modes

    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (_XT, _SEMI, 0), _CT, 12, 12)])
    dlm = mesh, gaf_from_box_modes(analytic_modes(mesh, _SWEPT_MODES), mesh, 0.8, [0.0], 0.5,
                                   symmetric=True)
    assert dlm[1][0, 0, 1].real == pytest.approx(1.5192, abs=2e-4)
    e = [_swept_lift_error(n, n // 2, dlm) for n in (8, 12)]
    assert 0.0 < e[1] < 0.5 * e[0] < 0.2, e
    assert e[1] < 0.10, e
