"""Tapered PBEAM and PBEAML in stick-model decks (asekit.io.bdf_beam, asekit.structure.frame;
issue 24).

References
----------
- Cantilever of bending stiffness E I(x) under a tip load P: tip deflection
  P int_0^L (L - x)^2 / (E I(x)) dx (+ P L / (K G A) ... for shear: P int 1 / (K G A(x)) dx),
  by the unit-load method (Timoshenko & Gere, *Mechanics of Materials*, Sec. 9.8; Roark 7th
  ed. Sec. 8.1). The integral is evaluated here by scipy's adaptive quadrature, independently
  of the element's Gauss rule. The element (stiffness from its cantilever flexibility) is
  exact for end loads, so one element must give it to quadrature precision.
- The frequencies of the tapered cantilever: a fine mesh of uniform CBAR elements, each with
  the section at its mid-length (a stepped beam, converging to the tapered one as the mesh is
  refined), is the reference for a coarse mesh of tapered CBEAM elements.
- MSC Nastran QRG PBEAML: the section from TYPE and DIMi at each station, the dimensions of
  PBARL (a uniform PBEAML equals the PBARL of the same dimensions).
"""

import os

import numpy as np
import pytest
from scipy.integrate import quad

if os.environ.get("ASEKIT_REQUIRE_PYNASTRAN"):
    import pyNastran  # noqa: F401
else:
    pytest.importorskip("pyNastran")

from asekit.io.bdf import BdfError  # noqa: E402
from asekit.io.bdf_beam import pbarl_section, read_stick_deck, stick_modes  # noqa: E402
from asekit.structure.frame import BarSection, bar_matrices, tapered_bar_matrices  # noqa: E402

E, NU, RHO, LEN = 7.0e10, 0.3, 2700.0, 1.2
G = E / (2 * (1 + NU))
# a width-tapered rectangle (PBARL BAR: DIM1 width b along z, DIM2 height h along y) from
# b0 at the root to b1 at the tip: A and I1 linear in x, I2 and J not
B0, B1, H = 0.06, 0.02, 0.01
TAIL = ",0.0,0.0,0.0,0.0,0.0,0.0,0.0,0.0"


def _props(x):
    """A, I1, I2, J of the tapered rectangle at x (m) from the root."""
    b = B0 + (B1 - B0) * x / LEN
    return pbarl_section("BAR", [b, H])


def _deck(path, nel, elem_lines, prop_lines):
    lines = ["SOL 103", "CEND", "SPC = 1", "BEGIN BULK"]
    lines += [f"GRID,{i + 1},,{LEN * i / nel!r},0.0,0.0" for i in range(nel + 1)]
    lines += [*elem_lines, *prop_lines, f"MAT1,1,{E!r},,{NU!r},{RHO!r}", "SPC1,1,123456,1",
              "PARAM,COUPMASS,1", "ENDDATA"]
    path.write_text("\n".join(lines) + "\n")
    return path


def _tapered_pbeam_deck(path, nel, k="0.0,0.0"):
    """nel CBEAMs, each with a PBEAM of its own end values (two stations, linear A, I1, I2, J
    between them: exact for A and I1 of the width taper)."""
    elems, props = [], []
    for e in range(nel):
        a, b = (_props(LEN * (e + t) / nel) for t in (0, 1))
        elems.append(f"CBEAM,{e + 1},{e + 1},{e + 1},{e + 2},0.0,0.0,1.0")
        props += [f"PBEAM,{e + 1},1,{a[0]!r},{a[1]!r},{a[2]!r},0.0,{a[3]!r}", TAIL,
                  f",YESA,1.0,{b[0]!r},{b[1]!r},{b[2]!r},0.0,{b[3]!r}", f",{k}"]
    return _deck(path, nel, elems, props)


def _tip_deflections(sm):
    """Tip deflections under a unit tip load in basic z (plane 1: v = z is e_y, I1) and in
    basic y (plane 2: e_z = e_x x e_y = -y, I2), from the stiffness of the free DOFs."""
    free = sm.free
    Kf = sm.K[np.ix_(free, free)]
    tip = 6 * (len(sm.node_ids) - 1)
    out = []
    for c in (2, 1):
        F = np.zeros(sm.K.shape[0])
        F[tip + c] = 1.0
        u = np.zeros(sm.K.shape[0])
        u[free] = np.linalg.solve(Kf, F[free])
        out.append(u[tip + c])
    return np.array(out)


def _flex(fn, x0=0.0, x1=LEN):
    return quad(fn, x0, x1, epsabs=0.0, epsrel=1e-13, limit=200)[0]


