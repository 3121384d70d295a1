"""The case layer: case-file checking, the pipeline on the reference fin, and the shipped
validation cases (AGARD 445.6 weakened wing 3, NAFEMS FV16) against their published values."""

from __future__ import annotations

import copy
import dataclasses
import math
import tomllib

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, load_case
from asekit.case import pipeline as P
from asekit.util.paths import CASES_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"
AGARD = CASES_DIR / "agard445_6.toml"
FV16 = CASES_DIR / "nafems_fv16.toml"


#: rebuilt GAF databases go to a session temporary folder (tests/conftest.py)
pytestmark = pytest.mark.usefixtures("session_gaf_cache")


def _fin_dict() -> dict:
    with open(FIN, "rb") as fh:
        return tomllib.load(fh)


# ---------------------------------------------------------------------------------------------
# the reference fin through the pipeline
# ---------------------------------------------------------------------------------------------
def test_fin_case_reads_the_shipped_database():
    """The fin's case (FN2 modal model, mesh-rule boxes, automatic k) has the fingerprint of the
    shipped GAF database ``data/gaf_fin.npz``: the pipeline reads it (the autouse fixture points
    the user cache at an empty folder, so nothing else could match), and its p-k at M 0.75, sea
    level, starts stable and finds flutter inside the sweep."""
    from asekit.aero.gaf import GAF_FILE
    from asekit.util.cache import load_npz
    case = load_case(FIN)
    arrays, meta = load_npz(GAF_FILE)
    db = P.gaf_database(case, progress=False)
    assert db.metadata["fingerprint"] == meta["fingerprint"]
    assert np.array_equal(db.Q, arrays["Q"]) and np.array_equal(db.k, arrays["k"])
    assert np.array_equal(db.machs, case.aero.machs)
    r = P.analyse_condition(case, db, 0.75, P.flight_conditions(case)[0])
    assert not r.unstable_at_start
    assert case.flight.velocities[0] < r.flutter.speed < case.flight.velocities[-1]


def test_fin_match_point_and_margin():
    """The sea-level match Mach interpolates U_f(M)/a = M between the analysed Machs; the margin
    at the envelope top (M 0.6) is U_f(0.6)/U(0.6) - 1, both checked against the raw p-k."""
    case = load_case(FIN)
    fa = P.flutter(case)
    sl = [r for r in fa.results if r.condition.altitude == 0.0]
    a0 = sl[0].condition.speed_of_sound
    m06 = next(r for r in sl if r.mach == 0.6)
    margin = next(m for m in fa.margins if m["altitude_m"] == 0.0)
    assert margin["margin"] == pytest.approx(m06.flutter.speed / (0.6 * a0) - 1, rel=1e-12)
    mm = next(m for m in fa.match_points if m["altitude_m"] == 0.0)["matched_mach"]
    assert 0.6 < mm < 0.75
    # at the match the flutter Mach equals the flight Mach (linear in between)
    m075 = next(r for r in sl if r.mach == 0.75)
    f = lambda m: np.interp(m, [0.6, 0.75], [m06.flutter.speed, m075.flutter.speed]) / a0 - m
    assert abs(f(mm)) < 1e-12


def test_first_point_instability_is_reported():
    """A sweep that starts above the flutter speed says so instead of returning no flutter."""
    d = _fin_dict()
    d["flight"]["velocities"] = {"min": 250.0, "max": 300.0, "step": 10.0}
    d["aero"]["machs"] = [0.4, 0.5, 0.6, 0.75]
    case = case_from_dict(d)
    r = P.analyse_condition(case, P.gaf_database(case, progress=False), 0.75,
                            P.flight_conditions(case)[0])
    assert r.unstable_at_start and r.start_mode == 1


