"""Stick-model decks (asekit.io.bdf_beam): CBAR/PBAR frame import against analytic beam
frequencies, rotation invariance and MSC's PT145 deck against its f06.

References
----------
- Cantilever Euler-Bernoulli beam: f_n = (beta_n L)^2 / (2 pi L^2) sqrt(E I / m),
  beta_1 L = 1.875104, beta_2 L = 4.694091 (Blevins, *Formulas for Natural Frequency and Mode
  Shape*, 1979, Table 8-1); axial: f_1 = sqrt(E / rho) / (4 L) (Blevins Table 8-16).
- PT145 (data/benchmarks/pt145/README.md): MSC Nastran 2020 f06, REAL EIGENVALUES table,
  CYCLES column of modes 1-6.
- BAH plane (data/benchmarks/bah_plane/README.md): MSC Nastran f06, REAL EIGENVALUES table,
  CYCLES column of modes 3-8.
"""

import os

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.io.bdf import BdfError  # noqa: E402
from asekit.io.bdf_beam import read_stick_deck, stick_modes  # noqa: E402
from asekit.util.paths import DATA_DIR  # noqa: E402

PT145 = DATA_DIR / "benchmarks" / "pt145" / "pt145.bdf"
BAH = DATA_DIR / "benchmarks" / "bah_plane" / "bah_plane_qhh.bdf"

# SI cantilever: steel bar, 1 m, 20 elements
E, NU, RHO, LEN, NEL = 2.0e11, 0.3, 7800.0, 1.0, 20
A, I1, I2, J = 1e-4, 2e-9, 8e-10, 1.5e-9


def _field(v) -> str:
    s = f"{v:.6g}" if isinstance(v, float) else str(v)
    return s.ljust(8)[:8] if len(s) <= 8 else f"{v:.2e}".replace("e", "").ljust(8)[:8]


def _card(*fields) -> str:
    return "".join(_field(f) for f in fields).rstrip()


