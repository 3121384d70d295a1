"""Stick-model cases (issue 24): the ``[[beam]]`` table (asekit.case.schema) and the pipeline's
beam seam (asekit.case.pipeline: beam modal model, beam-to-box spline, then the same GAF and
p-k path as a plate), checked on the shipped Goland wing (data/cases/goland_wing.toml).

References, as in tests/aeroelastic/test_goland.py:

* the same model built by hand from the physics layer (uniform_beam -> beam_spline_matrices ->
  gaf_from_box_modes -> pk_flutter): the case must give its flutter speed to 1e-6 relative
  (same 32 elements, 6 x 12 boxes, k list, velocities and density: only the route differs);
* SHARPy's linear UVLM Goland flutter test (ImperialCollegeLondon/sharpy,
  tests/linear/goland_wing): 166 m/s at rho = 1.02 kg/m^3 ("at current discretisation"), the
  same potential-flow model as the DLM, another lattice: 3 %.
"""

from __future__ import annotations

import copy
import math
import warnings

import numpy as np
import pytest

from asekit.aero.beam_spline import beam_spline_matrices
from asekit.aero.boxes import TrapezoidSurface, mesh_surfaces
from asekit.aero.gaf import TabulatedGaf, gaf_from_box_modes
from asekit.aero.spline import BoxModes
from asekit.aeroelastic.flutter import FlutterConvergenceWarning, pk_flutter, pk_instabilities
from asekit.aeroelastic.statespace import ModalArrays
from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.case.schema import CaseError, case_from_dict
from asekit.structure.beam import BeamSection, beam_modes, uniform_beam
from asekit.util.paths import CASES_DIR
from asekit.util.validate import read_toml

GOLAND = CASES_DIR / "goland_wing.toml"
CHORD, SPAN = 1.8288, 6.096            # Goland 1945 (Patil, Hodges & Cesnik 2001, Table 1)
X_EA = 0.33 * CHORD
KS = np.array([0.0, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.8, 1.0, 1.3])


@pytest.fixture(scope="module")
def goland_case():
    return load_case(GOLAND)


@pytest.fixture(scope="module")
def case_flutter(goland_case):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlutterConvergenceWarning)
        fa = P.flutter(goland_case)
    (r,) = fa.results
    return r


def _hand_built_speed() -> float:
    """The Goland wing's DLM p-k flutter speed at rho 1.02 built directly from the physics
    layer, as tests/aeroelastic/test_goland.py does (its 3 out-of-plane modes)."""
    sec = BeamSection(1e10, 0.987e6, 9.77e6, 1e9, 35.71, 8.64, 0.1 * CHORD)
    modes = beam_modes(uniform_beam((X_EA, 0.0), (0.0, 1.0), SPAN, 32, sec), 5)
    out_of_plane = np.abs(modes.shapes[:, 0, :]).max(axis=0) < 1e-9
    phi = modes.shapes.reshape(-1, modes.frequencies_hz.size)[:, out_of_plane][:, :3]
    omega = modes.omega[out_of_plane][:3]
    mesh = mesh_surfaces([TrapezoidSurface((0, 0, 0), CHORD, (0, SPAN, 0), CHORD, 6, 12)])
    g_cp, gx_cp = beam_spline_matrices(modes.beam, mesh.control_point)
    g_lp, _ = beam_spline_matrices(modes.beam, mesh.load_point)
    Q = gaf_from_box_modes(BoxModes(g_cp @ phi, gx_cp @ phi, g_lp @ phi), mesh, 0.0, KS,
                           CHORD / 2, symmetric=True)
    modal = ModalArrays(np.eye(3), np.diag(omega ** 2), np.zeros((3, 3)))
    gaf = TabulatedGaf(KS, Q, CHORD / 2)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FlutterConvergenceWarning)
        res = pk_flutter(modal, gaf, 1.02, np.arange(60.0, 220.0, 5.0))
        found = pk_instabilities(res, modal, gaf)
    return next(s.speed for s in found if s.kind == "flutter" and not s.at_first_point)


