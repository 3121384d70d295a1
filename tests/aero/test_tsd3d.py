"""The 3-D transonic small-disturbance solver (asekit.aero.tsd3d; issue 29, the 3-D step)."""

import numpy as np
import pytest

from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import gaf_from_box_modes
from asekit.aero.spline import analytic_modes, modal_forces
from asekit.aero.tsd import (
    biconvex,
    biconvex_linear_cp,
    harmonic_tsd,
    pitch_normalwash,
    steady_tsd,
    tsd_grid,
)
from asekit.aero.tsd3d import (
    TsdPlanform,
    biconvex_thickness,
    harmonic_tsd3d,
    planform_of_boxes,
    steady_tsd3d,
    thickness_flux,
    tsd3d_grid,
    tsd_gaf,
    tsd_pressure_matrices,
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


# --- the time-linearised lifting problem (zero thickness: the linear limit) -----------------
_MACH, _SEMI, _B = 0.8, 1.5, 0.5
_MODES = [lambda x, y: (1.0 + 0 * x, 0 * x),                 # heave
          lambda x, y: (-(x - 0.5), -1.0 + 0 * x)]           # nose-up pitch about mid-chord


def _dlm(n, ks):
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, _SEMI, 0), 1.0, n, n)])
    return mesh, gaf_from_box_modes(analytic_modes(mesh, _MODES), mesh, _MACH, ks, _B,
                                    symmetric=True)