def _cantilever(path, R=np.eye(3), extra=(), offt=""):
    """A cantilever CBAR deck along R's first row, plane-1 vector R's third row."""
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK"]
    for i in range(NEL + 1):
        x = (R[0] * LEN * i / NEL).tolist()
        lines.append(f"GRID,{i + 1},,{x[0]!r},{x[1]!r},{x[2]!r}")
    v = R[2].tolist()
    for i in range(NEL):
        lines.append(f"CBAR,{i + 1},1,{i + 1},{i + 2},{v[0]!r},{v[1]!r},{v[2]!r},{offt}")
    lines += [f"PBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}", f"MAT1,1,{E!r},,{NU!r},{RHO!r}",
              "SPC1,1,123456,1", "PARAM,COUPMASS,1", *extra, "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _rotation(a, b, c):
    ca, sa, cb, sb, cc, sc = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(c), np.sin(c)
    Rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    Rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    return (Rz @ Ry @ Rx).T                # rows: the rotated axes


def test_cantilever_cbar_matches_analytic_beam(tmp_path):
    modes = stick_modes(read_stick_deck(_cantilever(tmp_path / "c.bdf")), 16)
    m = RHO * A
    f = np.sort(modes.frequencies_hz)
    ref = sorted([1.875104 ** 2 / (2 * np.pi * LEN ** 2) * np.sqrt(E * I / m)
                  for I in (I1, I2)] + [4.694091 ** 2 / (2 * np.pi * LEN ** 2)
                                        * np.sqrt(E * I / m) for I in (I1, I2)])
    # Hermite elements converge as h^4: 20 elements are within 1e-5 for these modes
    np.testing.assert_allclose(f[:4], ref, rtol=1e-5)
    axial = np.sqrt(E / RHO) / (4 * LEN)
    assert np.min(np.abs(modes.frequencies_hz / axial - 1)) < 2e-3   # linear axial elements


def test_rotated_cantilever_has_the_same_frequencies(tmp_path):
    f0 = stick_modes(read_stick_deck(_cantilever(tmp_path / "a.bdf")), 8).frequencies_hz
    R = _rotation(0.7, -0.4, 1.1)
    f1 = stick_modes(read_stick_deck(_cantilever(tmp_path / "b.bdf", R)), 8).frequencies_hz
    np.testing.assert_allclose(f1, f0, rtol=1e-7)   # round-off of the rotation
    assert not np.allclose(R, np.eye(3))


def test_conm2_tip_mass_lowers_the_first_frequency_as_rayleigh(tmp_path):
    """A tip CONM2 of mass M_t: f = sqrt(3 EI / L^3 / (M_t + 0.2357 m L)) / (2 pi) (Blevins
    Table 8-1 case 'cantilever with end mass', Rayleigh; exact within 0.5 % for M_t >= m L)."""
    mt = 3 * RHO * A * LEN
    deck = _cantilever(tmp_path / "m.bdf", extra=(f"CONM2,99,{NEL + 1},,{mt!r}",))
    f = stick_modes(read_stick_deck(deck), 1).frequencies_hz[0]
    ref = np.sqrt(3 * E * I2 / LEN ** 3 / (mt + 0.2357 * RHO * A * LEN)) / (2 * np.pi)
    assert abs(f / ref - 1) < 5e-3


def test_pt145_modes_match_its_f06():
    """PT145 (PARAM COUPMASS 1: the consistent bar mass; the torsional inertia only from the
    CMASS2 cards) against the f06's eigenvalue table: the model is the same discretisation,
    so the tolerance is the f06's print precision (7 digits), taken as 1e-5."""
    f06 = [3.996147e1, 2.364137e2, 2.504423e2, 7.014011e2, 7.034198e2, 1.153105e3]
    modes = stick_modes(read_stick_deck(PT145, units="in-lbf-s"), 6)
    np.testing.assert_allclose(modes.frequencies_hz, f06, rtol=1e-5)


def test_refused_cards_and_fields_are_named(tmp_path):
    deck = _cantilever(tmp_path / "r.bdf", extra=("RBE1,500,1,123456,,,,,,", ",UM,2,123456",))
    with pytest.raises(BdfError, match=r"RBE1 \(x1, first id 500\)"):
        read_stick_deck(deck)
    deck = _cantilever(tmp_path / "o.bdf", offt="BGG")
    with pytest.raises(BdfError, match="CBAR 1: OFFT"):
        read_stick_deck(deck)
    deck = _cantilever(tmp_path / "cb.bdf", extra=("CBUSH,600,7,1,2,,,,0",
                                                    "PBUSH,7,K,1.0,1.0,1.0,1.0,1.0,1.0"))
    with pytest.raises(BdfError, match=r"CBUSH \(x1, first id 600\), PBUSH"):
        read_stick_deck(deck)
    deck = _cantilever(tmp_path / "rb.bdf", extra=("RBAR,501,1,2,123456,123456",))
    with pytest.raises(BdfError, match="RBAR 501: CNA"):
        read_stick_deck(deck)
    text = (tmp_path / "o.bdf").read_text().replace("CBAR,3,1,3,4,0.0,0.0,1.0,BGG",
                                                     "CBAR,3,1,3,4,0.0,0.0,1.0\n,,,0.0,0.1,0.0")
    (tmp_path / "w.bdf").write_text(text.replace("BGG", ""))
    with pytest.raises(BdfError, match="CBAR 3: offsets WA/WB"):
        read_stick_deck(tmp_path / "w.bdf")


# PT145 f06, FLUTTER SUMMARY POINT 2 (KE, M 0.45, density ratio 0.967), the mode that crosses:
# (k, V in/s, g, f Hz) rows; data/benchmarks/pt145/pt145_f06_excerpt.txt
PT145_POINT2 = np.array([
    [0.1429, 6112.9079, 1.0861521e-2, 134.24942], [0.1667, 5831.7574, -1.7230888e-2, 149.42071],
    [0.2000, 5412.4678, -3.8924506e-2, 166.40993], [0.1250, 6290.8529, 4.5013048e-2, 120.88529],
    [0.1000, 6438.5398, 1.3658872e-1, 98.978600]])
# POINT 1 and POINT 3 at k = 0.1 and 0.2 (V in/s, g, f Hz)
PT145_POINT1 = {0.1: (2869.9957, -0.25238915, 44.119966), 0.2: (1321.1585, -0.091635831, 40.619898)}
PT145_POINT3 = {0.1: (17339.353, -0.1253942, 266.55499), 0.2: (8230.6873, -0.057052865, 253.05797)}


def _pt145_flutter():
    from asekit.io.bdf_beam import stick_flutter
    return stick_flutter(PT145, units="in-lbf-s")


def test_pt145_ke_flutter_against_its_f06():
    """PT145's KE run from its deck (SPLINE2 beam spline, asekit's doublet lattice at the
    MKAERO1 k = 0.001, 0.1, 0.2, linear in k as IMETH = L) against the f06.

    The f06's crossing, interpolated linearly in g between its k = 0.1429 and 0.1667 rows (as
    asekit interpolates its own): V = 6004.2 in/s, f = 140.1 Hz. asekit gives 6094 in/s,
    136.5 Hz (+1.5 %, -2.5 %): within the issue's 3 %. The torsion-bending mode's damping is
    about 0.008 below the f06's at every k of the table (-0.0251 vs -0.0172 at k = 1/6), while
    modes 1 and 3 agree within 0.001 in g and 0.3 % in V: a difference of the two doublet
    lattices' unsteady pressure of the torsion mode, not of the structure (modes equal to 1e-6)
    or the spline (a box-centre downwash instead of the 3/4-chord one moves the crossing the
    other way, to 6174 in/s)."""
    from asekit.aeroelastic.nastran import crossings
    run = _pt145_flutter()
    (deck_flutter,) = run.results
    (res,) = deck_flutter.results
    req, rho = deck_flutter.request, res.density[0]
    assert req.method == "KE" and res.mach[0] == 0.45
    assert abs(rho / (0.967 * 1.145e-7 * 4.4482216152605 / 0.0254 ** 4) - 1) < 1e-12
    ks = res.k[:, 0]
    V = res.velocity / 0.0254
    for kk, v, g, f in PT145_POINT2:
        i = int(np.argmin(np.abs(ks - kk)))
        assert abs(V[i, 1] / v - 1) < 0.01, (kk, V[i, 1], v)
        assert abs(res.frequency_hz[i, 1] / f - 1) < 0.02, (kk, res.frequency_hz[i, 1], f)
        assert abs(res.damping_g[i, 1] - g) < 0.01, (kk, res.damping_g[i, 1], g)
    for col, table in ((0, PT145_POINT1), (2, PT145_POINT3)):
        for kk, (v, g, f) in table.items():
            i = int(np.argmin(np.abs(ks - kk)))
            assert abs(V[i, col] / v - 1) < 0.006
            assert abs(res.damping_g[i, col] - g) < 0.002
            assert abs(res.frequency_hz[i, col] / f - 1) < 0.006
    found = [c for c in crossings(res) if not c.unstable_at_first_point]
    assert [c.speed for c in deck_flutter.crossings] == [c.speed for c in found]
    assert [c.mode for c in found] == [1]
    t = 1.0861521e-2 / (1.0861521e-2 + 1.7230888e-2)
    v_f06 = 6112.9079 + t * (5831.7574 - 6112.9079)
    f_f06 = 134.24942 + t * (149.42071 - 134.24942)
    assert abs(found[0].speed / 0.0254 / v_f06 - 1) < 0.03
    assert abs(found[0].frequency_hz / f_f06 - 1) < 0.03


def test_spline2_fields_are_checked(tmp_path):
    text = PT145.read_text().replace("SPLINE2 100     101     101     124     100     .0 ",
                                     "SPLINE2 100     101     101     124     100     .5 ")
    (tmp_path / "p.bdf").write_text(text)
    from asekit.io.bdf_beam import stick_flutter
    with pytest.raises(BdfError, match="SPLINE2 100: DZ"):
        stick_flutter(tmp_path / "p.bdf", units="in-lbf-s")


def test_analyse_runs_the_pt145_deck(tmp_path, capsys):
    """``asekit analyse pt145.bdf``: the FLUTTER card's KE crossing as a JSON row (the same
    run as test_pt145_ke_flutter_against_its_f06; f06 6004.2 in/s, 140.1 Hz) and --report
    refused in one line."""
    import json

    from asekit.cli.main import main
    out = tmp_path / "pt145.json"
    assert main(["analyse", str(PT145), "--units", "in-lbf-s", "--quiet", "--json",
                 str(out)]) == 0
    s = json.loads(out.read_text())
    (row,) = s["flutter"]
    assert (row["method"], row["sid"], row["mode"]) == ("KE", 30, 2)
    assert abs(row["speed_ms"] / 0.0254 / 6004.2 - 1) < 0.03
    assert abs(row["frequency_hz"] / 140.1 - 1) < 0.03
    assert not row["unstable_at_first_point"]
    np.testing.assert_allclose(s["modes_hz"], [39.96147, 236.4137, 250.4423], rtol=1e-5)
    assert "FLUTTER SUMMARY" in capsys.readouterr().out
    assert main(["analyse", str(PT145), "--units", "in-lbf-s", "--report",
                 str(tmp_path / "r")]) == 2
    assert "--report" in capsys.readouterr().err


def test_beam_case_round_trip_through_a_cbar_deck(tmp_path):
    """A [[beam]] case (the Goland wing: mass axis aft of the elastic axis, consistent
    torsional inertia) written as CBAR/PBAR + CMASS2 and read back gives asekit's own beam
    matrices and modes (the reference: asekit.structure.beam, the case's model), to round-off;
    a swept beam with an offset point mass as well."""
    from stick_checks import assert_deck_is_the_beam

    from asekit.case import load_case
    from asekit.case import pipeline as pl
    from asekit.io.bdf_beam import write_beam_bdf
    from asekit.structure.beam import BeamSection, PointMass, straight_beam
    from asekit.util.paths import CASES_DIR

    goland = pl.case_beam(load_case(CASES_DIR / "goland_wing.toml"))
    sec = BeamSection(1e9, 2e6, 3e6, 5e7, 20.0, 4.0, -0.05)
    swept = straight_beam((0.3, 0.1), (np.sin(0.5), np.cos(0.5)), np.linspace(0, 4, 13), sec,
                          (PointMass(12, 5.0, (0.2, -0.1, 0.03), (0.1, 0.2, 0.3)),))
    for name, beam in (("goland", goland), ("swept", swept)):
        assert_deck_is_the_beam(read_stick_deck(write_beam_bdf(beam, tmp_path / f"{name}.bdf")),
                                beam)


def test_unconstrained_zero_stiffness_is_refused(tmp_path):
    """PT145 without its GRID PS: the in-plane DOFs have no stiffness (PBAR I2 = 0) and the
    modes are refused in one line instead of returning spurious zeros."""
    text = PT145.read_text().replace("1       126\n", "\n")
    (tmp_path / "free.bdf").write_text(text)
    sm = read_stick_deck(tmp_path / "free.bdf", units="in-lbf-s")
    with pytest.raises(BdfError, match="singular on its free DOFs"):
        stick_modes(sm, 3)


@pytest.mark.parametrize("link", ["RBE2,500,{tip},123456,{dep}", "RBAR,500,{tip},{dep},123456"])
def test_rigid_link_equals_the_offset_mass(tmp_path, link):
    """A CONM2 on a grid tied to the tip by an RBE2 / RBAR (the dependent grid's displacements
    in a rotated CD system) has the same modes as the CONM2 on the tip with the same offset
    (both are the rigid-link kinematics; Przemieniecki 1968 Sec. 11.7)."""
    tip, dep, off = NEL + 1, NEL + 2, (0.03, 0.2, 0.05)
    mt = 2 * RHO * A * LEN
    direct = _cantilever(tmp_path / "d.bdf", extra=(f"CONM2,99,{tip},,{mt!r},{off[0]!r},"
                                                    f"{off[1]!r},{off[2]!r}",))
    cd = "CORD2R,5,,0.0,0.0,0.0,0.3,0.4,0.8\n,0.9,-0.1,0.2"
    x = (LEN + off[0], off[1], off[2])
    linked = _cantilever(tmp_path / "l.bdf", extra=(
        cd, f"GRID,{dep},,{x[0]!r},{x[1]!r},{x[2]!r},5", f"CONM2,99,{dep},,{mt!r}",
        link.format(tip=tip, dep=dep)))
    f0 = stick_modes(read_stick_deck(direct), 8).frequencies_hz
    sm = read_stick_deck(linked)
    assert len(sm.rigid) == 6
    np.testing.assert_allclose(stick_modes(sm, 8).frequencies_hz, f0, rtol=1e-9)


def test_chained_rigid_links_equal_the_combined_offset_mass(tmp_path):
    """Two chained RBE2 (tip -> a grid in a rotated CD system -> the CONM2's grid, the middle
    grid dependent in one and independent in the other) carry the CONM2 as one offset mass at
    the tip with the summed offset: the reduced mass T^T M T equals the direct deck's to 1e-9
    (rigid kinematics compose: Przemieniecki 1968 Sec. 11.7), and so do the modes."""
    tip, mid, dep = NEL + 1, NEL + 2, NEL + 3
    o1, o2 = np.array([0.02, 0.15, -0.04]), np.array([0.01, 0.05, 0.09])
    off = (o1 + o2).tolist()
    mt = 2 * RHO * A * LEN
    direct = _cantilever(tmp_path / "d.bdf", extra=(f"CONM2,99,{tip},,{mt!r},{off[0]!r},"
                                                    f"{off[1]!r},{off[2]!r}",))
    cd = "CORD2R,5,,0.0,0.0,0.0,0.3,0.4,0.8\n,0.9,-0.1,0.2"
    xm, xd = (np.array([LEN, 0.0, 0.0]) + o1).tolist(), (np.array([LEN, 0.0, 0.0]) + off).tolist()
    linked = _cantilever(tmp_path / "l.bdf", extra=(
        cd, f"GRID,{mid},,{xm[0]!r},{xm[1]!r},{xm[2]!r},5",
        f"GRID,{dep},,{xd[0]!r},{xd[1]!r},{xd[2]!r}", f"CONM2,99,{dep},,{mt!r}",
        f"RBE2,501,{mid},123456,{dep}", f"RBE2,500,{tip},123456,{mid}"))
    sd, sl = read_stick_deck(direct), read_stick_deck(linked)
    assert len(sl.rigid) == 12
    assert all(i // 6 < NEL + 1 for _, row in sl.rigid for i, _ in row)  # only beam DOFs
    Md = sd.reduction().T @ sd.M @ sd.reduction()
    Ml = sl.reduction().T @ sl.M @ sl.reduction()
    np.testing.assert_allclose(Ml, Md, rtol=0, atol=1e-9 * np.abs(Md).max())
    np.testing.assert_allclose(stick_modes(sl, 8).frequencies_hz,
                               stick_modes(sd, 8).frequencies_hz, rtol=1e-9)


def test_rigid_link_cycle_is_refused(tmp_path):
    """Two RBE2 making each other's grid dependent (a cycle) are refused in one line naming
    both cards."""
    a, b = NEL + 2, NEL + 3
    deck = _cantilever(tmp_path / "c.bdf", extra=(
        f"GRID,{a},,1.1,0.0,0.0", f"GRID,{b},,1.2,0.0,0.0", f"CONM2,99,{b},,1.0",
        f"RBE2,500,{a},123456,{b}", f"RBE2,501,{b},123456,{a}"))
    with pytest.raises(BdfError, match=r"cycle.*RBE2 50[01].*RBE2 50[01]") as err:
        read_stick_deck(deck)
    assert "\n" not in str(err.value)


def test_free_free_bah_plane_modes_match_its_f06():
    """pyNastran's BAH plane deck (data/benchmarks/bah_plane/README.md): a free-free 2-DOF
    fuselage (plunge, pitch) with a CBAR wing, RBE2 mass arms and a chain of four RBAR to the
    tail (chained rigid elements). Its f06 (MSC Nastran, REAL EIGENVALUES, CYCLES): two
    rigid-body modes (< 3e-7 Hz, Nastran's round-off) and the elastic modes 3-8 below; same
    discretisation, so the tolerance is the print precision (7 digits), taken as 1e-5."""
    f06 = [2.454016, 3.753996, 8.702604, 9.002153, 14.50673, 22.15914]
    sm = read_stick_deck(BAH)
    assert len(sm.rigid) == 6 * (10 + 4)    # 5 RBE2 x 2 grids + 4 RBAR, 6 DOFs each
    f = stick_modes(sm, 8).frequencies_hz
    assert np.all(f[:2] < 1e-3)
    np.testing.assert_allclose(f[2:], f06, rtol=1e-5)


def test_orientation_vector_is_read_in_the_grids_cd_system(tmp_path):
    """The rotated cantilever again, its grids' displacements in a CORD2R along the rotated
    axes (CD) and the CBAR vector given there as (0, 0, 1) (MSC QRG CBAR: X1-X3 in GA's
    displacement system): the frequencies of the unrotated beam; given in basic components
    instead, plane 1 turns and they change."""
    R = _rotation(0.7, -0.4, 1.1)
    f0 = stick_modes(read_stick_deck(_cantilever(tmp_path / "a.bdf")), 6).frequencies_hz
    text = _cantilever(tmp_path / "r.bdf", R).read_text()
    a, c = R[2].tolist(), R[0].tolist()  # a point on the z axis and one in the x-z plane
    cord = f"CORD2R,7,,0.0,0.0,0.0,{a[0]!r},{a[1]!r},{a[2]!r}\n,{c[0]!r},{c[1]!r},{c[2]!r}"
    lines = []
    for line in text.splitlines():
        if line.startswith("GRID,"):
            line += ",7"
        elif line.startswith("CBAR,"):
            f = line.split(",")
            line = ",".join(f[:5] + ["0.0", "0.0", "1.0"] + f[8:])
        lines.append(line)
    lines.insert(lines.index("BEGIN BULK") + 1, cord)
    (tmp_path / "cd.bdf").write_text("\n".join(lines) + "\n")
    sm = read_stick_deck(tmp_path / "cd.bdf")
    np.testing.assert_allclose(sm.cd_axes[0], R, atol=1e-12)
    np.testing.assert_allclose(stick_modes(sm, 6).frequencies_hz, f0, rtol=1e-7)
    # mode 1 bends in plane 2 (I2 < I1): along e_z = e_x x v = R[0] x R[2] = -R[1], the CD y
    u = stick_modes(sm, 1).shapes[6 * NEL:6 * NEL + 3, 0]
    assert abs(u[1]) > 1e6 * max(abs(u[0]), abs(u[2]))
    (tmp_path / "basic.bdf").write_text("\n".join(lines).replace(",7\n", "\n") + "\n")
    u = stick_modes(read_stick_deck(tmp_path / "basic.bdf"), 1).shapes[6 * NEL:6 * NEL + 3, 0]
    # v = basic z: plane 2 is horizontal, mode 1 moves in the basic x-y plane (R[1] does not)
    assert abs(u[2]) < 1e-9 * np.linalg.norm(u) and abs(R[1, 2]) > 0.1