def test_goland_case_modes_tend_to_the_uncoupled_analytic_modes():
    """With the mass axis on the elastic axis (mass_offset = 0) bending and torsion uncouple:
    the clamped-free Euler-Bernoulli bending omega = 1.8751^2 sqrt(EI / (m L^4)) and the
    St Venant torsion omega = (pi / 2) sqrt(GJ / I_p) / L (e.g. Bisplinghoff, Ashley &
    Halfman, *Aeroelasticity*, 1955, Sec. 3-3), to the 32 elements' discretisation: the
    linear torsion element with consistent mass is high by (k h)^2 / 24 = 1.0e-4 (k h =
    (pi / 2) / 32), the Hermite bending element far less; 2e-4."""
    d = _raw()
    d["beam"][0]["mass_offset"] = 0.0
    m = P.modal_model(case_from_dict(d))
    assert m.n_rigid == 0 and m.frequencies_hz.size == 3
    bending = 1.8751041 ** 2 * math.sqrt(9.77e6 / (35.71 * SPAN ** 4))
    torsion = math.pi / 2 * math.sqrt(0.987e6 / 8.64) / SPAN
    np.testing.assert_allclose(2 * math.pi * m.frequencies_hz[:2], [bending, torsion],
                               rtol=2e-4)
    np.testing.assert_allclose(np.diag(m.K), (2 * math.pi * m.frequencies_hz) ** 2)


def test_the_mass_offset_couples_bending_and_torsion(goland_case):
    """Goland's mass axis 10 % of the chord aft of the elastic axis: the coupled modes spread
    apart (bending below, torsion above their uncoupled frequencies)."""
    f = 2 * math.pi * P.modal_model(goland_case).frequencies_hz
    assert f[0] < 1.8751041 ** 2 * math.sqrt(9.77e6 / (35.71 * SPAN ** 4))
    assert f[1] > math.pi / 2 * math.sqrt(0.987e6 / 8.64) / SPAN


def test_goland_case_flutter_equals_the_hand_built_model(case_flutter):
    assert not case_flutter.unstable_at_start
    assert case_flutter.flutter.speed == pytest.approx(_hand_built_speed(), rel=1e-6)


def test_goland_case_flutter_is_sharpy_s(case_flutter):
    # SHARPy linear UVLM, tests/linear/goland_wing: 166 m/s at rho 1.02 kg/m^3
    assert case_flutter.flutter.speed == pytest.approx(166.0, rel=0.03)
    # the bending-torsion mechanism: Goland's 70.7 rad/s (strip theory), 3 %
    assert 2 * math.pi * case_flutter.flutter.frequency_hz == pytest.approx(70.7, rel=0.03)


def test_the_twist_mode_loads_the_boxes_as_strip_theory_does(goland_case):
    """The beam's box motion reaches the GAFs: the torsion mode's steady aerodynamic
    stiffness on itself has the sign of strip theory's (tests/aeroelastic/test_goland.py:
    the DLM's Q_22 at k = 0 has strip theory's sign; the elastic axis at 33 % chord lies aft
    of the quarter chord, so a nose-up twist loads the wing nose-up, de-centering: Q > 0)."""
    db = P.gaf_database(goland_case, progress=False)
    assert db.Q.shape == (1, 11, 3, 3)
    assert db.Q[0, 0, 1, 1].real > 0


# ---------------------------------------------------------------------------------------------
# errors: the key path and the valid range, before any computation
# ---------------------------------------------------------------------------------------------
def _raw():
    return copy.deepcopy(read_toml(GOLAND, CaseError))


def _refused(d, *words):
    with pytest.raises(CaseError) as e:
        case_from_dict(d)
    msg = str(e.value)
    assert "\n" not in msg
    for w in words:
        assert w in msg, msg


def test_a_case_has_a_plate_structure_or_a_beam():
    d = _raw()
    d["thickness"] = {"root": 0.01, "tip": 0.01}
    _refused(d, "beam and thickness", "not both")
    d = _raw()
    del d["beam"]
    _refused(d, "[thickness]", "[[beam]]")


