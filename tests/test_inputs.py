"""Inputs that cannot lie (issue 11): resource bounds refused up front with the estimate and the
knob, duplicated/overlapping boxes, symmetric=True on a mesh crossing y = 0, OP4 writer/reader
edge cases, and the internal crashes the issue lists (each now a ValueError/TypeError naming the
argument)."""

import dataclasses
import tomllib

import numpy as np
import pytest

from asekit.aero.boxes import BoxMesh, TrapezoidSurface, mesh_surfaces
from asekit.aero.dlm import normalwash_matrix
from asekit.aero.vlm import lift_curve_slope, steady_pressure
from asekit.case import CaseError, case_from_dict, pipeline
from asekit.io.op4 import read_op4, write_op4
from asekit.servo.actuator import SYSTEM_3, ActuatorParameters, DCMotor, PDController
from asekit.servo.simulate import simulate
from asekit.util.paths import FIN_FILE


def _plate(n_chord=4, n_span=4, y0=0.0):
    return mesh_surfaces([TrapezoidSurface((0.0, y0, 0.0), 1.0, (0.0, y0 + 2.0, 0.0), 1.0,
                                           n_chord, n_span)])


# ---- boxes ------------------------------------------------------------------------------------
def test_duplicated_box_refused_before_vlm_and_dlm():
    m = _plate()
    c = np.concatenate([m.corners, m.corners[5:6]])
    with pytest.raises(ValueError, match=r"duplicated or overlap: .* of box (5|16) .* inside box (16|5)"):
        BoxMesh(c, np.r_[m.strip, m.strip[5]], np.r_[m.surface, 0])


def test_overlapping_box_refused():
    m = _plate()
    shifted = m.corners[5] + np.array([0.1, 0.1, 0.0])       # overlaps its neighbours by 40 %
    c = np.concatenate([m.corners, shifted[None]])
    with pytest.raises(ValueError, match="overlap"):
        BoxMesh(c, np.r_[m.strip, 0], np.r_[m.surface, 0])


def test_adjacent_and_swept_boxes_are_not_overlaps(fin_box_mesh):
    swept = TrapezoidSurface((0.0, 0.0, 0.0), 1.0, (1.5, 2.0, 0.3), 0.4, 8, 6)
    wing = TrapezoidSurface((0.0, 0.0, 0.0), 1.0, (0.5, 2.0, 0.0), 0.5, 5, 5, name="w")
    fin = TrapezoidSurface((0.0, 0.0, 0.0), 1.0, (0.5, 0.0, 1.0), 0.5, 5, 5, name="f")
    assert mesh_surfaces([swept]).n == 48
    assert mesh_surfaces([wing, fin]).n == 50            # a T: planes meet on a line only
    assert fin_box_mesh.n > 0


def test_symmetric_mesh_crossing_y0_refused():
    crossing = _plate(y0=-1.0)
    with pytest.raises(ValueError, match="symmetric=True needs the mesh on one side of y = 0"):
        lift_curve_slope(crossing, 0.5, symmetric=True)
    with pytest.raises(ValueError, match="symmetric=True"):
        normalwash_matrix(crossing, 0.5, 0.1, 1.0, symmetric=True)
    vertical = mesh_surfaces([TrapezoidSurface((0.0, 0.0, 0.0), 1.0, (0.0, 0.0, 1.0), 1.0, 2, 2)])
    with pytest.raises(ValueError, match="lie in the plane y = 0"):     # found by hypothesis
        lift_curve_slope(vertical, 0.5, symmetric=True)
    assert lift_curve_slope(vertical, 0.5) == pytest.approx(0.0, abs=1e-12)   # no lift: nz = 0
    # a half model touching the wall is fine, and equals the full mesh (image = other half)
    half = _plate(n_span=4, y0=0.0)
    full = mesh_surfaces([TrapezoidSurface((0.0, -2.0, 0.0), 1.0, (0.0, 2.0, 0.0), 1.0, 4, 8)])
    assert lift_curve_slope(half, 0.5, symmetric=True) == pytest.approx(
        lift_curve_slope(full, 0.5), rel=1e-10)


def test_lift_curve_slope_reference_area():
    m = _plate()
    for bad in (0.0, -1.0, float("nan")):
        with pytest.raises(ValueError, match="reference_area"):
            lift_curve_slope(m, 0.5, reference_area=bad)
    with pytest.raises(TypeError, match="reference_area"):
        lift_curve_slope(m, 0.5, reference_area=1j)


def _fin_dict_with(section, key, value):
    """The reference fin's case file as a dict, ``[section] key = value``."""
    with open(FIN_FILE, "rb") as fh:
        d = tomllib.load(fh)
    d[section][key] = value
    return d


