"""The 3-D Euler-Bernoulli beam (asekit/structure/beam.py) against closed-form solutions.

References used below:

* cantilever bending: omega_n = (beta_n L)^2 sqrt(EI / (m L^4)), beta_n L = 1.8751041,
  4.6940911, 7.8547574, 10.9955407 (roots of cos x cosh x = -1; Blevins, *Formulas for
  Natural Frequency and Mode Shape*, 1979, Table 8-1, clamped-free).
* torsion and axial vibration of a clamped-free bar: omega_n = (2n - 1) pi / 2 sqrt(GJ /
  (I_p L^2)) and (2n - 1) pi / 2 sqrt(EA / (m L^2)) (Blevins Table 8-16).
* the Goland wing's coupled bending-torsion modes: the exact solution of the uniform-beam
  equations (Goland, J. Appl. Mech. 12, 1945, A197, Eqs. 1-2 without air forces),
  EI w'''' = omega^2 m (w - d theta), GJ theta'' = -omega^2 (I_p theta - m d w), clamped at
  the root (w = w' = theta = 0), free at the tip (w'' = w''' = theta' = 0), solved below by
  the transfer matrix exp(A L) of that 6th-order system and a root search of its 3 x 3
  boundary determinant: an independent calculation, not the finite elements. The Goland
  properties (SI): EI = 9.77e6 N m^2, GJ = 0.987e6 N m^2, m = 35.71 kg/m,
  I_p = 8.64 kg m about the elastic axis, L = 6.096 m, chord 1.8288 m, elastic axis at 33 %
  and mass axis at 43 % chord (d = 0.1 c = 0.18288 m); Patil, Hodges & Cesnik, J. Aircraft
  38(1), 2001, Table 1, and the same numbers in public Goland-wing inputs (e.g. SHARPy's and
  AeroBeams' Goland cases).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm
from scipy.optimize import brentq

from asekit.structure.beam import (
    BeamSection,
    PointMass,
    assemble,
    beam_modes,
    element_matrices,
    straight_beam,
    uniform_beam,
)

BETA_L = (1.8751041, 4.6940911, 7.8547574, 10.9955407)

GOLAND = dict(EI=9.77e6, GJ=0.987e6, m=35.71, Ip=8.64, d=0.18288, L=6.096)


def goland_section(ea: float = 1e10, ei_chord: float = 1e9) -> BeamSection:
    g = GOLAND
    return BeamSection(ea, g["GJ"], g["EI"], ei_chord, g["m"], g["Ip"], g["d"])


def _boundary_det(omega, EI, GJ, m, Ip, d, L):
    w2 = omega * omega
    A = np.zeros((6, 6))                     # y = (w, w', w'', w''', theta, theta')
    A[0, 1] = A[1, 2] = A[2, 3] = A[4, 5] = 1.0
    A[3, 0], A[3, 4] = w2 * m / EI, -w2 * m * d / EI
    A[5, 4], A[5, 0] = -w2 * Ip / GJ, w2 * m * d / GJ
    T = expm(A * L)
    free = [2, 3, 5]                         # unknown root values w'', w''', theta'
    return np.linalg.det(T[np.ix_(free, free)])


def exact_coupled_frequencies(omega_max: float, EI, GJ, m, Ip, d, L) -> np.ndarray:
    """Roots (rad/s) of the clamped-free boundary determinant below ``omega_max``."""
    grid = np.linspace(1.0, omega_max, 500)      # root spacing >= 45 rad/s here
    f = np.array([_boundary_det(w, EI, GJ, m, Ip, d, L) for w in grid])
    brackets = np.flatnonzero(np.sign(f[:-1]) != np.sign(f[1:]))
    return np.array([brentq(_boundary_det, grid[i], grid[i + 1], args=(EI, GJ, m, Ip, d, L),
                            xtol=1e-12) for i in brackets])


def _omega(beam, n):
    return beam_modes(beam, n).omega


def test_element_matrices_are_symmetric_and_carry_the_mass():
    K, M = element_matrices(goland_section(), 0.7)
    assert np.allclose(K, K.T, rtol=0, atol=1e-6 * abs(K).max())
    assert np.allclose(M, M.T, rtol=0, atol=1e-12 * abs(M).max())
    assert np.all(np.linalg.eigvalsh(M) > 0)            # I_p > m d^2: positive definite
    t = np.zeros(12)
    t[[2, 8]] = 1.0                                     # unit translation along e3
    assert t @ M @ t == pytest.approx(GOLAND["m"] * 0.7, rel=1e-14)
    r = np.zeros(12)
    r[[3, 9]] = 1.0                                     # unit twist
    assert r @ M @ r == pytest.approx(GOLAND["Ip"] * 0.7, rel=1e-14)
    # the mass axis lies d aft: a unit twist (nose up) moves it down by d, so the
    # translation-twist product is -m d L
    assert t @ M @ r == pytest.approx(-GOLAND["m"] * GOLAND["d"] * 0.7, rel=1e-14)


@pytest.mark.parametrize("direction", [(0.0, 1.0), (1.0, 1.0), (-0.3, 2.0)])
def test_free_beam_has_six_rigid_modes_and_its_mass(direction):
    beam = straight_beam((0.2, -0.1, 0.0), direction, [0.0, 0.5, 1.4, 2.0],
                         BeamSection(3e8, 2e5, 4e5, 7e6, 12.0, 0.9, 0.05))
    K, M = assemble(beam)
    nodes = beam.nodes
    rigid = []
    for k in range(3):                                   # translations
        v = np.zeros((beam.n_nodes, 6))
        v[:, k] = 1.0
        rigid.append(v.ravel())
    for k in range(3):                                   # rotations about the origin
        axis = np.eye(3)[k]
        v = np.zeros((beam.n_nodes, 6))
        v[:, :3] = np.cross(axis, nodes)
        v[:, 3:] = axis
        rigid.append(v.ravel())
    R = np.array(rigid).T
    assert np.abs(K @ R).max() <= 1e-9 * np.abs(K).max()
    for k in range(3):
        assert R[:, k] @ M @ R[:, k] == pytest.approx(12.0 * 2.0, rel=1e-12)


@pytest.mark.parametrize("plane", ["flap", "chord"])
def test_cantilever_bending_frequencies(plane):
    EI, m, L = 2.5e4, 3.0, 1.7
    stiff = 1e9                                   # the other plane far stiffer
    sec = BeamSection(1e10, 1e9, EI if plane == "flap" else stiff,
                      EI if plane == "chord" else stiff, m, 1e-3)
    w = _omega(uniform_beam((0, 0), (0.6, 0.8), L, 40, sec), 4)
    exact = np.array(BETA_L) ** 2 * math.sqrt(EI / (m * L ** 4))
    # Hermite cubics: frequency error O(h^4): 3e-8 (mode 1) to 4e-6 (mode 4) for 40 elements
    np.testing.assert_allclose(w, exact, rtol=1e-5)


def test_cantilever_torsion_and_axial_frequencies():
    GJ, Ip, EA, m, L = 3e4, 0.2, 6e6, 4.0, 2.0
    sec = BeamSection(EA, GJ, 1e12, 1e12, m, Ip)          # bending out of the way
    w = _omega(uniform_beam((0, 0), (0, 1), L, 60, sec), 4)
    n = np.arange(1, 4)
    torsion = (2 * n - 1) * math.pi / 2 * math.sqrt(GJ / (Ip * L * L))
    axial = (2 * n - 1) * math.pi / 2 * math.sqrt(EA / (m * L * L))
    exact = np.sort(np.concatenate([torsion, axial]))[:4]
    # linear twist and axial elements with consistent mass: omega_h / omega - 1 ~ (k h)^2 / 24,
    # k = (2n - 1) pi / (2 L), h = L / 60: 7e-4 for n = 3
    np.testing.assert_allclose(w, exact, rtol=1e-3)
    assert np.all(w >= exact)


def test_convergence_orders_bending_4_torsion_2():
    EI, GJ, m, Ip, L = 1e4, 1e4, 1.0, 1.0, 1.0
    bend = BeamSection(1e10, 1e12, EI, 1e12, m, 1e-6)
    twist = BeamSection(1e10, GJ, 1e12, 1e12, m, Ip)
    e_b, e_t = [], []
    for n in (4, 8, 16):
        wb = _omega(uniform_beam((0, 0), (0, 1), L, n, bend), 2)[1]
        wt = _omega(uniform_beam((0, 0), (0, 1), L, n, twist), 1)[0]
        e_b.append(wb / (BETA_L[1] ** 2 * math.sqrt(EI / m)) - 1)
        e_t.append(wt / (math.pi / 2 * math.sqrt(GJ / Ip)) - 1)
    order_b = np.log2(np.array(e_b[:-1]) / np.array(e_b[1:]))
    order_t = np.log2(np.array(e_t[:-1]) / np.array(e_t[1:]))
    assert np.all(np.array(e_b) > 0) and np.all(np.array(e_t) > 0)   # consistent mass: upper
    np.testing.assert_allclose(order_b, 4.0, atol=0.15)
    np.testing.assert_allclose(order_t, 2.0, atol=0.05)


def test_goland_coupled_modes_match_the_exact_uniform_beam_solution():
    g = GOLAND
    exact = exact_coupled_frequencies(460.0, g["EI"], g["GJ"], g["m"], g["Ip"], g["d"], g["L"])
    assert exact.size == 5
    beam = uniform_beam((0.33 * 1.8288, 0.0), (0.0, 1.0), g["L"], 64, goland_section())
    modes = beam_modes(beam, 6)
    w = modes.omega
    # the in-plane (chordwise) bending mode is uncoupled from the rest: drop it
    share = np.abs(modes.shapes[:, 0, :]).max(axis=0)
    out_of_plane = w[share < 1e-9][:5]
    # 64 elements: the linear twist field's O(h^2) error, 5.4e-4 in mode 5
    np.testing.assert_allclose(out_of_plane, exact, rtol=1e-3)
    np.testing.assert_allclose(out_of_plane[:3], exact[:3], rtol=2e-4)
    # the coupled first mode is bounded by the uncoupled bending frequency (Rayleigh quotient
    # of the pure bending shape): 1.8751041^2 sqrt(EI / (m L^4)) = 49.49 rad/s
    uncoupled = BETA_L[0] ** 2 * math.sqrt(g["EI"] / (g["m"] * g["L"] ** 4))
    assert out_of_plane[0] < uncoupled
    # the mass offset couples: the first (bending) mode twists at the tip by a chord-scaled
    # amount comparable to its deflection; without the offset it does not twist at all
    twist = lambda m: abs(m.shapes[-1, 4, 0]) * 1.8288 / abs(m.shapes[-1, 2, 0])  # noqa: E731
    assert twist(modes) > 0.1            # 0.42 for these properties
    plain = beam_modes(uniform_beam((0.6, 0.0), (0.0, 1.0), g["L"], 16,
                                    BeamSection(1e10, g["GJ"], g["EI"], 1e9, g["m"], g["Ip"])), 1)
    assert twist(plain) < 1e-12


def test_modes_are_mass_normalised_and_clamped():
    beam = uniform_beam((0, 0), (0, 1), 6.096, 12, goland_section())
    modes = beam_modes(beam, 5)
    K, M = assemble(beam)
    phi = modes.shapes.reshape(-1, 5)
    np.testing.assert_allclose(phi.T @ M @ phi, np.eye(5), atol=1e-10)
    np.testing.assert_allclose(phi.T @ K @ phi, np.diag(modes.omega ** 2),
                               atol=1e-8 * modes.omega[-1] ** 2)
    assert np.all(modes.shapes[0] == 0.0)
    Mm, Km, Cm = modes.modal_matrices()
    assert np.allclose(Mm, np.eye(5)) and not Cm.any() and np.allclose(np.diag(Km),
                                                                        modes.omega ** 2)


@pytest.mark.parametrize("kwargs, match", [
    (dict(ea=-1.0), "ea"),
    (dict(polar_inertia=0.5, mass_offset=0.5), "polar_inertia must be >= mass"),
    (dict(mass=float("nan")), "mass"),
    (dict(mass_offset=float("inf")), "mass_offset must be a finite number"),
    (dict(gj="stiff"), "gj"),
])
def test_section_refuses_bad_values(kwargs, match):
    base = dict(ea=1e9, gj=1e6, ei_flap=1e7, ei_chord=1e8, mass=30.0, polar_inertia=8.0,
                mass_offset=0.1)
    base.update(kwargs)
    with pytest.raises(ValueError, match=match):
        BeamSection(**base)


def test_beam_refuses_bad_geometry():
    sec = goland_section()
    with pytest.raises(ValueError, match="stations"):
        straight_beam((0, 0), (0, 1), [0.1, 1.0], sec)
    with pytest.raises(ValueError, match="stations"):
        straight_beam((0, 0), (0, 1), [0.0, 1.0, 1.0], sec)
    with pytest.raises(ValueError, match="direction"):
        straight_beam((0, 0), (0, 0), [0.0, 1.0], sec)
    with pytest.raises(ValueError, match="sections"):
        straight_beam((0, 0), (0, 1), [0.0, 1.0, 2.0], [sec])
    with pytest.raises(ValueError, match="sections .* got NoneType"):
        straight_beam((0, 0), (0, 1), [0.0, 1.0], None)
    with pytest.raises(ValueError, match="n_modes"):
        beam_modes(straight_beam((0, 0), (0, 1), [0.0, 1.0], sec), 7)


# ---- point masses (CONM2-like) ------------------------------------------------------------------
def test_tip_mass_on_a_light_cantilever():
    """Bending: omega^2 = 3 EI / ((M + 33/140 m L) L^3) (Rayleigh, the static tip-load shape;
    Blevins Table 8-8 case 3, within 0.5 % for m L << M); torsion: omega^2 = GJ / (L J) for
    a tip inertia J on a light shaft (plus I_p L / 3)."""
    EI, GJ, L, m, Ip, M, J = 2e4, 5e3, 1.5, 1e-3, 1e-6, 4.0, 0.3
    sec = BeamSection(1e10, GJ, EI, 1e10, m, Ip)
    tip = PointMass(8, M, inertia=(J, J, J))      # J about the tip's own axes
    beam = straight_beam((0, 0), (0, 1), np.linspace(0, L, 9), sec, [tip])
    w = beam_modes(beam, 2).omega
    bending = math.sqrt(3 * EI / ((M + 33 / 140 * m * L) * L ** 3))
    torsion = math.sqrt(GJ / (L * (J + Ip * L / 3)))
    # the tip inertia about x also rotates with the bending slope: bending is lowered by
    # (1 + J 9 / (4 M L^2))^(-1/2) to first order in the slope-rotation energy (J theta'^2,
    # theta' = 3 w / (2 L))
    bending_rot = bending / math.sqrt(1 + 9 * J / (4 * M * L * L))
    # Rayleigh's quotient is an upper bound (FE: 0.08 % below; without the rotary term 3.6 %)
    assert bending_rot * (1 - 5e-3) < w[0] <= bending_rot
    assert w[1] == pytest.approx(torsion, rel=1e-9)   # linear twist: exact for a tip inertia


def test_offset_mass_has_the_rigid_body_inertia_of_its_position():
    """Free beam: the kinetic energy of a rigid rotation e about the origin includes the
    offset mass at p_node + o exactly: m |e x (p + o)|^2 + e^T J e."""
    sec = BeamSection(1e9, 1e6, 1e7, 1e8, 1e-9, 1e-9)
    o = np.array([0.4, -0.2, 0.1])
    J = np.array([[0.3, 0.01, 0.0], [0.01, 0.2, 0.0], [0.0, 0.0, 0.1]])
    beam = straight_beam((0.5, 0.2), (1.0, 2.0), [0.0, 1.0, 2.5], sec,
                         [PointMass(1, 3.0, o, J)])
    _, M = assemble(beam)
    p = beam.nodes[1] + o
    for e in np.eye(3):
        v = np.zeros((beam.n_nodes, 6))
        v[:, :3] = np.cross(e, beam.nodes)
        v[:, 3:] = e
        expected = 3.0 * np.sum(np.cross(e, p) ** 2) + e @ J @ e
        assert v.ravel() @ M @ v.ravel() == pytest.approx(expected, rel=1e-6)


def test_point_masses_refuse_bad_values():
    sec = BeamSection(1e9, 1e6, 1e7, 1e8, 1.0, 1.0)
    with pytest.raises(ValueError, match="mass must be >= 0"):
        PointMass(1, -1.0)
    with pytest.raises(ValueError, match="offset must be a 3-vector"):
        PointMass(1, 1.0, (0.1, 0.2))
    with pytest.raises(ValueError, match="inertia must be"):
        PointMass(1, 1.0, inertia=[[1.0, 2.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    with pytest.raises(ValueError, match="inertia must be"):
        PointMass(1, 1.0, inertia=(-1.0, 1.0, 1.0))
    with pytest.raises(ValueError, match=r"point_masses\[0\] must be a PointMass on a node in \[0, 1\]"):
        straight_beam((0, 0), (0, 1), [0.0, 1.0], sec, [PointMass(2, 1.0)])
