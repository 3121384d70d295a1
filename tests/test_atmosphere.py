"""1976 U.S. Standard Atmosphere: values from NOAA-S/T 76-1562 tables (geometric altitude)."""

import numpy as np
import pytest

from asekit.atmosphere import (
    density,
    equivalent_airspeed,
    mach_number,
    speed_of_sound,
    standard_atmosphere,
    true_airspeed,
)


def test_sea_level():
    s = standard_atmosphere(0.0)
    assert s.temperature == pytest.approx(288.15)
    assert s.pressure == pytest.approx(101325.0)
    assert s.density == pytest.approx(1.2250, abs=1e-4)
    assert s.speed_of_sound == pytest.approx(340.294, abs=1e-3)


@pytest.mark.parametrize("h, rho, a, T", [
    # U.S. Standard Atmosphere 1976, Table I (geometric altitude)
    (2500.0, 0.95697, 330.563, 271.906),
    (5000.0, 0.73643, 320.545, 255.676),
    (11000.0, 0.36480, 295.154, 216.774),
    (20000.0, 0.088910, 295.069, 216.650),
])
def test_table_values(h, rho, a, T):
    s = standard_atmosphere(h)
    assert s.density == pytest.approx(rho, rel=2e-4)
    assert s.speed_of_sound == pytest.approx(a, abs=2e-3)
    assert s.temperature == pytest.approx(T, abs=2e-3)


def test_vectorised_and_monotone():
    h = np.linspace(0, 20000, 41)
    r = density(h)
    assert r.shape == h.shape
    assert np.all(np.diff(r) < 0)
    assert speed_of_sound(h.reshape(1, -1)).shape == (1, 41)


def test_hydrostatic_consistency():
    # dp/dh = -rho g (geopotential ~ geometric at low altitude): centred difference
    h, dh = 3000.0, 1.0
    p1, p2 = standard_atmosphere([h - dh, h + dh]).pressure
    g = 9.80665 * (6356766 / (6356766 + h)) ** 2
    assert (p2 - p1) / (2 * dh) == pytest.approx(-density(h) * g, rel=1e-5)


def test_equivalent_airspeed_and_mach():
    assert equivalent_airspeed(250.0, 0.0) == pytest.approx(250.0, rel=1e-6)
    assert equivalent_airspeed(250.0, 5000.0) == pytest.approx(250 * np.sqrt(0.73643 / 1.225),
                                                               rel=1e-4)
    u = true_airspeed(0.75, 2500.0)
    assert mach_number(u, 2500.0) == pytest.approx(0.75)


@pytest.mark.parametrize("bad", [-6000.0, 60000.0, np.nan])
def test_bad_altitude(bad):
    with pytest.raises(ValueError, match="altitude"):
        density(bad)


def test_bad_speed():
    with pytest.raises(ValueError, match="true_airspeed"):
        equivalent_airspeed(-1.0, 0.0)


# ---- issue 22: strict types -------------------------------------------------------------------
@pytest.mark.parametrize("altitude, error, word", [
    (np.array([1000.0 + 5j]), TypeError, r"altitude must be real numbers.*altitude\[0\]"),
    (1000.0 + 5j, TypeError, "altitude must be real numbers"),
    ("1000", ValueError, "altitude must be real numbers, got the string"),
    (["1000", "2000"], ValueError, "altitude must be real numbers, got strings"),
    ([1000.0, None], TypeError, "altitude must be real numbers"),
])
def test_altitude_must_be_real_numbers(altitude, error, word):
    """Issue 22: a complex altitude lost its imaginary part and "1000" was parsed silently."""
    with pytest.raises(error, match=word):
        standard_atmosphere(altitude)


def test_mach_and_airspeed_must_be_real_numbers():
    from asekit.atmosphere import dynamic_pressure, true_airspeed
    with pytest.raises(TypeError, match=r"mach must be real numbers.*mach\[0\]"):
        true_airspeed(np.array([0.5 + 1j]), 0.0)
    with pytest.raises(ValueError, match="true_airspeed_ms must be real numbers"):
        dynamic_pressure("100", 0.0)


def test_numpy_real_altitudes_are_accepted():
    s = standard_atmosphere(np.float32(0.0))
    assert float(s.density) == pytest.approx(1.225, rel=1e-4)   # sea level, US 1976 Table 1
