"""CBEAM / PBEAM / PBARL in stick-model decks (asekit.io.bdf_beam, issue 24).

References
----------
- A CBEAM with a constant-section PBEAM and K1 = K2 = 0.0 (MSC Nastran Quick Reference Guide,
  PBEAM: "K1, K2 ... 0.0: shear flexibility neglected") is the same Euler-Bernoulli element as
  a CBAR with the PBAR of the same values: their matrices agree to round-off.
- PBARL closed forms (MSC QRG PBARL figures for the dimensions): rectangle, circle and tube
  second moments (any statics text); torsion constant of a square, J = 0.1406 a^4 (Roark,
  *Formulas for Stress and Strain*, 7th ed., Table 10.7 case 4: K = 2.25 (a/2)^4); a thin
  square box of mid-line side s and wall t, J = t s^3 (Bredt-Batho, 4 A_m^2 t / perimeter).
- Cantilever Euler-Bernoulli beam: f_1 = 1.875104^2 / (2 pi L^2) sqrt(E I / m) (Blevins,
  *Formulas for Natural Frequency and Mode Shape*, 1979, Table 8-1).
- The Goland wing (data/cases/goland_wing.toml): asekit's own [[beam]] model is the reference
  of its CBEAM deck (the deck is that model written out), to round-off.
"""

import os

import numpy as np
import pytest

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.io.bdf import BdfError  # noqa: E402
from asekit.io.bdf_beam import pbarl_section, read_stick_deck, stick_modes  # noqa: E402

E, NU, RHO, LEN, NEL = 2.0e11, 0.3, 7800.0, 1.0, 20
A, I1, I2, J = 1e-4, 2e-9, 8e-10, 1.5e-9
PBEAM_TAIL = (",0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0", ",YESA,1.0", ",0.0,0.0")