def test_uniform_section_gives_the_uniform_bar():
    """tapered_bar_matrices of a constant section equals bar_matrices (Przemieniecki Eq. 5.116
    with shear Phi, Eq. 11.41), consistent and lumped, to round-off."""
    s = BarSection(2.0e6, 30.0, 50.0, 70.0, 4.0, gas1=3.0e5, gas2=9.0e5)
    for coupled in (True, False):
        K, M = tapered_bar_matrices(lambda xi: s, 0.7, (0.0, 0.4, 1.0), coupled)
        K0, M0 = bar_matrices(s, 0.7, coupled)
        np.testing.assert_allclose(K, K0, rtol=0, atol=1e-12 * np.abs(K0).max())
        np.testing.assert_allclose(M, M0, rtol=0, atol=1e-12 * np.abs(M0).max())


@pytest.mark.parametrize("k", ["0.0,0.0", "0.833,0.833"])
def test_one_tapered_cbeam_gives_the_exact_tip_deflection(tmp_path, k):
    """One CBEAM, PBEAM with end A and end B (A, I1, I2, J linear between them): the tip
    deflection of the cantilever under a tip load in each plane is the unit-load integral
    with E I(x) linear (+ the shear term with K G A(x) when K1 = K2 = 0.833)."""
    sm = read_stick_deck(_tapered_pbeam_deck(tmp_path / "t.bdf", 1, k))
    kk = float(k.split(",")[0])
    a, b = _props(0.0), _props(LEN)

    def lin(i, x):
        return a[i] + (b[i] - a[i]) * x / LEN

    ref = []
    for i in (1, 2):          # plane 1 (e_y = basic z, I1), plane 2 (e_z = -basic y, I2)
        d = _flex(lambda x: (LEN - x) ** 2 / (E * lin(i, x)))
        if kk:
            d += _flex(lambda x: 1.0 / (kk * G * lin(0, x)))
        ref.append(d)
    np.testing.assert_allclose(_tip_deflections(sm), ref, rtol=1e-10)


def _stepped_frequencies(tmp_path, n, n_modes=4):
    """The first frequencies of the tapered cantilever as n uniform CBARs (mid-length
    sections)."""
    elems, props = [], []
    for e in range(n):
        A, i1, i2, j = _props(LEN * (e + 0.5) / n)
        elems.append(f"CBAR,{e + 1},{e + 1},{e + 1},{e + 2},0.0,0.0,1.0")
        props.append(f"PBAR,{e + 1},1,{A!r},{i1!r},{i2!r},{j!r}")
    sm = read_stick_deck(_deck(tmp_path / f"s{n}.bdf", n, elems, props))
    return stick_modes(sm, n_modes).frequencies_hz


def test_tapered_cantilever_frequencies_converge_to_the_fine_stepped_mesh(tmp_path):
    """Tapered CBEAMs (2, 4, 8 elements) against the stepped beam of 30 and 60 uniform CBARs
    extrapolated to zero step (Richardson, the stepped mesh's error being O(h^2): f = (4 f_60
    - f_30) / 3; 40 and 80 give the same to 1e-6). Modes 1, 3, 4 bend in plane 1, where A, I1 and m are linear as the PBEAM
    interpolates them; mode 2 bends in plane 2, whose I2 ~ b^3 each PBEAM interpolates
    linearly (an O(h^2) error of its own). Measured errors (8 elements): 3e-7, 2.7e-3, 5e-5,
    5.2e-4; asserted: falling with the mesh, below 4e-3 for all and 1e-3 for plane 1."""
    f30, f60 = _stepped_frequencies(tmp_path, 30), _stepped_frequencies(tmp_path, 60)
    f_ref = (4 * f60 - f30) / 3
    assert np.abs(f60 / f_ref - 1).max() < 3e-4          # the extrapolation is a small step
    errs = []
    for nel in (2, 4, 8):
        sm = read_stick_deck(_tapered_pbeam_deck(tmp_path / f"t{nel}.bdf", nel))
        errs.append(np.abs(stick_modes(sm, 4).frequencies_hz / f_ref - 1))
    errs = np.array(errs)
    assert np.all(errs[1:] < errs[:-1])
    assert errs[2].max() < 4e-3 and errs[2][[0, 2, 3]].max() < 1e-3


@pytest.mark.parametrize("kind,dims", [("BAR", [0.05, 0.012]), ("ROD", [0.01]),
                                       ("TUBE", [0.012, 0.009]), ("BOX", [0.05, 0.03, 0.003, 0.002]),
                                       ("I", [0.08, 0.05, 0.05, 0.004, 0.006, 0.006])])
