"""The 3-D transonic small-disturbance solver (asekit.aero.tsd3d; issue 29, the 3-D step)."""

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface
from asekit.aero.tsd import biconvex, biconvex_linear_cp, steady_tsd, tsd_grid
from asekit.aero.tsd3d import (
    TsdPlanform,
    biconvex_thickness,
    steady_tsd3d,
    thickness_flux,
    tsd3d_grid,
)


def _root_error(sol, tau, mach):
    """Max |Cp - linear 2-D thin-airfoil Cp| on 0.1 < xi < 0.9 of the root (the full wing's
    mid-span) over the peak |Cp|."""
    xi, cp = sol.section_cp(0.0)
    mid = (xi > 0.1) & (xi < 0.9)
    ref = biconvex_linear_cp(tau, mach, xi[mid])
    return float(np.max(np.abs(cp[mid] - ref)) / np.max(np.abs(ref)))


def _linear(semispan, n_chord, n_span, far=6.0):
    wing = TsdPlanform.rectangular(1.0, semispan)
    grid = tsd3d_grid(wing, n_chord=n_chord, n_span=n_span, far=far, ratio=1.3)
    return steady_tsd3d(wing, biconvex_thickness(0.02), 0.5, grid, gamma=-1.0)


def test_linear_limit_at_mid_span_of_a_long_wing_is_the_2d_thin_airfoil_cp():
    """gamma = -1: Eq. (1) is the Prandtl-Glauert equation. At the mid-span of a rectangular
    wing of aspect ratio 8 (semi-span 4 chords, root plane y = 0) the biconvex Cp approaches
    the 2-D thin-airfoil value (Katz & Plotkin Sec. 5.2 with the Prandtl-Glauert rule,
    asekit.aero.tsd.biconvex_linear_cp). Measured on 16 cosine chord cells x 8 span cells
    (55 x 15 x 21 nodes, far 6 chords, 0.9 s): 1.63 % (the finite span relieves the suction
    by a near-uniform 0.0007; 24 x 12 cells: 1.18 %, the slow test below). The linear
    solution is fore-aft symmetric (the flow reversal theorem of linear potential flow),
    which the symmetric grid keeps to round-off."""
    sol = _linear(4.0, 16, 8)
    assert sol.converged and sol.supersonic_points == 0
    assert _root_error(sol, 0.02, 0.5) < 0.025
    _, cp = sol.section_cp(0.0)
    assert np.max(np.abs(cp - cp[::-1])) < 1e-10 * np.max(np.abs(cp))
    # the suction falls toward the tip (3-D relief) and is nearly zero beyond it
    xi, tip = sol.section_cp(4.0)
    assert np.min(tip) > 0.8 * np.min(cp)
    mid = sol.cp[:, np.argmin(np.abs(sol.grid.y - 6.0))]
    assert np.max(np.abs(mid)) < 0.2 * np.max(np.abs(cp))


