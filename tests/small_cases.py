"""Small variants of the shipped cases shared by several test files (plain functions returning
the raw TOML dictionary, so each test can adjust or write it)."""

import tomllib

import numpy as np

from asekit.util.paths import FIN_FILE

#: The speed grid (m/s) on which the active-flutter-suppression tests bracket a boundary
#: (tests/ase/test_afs.py, tests/ase/test_sensors.py and conftest's ``afs_open_loop``).
AFS_GRID = np.array([150.0, 200.0, 250.0, 300.0, 350.0, 400.0])
AFS_GRID.setflags(write=False)


def small_fin_raw(point_mass: bool = True) -> dict:
    """The reference fin coarsened for fast design and optimisation tests: 4 x 4 elements,
    3 modes with the rigid pitch mode, 6 x 6 boxes, Mach 0.4 and 0.6, two altitudes, 120-420 m/s
    in 20 m/s steps, no actuator; with ``point_mass`` a 10 g mass at (0.12, 0.14) m."""
    raw = tomllib.loads(FIN_FILE.read_text())
    raw["panel"][0].update(n_chord=4, n_span=4)
    raw["modes"] = {"count": 3, "keep_rigid": True}
    raw["aero"].update(machs=[0.4, 0.6], boxes=[{"n_chord": 6, "n_span": 6}],
                       reduced_frequencies=[0.001, 0.1, 0.2, 0.3, 0.45, 0.6, 0.8])
    raw["flight"].update(altitudes=[0.0, 2500.0],
                         velocities={"min": 120.0, "max": 420.0, "step": 20.0})
    if point_mass:
        raw["point_mass"] = [{"position": [0.12, 0.14], "mass": 0.01}]
    raw.pop("actuator", None)
    return raw
