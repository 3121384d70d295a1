"""No silent wrong answer, round 2 (issue 22): every failure after validation is a named error.

The reproducers of the issue, each refused by the loader with its key path and valid range
before any computation, or -- for a case built in Python past the loader -- re-raised at the
pipeline's door as a one-line :class:`asekit.case.SolverError` that says what to change."""

from __future__ import annotations

import dataclasses
import math
import tomllib

import numpy as np
import pytest

from asekit.atmosphere import MAX_ALTITUDE, standard_atmosphere
from asekit.case import CaseError, SolverError, case_from_dict, load_case, schema
from asekit.case import pipeline as P
from asekit.geometry import Material, Planform
from asekit.util.paths import CASES_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"
AGARD = CASES_DIR / "agard445_6.toml"


def _dict(path=FIN) -> dict:
    with open(path, "rb") as fh:
        return tomllib.load(fh)


def _refused(d: dict, *fragments: str) -> str:
    with pytest.raises(CaseError) as e:
        case_from_dict(d)
    msg = str(e.value)
    assert "\n" not in msg
    for f in fragments:
        assert f in msg, msg
    return msg


# ---- the atmosphere's range ------------------------------------------------------------------
def test_altitude_above_the_atmosphere_refused_by_the_loader():
    """Reproducer: flight.altitudes = [50000] passed the loader (up to 80 km) and failed in the
    atmosphere model (its layers end at 47 km)."""
    d = _dict(AGARD)
    del d["flight"]["densities"]
    d["flight"]["altitudes"] = [50000.0]
    _refused(d, "flight.altitudes[0]", "<= 47000 m", "50000")
    d["flight"]["altitudes"] = [MAX_ALTITUDE]           # the top is accepted and computable
    case = case_from_dict(d)
    (c,) = P.flight_conditions(case)
    assert c.density == pytest.approx(float(standard_atmosphere(MAX_ALTITUDE).density))
    fin = _dict()
    fin["flight"]["envelope"]["altitude"] = [0.0, 60000.0]
    _refused(fin, "flight.envelope.altitude[1]", "<= 47000 m")
    fin = _dict()
    fin["actuator"]["condition"]["altitude"] = 50000.0
    _refused(fin, "actuator.condition.altitude", "<= 47000 m")


def test_sweep_altitude_range_is_the_atmosphere_range():
    """sweep._check_condition allowed -1000..80000 m: it now uses the atmosphere's constants."""
    from asekit import sweep as S
    from asekit.atmosphere import MIN_ALTITUDE
    with pytest.raises(S.SweepError, match=r"parameter\[0\].*\[-5000, 47000\] m.*50000"):
        S._check_condition("parameter[0]", "flight.altitude", 50000.0)
    S._check_condition("x", "flight.altitude", MAX_ALTITUDE)
    S._check_condition("x", "flight.altitude", MIN_ALTITUDE)
    standard_atmosphere([MIN_ALTITUDE, MAX_ALTITUDE])       # both ends are computable


# ---- point masses on the planform ------------------------------------------------------------
def test_point_mass_off_the_planform_refused_by_the_loader():
    """Reproducer: a point mass at (5, 5) m passed the loader and failed in the assembly."""
    d = _dict()
    d["point_mass"] = [{"position": [0.05, 0.05], "mass": 0.01},
                       {"position": [5.0, 5.0], "mass": 0.01}]
    _refused(d, "point_mass[1].position [5.0, 5.0] m is off the planform", "y 0 to 0.15 m")
    # just outside the tip trailing edge corner (0.156, 0.15): off; the corner itself: on
    d["point_mass"] = [{"position": [0.156 + 1e-4, 0.15], "mass": 0.01}]
    _refused(d, "point_mass[0]")
    d["point_mass"] = [{"position": [0.156, 0.15], "mass": 0.01}]
    _, M = P.mass_and_stiffness(case_from_dict(d))       # the assembly accepts the corner
    _, M0 = P.mass_and_stiffness(case_from_dict(_dict()))
    assert (M - M0)[0::3, 0::3].sum() == pytest.approx(0.01, rel=1e-9)   # the w-w block: m


def test_point_mass_on_a_second_panel_accepted():
    d = _dict()
    p0 = dict(d["panel"][0], tip_leading_edge=[0.039, 0.075], tip_chord=0.117, n_span=4)
    p1 = dict(d["panel"][0], root_leading_edge=[0.039, 0.075], root_chord=0.117, n_span=4)
    d["panel"] = [p0, p1]
    d["point_mass"] = [{"position": [0.1, 0.14], "mass": 0.01}]
    case_from_dict(d)
    d["point_mass"] = [{"position": [0.03, 0.14], "mass": 0.01}]   # ahead of panel[1]'s LE
    _refused(d, "point_mass[0]")


