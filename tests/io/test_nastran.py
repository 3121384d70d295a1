"""The OUTPUT4 reader: round trips, fixed-width parsing, bad input, and Nastran's HA145B file."""

import numpy as np
import pytest

from asekit.io.op4 import load_ha145b, read_op4, split_qhhl, write_op4


def test_round_trip_real_and_complex(tmp_path):
    rng = np.random.default_rng(0)
    a = rng.normal(size=(7, 4)) * 10.0 ** rng.integers(-5, 5, size=(7, 4))
    a[2:5, 1] = 0.0           # a column with an interior gap of zeros
    a[:, 3] = 0.0             # an all-zero column (not written)
    c = rng.normal(size=(3, 6)) + 1j * rng.normal(size=(3, 6))
    path = write_op4(tmp_path / "m.op4", {"A": a, "CPLX": c})
    m = read_op4(path)
    assert list(m) == ["A", "CPLX"]
    assert m["A"].ntype == 2 and m["CPLX"].ntype == 4
    np.testing.assert_allclose(m["A"].data, a, rtol=1e-9, atol=0)
    np.testing.assert_allclose(m["CPLX"].data, c, rtol=1e-8)


def test_adjacent_negative_fields(tmp_path):
    # Nastran writes fields with no separating blanks: "-1.0E+00-2.0E+00"
    text = ("       2       2       1       2A       1P,5E16.9\n"
            "       1       1       2\n"
            "-1.500000000E+00-2.500000000E-03\n"
            "       3       1       1\n"
            " 1.000000000E+00\n")
    p = tmp_path / "n.op4"
    p.write_text(text)
    d = read_op4(p)["A"].data
    np.testing.assert_array_equal(d, [[-1.5, 0.0], [-2.5e-3, 0.0]])


def test_truncated_file_raises(tmp_path):
    p = tmp_path / "bad.op4"
    p.write_text("       2       2       1       2A       1P,5E16.9\n"
                 "       1       1       2\n 1.0E+00\n")
    with pytest.raises(ValueError):
        read_op4(p)


def test_split_qhhl_shape_check():
    with pytest.raises(ValueError, match="QHHL"):
        split_qhhl(np.zeros((3, 10)), 3)


def test_ha145b_contents():
    case = load_ha145b()
    assert case.M.shape == case.K.shape == (10, 10)
    assert case.Q.shape == (7, 10, 10)
    # modal matrices: symmetric, positive definite; frequencies of the BAH wing
    np.testing.assert_allclose(case.M, case.M.T)
    assert np.all(np.linalg.eigvalsh(case.M) > 0) and np.all(np.linalg.eigvalsh(case.K) > 0)
    f = np.sort(np.sqrt(np.linalg.eigvals(np.linalg.solve(case.M, case.K)).real)) / (2 * np.pi)
    assert 1.5 < f[0] < 2.5 and 3.0 < f[1] < 4.0      # first bending ~2 Hz, ~3.5 Hz
    # the GAFs at k ~ 0 are (almost) real: Im Q = O(k)
    assert np.abs(case.Q[0].imag).max() < 1e-3 * np.abs(case.Q[0].real).max()
    assert np.abs(case.Q[-1].imag).max() > 0.1 * np.abs(case.Q[-1].real).max()