def _deck(path, element_lines, prop_lines, extra=()):
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK"]
    lines += [f"GRID,{i + 1},,{LEN * i / NEL!r},0.0,0.0" for i in range(NEL + 1)]
    lines += [*element_lines, *prop_lines, f"MAT1,1,{E!r},,{NU!r},{RHO!r}",
              "SPC1,1,123456,1", "PARAM,COUPMASS,1", *extra, "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _elements(card, tail=""):
    return [f"{card},{i + 1},1,{i + 1},{i + 2},0.0,0.3,1.0{tail}" for i in range(NEL)]


def _pbeam(k="0.0,0.0", a2=None):
    end_b = ",YESA,1.0" if a2 is None else f",YES,1.0,{a2!r},{I1!r},{I2!r},0.0,{J!r}"
    return [f"PBEAM,1,1,{A!r},{I1!r},{I2!r},0.0,{J!r}", PBEAM_TAIL[0], end_b, f",{k}"]


def test_cbeam_cantilever_equals_the_cbar_one_but_its_twist_mass(tmp_path):
    """Same stiffness; the CBEAM's mass adds the polar moment rho (I1 + I2) on the twist,
    consistent (rho I_p h / 6 [[2, 1], [1, 2]] per element), which the CBAR has not
    (Simcenter Nastran's modes of data/benchmarks/beam_modes need it on the CBEAM only)."""
    bar = read_stick_deck(_deck(tmp_path / "bar.bdf", _elements("CBAR"),
                                [f"PBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}"]))
    beam = read_stick_deck(_deck(tmp_path / "beam.bdf", _elements("CBEAM"), _pbeam()))
    assert np.abs(beam.K - bar.K).max() <= 1e-9 * np.abs(bar.K).max()
    polar = np.zeros_like(bar.M)
    h = LEN / NEL
    for e in range(NEL):
        d = [6 * e + 3, 6 * e + 9]                   # the twists (basic R1: the beam is along x)
        polar[np.ix_(d, d)] += RHO * (I1 + I2) * h / 6 * np.array([[2.0, 1.0], [1.0, 2.0]])
    assert np.abs(beam.M - bar.M - polar).max() <= 1e-9 * np.abs(bar.M).max()
    assert np.abs(polar).max() > 1e-6 * np.abs(bar.M).max()
    assert "20 CBEAM" in beam.notes[0]


@pytest.mark.parametrize("element,props", [
    ("CBEAM", _pbeam(k="0.8,0.6")),
    ("CBAR", [f"PBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}", ",,,,,,,,", ",0.8,0.6"])])
def test_shear_flexible_cantilever_tip_deflection(tmp_path, element, props):
    """K1 / K2 > 0: the shear-flexible (Timoshenko) bar, exact for an end load: tip deflection
    P L^3 / (3 E I) + P L / (K G A) in each plane (Przemieniecki 1968, Eq. 5.116 with Phi;
    G = E / (2 (1 + nu)) from MAT1)."""
    sm = read_stick_deck(_deck(tmp_path / "s.bdf", _elements(element), props))
    free = sm.free
    G = E / (2 * (1 + NU))
    v = np.array([0.0, 0.3, 1.0])
    e_y = v / np.linalg.norm(v)
    e_z = np.cross([1.0, 0.0, 0.0], e_y)
    tip = 6 * NEL
    for e, I, K in ((e_y, I1, 0.8), (e_z, I2, 0.6)):
        F = np.zeros(sm.K.shape[0])
        F[tip:tip + 3] = e                       # 1 N at the tip along the plane's deflection
        u = np.zeros_like(F)
        u[free] = np.linalg.solve(sm.K[np.ix_(free, free)], F[free])
        ref = LEN ** 3 / (3 * E * I) + LEN / (K * G * A)
        assert u[tip:tip + 3] @ e == pytest.approx(ref, rel=1e-9)
        assert LEN / (K * G * A) > 1e-5 * ref    # the shear part is resolved by the test


def test_pbarl_closed_forms():
    b, h = 0.2, 0.1
    assert pbarl_section("BAR", [b, h])[:3] == pytest.approx((b * h, b * h ** 3 / 12,
                                                              h * b ** 3 / 12), rel=1e-14)
    # Roark's formula for the rectangle is itself a fit of the exact series: at the square it
    # gives 0.14083 a^4 against the exact 0.1406 a^4 (0.2 %)
    assert pbarl_section("BAR", [0.3, 0.3])[3] == pytest.approx(0.1406 * 0.3 ** 4, rel=2.5e-3)
    r = 0.05
    assert pbarl_section("ROD", [r]) == pytest.approx(
        (np.pi * r ** 2, np.pi * r ** 4 / 4, np.pi * r ** 4 / 4, np.pi * r ** 4 / 2), rel=1e-14)
    tube = pbarl_section("TUBE", [r, 0.8 * r])
    assert tube == pytest.approx(np.subtract(pbarl_section("ROD", [r]),
                                             pbarl_section("ROD", [0.8 * r])), rel=1e-12)
    s, t = 0.5, 1e-3                                   # thin square box, mid-line side s
    A_, i1, i2, j = pbarl_section("BOX", [s + t, s + t, t, t])
    assert j == pytest.approx(t * s ** 3, rel=1e-12)   # Bredt-Batho, exact on mid-lines
    assert A_ == pytest.approx(4 * s * t, rel=1e-12) and i1 == pytest.approx(i2, rel=1e-14)
    assert i1 == pytest.approx(2 * s ** 3 * t / 3, rel=5e-3)   # thin-wall limit, O(t/s)
    h, bf, tw, tf = 0.3, 0.15, 0.006, 0.01             # doubly symmetric I: flanges + web
    A_, i1, i2, j = pbarl_section("I", [h, bf, bf, tw, tf, tf])
    hw = h - 2 * tf
    flange_i1 = bf * tf ** 3 / 12 + bf * tf * ((h - tf) / 2) ** 2     # parallel-axis theorem
    assert A_ == pytest.approx(2 * bf * tf + hw * tw, rel=1e-14)
    assert i1 == pytest.approx(2 * flange_i1 + tw * hw ** 3 / 12, rel=1e-12)
    assert i2 == pytest.approx(2 * tf * bf ** 3 / 12 + hw * tw ** 3 / 12, rel=1e-12)
    assert j == pytest.approx((2 * bf * tf ** 3 + hw * tw ** 3) / 3, rel=1e-14)


@pytest.mark.parametrize("kind,dims", [("BAR", [0.2, 0.1]), ("ROD", [0.05]),
                                       ("TUBE", [0.05, 0.03]), ("BOX", [0.2, 0.1, 0.01, 0.02])])
def test_pbarl_area_and_inertia_equal_pynastrans(tmp_path, kind, dims):
    """A second implementation of the same figures: pyNastran's PBARL area and I1/I2 (it has
    no I1/I2 for the I section, checked by the parallel-axis theorem above)."""
    from pyNastran.bdf.bdf import BDF
    m = BDF(debug=None)
    m.add_mat1(1, E, None, NU, rho=RHO)
    p = m.add_pbarl(7, 1, kind, dims)
    m.cross_reference()
    A_, i1, i2, _ = pbarl_section(kind, dims)
    assert (A_, i1, i2) == pytest.approx((p.Area(), p.I11(), p.I22()), rel=1e-12)


def test_pbarl_rod_cantilever_frequency(tmp_path):
    """A PBARL ROD is the PBAR Simcenter Nastran echoes for it (A, I, J of the circle, K1 = K2
    = 0.9: data/benchmarks/beam_modes), to round-off; its first frequency is the slender
    Euler-Bernoulli one lowered slightly by the shear flexibility (r / L = 0.01)."""
    r = 0.01
    deck = _deck(tmp_path / "rod.bdf", _elements("CBAR"), ["PBARL,1,1,,ROD", f",{r!r}"])
    sm = read_stick_deck(deck)
    f = stick_modes(sm, 1).frequencies_hz[0]
    I = np.pi * r ** 4 / 4
    pbar = _deck(tmp_path / "pbar.bdf", _elements("CBAR"), [
        f"PBAR,1,1,{np.pi * r * r!r},{I!r},{I!r},{2 * I!r}", ",,,,,,,,", ",0.9,0.9"])
    np.testing.assert_allclose(sm.K, read_stick_deck(pbar).K, rtol=0,
                               atol=1e-12 * np.abs(sm.K).max())
    ref = 1.875104 ** 2 / (2 * np.pi * LEN ** 2) * np.sqrt(E * I / (RHO * np.pi * r ** 2))
    assert -5e-4 < f / ref - 1 < -1e-5        # 20 Hermite elements: h^4 convergence


def test_goland_wing_as_a_cbeam_deck_reads_back_to_its_modes(tmp_path):
    from stick_checks import assert_deck_is_the_beam

    from asekit.case import load_case
    from asekit.case import pipeline as pl
    from asekit.io.bdf_beam import write_beam_bdf
    from asekit.util.paths import CASES_DIR

    goland = pl.case_beam(load_case(CASES_DIR / "goland_wing.toml"))
    path = write_beam_bdf(goland, tmp_path / "goland.bdf", element="CBEAM")
    assert "CBEAM" in path.read_text() and "PBAR," not in path.read_text()
    assert_deck_is_the_beam(read_stick_deck(path), goland)


@pytest.mark.parametrize("elements,props,match", [
    (_elements("CBEAM"), _pbeam(k="0.0,0.0") + [",0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.1"],
     r"PBEAM 1: N2B = 0.1 is not supported"),
    (_elements("CBEAM"), [f"PBEAM,1,1,{A!r},{I1!r},{I2!r},0.0,{J!r}", PBEAM_TAIL[0],
                          f",YESA,1.0,{A!r},{I1!r},{I2!r},1e-10,{J!r}", ",0.0,0.0"],
     r"PBEAM 1: I12 = 1e-10 is not supported"),
    (_elements("CBEAM"), [f"PBAR,1,1,{A!r},{I1!r},{I2!r},{J!r}"],
     r"CBEAM 1: PID 1 is a PBAR; a CBEAM takes PBEAM or PBARL"),
    (_elements("CBEAM", "\n,,,0.0,0.1,0.0"), _pbeam(), r"CBEAM 1: offsets WA/WB"),
    (_elements("CBAR"), ["PBARL,1,1,,HAT", ",0.1,0.01,0.05,0.02"],
     r"PBARL 1: TYPE = 'HAT' is not supported"),
    (_elements("CBAR"), ["PBARL,1,1,,I", ",0.3,0.15,0.1,0.006,0.01,0.01"],
     r"PBARL 1: TYPE I .*doubly symmetric"),
    (_elements("CBAR"), ["PBARL,1,1,,TUBE", ",0.03,0.05"],
     r"PBARL 1: TYPE TUBE .*DIM2 \(inner radius\) must be < DIM1"),
])
def test_unrepresentable_fields_are_named(tmp_path, elements, props, match):
    with pytest.raises(BdfError, match=match):
        read_stick_deck(_deck(tmp_path / "x.bdf", elements, props))


def test_pt145_as_a_cbeam_deck_runs_as_the_cbar_one(tmp_path):
    """PT145 with its CBAR / PBAR written as CBEAM / PBEAM (K1 = K2 = 0.0) gives the same
    modes and the same KE flutter crossing (the same element; tests/io/test_bdf_beam.py holds
    the CBAR deck against its f06). PBEAM needs I2 > 0 (QRG: I1 I2 - I12^2 > 0) where the PBAR
    has it blank; the grids' PS 126 fixes the in-plane bending I2 acts on, so any value does."""
    import re

    from asekit.io.bdf_beam import stick_flutter
    from asekit.util.paths import DATA_DIR

    pt145 = DATA_DIR / "benchmarks" / "pt145" / "pt145.bdf"
    text = re.sub(r"^CBAR    (\d+)\s+1\s+(\d+)\s+(\d+)\s+\.0\s+\.0\s+1\.0\s+1$",
                  r"CBEAM,\1,1,\2,\3,0.0,0.0,1.0", pt145.read_text(), flags=re.M)
    assert text.count("CBEAM,") == 10 and "\nCBAR" not in text
    # the CBEAM's polar mass rho (I1 + I2) (the CBAR has none) left out: rho as NSM instead
    text = text.replace("PBAR    1       1       7.175-2 9.83-6          36.8-6",
                        "\n".join([f"PBEAM,1,1,7.175-2,9.83-6,1.0-6,0.0,36.8-6,"
                                    f"{2.61e-4 * 7.175e-2!r}", *PBEAM_TAIL]))
    assert text.count("2.61-4") == 1
    text = text.replace("2.61-4", "0.0   ")
    deck = tmp_path / "pt145_cbeam.bdf"
    deck.write_text(text)
    bar, beam = (stick_flutter(p, units="in-lbf-s") for p in (pt145, deck))
    np.testing.assert_allclose(beam.modes.frequencies_hz, bar.modes.frequencies_hz, rtol=1e-9)
    (c_bar,) = [c for d in bar.results for c in d.crossings]
    (c_beam,) = [c for d in beam.results for c in d.crossings]
    assert c_beam.speed == pytest.approx(c_bar.speed, rel=1e-9)