# ---- memory of the DLM and structural matrices -----------------------------------------------
def test_200_x_200_boxes_refused_by_the_loader_with_the_count_that_fits():
    """Reproducer: 200 x 200 boxes gave the right 23.8 GiB estimate, as a traceback after the
    modes. 40000 boxes: 16 x 40000^2 B = 2.56e10 B = 23.8 GiB; 4 GiB holds sqrt(2^32 / 16) =
    16384 boxes."""
    d = _dict(AGARD)
    d["aero"]["boxes"] = [{"n_chord": 200, "n_span": 200}]
    _refused(d, "aero.boxes", "40000 boxes", "23.8 GiB", "at most 16384 boxes", "lower aero.boxes")
    d["aero"]["boxes"] = [{"n_chord": 128, "n_span": 128}]          # exactly the limit
    case_from_dict(d)


def test_automatic_boxes_refused_by_the_loader_naming_the_mesh_rule_keys():
    d = _dict()
    d["aero"]["f_max"] = 20000.0              # 20x the fin's: about 20^2 x 140 boxes
    _refused(d, "aero.boxes", "from the mesh rules", "aero.f_max")


def test_500_x_500_structural_mesh_refused_by_the_loader():
    """Reproducer: a 500 x 500 plate mesh ran SuperLU out of memory after 43 s."""
    d = _dict(AGARD)
    d["panel"][0].update(n_chord=500, n_span=500)
    msg = _refused(d, "n_chord", "n_span", "500 x 500 elements", "753003 dof",
                   "MAX_STRUCTURAL_BYTES")
    side = int(msg.split("(e.g. ")[1].split(" x ")[0])
    d["panel"][0].update(n_chord=side, n_span=side)                 # the size it names fits
    case_from_dict(d)


def test_structural_factor_estimate_matches_superlu():
    """The loader's estimate of the LU factor against SuperLU's own fill (the symmetric
    MMD_AT_PLUS_A factor asekit.structure.modes uses) on a mesh size outside the fit's points
    (30 x 50 elements; the fit used square meshes 20 to 160): within 25 %."""
    import scipy.sparse.linalg as spla
    case = load_case(AGARD)
    case = dataclasses.replace(case, panels=(dataclasses.replace(case.panels[0], n_chord=30,
                                                                 n_span=50),))
    s = P.supported_system(case)
    lu = spla.splu((s.K + s.M).tocsc(), permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                   options={"SymmetricMode": True})
    measured = 12.0 * (lu.L.nnz + lu.U.nnz)
    n_dof = 3 * 31 * 51                      # all nodes' dofs: the estimate the loader uses
    assert schema.structural_factor_bytes(n_dof) == pytest.approx(measured, rel=0.25)


# ---- mesh validity ---------------------------------------------------------------------------
@pytest.mark.parametrize("tip_x", [30.0, -100.0])
def test_folded_planform_refused_by_the_loader(tip_x):
    """Reproducer: a planform whose leading edge runs 30 m downstream over a 0.15 m span (all
    but folded onto itself) failed in the modal model ("rigid mode carries strain energy")."""
    d = _dict()
    d["panel"][0]["tip_leading_edge"] = [tip_x, 0.15]
    _refused(d, "panel[0]", "swept", "+-85 deg")


def test_85_deg_sweep_is_analysable():
    """Below the limit the modal model holds (its rigid-mode energy check passes)."""
    d = _dict()
    d["panel"][0]["tip_leading_edge"] = [0.15 * math.tan(math.radians(84.9)), 0.15]
    m = P.modal_model(case_from_dict(d))
    assert m.n_rigid == 1 and np.all(np.diff(m.frequencies_hz) > 0)


# ---- material ranges -------------------------------------------------------------------------
@pytest.mark.parametrize("key, value, fragment", [
    ("youngs_modulus", 1e-30, "material.youngs_modulus = 1e-30 Pa is outside"),
    ("density", 1e-30, "material.density = 1e-30 kg/m^3 is outside"),
    ("youngs_modulus", 1e14, "[10000, 1e+13] Pa"),
])
def test_material_far_outside_engineering_materials_refused(key, value, fragment):
    """Reproducer: a tiny modulus made ARPACK fail (error 3) after the loader."""
    d = _dict()
    d["material"][key] = value
    _refused(d, fragment)