def test_uniform_pbeaml_equals_the_pbarl(tmp_path, kind, dims):
    """A PBEAML with one station (end B blank: end A's) is the PBARL of the same dimensions
    (MSC QRG PBEAML remark 4 and its shared section library): K and M to 1e-12."""
    nel = 4
    d = ",".join(repr(float(x)) for x in dims)
    elems = [f"CBEAM,{e + 1},1,{e + 1},{e + 2},0.0,0.3,1.0" for e in range(nel)]
    beaml = read_stick_deck(_deck(tmp_path / "l.bdf", nel, elems, [f"PBEAML,1,1,,{kind}",
                                                                   f",{d},0.0"]))
    barl = read_stick_deck(_deck(tmp_path / "r.bdf", nel, elems, [f"PBARL,1,1,,{kind}",
                                                                  f",{d},0.0"]))
    np.testing.assert_allclose(beaml.K, barl.K, rtol=0, atol=1e-12 * np.abs(barl.K).max())
    np.testing.assert_allclose(beaml.M, barl.M, rtol=0, atol=1e-12 * np.abs(barl.M).max())


def test_tapered_pbeaml_interpolates_the_dimensions(tmp_path):
    """One CBEAM with a PBEAML BAR whose width DIM1 goes from B0 to B1 (end B on the
    continuation): the section at each point is the BAR of the interpolated dimensions, so
    I1 = b h^3 / 12 is linear and I2 = h b^3 / 12 cubic in x; both tip deflections equal the
    unit-load integrals of those, and the mass is rho int A dx = rho H (B0 + B1) L / 2."""
    lines = ["PBEAML,1,1,,BAR", f",{B0!r},{H!r},0.0,YES,1.0,{B1!r},{H!r},0.0"]
    sm = read_stick_deck(_deck(tmp_path / "l.bdf", 1,
                               ["CBEAM,1,1,1,2,0.0,0.0,1.0"], lines))
    ref = [_flex(lambda x: (LEN - x) ** 2 / (E * _props(x)[i])) for i in (1, 2)]
    np.testing.assert_allclose(_tip_deflections(sm), ref, rtol=1e-10)
    mass = sm.M[np.ix_([2, 8], [2, 8])].sum()
    assert mass == pytest.approx(RHO * H * (B0 + B1) * LEN / 2, rel=1e-12)


@pytest.mark.parametrize("props,match", [
    (["PBEAML,1,1,,HAT", ",0.1,0.01,0.05,0.02,0.0"], r"PBEAML 1: TYPE = 'HAT' is not supported"),
    (["PBEAML,1,1,,I", ",0.08,0.05,0.05,0.004,0.006,0.006,0.0,YES", ",1.0,0.08,0.05,0.04,0.004,"
      "0.006,0.006,0.0"], r"PBEAML 1: TYPE I .*doubly symmetric"),
    (["PBEAML,1,1,MYLIB,BAR", ",0.01,0.005"], r"PBEAML 1: GROUP = 'MYLIB' is not supported"),
])
def test_unsupported_pbeaml_is_named(tmp_path, props, match):
    deck = _deck(tmp_path / "x.bdf", 1, ["CBEAM,1,1,1,2,0.0,0.0,1.0"], props)
    with pytest.raises(BdfError, match=match):
        read_stick_deck(deck)


def test_convert_refuses_a_tapered_beam(tmp_path):
    """A case's [[beam]] segment is uniform: ``stick_case_dict`` of PT145 with its PBAR as a
    tapered PBEAM is refused naming the PBEAM (the deck itself is read)."""
    import re

    from asekit.io.stick_case import stick_case_dict
    from asekit.util.paths import DATA_DIR

    text = (DATA_DIR / "benchmarks" / "pt145" / "pt145.bdf").read_text()
    text = re.sub(r"^CBAR    (\d+)\s+1\s+(\d+)\s+(\d+)\s+\.0\s+\.0\s+1\.0\s+1$",
                  r"CBEAM,\1,1,\2,\3,0.0,0.0,1.0", text, flags=re.M)
    text = text.replace("PBAR    1       1       7.175-2 9.83-6          36.8-6", "\n".join([
        "PBEAM,1,1,7.175-2,9.83-6,1.0-6,0.0,36.8-6", TAIL,
        ",YESA,1.0,6.0-2,8.0-6,1.0-6,0.0,30.0-6", ",0.0,0.0"]))
    deck = tmp_path / "t.bdf"
    deck.write_text(text)
    assert read_stick_deck(deck, units="in-lbf-s").K.shape == (66, 66)
    with pytest.raises(BdfError, match=r"PBEAM 1: the section varies along the beam"):
        stick_case_dict(deck, "in-lbf-s")
