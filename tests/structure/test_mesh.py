"""Structured plate meshes with given or graded node stations (asekit/structure/mesh.py)."""

import math

import numpy as np
import pytest
from scipy.sparse.linalg import eigsh

from asekit.geometry import LinearThickness, Material, Planform
from asekit.structure.assembly import assemble
from asekit.structure.mesh import (
    Grading,
    Stations,
    graded_stations,
    panels_mesh,
    station_array,
    structured_mesh,
)

ALU = Material(70e9, 0.3, 2700.0)
#: The reference fin's planform and thickness (data/cases/nalci2013_fin.toml).
FIN = Planform((0.0, 0.0), 0.156, (0.078, 0.150), 0.078)
FIN_T = LinearThickness(0.004, 0.002)


# ---- stations ------------------------------------------------------------------------------

@pytest.mark.parametrize("n, toward, ratio, width, ramp", [
    (8, 0.0, 8.0, 0.0, None), (9, 1.0, 30.0, 0.0, None), (12, 0.5, 20.0, 0.05, None),
    (17, (0.3, 0.7), 50.0, 0.02, 0.1), (40, (0.0, 0.03), 25.0, 0.005, 0.2), (3, 0.2, 1e6, 0.0, None),
])
def test_graded_stations_are_monotone_from_0_to_1_with_the_points_as_nodes(n, toward, ratio,
                                                                           width, ramp):
    s = graded_stations(n, toward, ratio, width, ramp)
    assert s.shape == (n + 1,) and s[0] == 0.0 and s[-1] == 1.0
    assert np.all(np.diff(s) > 0)
    for t in np.atleast_1d(toward):
        assert np.min(np.abs(s - t)) < 1e-12                 # every clustering point is a node


def test_graded_stations_cluster_toward_the_point_and_grow_geometrically():
    s = graded_stations(20, 0.0, 10.0)
    h = np.diff(s)
    assert np.all(np.diff(h) > 0)                            # finest at the root
    np.testing.assert_allclose(h[1:] / h[:-1], 10.0 ** (1 / 20), rtol=1e-9)   # geometric
    np.testing.assert_allclose(h[-1] / h[0], 10.0 ** (19 / 20), rtol=1e-9)
    s = graded_stations(40, 0.5, 10.0, width=0.1)
    h = np.diff(s)
    plateau = h[(s[:-1] >= 0.4 - 1e-12) & (s[1:] <= 0.6 + 1e-12)]
    np.testing.assert_allclose(plateau, h.min(), rtol=1e-6)  # uniform finest on the plateau
    np.testing.assert_allclose(h, h[::-1], rtol=1e-9)        # symmetric about 0.5


def test_the_ramp_caps_the_element_size():
    s = graded_stations(60, 0.0, 5.0, ramp=0.2)
    h = np.diff(s)
    beyond = h[s[:-1] >= 0.2]
    np.testing.assert_allclose(beyond, beyond[0], rtol=1e-9)   # flat beyond the ramp
    assert 4.5 < beyond[0] / h.min() <= 5.0                    # at about ratio x the finest


@pytest.mark.parametrize("n, toward", [(7, 0.0), (7, 1.0), (8, 0.5), (12, (0.25, 0.75))])
def test_ratio_one_recovers_the_uniform_mesh(n, toward):
    np.testing.assert_allclose(graded_stations(n, toward, 1.0), np.linspace(0, 1, n + 1),
                               atol=1e-14)
    np.testing.assert_allclose(Grading(toward, 1.0).stations(n), np.linspace(0, 1, n + 1),
                               atol=1e-14)


def test_doubling_the_count_halves_every_element_of_a_one_sided_grading():
    coarse, fine = graded_stations(10, 0.0, 20.0), graded_stations(20, 0.0, 20.0)
    np.testing.assert_allclose(fine[::2], coarse, atol=1e-12)          # nested