# ---------------------------------------------------------------------------------------------
# validation cases
# ---------------------------------------------------------------------------------------------
def test_nafems_fv16_frequencies():
    # NAFEMS R0015 (1987), test FV16: cantilevered square plate 10 x 10 x 0.05 m, E 200 GPa,
    # nu 0.3, rho 8000 kg/m^3: 0.421, 1.029, 2.582, 3.306, 3.753, 6.555 Hz
    ref = np.array([0.421, 1.029, 2.582, 3.306, 3.753, 6.555])
    f = P.modal_model(load_case(FV16)).frequencies_hz
    assert np.all(np.abs(f / ref - 1) < 0.02), f


def test_agard445_6_weakened_3():
    """Yates (1987), AGARD R-765: measured modes 9.60, 38.10, 50.70, 98.50 Hz; flutter at
    M 0.499 (rho 0.4278 kg/m^3): FSI 0.4459, omega_f/omega_alpha 0.5353 (omega_alpha 2 pi 38.10).
    Expect modes within 5 %, FSI within 7 %, the frequency ratio within 15 % (issue 9)."""
    case = load_case(AGARD)
    f = P.modal_model(case).frequencies_hz
    assert np.all(np.abs(f / np.array([9.60, 38.10, 50.70, 98.50]) - 1) < 0.05), f
    fa = P.flutter(case)
    r = fa.results[0]
    fs = case.flutter_index
    fsi = r.flutter.speed / (fs.semichord * 2 * math.pi * fs.f_alpha * math.sqrt(fs.mass_ratio))
    assert fsi == pytest.approx(0.4459, rel=0.07)
    assert r.flutter.frequency_hz / fs.f_alpha == pytest.approx(0.5353, rel=0.15)
    assert r.flutter.mode == 0                     # the first bending-torsion coalescence


# ---------------------------------------------------------------------------------------------
# bad case files: one clear error naming the key path
# ---------------------------------------------------------------------------------------------
def _edit(path, value):
    def f(d):
        *head, last = path
        t = d
        for k in head:
            t = t[k]
        if value is KeyError:
            del t[last]
        else:
            t[last] = value
    return f


BAD = [
    (_edit(("panel", 0, "tip_chord"), -0.1), r"panel\[0\]\.tip_chord must be > 0 m, got -0\.1"),
    (_edit(("thickness", "root"), -0.004), r"thickness\.root must be > 0 m"),
    (_edit(("material", "youngs_modulus"), KeyError), r"material\.youngs_modulus is missing"),
    (_edit(("material", "youngs_modulu"), 7e10), r"material\.youngs_modulu is not a known key"),
    (_edit(("aero", "machs"), [0.5, 1.2]),
     r"aero\.machs\[1\] = 1.2 with aero\.method = 'dlm': mach must be < 1 for the DLM"),
    (_edit(("modes",), {"count": 0}), r"modes\.count must be an integer in \[1, 500\]"),
    (_edit(("panel", 0, "tip_leading_edge"), [0.078, -0.15]), r"crossed or has zero span"),
    (_edit(("panel", 0, "n_chord"), 6.5), r"panel\[0\]\.n_chord must be an integer"),
    (_edit(("support", "axis_point"), [0.3, 0.0]), r"support\.axis_point .* on the root chord"),
    (_edit(("thickness", "profile"), "NACA 2412"), r"thickness\.profile: .*symmetric"),
    (_edit(("flight", "velocities"), {"min": 300.0, "max": 100.0, "step": 2.0}),
     r"flight\.velocities\.max must be > min"),
    (_edit(("aero", "kernel"), "cubic"), r"aero\.kernel must be one of"),
    (_edit(("damping",), {"modal_damping_ratio": 1.5}), r"damping\.modal_damping_ratio"),
    (_edit(("case",), {"name": "x", "referense": "typo"}), r"case\.referense is not a known key"),
    (_edit(("actuator", "condition", "mach"), 0.3), r"actuator\.condition\.mach must lie within"),
]


@pytest.mark.parametrize("edit, message", BAD)
def test_bad_case_is_refused_with_key_path(edit, message):
    d = _fin_dict()
    edit(d)
    with pytest.raises(CaseError, match=message):
        case_from_dict(d)


