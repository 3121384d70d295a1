"""The validity of a TSD result (issue 29): :func:`asekit.aero.tsd3d.tsd_validity`, von
Karman's transonic similarity parameter and the shock presence of the steady background."""

from __future__ import annotations

import math

import numpy as np
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


def test_steady_background_is_cached_verified_and_recomputed_when_corrupt(tmp_path,
                                                                          monkeypatch):
    """cached_steady_tsd3d writes the background once; a second call reads it bit for bit
    without solving; a corrupted file fails its digest and is solved again; another
    thickness is another key."""
    from asekit.aero import tsd3d as T

    first = T.cached_steady_tsd3d(_WING, _GRID, 0.04, 0.7, cache_dir=tmp_path)
    (path,) = tmp_path.glob("tsd_steady_*.npz")
    real = T.steady_tsd3d

    def refuse(*args, **kwargs):
        raise AssertionError("solved again")

    monkeypatch.setattr(T, "steady_tsd3d", refuse)
    again = T.cached_steady_tsd3d(_WING, _GRID, 0.04, 0.7, cache_dir=tmp_path)
    assert np.array_equal(again.phi, first.phi) and np.array_equal(again.cp, first.cp)
    assert again.converged == first.converged and again.supersonic_points == first.supersonic_points
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(AssertionError, match="solved again"):
        T.cached_steady_tsd3d(_WING, _GRID, 0.04, 0.7, cache_dir=tmp_path)
    monkeypatch.setattr(T, "steady_tsd3d", real)
    fresh = T.cached_steady_tsd3d(_WING, _GRID, 0.04, 0.7, cache_dir=tmp_path)
    assert np.allclose(fresh.phi, first.phi, rtol=0, atol=1e-14)
    assert T.steady_key(_WING, _GRID, 0.04, 0.7) != T.steady_key(_WING, _GRID, 0.05, 0.7)