@pytest.mark.parametrize("key, value, words", [
    ("gj", -1.0, ("beam[0].gj", "> 0")),
    ("ei_flap", [1e6, 2e6], ("beam[0].ei_flap", "1 numbers")),
    ("stations", [0.0, 0.5], ("beam[0].stations", "from 0 to 1")),
    ("n_elements", 0, ("beam[0].n_elements", "[1, 2000]")),
    ("mass_offset", 1.0, ("beam[0].polar_inertia", ">= mass_per_length * mass_offset^2")),
    ("tip", [0.6, -1.0], ("beam[0].tip", "outboard")),
    ("sweep_deg", 10.0, ("beam[0]", "not both")),
    ("spring", 1.0, ("beam[0].spring is not a known key",)),
])
def test_beam_keys_are_checked(key, value, words):
    d = _raw()
    d["beam"][0][key] = value
    _refused(d, *words)


def test_a_shorter_beam_than_the_panel_is_refused():
    d = _raw()
    d["beam"][0]["tip"] = [0.603504, 5.0]
    _refused(d, "panel[0] corner", "outside the beam")


def test_per_segment_properties_and_the_sweep_form():
    d = _raw()
    b = d["beam"][0]
    del b["tip"]
    b.update(length=6.096, sweep_deg=0.0, stations=[0.0, 0.5, 1.0], n_elements=16,
             gj=[0.987e6, 0.987e6])
    case = case_from_dict(d)
    beam = P.case_beam(case)
    assert beam.n_nodes == 33 and len(beam.sections) == 32
    np.testing.assert_allclose(beam.nodes[-1], [0.603504, 6.096, 0.0])
    # the same uniform wing: the same modes as the one-segment case
    np.testing.assert_allclose(P.modal_model(case).frequencies_hz,
                               P.modal_model(load_case(GOLAND)).frequencies_hz, rtol=1e-9)


def test_beam_cases_refuse_plate_only_tables():
    d = _raw()
    d["point_mass"] = [{"position": [0.5, 3.0], "mass": 1.0}]
    _refused(d, "point_mass is not supported with [[beam]]")
    d = _raw()
    d["panel"][0]["n_chord"] = 4
    _refused(d, "panel[0].n_chord is not a known key")


def test_analyse_runs_the_goland_case_with_json_and_report(tmp_path, case_flutter):
    """`asekit analyse` on the shipped stick model: one JSON flutter row (the pipeline's
    crossing) and a report with the beam's planform and mode figures."""
    import json

    from asekit.cli.main import main
    out, rep = tmp_path / "g.json", tmp_path / "rep"
    assert main(["analyse", str(GOLAND), "--quiet", "--json", str(out), "--report",
                 str(rep)]) == 0
    (row,) = json.loads(out.read_text())["flutter"]
    assert row["density"] == 1.02 and row["speed_ms"] == pytest.approx(
        case_flutter.flutter.speed, rel=1e-12)
    assert {"planform.png", "modes.png", "index.html"} <= {p.name for p in rep.iterdir()}


def test_the_mesh_study_of_a_beam_case_is_refused_in_one_line(capsys):
    from asekit.cli.main import main
    assert main(["analyse", str(GOLAND), "--quiet", "--convergence"]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "[[beam]]" in err and "--convergence" in err


def test_modes_below_f_max_and_a_sweep_over_a_beam_key():
    """modes.f_max keeps the beam modes below it (7.66 and 15.2 Hz below 20 Hz); the sweep's
    key paths reach [[beam]] like any table (asekit.sweep.set_key, then the loader's checks)."""
    from asekit.sweep import set_key
    d = _raw()
    d["modes"] = {"f_max": 20.0}
    assert P.modal_model(case_from_dict(d)).frequencies_hz.size == 2
    d = _raw()
    set_key(d, "beam[0].gj", 2 * 0.987e6)
    f = P.modal_model(case_from_dict(d)).frequencies_hz
    assert f[1] > P.modal_model(load_case(GOLAND)).frequencies_hz[1] * 1.2   # stiffer torsion
    set_key(d, "beam[0].gj", -1.0)
    _refused(d, "beam[0].gj must be > 0")
