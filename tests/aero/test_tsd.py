"""The steady transonic small-disturbance solver (asekit.aero.tsd; issue 29, first step)."""

import numpy as np
import pytest

from asekit.aero.tsd import biconvex, biconvex_linear_cp, steady_tsd, tsd_grid


def _mid_error(sol, tau, mach):
    x = sol.x_surface
    mid = (x > 0.1) & (x < 0.9)                 # away from the log singularities at the edges
    ref = biconvex_linear_cp(tau, mach, x[mid])
    return float(np.max(np.abs(sol.cp[mid] - ref)) / np.max(np.abs(ref)))


def test_linear_limit_converges_to_thin_airfoil_theory():
    """gamma = -1 removes the nonlinear term: Eq. (1) is the Prandtl-Glauert equation, whose
    thin-airfoil solution on a biconvex airfoil is closed form (Katz & Plotkin, Sec. 5.2, with
    the Prandtl-Glauert rule). Measured: 6.4 %, 3.5 % and 1.8 % of the peak |Cp| on 40, 80 and
    160 chord cells: first-order convergence (the one-sided wall flux of the half cell at
    y = 0), the error halving per refinement."""
    e = [_mid_error(steady_tsd(biconvex(0.02), 0.5, tsd_grid(n_chord=n), gamma=-1.0), 0.02, 0.5)
         for n in (80, 160)]
    assert e[1] < 0.022
    assert e[0] / e[1] > 1.8


def test_subcritical_flow_is_nearly_linear():
    """A 2 % biconvex airfoil at M 0.5: no supersonic point, and Cp within 4 % of the linear
    theory (the nonlinear term (gamma+1) M^2 phi_x is 0.6 % of 1 - M^2 here; the rest is the
    discretisation, 3.5 % at 80 cells in the linear test)."""
    sol = steady_tsd(biconvex(0.02), 0.5, tsd_grid(n_chord=80))
    assert sol.converged and sol.supersonic_points == 0
    assert _mid_error(sol, 0.02, 0.5) < 0.05
    assert np.all(sol.cp > sol.cp_critical)


def test_transonic_shock_obeys_the_tsd_jump_condition():
    """10 % biconvex at M 0.85 (transonic similarity parameter K = (1 - M^2) / ((gamma+1) M^2
    tau)^(2/3) = 0.83): a supersonic pocket closed by a shock. Across a shock of Eq. (1) the
    flux f(u) = (1 - M^2) u - (gamma+1)/2 M^2 u^2 is continuous, so u1 + u2 = 2 u*, i.e. the
    Cp just before and after the shock average to the critical Cp* (Murman 1974: the conservative
    shock-point operator gives this jump). Measured on 100 chord cells: shock at x = 0.88, mean of
    the Cp two cells either side within 5 % of Cp* = -0.320."""
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