def test_explicit_stations_refine_by_splitting_each_interval():
    s = Stations((0.0, 0.125, 0.875, 1.0))
    assert s.n_elements == 3
    np.testing.assert_allclose(s.stations(), [0, 0.125, 0.875, 1])
    np.testing.assert_allclose(s.stations(6), [0, 0.0625, 0.125, 0.5, 0.875, 0.9375, 1])
    with pytest.raises(ValueError, match="multiple of 3, got 4"):
        s.stations(4)


@pytest.mark.parametrize("values, message", [
    ((0.0, 0.5, 0.4, 1.0), r"strictly ascending, got stations\[2\] = 0.4 after 0.5"),
    ((0.1, 0.5, 1.0), "start at 0 and end at 1"),
    ((0.0, 0.5, 0.9), "start at 0 and end at 1"),
    ((0.0,), "at least 2"),
    ((0.0, float("nan"), 1.0), "finite"),
])
def test_bad_stations_are_refused(values, message):
    with pytest.raises(ValueError, match=message):
        Stations(values)


@pytest.mark.parametrize("kwargs, message", [
    ({"toward": 1.5, "ratio": 2.0}, r"grading.toward must be a finite number in \[0, 1\]"),
    ({"toward": (0.6, 0.4), "ratio": 2.0}, "strictly ascending"),
    ({"toward": 0.5, "ratio": 0.5}, r"grading.ratio must be a finite number in \[1, 1e\+06\]"),
    ({"toward": 0.5, "ratio": 2.0, "width": 1.0}, "grading.width"),
    ({"toward": 0.5, "ratio": 2.0, "ramp": 0.0}, "grading.ramp"),
])
def test_bad_gradings_are_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Grading(**kwargs)


def test_a_station_list_must_match_the_count():
    with pytest.raises(ValueError, match="n \\+ 1 = 5 stations for 4 elements, got 3"):
        station_array([0.0, 0.5, 1.0], 4, "chord_spacing")
    with pytest.raises(ValueError, match="needs at least 3 elements, got 2"):
        graded_stations(2, (0.3, 0.6), 2.0)


# ---- meshes --------------------------------------------------------------------------------

def _signed_areas(mesh):
    x, y = mesh.nodes[mesh.elements, 0], mesh.nodes[mesh.elements, 1]
    return 0.5 * np.sum(x * np.roll(y, -1, axis=1) - np.roll(x, -1, axis=1) * y, axis=1)


def test_graded_fin_mesh_is_inside_the_planform_counter_clockwise_and_tiles_it():
    chord = Grading((0.47, 0.53), 25.0, 0.005, 0.15)
    span = Grading((0.0, 0.03), 25.0, 0.005, 0.2)
    mesh = structured_mesh(FIN, FIN_T, 40, 30, chord, span)
    assert mesh.n_nodes == 41 * 31 and mesh.n_elements == 40 * 30
    # every node inside the trapezoid: between the leading and trailing edges at its y
    x, y = mesh.nodes.T
    eta = y / FIN.span
    le = FIN.root_le[0] + eta * (FIN.tip_le[0] - FIN.root_le[0])
    c = FIN.root_chord + eta * (FIN.tip_chord - FIN.root_chord)
    assert np.all((eta >= -1e-12) & (eta <= 1 + 1e-12))
    assert np.all((x >= le - 1e-12) & (x <= le + c + 1e-12))
    areas = _signed_areas(mesh)
    assert np.all(areas > 0)                                  # counter-clockwise seen from +z
    area = 0.5 * (FIN.root_chord + FIN.tip_chord) * FIN.span
    np.testing.assert_allclose(areas.sum(), area, rtol=1e-12)  # no gap, no overlap
    # the graded chord fraction 0.47 is a node line at the root, as the support needs
    assert np.min(np.hypot(x - 0.47 * 0.156, y)) < 1e-12


def test_uniform_spacing_is_the_default_and_ratio_one_reproduces_it():
    a = structured_mesh(FIN, FIN_T, 6, 8)
    b = structured_mesh(FIN, FIN_T, 6, 8, Grading(0.5, 1.0), Grading(0.0, 1.0))
    c = structured_mesh(FIN, FIN_T, 6, 8, list(np.linspace(0, 1, 7)), None)
    np.testing.assert_allclose(b.nodes, a.nodes, atol=1e-15)
    np.testing.assert_allclose(c.nodes, a.nodes, atol=1e-15)
    np.testing.assert_array_equal(b.elements, a.elements)


