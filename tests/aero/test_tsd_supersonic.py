"""Supersonic free streams of the 3-D TSD (asekit.aero.tsd3d; issue 29, tsdfin): the fin's
envelope runs the TSD from M 0.8 to 1.2, so the linear limit above M 1 is checked against
exact linear supersonic theory and against asekit's Mach-box method."""

import math

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.methods import AERO_METHODS
from asekit.aero.spline import analytic_modes
from asekit.aero.tsd3d import (
    TsdPlanform,
    biconvex_thickness,
    steady_tsd3d,
    tsd3d_grid,
    tsd_gaf,
)

_SEMI, _B = 2.0, 0.5            # semi-span (chords) of the rectangular half wing; b = c / 2
_MODES = [lambda x, y: (1.0 + 0 * x, 0 * x),                 # heave
          lambda x, y: (-(x - 0.5), -1.0 + 0 * x)]           # nose-up pitch about mid-chord


def _exact_lift(mach: float) -> float:
    """Lift per unit dynamic pressure and radian (m^2, chord 1) of the rectangular half wing
    (root on a reflection plane, one tip) in linear supersonic theory: CL_alpha =
    4 / beta (1 - 1 / (2 beta A)) for beta A >= 1, A the full wing's aspect ratio 2 s / c
    (the tip Mach cone carries half the 2-D loading on average; Bisplinghoff, Ashley & Halfman
    1955, Aeroelasticity, Sec. 7-6; Jones & Cohen 1957, High Speed Wing Theory, Sec. 8),
    times the half wing's area s c."""
    beta = math.sqrt(mach ** 2 - 1.0)
    assert beta * 2.0 * _SEMI >= 1.0
    return 4.0 / beta * (1.0 - 1.0 / (4.0 * beta * _SEMI)) * _SEMI


def _tsd(n: int, mach: float, ks, tau: float = 0.0, mesh=None):
    wing = TsdPlanform.rectangular(1.0, _SEMI)
    g = tsd3d_grid(wing, n, n, far=6.0, ratio=1.3, edges="faces")
    bg = steady_tsd3d(wing, biconvex_thickness(tau), mach, g)
    assert bg.converged
    mesh = mesh if mesh is not None else _mesh()
    return bg, tsd_gaf(bg, mesh, _MODES, ks, _B)


def _mesh():
    return mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, _SEMI, 0), 1.0, 12, 24)])


def test_the_registry_allows_the_whole_gap():
    """The TSD's range covers 0.9 < M < 1.15, the gap "auto" refuses, and stops below 1.3."""
    r = AERO_METHODS["tsd"].mach_range
    assert all(r.contains(m) for m in (0.8, 0.95, 1.0, 1.05, 1.15, 1.2))
    assert not r.contains(1.3) and not r.contains(0.0)


def test_supersonic_lift_of_a_rectangular_wing_approaches_linear_theory():
    """Zero thickness, k = 0, M 1.2 (beta 0.663, beta A 2.65): the TSD's Murman-Cole operator is
    upwind at every node (the linear supersonic wave equation, first order). Measured
    Q_heave,pitch (lift per radian): 9.2415, 9.3266, 9.4030 on 8, 12, 16 chordwise cells
    (-5.6 %, -4.7 %, -3.9 % from the exact 9.7877; the first-order upwind scheme's
    dissipation smears the leading-edge load; first-order Richardson 12/16: 9.632, -1.6 %);
    the Mach-box method on 12 x 24 boxes gives 9.8629 (+0.8 %). 8 cells here (1 s); the
    refinement in the slow test below."""
    exact = _exact_lift(1.2)
    _, q = _tsd(8, 1.2, [0.0])
    err = q[0, 0, 1].real / exact - 1.0
    assert -0.07 < err < 0.0
    assert abs(q[0, 0, 1].imag) < 1e-12 and abs(q[0, 0, 0]) < 1e-12   # heave: no steady load


