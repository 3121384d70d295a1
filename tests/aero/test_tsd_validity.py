"""The validity of a TSD result (issue 29): :func:`asekit.aero.tsd3d.tsd_validity`, von
Karman's transonic similarity parameter and the shock presence of the steady background."""

from __future__ import annotations

import math

import pytest

from asekit.aero.tsd3d import (
    TsdPlanform,
    biconvex_thickness,
    steady_tsd3d,
    tsd3d_grid,
    tsd_validity,
)

_WING = TsdPlanform.rectangular(1.0, 2.0)
_GRID = tsd3d_grid(_WING, 8, 4, far=4.0, ratio=1.4, edges="faces")


def _validity(mach, tau=0.06):
    return tsd_validity(steady_tsd3d(_WING, biconvex_thickness(tau), mach, _GRID,
                                     max_iter=100), tau)


def test_similarity_parameter_is_von_karmans():
    """K = (1 - M^2) / (M^2 tau)^(2/3) (von Karman 1947): 0.75 / 0.01^(2/3) = 16.158 at
    M 0.5, tau 0.04 (hand value); inf with zero thickness (the linear limit)."""
    v = _validity(0.5, 0.04)
    assert v.similarity == pytest.approx(0.75 / 0.01 ** (2 / 3), rel=1e-12)
    assert math.isinf(_validity(0.5, 0.0).similarity)
    assert "similarity K = inf (linear)" in _validity(0.5, 0.0).text()


def test_a_shock_appears_where_the_surface_cp_passes_the_sonic_cp():
    """6 % biconvex, aspect ratio 4 with its image, 8 x 4 cells. Measured: M 0.8 Cp_min
    -0.262 above Cp* -0.469, no supersonic node; M 0.95 Cp_min -0.666 below Cp* -0.090, 420
    supersonic nodes. The supersonic pocket (Murman-Cole's upwind points) is present exactly
    when the lowest surface Cp passes the small-disturbance sonic Cp*, and K falls through 1
    as the pocket appears."""
    sub, sup = _validity(0.8), _validity(0.95)
    assert not sub.shock and sub.cp_min > sub.cp_critical and sub.similarity > 1.0
    assert sup.shock and sup.cp_min < sup.cp_critical and sup.similarity < 1.0
    assert sub.converged and sup.converged
    assert "supersonic pocket" in sup.text() and "subcritical" in sub.text()


def test_bad_thickness_is_refused():
    bg = steady_tsd3d(_WING, biconvex_thickness(0.0), 0.5, _GRID)
    with pytest.raises(ValueError, match="thickness_ratio must be in"):
        tsd_validity(bg, 0.3)