def _tsd(n_chord, mesh, ks):
    wing = TsdPlanform.rectangular(1.0, _SEMI)
    g = tsd3d_grid(wing, n_chord, n_chord // 2, far=6.0, ratio=1.3, edges="faces")
    bg = steady_tsd3d(wing, biconvex_thickness(0.0), _MACH, g)
    return tsd_gaf(bg, mesh, _MODES, ks, _B)


def test_steady_lift_of_a_rectangular_wing_matches_the_dlm_in_the_linear_limit():
    """Zero thickness, k = 0, M 0.8, rectangular wing of aspect ratio 3 (semi-span 1.5 chords,
    symmetric about the root). Both methods converge at first order in the cell / box size,
    so both are Richardson-extrapolated (Q(h) = Q0 + C h) from two meshes. Lift per unit pitch,
    Q_heave,pitch (m^2), measured: TSD 6.3939, 6.1841, 6.0812 on 8 x 4, 12 x 6, 16 x 8 cells
    (far 6 chords), extrapolated 5.7645 (8/12), 0.03 % from the DLM's 5.766 (issue 29's
    tsdswept projection, box_pressures sampling each row between its edge nodes; before it:
    5.5653, 5.6376, 5.6745, 5.6949 on 8 x 4 to 24 x 12 cells, extrapolated 5.782); DLM 6.0598,
    5.9620, 5.8828 on 8 x 8, 12 x 12, 20 x 20 boxes, extrapolated 5.766 (8/12) and 5.764
    (12/20): 0.3 % apart. (The far boundary at 6 chords adds about 1.3 % to the TSD lift:
    5.638, 5.597, 5.568 at far 6, 15, 30 on 12 x 6 cells.)"""
    mesh8, d8 = _dlm(8, [0.0])
    mesh12, d12 = _dlm(12, [0.0])
    t8, t12 = _tsd(8, mesh12, [0.0]), _tsd(12, mesh12, [0.0])
    dlm = (12 * d12[0, 0, 1] - 8 * d8[0, 0, 1]) / 4
    tsd = (12 * t12[0, 0, 1] - 8 * t8[0, 0, 1]) / 4
    assert abs(tsd.real / dlm.real - 1) < 0.015
    assert abs(tsd.imag) < 1e-12 and abs(t12[0, 0, 0]) < 1e-12      # heave: no steady load
    assert abs(t12[0, 0, 1] / d12[0, 0, 1] - 1) < 0.07                # one grid: first order


def test_harmonic_gafs_of_a_rectangular_wing_approach_the_dlm():
    """k = 0.3 (b = c/2), M 0.8, heave and pitch, zero thickness. Measured max |Q/Q_DLM - 1|
    over the four entries against the DLM on 12 x 12 boxes: 7.8 %, 5.9 %, 4.9 % on 8 x 4,
    12 x 6, 16 x 8 cells (far 6 chords), Q_heave,pitch 6.2224 + 1.0699i on 16 x 8 cells
    against 6.1209 + 1.1191i (DLM 20 x 20 boxes: 6.0785 + 1.1131i) (issue 29's tsdswept
    projection; before it 12.2 %, 8.3 %, 6.4 %, 5.9105 + 1.3046i; the slow test below still
    passes, its numbers are those before). The issue's 1 % needs finer grids and a better far field than a
    unit test affords (the far-field extent still moves the 8 x 4 result by several per cent,
    see harmonic_tsd3d); this test checks the coarse grid's level and the sign of every real
    and imaginary part (stiffness and damping)."""
    mesh, d = _dlm(12, [0.3])
    t = _tsd(8, mesh, [0.3])
    assert np.max(np.abs(t / d - 1)) < 0.15
    assert np.all(np.sign(t.real) == np.sign(d.real))
    assert np.all(np.sign(t.imag) == np.sign(d.imag))


@pytest.mark.slow
def test_harmonic_gafs_richardson_extrapolated_match_the_dlm():
    """k = 0.3, M 0.8: both methods converge at first order, so both are extrapolated
    (Q0 = (n2 Q(n2) - n1 Q(n1)) / (n2 - n1)): the TSD from 12 x 6 and 16 x 8 cells, the DLM
    from 12 x 12 and 20 x 20 boxes. Measured: the lift row (heave, pitch columns) 1.2 % and
    1.2 % apart (5.9441 + 1.0874i against 6.0149 + 1.1041i for Q_heave,pitch), the pitch-moment
    row 3.9 % and 4.4 % (the moment depends on where a box's pressure acts: the load point,
    as the DLM). About 40 s."""
    mesh12, d12 = _dlm(12, [0.3])
    mesh20, d20 = _dlm(20, [0.3])
    t12, t16 = _tsd(12, mesh12, [0.3]), _tsd(16, mesh12, [0.3])
    tsd = (16 * t16[0] - 12 * t12[0]) / 4
    dlm = (20 * d20[0] - 12 * d12[0]) / 8
    err = np.abs(tsd / dlm - 1)
    assert np.max(err[0]) < 0.02
    assert np.max(err[1]) < 0.06


def test_harmonic_refuses_a_bad_frequency():
    wing = TsdPlanform.rectangular(1.0, 1.0)
    bg = steady_tsd3d(wing, biconvex_thickness(0.0), 0.5,
                      tsd3d_grid(wing, 4, 2, far=3.0, edges="faces"))
    with pytest.raises(ValueError, match="kappa"):
        harmonic_tsd3d(bg, _MODES, -0.1)
    with pytest.raises(ValueError, match="b_ref"):
        tsd_gaf(bg, None, _MODES, [0.1], 0.0)


def test_thickness_raises_the_lift_more_as_the_mach_number_rises():
    """The time-linearised problem about a thick background: the local flow over the section is
    faster than the free stream, so the local Prandtl-Glauert factor A0 = 1 - M^2 - (gamma+1)
    M^2 phi0_x is smaller and the lift larger, the more so the nearer M is to 1 (transonic
    similarity: the term scales as (gamma+1) M^2 tau / (1 - M^2)). Measured on 12 x 6 cells,
    semi-span 2 chords, steady lift per pitch with 6 % biconvex over zero thickness: +3.0 % at
    M 0.7, +10.3 % at M 0.85; on the 8 x 4 cells of this test +3.5 % and +12.0 %."""
    wing = TsdPlanform.rectangular(1.0, 2.0)
    g = tsd3d_grid(wing, 8, 4, far=6.0, ratio=1.3, edges="faces")
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, 2.0, 0), 1.0, 8, 8)])
    rise = []
    for mach in (0.7, 0.85):
        q = [tsd_gaf(steady_tsd3d(wing, biconvex_thickness(tau), mach, g), mesh, _MODES,
                     [0.0], _B)[0, 0, 1].real for tau in (0.0, 0.06)]
        rise.append(q[1] / q[0] - 1)
    assert 0.01 < rise[0] < 0.06, rise
    assert rise[1] > 2 * rise[0], rise