def test_box_count_and_matrix_memory_bounds():
    # the fin's mesh rules at f_max = 1 MHz ask for 13001 x 9260 boxes: refused before any box
    # or allocation, by the dense-matrix bound -- by the loader (issue 22), and by box_mesh for
    # a case built in Python past the loader
    with pytest.raises(CaseError, match=r"GiB.*aero\.f_max"):
        case_from_dict(_fin_dict_with("aero", "f_max", 1e6))
    fin = case_from_dict(_fin_dict_with("aero", "f_max", 1000.0))
    big = dataclasses.replace(fin, aero=dataclasses.replace(fin.aero, f_max=1e6))
    with pytest.raises(ValueError, match=r"GiB.*aero\.f_max"):
        pipeline.box_mesh(big)
    with pytest.raises(ValueError, match="MAX_BOXES"):
        TrapezoidSurface((0, 0, 0), 1.0, (0, 1, 0), 1.0, 1000, 1000)
    with pytest.raises(CaseError, match="aero.u_min"):
        case_from_dict(_fin_dict_with("aero", "u_min", 0.0))
    m = _plate()
    with pytest.raises(ValueError, match="GiB.*fewer reduced frequencies"):
        from asekit.aero.dlm import normalwash_matrices
        normalwash_matrices(m, 0.5, np.linspace(0, 1, 10 ** 8), 1.0)
    with pytest.raises(TypeError, match="mesh"):
        steady_pressure("mesh", 0.5, np.zeros(3))


def test_automatic_box_count_refusal_names_the_case_keys():
    # issue 11: a resource bound refused up front names the estimate and the knob to turn
    with pytest.raises(CaseError, match=r"aero\.boxes: .* from the mesh rules .*aero\.f_max"):
        case_from_dict(_fin_dict_with("aero", "f_max", 1e6))


# ---- simulations --------------------------------------------------------------------------------
@pytest.mark.parametrize("kwargs, match", [
    (dict(controller=PDController(10, 275, 1e30), t_final=0.005), "integrator steps"),
    (dict(params=ActuatorParameters(motor=DCMotor(inductance=1e-12))), "integrator steps"),
    (dict(sample_time=1e-8), "sample_time = 1e-08"),
    (dict(max_step=1e-12), "max_step = 1e-12"),
])
def test_simulate_refuses_runaway_step_counts(kwargs, match):
    args = dict(params=ActuatorParameters(), controller=SYSTEM_3, command=0.1, t_final=0.1)
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        simulate(**args)


def test_simulate_bad_arguments_named():
    P = ActuatorParameters()
    with pytest.raises(TypeError, match="limits"):
        simulate(P, SYSTEM_3, 0.1, limits="x")
    with pytest.raises(TypeError, match="controller"):
        simulate(P, "System 3", 0.1)
    with pytest.raises(ValueError, match="command"):
        simulate(P, SYSTEM_3, float("nan"))
    with pytest.raises(ValueError, match="n_out"):
        simulate(P, SYSTEM_3, 0.1, n_out=1)
    with pytest.raises(ValueError, match="theta0"):
        simulate(P, SYSTEM_3, 0.1, theta0=float("inf"))


def test_gaf_database_at_nan():
    from asekit.aero.gaf import GafDatabase
    db = GafDatabase(np.array([0.4, 0.6]), np.array([0.0, 1.0]), np.zeros((2, 2, 1, 1), complex),
                     1.0, 0, {})
    with pytest.raises(ValueError, match="mach must be a finite Mach number"):
        db.at(float("nan"), interpolate=True)
    assert db.at(0.5, interpolate=True).Q.shape == (2, 1, 1)


# ---- OP4 ------------------------------------------------------------------------------------------
def test_op4_three_digit_exponents_round_trip(tmp_path):
    a = np.array([[1.5e100, -2.5e-200, 0.0], [1e-5, 3.0, -1.7e308]]) / 2
    p = write_op4(tmp_path / "x.op4", {"A": a, "C": a * (1 - 2j)})
    for line in p.read_text().splitlines()[1:]:
        assert len(line) <= 80                       # 5 fields of 16: every field kept its width
    r = read_op4(p)
    np.testing.assert_allclose(r["A"].data, a, rtol=1e-9)
    np.testing.assert_allclose(r["C"].data, a * (1 - 2j), rtol=1e-9)


def test_op4_bad_files(tmp_path):
    p = tmp_path / "e.op4"
    p.write_text("")
    with pytest.raises(ValueError, match="no matrix"):
        read_op4(p)
    p.write_text("       1       1       2       2A       1P,0E16.9\n")
    with pytest.raises(ValueError, match="format"):
        read_op4(p)
    p.write_text("       1       1       2       2A       1P,5E16.9\n       1       1       1\n"
                 "       garbage!!\n       2       1       1\n 1.000000000E+00\n")
    with pytest.raises(ValueError, match="line 3: value 'garbage!!' is not a number"):
        read_op4(p)


def test_op4_writer_refuses_bad_input(tmp_path):
    p = tmp_path / "w.op4"
    with pytest.raises(ValueError, match="non-finite"):
        write_op4(p, {"A": np.array([[np.nan]])})
    with pytest.raises(ValueError, match="names"):
        write_op4(p, {"TOO_LONG_NAME": np.eye(2)})
    with pytest.raises(ValueError, match="non-empty"):
        write_op4(p, {})
    with pytest.raises(ValueError, match="1-D or 2-D"):
        write_op4(p, {"A": np.zeros((2, 2, 2))})
    with pytest.raises(ValueError, match="digits"):
        write_op4(p, {"A": np.eye(2)}, digits=0)
