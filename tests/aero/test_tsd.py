"""The steady transonic small-disturbance solver (asekit.aero.tsd; issue 29, first step)."""

import numpy as np
import pytest

from asekit.aero.tsd import (
    biconvex,
    biconvex_linear_cp,
    harmonic_tsd,
    pitch_normalwash,
    steady_tsd,
    tsd_grid,
)
from asekit.aeroelastic.typical_section import theodorsen_function


def _mid_error(sol, tau, mach):
    x = sol.x_surface
    mid = (x > 0.1) & (x < 0.9)                 # away from the log singularities at the edges
    ref = biconvex_linear_cp(tau, mach, x[mid])
    return float(np.max(np.abs(sol.cp[mid] - ref)) / np.max(np.abs(ref)))


def test_linear_limit_converges_to_thin_airfoil_theory():
    """gamma = -1 removes the nonlinear term: Eq. (1) is the Prandtl-Glauert equation, whose
    thin-airfoil solution on a biconvex airfoil is closed form (Katz & Plotkin, Sec. 5.2, with
    the Prandtl-Glauert rule). Measured (max error on 0.1 < x < 0.9 over the peak |Cp|):
    uniform chord cells 6.4 %, 3.5 %, 1.8 % on 40, 80, 160 cells (first order); cosine
    spacing 0.41 %, 0.08 % on 40 and 80."""
    e = [_mid_error(steady_tsd(biconvex(0.02), 0.5, tsd_grid(n_chord=n, spacing="uniform"),
                               gamma=-1.0), 0.02, 0.5) for n in (80, 160)]
    assert e[1] < 0.022
    assert e[0] / e[1] > 1.8
    cos = _mid_error(steady_tsd(biconvex(0.02), 0.5, tsd_grid(n_chord=40), gamma=-1.0),
                     0.02, 0.5)
    assert cos < 0.006


def test_subcritical_flow_is_nearly_linear():
    """A 2 % biconvex airfoil at M 0.5: no supersonic point, and Cp within 4 % of the linear
    theory (the nonlinear term (gamma+1) M^2 phi_x is 0.6 % of 1 - M^2 here; the rest is the
    discretisation)."""
    sol = steady_tsd(biconvex(0.02), 0.5, tsd_grid(n_chord=80))
    assert sol.converged and sol.supersonic_points == 0
    assert _mid_error(sol, 0.02, 0.5) < 0.02
    assert np.all(sol.cp > sol.cp_critical)


def test_transonic_shock_obeys_the_tsd_jump_condition():
    """10 % biconvex at M 0.85 (transonic similarity parameter K = (1 - M^2) / ((gamma+1) M^2
    tau)^(2/3) = 0.83): a supersonic pocket closed by a shock. Across a shock of Eq. (1) the
    flux f(u) = (1 - M^2) u - (gamma+1)/2 M^2 u^2 is continuous, so u1 + u2 = 2 u*, i.e. the
    Cp just before and after the shock average to the critical Cp* (Murman 1974: the conservative
    shock-point operator gives this jump). Measured on 100 cosine-spaced chord cells: shock at
    x = 0.87, mean of the Cp one cell before and two after within 3.9 % of Cp* = -0.320."""
    sol = steady_tsd(biconvex(0.1), 0.85, tsd_grid(n_chord=100), max_iter=200)
    assert sol.converged
    assert sol.supersonic_points > 0
    cp, x = sol.cp, sol.x_surface
    i = int(np.argmax(np.diff(cp)))               # the steepest compression
    assert 0.7 < x[i] < 0.95
    before, after = cp[i - 1], cp[i + 2]
    assert before < sol.cp_critical < after
    assert abs(0.5 * (before + after) / sol.cp_critical - 1.0) < 0.05
    # the pocket starts near x = 0.3: subsonic ahead of it
    assert np.all(cp[x < 0.25] > sol.cp_critical)


@pytest.mark.parametrize("kwargs, match", [
    (dict(mach=1.5), "mach must be in"),
    (dict(mach=-0.1), "mach must be in"),
])
def test_bad_mach_is_refused(kwargs, match):
    with pytest.raises(ValueError, match=match):
        steady_tsd(biconvex(0.05), grid=tsd_grid(n_chord=8), **kwargs)


def test_bad_geometry_and_grid_are_refused():
    with pytest.raises(ValueError, match="thickness_ratio"):
        biconvex(0.5)
    with pytest.raises(ValueError, match="n_chord"):
        tsd_grid(n_chord=2)
    with pytest.raises(ValueError, match="ratio"):
        tsd_grid(ratio=2.0)


def _lift(n, mach, kc, pivot=0.5):
    bg = steady_tsd(biconvex(0.0), mach, tsd_grid(n_chord=n, far=100.0))
    return harmonic_tsd(bg, pitch_normalwash(pivot, kc), kc)


def test_harmonic_lift_of_a_flat_plate_approaches_theodorsen():
    """Zero thickness at M 0: the time-linearised equation is Laplace's, and the lift of a
    plate pitching about mid-chord is Theodorsen's (NACA Report 496):
    CL / alpha = 2 pi C(k) (1 + i k / 2) + i pi k, k = omega b / U = k_c / 2. Measured: 2.2-2.3 %
    off on 80 cosine-spaced chord cells at k_c = 0-1 (first order), and the Richardson value
    of 40 and 80 cells within 0.14-0.18 % (0.28 % at k_c = 2)."""
    kc = 0.4
    k = kc / 2
    theo = 2 * np.pi * complex(theodorsen_function(k)) * (1 + 0.5j * k) + 1j * np.pi * k
    c40, c80 = _lift(40, 0.0, kc).cl, _lift(80, 0.0, kc).cl
    assert abs(c80 / theo - 1) < 0.03
    assert abs((2 * c80 - c40) / theo - 1) < 0.004


def test_steady_lift_follows_prandtl_glauert_and_the_quarter_chord():
    """k_c = 0 on a flat plate: CL_alpha = 2 pi / beta (thin-airfoil theory with the
    Prandtl-Glauert rule), the centre of pressure at the quarter chord. Measured at M 0.5 on
    40 and 80 cells: 0.956 and 0.977 of 2 pi / beta; Richardson 0.999."""
    s40, s80 = _lift(40, 0.5, 0.0), _lift(80, 0.5, 0.0)
    ref = 2 * np.pi / np.sqrt(1 - 0.25)
    assert abs((2 * s80.cl - s40.cl).real / ref - 1) < 0.005
    assert abs((-s80.cm_le / s80.cl).real - 0.25) < 0.01


def test_harmonic_refuses_a_bad_frequency():
    bg = steady_tsd(biconvex(0.0), 0.0, tsd_grid(n_chord=8))
    with pytest.raises(ValueError, match="reduced_frequency"):
        harmonic_tsd(bg, pitch_normalwash(0.25, 0.1), -0.1)