def test_pressure_matrices_reproduce_the_modal_gafs():
    """tsd_pressure_matrices (each box's unit normalwash on the grid nodes inside it) applied
    to the modes' box normalwash and projected with modal_forces gives the GAFs of tsd_gaf
    (the modes' pointwise normalwash) up to the box-constant normalwash: at k = 0 the modes'
    normalwash is constant per box and the two agree to round-off; at k = 0.3 (the pitch
    mode's i k h / b varies across a box) measured 2.3 % and 4.2 % on the pitch column with
    4 x 4 boxes, 1.2 % and 3.0 % with 6 x 6 (8 x 4 cells, M 0.8)."""
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), 1.0, (0, _SEMI, 0), 1.0, 4, 4)])
    assert np.allclose(planform_of_boxes(mesh).chord, 1.0)
    ks = [0.0, 0.3]
    a = tsd_pressure_matrices(mesh, _MACH, ks, _B,
                              grid_options=dict(n_chord=8, n_span=4, far=6.0, ratio=1.3))
    bm = analytic_modes(mesh, _MODES)
    q = np.stack([modal_forces(bm, a[i] @ bm.normalwash(k, _B), mesh.area)
                  for i, k in enumerate(ks)])
    ref = _tsd(8, mesh, ks)
    assert np.max(np.abs(q[0] - ref[0])) < 1e-10 * np.max(np.abs(ref[0]))
    big = np.abs(ref) > 0.1
    assert np.max(np.abs(q[big] / ref[big] - 1)) < 0.06


@pytest.mark.slow
def test_transonic_lift_rise_at_the_root_approaches_the_2d_one_as_the_span_grows():
    """Steady lift per pitch about a 6 % biconvex background over that about a flat plate, at
    M 0.85: 2-D (asekit.aero.tsd, 24 cosine cells, far 30 chords) 1.336; 3-D root section
    (4 phi at the first wake node: the section circulation times 2, 12 x 2S cells) 1.074 at
    semi-span 2 chords, 1.146 at 4 (18 supersonic nodes): the 3-D relief shrinks as the span
    grows and the transonic rise approaches the 2-D one from below. About 15 s."""
    mach, rise = 0.85, []
    for s in (2.0, 4.0):
        wing = TsdPlanform.rectangular(1.0, s)
        g = tsd3d_grid(wing, 12, int(2 * s), far=6.0, ratio=1.3, edges="faces")
        cl = []
        for tau in (0.0, 0.06):
            bg = steady_tsd3d(wing, biconvex_thickness(tau), mach, g, max_iter=100)
            sol = harmonic_tsd3d(bg, _MODES[1:], 0.0)
            te = np.flatnonzero(sol.wing[:, 0])[-1] + 1
            cl.append(4.0 * sol.phi[0, te, 0].real)
        rise.append(cl[1] / cl[0])
    two_d = [harmonic_tsd(steady_tsd(biconvex(tau), mach, tsd_grid(n_chord=24, far=30.0),
                                     max_iter=200), pitch_normalwash(0.5, 0.0), 0.0).cl.real
             for tau in (0.0, 0.06)]
    ref = two_d[1] / two_d[0]
    assert 1.0 < rise[0] < rise[1] < ref
    assert 1.25 < ref < 1.45