def test_modes_count_beyond_mesh_refused():
    d = _fin_dict()
    d["modes"] = {"count": 400}
    with pytest.raises(CaseError, match="modes.count"):
        P.modal_model(case_from_dict(d))


CLI_BAD = [  # issue 9: missing key, unknown key, negative thickness, crossed planform,
             # Mach >= 1 for the DLM, zero modes
    (("youngs_modulus = 70.0e9", ""), "material.youngs_modulus is missing"),
    (("poisson_ratio = 0.3 ", "poisson_ratio = 0.3\nyoungs_modulos = 7e10 "),
     "material.youngs_modulos is not a known key"),
    (("root = 0.004", "root = -0.004"), "thickness.root must be > 0 m, got -0.004"),
    (("tip_leading_edge = [0.078, 0.150]", "tip_leading_edge = [0.078, -0.150]"),
     "planform is crossed or has zero span"),
    (("machs = [0.4, 0.5, 0.6, 0.75]", "machs = [0.4, 0.5, 0.6, 1.2]"),
     "aero.machs[3] = 1.2 with aero.method = 'dlm': mach must be < 1 for the DLM"),
    (("f_max = 1000.0                       # Hz (thesis Sec. 3.1.1)", "count = 0"),
     "modes.count must be an integer in [1, 500], got 0"),
    (("tip_chord = 0.078", "tip_chord = -0.1"), "panel[0].tip_chord must be > 0 m, got -0.1"),
]