@pytest.mark.slow
def test_linear_limit_converges_under_grid_refinement():
    """Measured: 1.63 % on 16 x 8 cells, 1.18 % on 24 x 12 (71 x 20 x 25 nodes, 4 s)."""
    e = [_root_error(_linear(4.0, n, n // 2), 0.02, 0.5) for n in (16, 24)]
    assert e[1] < e[0] < 0.025


def test_transonic_mid_span_approaches_the_2d_tsd_solution_as_the_span_grows():
    """6 % biconvex at M 0.85 (K = 0.74): a supersonic pocket on the root section. The 2-D
    solver (asekit.aero.tsd) on the same x-z grid is the infinite-span limit; the 3-D root Cp
    approaches it as the semi-span grows (3-D relief weakens the pocket). Measured on 20 chord
    cells (2 cells per chord of span), on 0.1 < xi < 0.9, max |Cp_3D - Cp_2D| over the 2-D
    peak: semi-span 1 chord 26 % (subcritical: no pocket at all), 2 chords 12 %, 4 chords
    5.2 % (the last 7 s, so only semi-spans 1 and 2 are run here, 2-6 s on the shared
    machine)."""
    tau, mach = 0.06, 0.85
    ref = steady_tsd(biconvex(tau), mach, tsd_grid(n_chord=20, far=6.0, ratio=1.3),
                     max_iter=200)
    assert ref.converged and ref.supersonic_points > 0
    mid = (ref.x_surface > 0.1) & (ref.x_surface < 0.9)
    err = []
    for s in (1.0, 2.0):
        wing = TsdPlanform.rectangular(1.0, s)
        sol = steady_tsd3d(wing, biconvex_thickness(tau), mach,
                           tsd3d_grid(wing, n_chord=20, n_span=int(2 * s), far=6.0, ratio=1.3))
        assert sol.converged and (sol.supersonic_points > 0) == (s > 1.0)
        xi, cp = sol.section_cp(0.0)
        np.testing.assert_allclose(xi, ref.x_surface, atol=1e-12)
        err.append(float(np.max(np.abs(cp[mid] - ref.cp[mid])) / np.max(np.abs(ref.cp))))
        assert np.min(cp) > np.min(ref.cp)           # the 3-D suction peak is weaker
    assert err[1] < 0.7 * err[0]
    assert err[1] < 0.16


def test_thickness_flux_integrates_the_volume_exactly():
    """The bottom-face fluxes sum to int int dz_t/dx dx dy = 0 for a closed section, and the
    fluxes of the first half chord to the section's half-chord ordinate times the span:
    a tapered panel of 4 % biconvex, root chord 2, tip chord 1, semi-span 3, tip between
    grid lines."""
    wing = TsdPlanform(np.array([0.0, 3.0]), np.array([0.0, 0.5]), np.array([2.0, 1.0]))
    g = tsd3d_grid(wing, n_chord=12, n_span=5, far=4.0)
    f = thickness_flux(wing, biconvex_thickness(0.04), g, n_sub=64)
    assert abs(f.sum()) < 1e-12
    # cells ahead of the local mid-chord carry + int_0^{c/2} z_t' dx = z_t(c/2) = 0.02 c
    area_weighted = 0.02 * (2.0 + 1.0) / 2 * 3.0           # int c(y) dy * 0.02
    assert abs(np.clip(f, 0, None).sum() / area_weighted - 1) < 0.05


def test_planform_from_trapezoid_surfaces_and_bad_input():
    s1 = TrapezoidSurface((0, 0, 0), 2.0, (0.5, 1.0, 0), 1.5, 4, 2, "inner")
    s2 = TrapezoidSurface((0.5, 1.0, 0), 1.5, (1.0, 2.0, 0), 1.0, 4, 2, "outer")
    p = TsdPlanform.from_surfaces([s1, s2])
    assert p.y.tolist() == [0.0, 1.0, 2.0] and p.chord.tolist() == [2.0, 1.5, 1.0]
    xl, c = p.edges(np.array([0.5, 2.5]))
    assert xl[0] == pytest.approx(0.25) and c[0] == pytest.approx(1.75) and c[1] == 0.0
    with pytest.raises(ValueError, match="does not continue"):
        TsdPlanform.from_surfaces([s1, TrapezoidSurface((0.4, 1.0, 0), 1.5, (1, 2, 0), 1, 2, 2)])
    with pytest.raises(ValueError, match="chord must be > 0"):
        TsdPlanform(np.array([0.0, 1.0]), np.zeros(2), np.array([1.0, 0.0]))
    with pytest.raises(ValueError, match="y must start"):
        TsdPlanform(np.array([0.5, 1.0]), np.zeros(2), np.ones(2))
    with pytest.raises(ValueError, match="n_span"):
        tsd3d_grid(p, n_span=1)
    with pytest.raises(ValueError, match="mach must be in"):
        steady_tsd3d(p, biconvex_thickness(0.04), 1.4, tsd3d_grid(p, 4, 2, far=3.0))