def test_orthotropic_modulus_range_and_the_sign_message_kept():
    d = _dict(AGARD)
    d["material"]["g12"] = 1.0
    _refused(d, "material.g12 = 1 Pa is outside")
    d = _dict()
    d["material"]["youngs_modulus"] = -1.0       # the sign check comes first, as before
    _refused(d, "material.youngs_modulus must be > 0 Pa, got -1")


# ---- the pipeline's door ---------------------------------------------------------------------
def test_arpack_failure_of_a_python_built_case_is_a_solver_error():
    """A case built in Python skips the loader's ranges: ARPACK's error 3 on a 1e-30 Pa plate
    becomes a SolverError naming the step and the keys to check."""
    case = load_case(FIN)
    case = dataclasses.replace(case, material=Material(1e-30, 0.3, 2700.0))
    with pytest.raises(SolverError) as e:
        P.modal_model(case)
    msg = str(e.value)
    assert "\n" not in msg and msg.startswith("the modal model") and "ArpackError" in msg
    assert "check material (moduli, density)" in msg
    assert isinstance(e.value.__cause__, RuntimeError)


def test_folded_python_built_case_is_a_solver_error():
    case = load_case(FIN)
    p = case.panels[0]
    pf = Planform(p.planform.root_le, p.planform.root_chord, (30.0, 0.15), p.planform.tip_chord)
    case = dataclasses.replace(case, panels=(dataclasses.replace(p, planform=pf),))
    with pytest.raises(SolverError, match="rigid mode carries strain energy.*panel"):
        P.modal_model(case)


def test_door_wraps_linalg_and_memory_errors_and_passes_input_errors(monkeypatch):
    case = load_case(AGARD)
    calls = {"n": 0}

    def fail(*a, **k):
        calls["n"] += 1
        raise [np.linalg.LinAlgError("Singular matrix"), MemoryError(),
               CaseError("aero.x is wrong"), ValueError("velocities must be > 0")][calls["n"] - 1]

    monkeypatch.setattr(P, "flutter_method", lambda name: type("M", (), {
        "needs_rfa": False, "solve": staticmethod(fail)}))
    monkeypatch.setattr(P, "modal_model", lambda c: None)
    gaf = type("G", (), {"at": lambda self, m: None})()
    cond = P.FlightCondition(None, 0.4, None)
    with pytest.raises(SolverError, match=r"the flutter solution failed \(LinAlgError: "
                                          r"Singular matrix\): check flight.velocities"):
        P.analyse_condition(case, gaf, 0.499, cond)
    with pytest.raises(SolverError, match=r"MemoryError: out of memory"):
        P.analyse_condition(case, gaf, 0.499, cond)
    with pytest.raises(CaseError, match="aero.x is wrong"):
        P.analyse_condition(case, gaf, 0.499, cond)
    with pytest.raises(ValueError, match="velocities must be > 0") as e:
        P.analyse_condition(case, gaf, 0.499, cond)
    assert not isinstance(e.value, SolverError)


def test_door_keeps_the_memo_and_the_doctests():
    """The decorator sits under the memo: cache_clear still works, docstrings are kept."""
    assert callable(P.modal_model.cache_clear) and callable(P.box_mesh.cache_clear)
    assert "Examples" in P.modal_model.__doc__ and P.flutter.__name__ == "flutter"


# ---- file encodings and kinds ----------------------------------------------------------------
def test_utf8_with_bom_is_read(tmp_path):
    """Reproducer: a UTF-8 file with a byte-order mark was refused as invalid TOML."""
    f = tmp_path / "bom.toml"
    f.write_bytes(b"\xef\xbb\xbf" + FIN.read_bytes())
    assert load_case(f) == load_case(FIN)


def test_latin1_file_is_one_line_error(tmp_path):
    """Reproducer: a Latin-1 file raised UnicodeDecodeError."""
    f = tmp_path / "latin1.toml"
    text = FIN.read_text()
    line = text[:text.index("aluminium")].count("\n") + 1
    f.write_bytes(text.replace("aluminium", "alumínium").encode("latin-1"))   # i acute: 0xed
    with pytest.raises(CaseError, match=rf"latin1.toml is not UTF-8 \(byte 0xed on line {line}\):"
                                        r" save it as UTF-8$"):
        load_case(f)


def test_directory_as_case_is_one_line_error(tmp_path):
    """Reproducer: a directory given as the case raised IsADirectoryError."""
    with pytest.raises(CaseError, match="is a directory, not a TOML file"):
        load_case(tmp_path)