@pytest.mark.parametrize("edit, message", CLI_BAD)
def test_cli_bad_case_one_line_exit_2(tmp_path, capsys, edit, message):
    from asekit.cli.main import main
    text = FIN.read_text()
    assert edit[0] in text
    bad = tmp_path / "bad.toml"
    bad.write_text(text.replace(edit[0], edit[1], 1))
    assert main(["analyse", str(bad)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message in err[0], err


def test_cli_missing_case_file(tmp_path, capsys):
    from asekit.cli.main import main
    assert main(["analyse", str(tmp_path / "missing.toml")]) == 2
    assert "not found" in capsys.readouterr().err


def test_cli_analyse_json(tmp_path):
    import json

    from asekit.cli.main import main
    out = tmp_path / "out.json"
    assert main(["analyse", str(FV16), "--json", str(out), "--quiet"]) == 0
    s = json.loads(out.read_text())
    assert s["case"] == "nafems_fv16" and len(s["modes"]["frequencies_hz"]) == 6
    assert set(s["flutter"][0]) >= {"mach", "altitude_m", "density", "speed_ms", "frequency_hz",
                                    "mode"}
    assert "flutter" in s["seconds"]


# ---------------------------------------------------------------------------------------------
# the model features a case can express
# ---------------------------------------------------------------------------------------------
def test_orthotropic_with_isotropic_constants_equals_isotropic():
    from asekit.geometry import Material, OrthotropicMaterial
    iso = Material(70e9, 0.3, 2700.0)
    G = 70e9 / 2.6
    for ang in (0.0, 0.3, 1.2):
        ortho = OrthotropicMaterial(70e9, 70e9, G, 0.3, 2700.0, fibre_angle=ang)
        assert np.allclose(ortho.plane_stress_matrix(), iso.plane_stress_matrix(), rtol=1e-12,
                           atol=1e-12 * 7.7e10)
        assert np.allclose(ortho.transverse_shear_matrix(), iso.transverse_shear_matrix(),
                           rtol=1e-12, atol=1e-12 * 2.7e10)


def test_orthotropic_rotation():
    """Turning the fibres by 90 deg is the same as swapping E1/E2 (and G13/G23); strain energy
    is invariant: a strain rotated with the fibres gives the same energy."""
    from asekit.geometry import OrthotropicMaterial
    a = OrthotropicMaterial(3.15e9, 0.42e9, 0.44e9, 0.31, 382.0, g13=0.3e9, g23=0.2e9,
                            fibre_angle=math.pi / 2)
    b = OrthotropicMaterial(0.42e9, 3.15e9, 0.44e9, 0.31 * 0.42 / 3.15, 382.0, g13=0.2e9,
                            g23=0.3e9)
    assert np.allclose(a.plane_stress_matrix(), b.plane_stress_matrix(), rtol=1e-12, atol=1e-3)
    assert np.allclose(a.transverse_shear_matrix(), b.transverse_shear_matrix())
    th = 0.7
    c = OrthotropicMaterial(3.15e9, 0.42e9, 0.44e9, 0.31, 382.0, fibre_angle=th)
    c0 = dataclasses.replace(c, fibre_angle=0.0)
    e_mat = np.array([1e-4, -3e-5, 2e-5])         # strain in fibre axes
    co, si = math.cos(th), math.sin(th)
    T = np.array([[co * co, si * si, co * si], [si * si, co * co, -co * si],
                  [-2 * co * si, 2 * co * si, co * co - si * si]])
    e_xy = np.linalg.solve(T, e_mat)
    assert e_xy @ c.plane_stress_matrix() @ e_xy == pytest.approx(
        e_mat @ c0.plane_stress_matrix() @ e_mat, rel=1e-12)


def test_profile_thickness_per_integration_point():
    """A biconvex plate's FE mass is rho (2/3) t_max A (the section area of t 4 xi (1 - xi)),
    which a per-element (centroid) thickness would not give on a coarse mesh."""
    from asekit.geometry import Material, Planform, Thickness
    from asekit.structure.assembly import assemble
    from asekit.structure.mesh import structured_mesh
    pf = Planform((0.0, 0.0), 1.0, (0.0, 2.0), 1.0)
    mesh = structured_mesh(pf, Thickness(0.01, 0.01, "biconvex"), 8, 4)
    _, M = assemble(mesh, Material(70e9, 0.3, 1000.0))
    one = np.zeros(M.shape[0])
    one[0::3] = 1.0
    assert one @ (M @ one) == pytest.approx(1000.0 * 0.01 * 2.0 * 2 / 3, rel=2e-4)


@pytest.mark.parametrize("name, peak_x, mean", [("NACA 0012", 0.30, 0.685), ("biconvex", 0.5, 2 / 3),
                                                 ("NACA 65A004", 0.40, 0.675)])
def test_named_profiles(name, peak_x, mean):
    # NACA 00xx: maximum thickness at 30 % chord (Abbott & von Doenhoff 1959, Sec. 6.4);
    # 65A series: at 40 % (the 65A010 table); biconvex: mid-chord
    from asekit.geometry import chordwise_profile
    p = chordwise_profile(name)
    x = np.array(p.x_over_c)
    assert x[int(np.argmax(p.t_over_tmax))] == pytest.approx(peak_x, abs=0.02)
    assert max(p.t_over_tmax) == pytest.approx(1.0, abs=2e-3)
    assert p.mean() == pytest.approx(mean, rel=5e-3)


def test_point_mass_adds_its_mass_and_lowers_frequencies():
    d = _fin_dict()
    base = case_from_dict(d)
    d["point_mass"] = [{"position": [0.10, 0.10], "mass": 0.05}]
    heavy = case_from_dict(d)
    _, M0 = P.mass_and_stiffness(base)
    _, M1 = P.mass_and_stiffness(heavy)
    one = np.zeros(M0.shape[0])
    one[0::3] = 1.0
    assert one @ ((M1 - M0) @ one) == pytest.approx(0.05, rel=1e-12)
    f0 = P.modal_model(base).frequencies_hz[1:]
    f1 = P.modal_model(heavy).frequencies_hz[1:]
    assert np.all(f1 < f0)


def test_bending_stiffness_limit():
    """A connection stiff in bending about x returns the rigidly held shaft; a soft one lowers
    every frequency (Rayleigh: less stiffness, same mass)."""
    d = _fin_dict()
    ref = P.modal_model(case_from_dict(d)).frequencies_hz
    d["support"]["bending_stiffness"] = 1e9
    stiff = P.modal_model(case_from_dict(d)).frequencies_hz
    d["support"]["bending_stiffness"] = 50.0
    soft = P.modal_model(case_from_dict(d)).frequencies_hz
    assert np.allclose(stiff[1:], ref[1:], rtol=1e-4)
    assert np.all(soft[1:] <= ref[1:] * (1 + 1e-9)) and soft[1] < 0.99 * ref[1]


def test_two_panels_equal_one():
    """A rectangle split into two spanwise panels (same nodes) has the same modes."""
    d = {"case": {"name": "plate"},
         "panel": [{"root_leading_edge": [0.0, 0.0], "root_chord": 0.3,
                    "tip_leading_edge": [0.0, 0.5], "tip_chord": 0.3, "n_chord": 6,
                    "n_span": 8}],
         "thickness": {"root": 0.003, "tip": 0.003},
         "material": {"youngs_modulus": 70e9, "poisson_ratio": 0.3, "density": 2700.0},
         "support": {"kind": "clamped_root"}, "modes": {"count": 4},
         "aero": {"machs": [0.5], "reference_semichord": 0.15},
         "flight": {"densities": [1.2], "velocities": {"min": 10.0, "max": 50.0, "step": 10.0}}}
    one = P.modal_model(case_from_dict(d)).frequencies_hz
    d2 = copy.deepcopy(d)
    d2["panel"] = [dict(d["panel"][0], tip_leading_edge=[0.0, 0.25], n_span=4),
                   dict(d["panel"][0], root_leading_edge=[0.0, 0.25], n_span=4)]
    two = P.modal_model(case_from_dict(d2)).frequencies_hz
    assert np.allclose(one, two, rtol=1e-10)


def test_wall_symmetry_variant_raises_the_hinge_moment(fin_variant, fin_gafs):
    """``aero.symmetry = "wall"`` reaches the GAF database: a reflection plane at the fin root
    (the fin on a wall, its image closing the root gap) raises the steady de-centring hinge
    moment Re Q_cc at every Mach, by more than 20 % as on 8 x 6 boxes (tests/aero/test_gaf.py), and
    the database is not the isolated fin's (its fingerprint records the symmetry)."""
    db = P.gaf_database(fin_variant(symmetry="wall"), progress=False)
    assert db.metadata["symmetric"] is True and fin_gafs.metadata["symmetric"] is False
    assert np.array_equal(db.machs, fin_gafs.machs) and np.array_equal(db.k, fin_gafs.k)
    assert np.all(db.Q[:, 0, 0, 0].real > 1.2 * fin_gafs.Q[:, 0, 0, 0].real)


def test_modal_damping_raises_flutter_speed():
    d = _fin_dict()
    d["aero"]["machs"] = [0.4, 0.5, 0.6, 0.75]
    base = case_from_dict(d)
    d["damping"] = {"modal_damping_ratio": 0.01}
    damped = case_from_dict(d)
    m = P.modal_model(damped)
    w = 2 * np.pi * m.frequencies_hz[1:]
    assert np.allclose(np.diag(m.C)[1:], 2 * 0.01 * w)       # C = 2 zeta omega (M_ss = I)
    db = P.gaf_database(base, progress=False)
    c0 = P.flight_conditions(base)[0]
    u0 = P.analyse_condition(base, db, 0.75, c0).flutter.speed
    u1 = P.analyse_condition(damped, db, 0.75, c0, m).flutter.speed
    assert u1 > u0 + 5.0


def test_documented_example_is_a_valid_case():
    """The commented example of docs/case-format.md parses and builds its modal model."""
    import re
    from pathlib import Path
    doc = (Path(__file__).resolve().parents[2] / "docs" / "case-format.md").read_text()
    block = re.search(r"```toml\n(.*?)```", doc, re.S).group(1)
    case = case_from_dict(tomllib.loads(block))
    m = P.modal_model(case)
    assert m.n_rigid == 1 and len(m.frequencies_hz) == 6 and np.all(np.diag(m.C)[1:] > 0)


def _plate_dict(support, machs=(0.5,), method="dlm"):
    return {"case": {"name": "plate"},
            "panel": [{"root_leading_edge": [0.0, 0.0], "root_chord": 0.4,
                       "tip_leading_edge": [0.0, 0.4], "tip_chord": 0.4, "n_chord": 16,
                       "n_span": 16}],
            "thickness": {"root": 0.002, "tip": 0.002},
            "material": {"youngs_modulus": 70e9, "poisson_ratio": 0.3, "density": 2700.0},
            "support": support, "modes": {"count": 4},
            "aero": {"machs": list(machs), "reference_semichord": 0.2, "method": method,
                     "boxes": [{"n_chord": 8, "n_span": 8}],
                     "reduced_frequencies": [0.001, 0.1, 0.5]},
            "flight": {"densities": [1.2], "velocities": {"min": 100.0, "max": 400.0,
                                                          "step": 50.0}}}


def test_edges_support_simply_supported_square_plate():
    """Simply supported square plate: f_mn = (pi / 2) (m^2 + n^2) / a^2 sqrt(D / (rho h))
    (Leissa 1969, NASA SP-160, Sec. 4.1): modes (1,1), (1,2)/(2,1), (2,2)."""
    ss = {"kind": "edges", "root": "simply_supported", "tip": "simply_supported",
          "leading_edge": "simply_supported", "trailing_edge": "simply_supported"}
    f = P.modal_model(case_from_dict(_plate_dict(ss))).frequencies_hz
    a, h, E, nu, rho = 0.4, 0.002, 70e9, 0.3, 2700.0
    D = E * h**3 / (12 * (1 - nu**2))
    ref = np.pi / 2 / a**2 * np.sqrt(D / (rho * h)) * np.array([2, 5, 5, 8])
    # 16 x 16 MITC4: +0.4 % on (1,1), about +1.6 % on the higher modes (discretisation)
    assert abs(f[0] / ref[0] - 1) < 0.005 and np.allclose(f, ref, rtol=0.02), (f, ref)


def test_edges_all_free_refused():
    free = {"kind": "edges", "root": "free"}
    with pytest.raises(CaseError, match="all four edges free"):
        case_from_dict(_plate_dict(free))


def test_aero_method_and_mach_range():
    clamped = {"kind": "clamped_root"}
    with pytest.raises(CaseError, match=r"aero\.machs\[0\] = 2 with aero\.method = 'dlm': mach "
                                        r"must be < 1 for the DLM \(subsonic: 0 <= M < 1\)"):
        case_from_dict(_plate_dict(clamped, machs=(2.0,)))
    with pytest.raises(CaseError, match=r"aero\.method must be one of 'auto', 'dlm', "
                                        r"'supersonic', 'piston', 'tsd', got 'zona51'"):
        case_from_dict(_plate_dict(clamped, method="zona51"))
    with pytest.raises(CaseError, match=r"aero\.machs\[1\] = 1 with aero\.method = 'auto'"):
        case_from_dict(_plate_dict(clamped, machs=(0.5, 1.0), method="auto"))
    with pytest.raises(CaseError, match=r"aero\.machs\[0\] = 0\.5 with aero\.method = 'supersonic'"):
        case_from_dict(_plate_dict(clamped, machs=(0.5,), method="supersonic"))
    case = case_from_dict(_plate_dict(clamped, machs=(0.5, 2.0), method="auto"))
    db = P.gaf_database(case, progress=False)
    assert db.Q.shape[:2] == (2, 3) and np.all(np.isfinite(db.Q))