@pytest.mark.slow
def test_supersonic_lift_converges_under_grid_refinement():
    """The error of the test above falls with the cell size (first order) and the
    Richardson-extrapolated lift of 12 and 16 cells lies within 2.5 % of linear theory
    (measured -1.6 %). About 20 s."""
    exact = _exact_lift(1.2)
    q = {n: _tsd(n, 1.2, [0.0])[1][0, 0, 1].real for n in (8, 12, 16)}
    assert abs(q[16] - exact) < abs(q[12] - exact) < abs(q[8] - exact)
    assert abs((16 * q[16] - 12 * q[12]) / 4 / exact - 1.0) < 0.025


@pytest.mark.slow
def test_supersonic_harmonic_gafs_approach_the_mach_box_method():
    """k = 0.3, M 1.2, zero thickness, 8 x 8 cells against the Mach-box method on 12 x 24
    boxes (reflection plane at the root, asekit.aero.supersonic). Measured max |Q/Q_MB - 1|
    over the four entries: 9.2 % with the time term -2 i kappa M^2 phi_x upwind at the
    supersonic nodes (issue 29, tsdfin), 18 % with it central (as before: one node of
    downstream influence). Every real and imaginary part has the Mach box's sign.
    About 10 s."""
    mesh = _mesh()
    d = gaf_from_box_modes(analytic_modes(mesh, _MODES), mesh, 1.2, [0.3], _B,
                           symmetric=True, method="supersonic")
    _, t = _tsd(8, 1.2, [0.3], mesh=mesh)
    assert np.max(np.abs(t / d - 1.0)) < 0.11
    assert np.all(np.sign(t.real) == np.sign(d.real))
    assert np.all(np.sign(t.imag) == np.sign(d.imag))


def test_linear_supersonic_thickness_pressure_approaches_ackeret():
    """gamma = -1 (the linear equation), 2 % biconvex, M 1.2: at the root of the rectangular
    half wing (outside the tip's Mach cone: 2-D flow) the thickness Cp is Ackeret's
    Cp = 2 (dz/dx) / beta (Ackeret 1925; Liepmann & Roshko 1957, Elements of Gasdynamics,
    Sec. 9.4). Measured max |Cp - Ackeret| / max |Ackeret| on 0 < xi < 1: 24.8 % on 8 cosine
    cells, 15.7 % on 16: the first-order upwind operator lags the pressure by about one cell
    (the 8-cell Cp is Ackeret's shifted aft), converging with the cell size."""
    wing = TsdPlanform.rectangular(1.0, _SEMI)
    err = []
    for n in (8, 16):
        g = tsd3d_grid(wing, n, 4, far=6.0, ratio=1.3, edges="faces")
        sol = steady_tsd3d(wing, biconvex_thickness(0.02), 1.2, g, gamma=-1.0)
        assert sol.converged
        xi, cp = sol.section_cp(0.0)
        ack = 2.0 * 2.0 * 0.02 * (1.0 - 2.0 * xi) / math.sqrt(1.2 ** 2 - 1.0)
        err.append(float(np.max(np.abs(cp - ack)) / np.max(np.abs(ack))))
    assert err[1] < err[0] < 0.3 and err[1] < 0.2


@pytest.mark.parametrize("mach", [pytest.param(1.05, marks=pytest.mark.slow), 1.2])
def test_a_thin_biconvex_background_converges_in_a_supersonic_stream(mach):
    """A 2 % biconvex rectangular wing at M 1.05 and 1.2 converges with
    the cross-flow terms on (25 and 8 steps on 8 x 4 cells, edges between nodes as the lifting
    grids have; on the grid with nodes on the edges M 1.05 stalls at residual 2e-2) and is
    supersonic nearly everywhere on the wing; the leading-edge compression and the aft
    expansion keep Ackeret's sign pattern at the root: Cp > 0 on the front fifth, < 0 behind
    mid-chord (measured at M 1.2: 0.100 at xi 0.06, -0.119 at 0.94; Ackeret +-0.106)."""
    wing = TsdPlanform.rectangular(1.0, _SEMI)
    g = tsd3d_grid(wing, 8, 4, far=6.0, ratio=1.3, edges="faces")
    bg = steady_tsd3d(wing, biconvex_thickness(0.02), mach, g, cross_flow=True)
    assert bg.converged and bg.supersonic_points > 0
    xi, cp = bg.section_cp(0.0)
    assert np.all(cp[xi < 0.2] > 0) and np.all(cp[xi > 0.5] < 0)
