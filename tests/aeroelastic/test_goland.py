"""The Goland wing as a stick model: beam modes (asekit.structure.beam) -> beam-to-box spline
(asekit.aero.beam_spline) -> strip theory (asekit.aero.strip) or DLM boxes (asekit.aero.dlm)
-> p-k (asekit.aeroelastic.flutter). A test-side model: nothing in asekit knows this wing.

The wing (SI; Goland, "The flutter of a uniform cantilever wing", J. Appl. Mech. 12, 1945,
A197-A208; the same numbers in Patil, Hodges & Cesnik, J. Aircraft 38(1), 2001, Table 1):
semi-span 6.096 m, chord 1.8288 m, elastic axis at 33 % chord, mass axis at 43 % chord,
EI = 9.77e6 N m^2, GJ = 0.987e6 N m^2, m = 35.71 kg/m, I_p = 8.64 kg m about the elastic axis,
clamped at the root. In-plane bending and extension are made stiff (EI_chord = 1e9 N m^2,
EA = 1e10 N): they are not part of the model and do not couple.

References, and which theory each belongs to:

* Strip theory (Theodorsen, two-dimensional): flutter at 137.2 m/s and 70.7 rad/s at sea
  level (rho = 1.225 kg/m^3), Goland's own solution as tabulated by Patil, Hodges & Cesnik
  2001 and quoted in issue 24. The p-k root at g = 0 is exactly the flutter point of this
  aerodynamics, so the comparison is same-theory: 1 % on speed, 2 % on frequency.
* Three-dimensional linear potential flow: SHARPy's linear UVLM Goland flutter test
  (ImperialCollegeLondon/sharpy, tests/linear/goland_wing: density 1.02 kg/m^3, flutter
  reference 166 m/s "at current discretisation", 169 m/s in an earlier version of the same
  test with another lattice, each asserted there to 1 %). The DLM here is the frequency-domain
  counterpart of that lattice (same potential-flow model, wall at the root); the two
  discretisations differ, so the tolerance is 3 % on 166 m/s. No published DLM value for the
  clean Goland wing was found with the search tool; issue 24's "around 137 m/s and 70 rad/s
  with DLM" is the strip-theory value: 3-D flow lowers the lift slope of this AR 6.7 wing
  and raises the flutter speed (the DLM gives about 155 m/s at sea level, below).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from asekit.aero.beam_spline import beam_box_modes, beam_spline_matrices
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import TabulatedGaf, gaf_from_box_modes
from asekit.aero.spline import BoxModes
from asekit.aero.strip import strip_gaf
from asekit.aeroelastic.flutter import FlutterConvergenceWarning, pk_flutter, pk_instabilities
from asekit.aeroelastic.statespace import ModalArrays
from asekit.structure.beam import BeamSection, beam_modes, uniform_beam

CHORD, SPAN = 1.8288, 6.096
B = CHORD / 2
X_EA = 0.33 * CHORD
SEA_LEVEL, SHARPY_RHO = 1.225, 1.02
#: reduced frequencies of the GAF tables (flutter at k = omega b / U ~ 0.4-0.5)
KS = np.array([0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.3])
VELOCITIES = np.arange(60.0, 220.0, 5.0)      # crossings refined by Brent between points


def goland_modes(n_elements: int = 32, n_modes: int = 3):
    """The Goland wing's lowest out-of-plane modes: (BeamModes, phi (6 n_nodes, n_modes),
    omega (n_modes,) rad/s)."""
    sec = BeamSection(1e10, 0.987e6, 9.77e6, 1e9, 35.71, 8.64, 0.1 * CHORD)
    modes = beam_modes(uniform_beam((X_EA, 0.0), (0.0, 1.0), SPAN, n_elements, sec),
                       n_modes + 2)
    out_of_plane = np.abs(modes.shapes[:, 0, :]).max(axis=0) < 1e-9      # no ux motion
    phi = modes.shapes.reshape(-1, modes.frequencies_hz.size)[:, out_of_plane][:, :n_modes]
    return modes, phi, modes.omega[out_of_plane][:n_modes]


def _flutter(omega, Q, rho):
    n = omega.size
    modal = ModalArrays(np.eye(n), np.diag(omega ** 2), np.zeros((n, n)))
    gaf = TabulatedGaf(KS, Q, B)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlutterConvergenceWarning)
        res = pk_flutter(modal, gaf, rho, VELOCITIES)          # Q linear in k (Nastran's L)
        found = pk_instabilities(res, modal, gaf)
    flutter = [s for s in found if s.kind == "flutter" and not s.at_first_point]
    assert flutter, "no flutter crossing in the sweep"
    return flutter[0].speed, 2 * math.pi * flutter[0].frequency_hz


@pytest.fixture(scope="module")
def goland():
    return goland_modes()


@pytest.fixture(scope="module")
def strip_table(goland):
    modes, phi, _ = goland
    n = 60
    y = (np.arange(n) + 0.5) * SPAN / n
    G, Gx = beam_spline_matrices(modes.beam, np.column_stack([np.full(n, X_EA), y]))
    # on the unswept axis the spline's w is the deflection and -dh/dx the nose-up twist
    return strip_gaf(G @ phi, -Gx @ phi, np.full(n, SPAN / n), B, (X_EA - B) / B, KS)


def dlm_gaf(goland, n_chord: int, n_span: int) -> np.ndarray:
    """Q (n_k, n, n) of the DLM (Mach 0, wall at the root) on n_chord x n_span boxes."""
    modes, phi, _ = goland
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), CHORD, (0, SPAN, 0), CHORD, n_chord,
                                           n_span)])
    g_cp, gx_cp = beam_spline_matrices(modes.beam, mesh.control_point)
    g_lp, _ = beam_spline_matrices(modes.beam, mesh.load_point)
    box = BoxModes(g_cp @ phi, gx_cp @ phi, g_lp @ phi)
    return gaf_from_box_modes(box, mesh, 0.0, KS, B, symmetric=True)


@pytest.fixture(scope="module")
def dlm_table(goland):
    return dlm_gaf(goland, 6, 12)


def test_strip_theory_flutter_is_goland_1945(goland, strip_table):
    speed, omega = _flutter(goland[2], strip_table, SEA_LEVEL)
    assert speed == pytest.approx(137.2, rel=0.01)          # Goland 1945: 137.2 m/s
    assert omega == pytest.approx(70.7, rel=0.02)           # 70.7 rad/s


def test_dlm_flutter_matches_the_3d_potential_flow_reference(goland, dlm_table, strip_table):
    speed, omega = _flutter(goland[2], dlm_table, SHARPY_RHO)
    assert speed == pytest.approx(166.0, rel=0.03)          # SHARPy linear UVLM, rho 1.02
    # the same bending-torsion mechanism as strip theory (70 rad/s)
    assert omega == pytest.approx(70.7, rel=0.03)
    # 3-D relief: the lifting surface flutters above strip theory (sea level: about 155
    # against 137 m/s)
    s3d, _ = _flutter(goland[2], dlm_table, SEA_LEVEL)
    s2d, _ = _flutter(goland[2], strip_table, SEA_LEVEL)
    assert 1.05 < s3d / s2d < 1.25


def test_dlm_gaf_tends_to_strip_theory_at_low_frequency_in_sign_and_size(dlm_table,
                                                                         strip_table):
    """Both tables in asekit's convention (F = q Q zeta): the steady aerodynamic stiffness of
    the twist mode on itself has the same sign, and 3-D flow makes it smaller in size
    (lift slope of the finite wing below 2 pi)."""
    twist = 1                                 # mode 2 (index 1) is the torsion-dominated mode
    q3, q2 = dlm_table[0, twist, twist].real, strip_table[0, twist, twist].real
    assert np.sign(q3) == np.sign(q2)
    assert 0.4 < q3 / q2 < 1.0


@pytest.mark.slow
def test_dlm_flutter_converges_with_the_box_mesh(goland):
    """8 x 16 and 10 x 20 boxes: the speed changes by less than 1 % between them and stays
    within 3 % of SHARPy's 166 m/s."""
    speeds = [_flutter(goland[2], dlm_gaf(goland, nc, ns), SHARPY_RHO)[0]
              for nc, ns in ((8, 16), (10, 20))]
    assert abs(speeds[1] / speeds[0] - 1) < 0.01
    assert speeds[1] == pytest.approx(166.0, rel=0.03)


def test_beam_box_modes_carry_every_beam_mode(goland):
    """beam_box_modes splines all of a BeamModes' columns; the in-plane mode has no normal
    motion on the boxes."""
    modes = beam_modes(goland[0].beam, 6)
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), CHORD, (0, SPAN, 0), CHORD, 2, 4)])
    bm = beam_box_modes(modes, mesh)
    in_plane = np.abs(modes.shapes[:, 0, :]).max(axis=0) > 1e-9
    assert in_plane.any()
    assert np.abs(bm.h_cp[:, in_plane]).max() < 1e-12
    assert np.abs(bm.h_cp[:, ~in_plane]).max(axis=0).min() > 1e-3