def test_two_panels_share_the_chord_spacing_and_keep_their_own_span_spacing():
    inner = Planform((0.0, 0.0), 0.2, (0.05, 0.1), 0.15)
    outer = Planform((0.05, 0.1), 0.15, (0.1, 0.2), 0.1)
    m = panels_mesh([inner, outer], FIN_T, 4, [3, 5], Stations((0.0, 0.5, 1.0)),
                    [Grading(0.0, 4.0), None])
    assert m.n_nodes == 5 * 9
    y = np.unique(np.round(m.nodes[:, 1], 12))
    np.testing.assert_allclose(y[3:], 0.1 + 0.02 * np.arange(6), atol=1e-12)   # outer: uniform
    h_in = np.diff(y[:4])
    assert np.all(np.diff(h_in) > 0)                          # inner: graded toward its root
    with pytest.raises(ValueError, match=r"panel\[1\].span_spacing"):
        panels_mesh([inner, outer], FIN_T, 4, [3, 5], None, [None, [0.0, 0.5, 1.0]])


# ---- the plate on graded meshes ------------------------------------------------------------

def _clamped_square_lambda(n, spacing):
    """omega a^2 sqrt(rho h / D) of the first mode of a clamped square plate (a = 1 m,
    h = 0.01 m) on an n x n mesh."""
    a, h = 1.0, 0.01
    mesh = structured_mesh(Planform((0.0, 0.0), a, (0.0, a), a), LinearThickness(h, h), n, n,
                           spacing, spacing)
    K, M = assemble(mesh, ALU)
    edge = np.flatnonzero((mesh.nodes[:, 0] < 1e-12) | (mesh.nodes[:, 0] > a - 1e-12)
                          | (mesh.nodes[:, 1] < 1e-12) | (mesh.nodes[:, 1] > a - 1e-12))
    free = np.setdiff1d(np.arange(3 * mesh.n_nodes), (3 * edge[:, None] + np.arange(3)).ravel())
    Kf, Mf = K[free][:, free], M[free][:, free]
    w2 = eigsh(Kf.tocsc(), 1, Mf.tocsc(), sigma=0.0, which="LM", return_eigenvectors=False)
    D = ALU.youngs_modulus * h ** 3 / (12 * (1 - ALU.poisson_ratio ** 2))
    return math.sqrt(float(w2[0])) * a ** 2 * math.sqrt(ALU.density * h / D)


def test_clamped_plate_converges_to_the_leissa_value_on_graded_and_uniform_meshes():
    # Clamped (CCCC) square plate, first mode: omega a^2 sqrt(rho h / D) = 35.99 (Leissa,
    # "Vibration of Plates", NASA SP-160 (1969), Table 4.23, thin-plate theory), independent of
    # the mesh. On meshes graded toward the four clamped edges and on uniform ones the errors
    # fall with refinement and the Richardson limits of 8, 16, 32 agree with each other (the
    # same limit) and with Leissa's value (within 0.3 %: MITC4 is a Mindlin plate, h / a = 0.01).
    leissa = 35.99
    limits = []
    for spacing in (None, Grading((0.0, 1.0), 3.0)):
        lam = [_clamped_square_lambda(n, spacing) for n in (8, 16, 32)]
        err = [abs(v / leissa - 1) for v in lam]
        assert err[2] < err[1] < err[0] and err[2] < 0.003, (spacing, err)
        p = math.log2((lam[1] - lam[0]) / (lam[2] - lam[1]))
        assert 1.5 < p < 2.5, (spacing, p)                    # second order, graded or not
        limits.append(lam[2] + (lam[2] - lam[1]) / (2 ** p - 1))
    assert abs(limits[1] / limits[0] - 1) < 5e-4, limits
    assert abs(limits[0] / leissa - 1) < 0.003, limits
