"""The OUTPUT4 reader: round trips, fixed-width parsing, bad input, and Nastran's HA145B file."""

import numpy as np
import pytest

from asekit.io.op4 import ha145b_path, load_ha145b, read_op4, split_qhhl, write_op4


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


# ---- issue 22: the fixed-width fields are read strictly ---------------------------------------
#: QHHL of HA145B, column record 24 (line 163 of the shipped file): its third data line (line 166)
#: ends with the real part 2.743123126E+01 of Q(k=0.05)[7, 3] = 27.43 + 10.45j.
_HA145B_REC_LINE, _HA145B_FULL_LINE = 163, 166


def _mutated_ha145b(tmp_path, line, edit):
    lines = ha145b_path().read_text().splitlines()
    lines[line - 1] = edit(lines[line - 1])
    p = tmp_path / "mutated.op4"
    p.write_text("\n".join(lines) + "\n")
    return p


def test_ha145b_mutation_sites_are_what_the_tests_say():
    # the unmutated value the truncation used to turn into 2.743 + 10.45j
    lines = ha145b_path().read_text().splitlines()
    assert lines[_HA145B_REC_LINE - 1] == "      24       1      20"
    assert len(lines[_HA145B_FULL_LINE - 1]) == 80
    assert load_ha145b().Q[2, 7, 3] == pytest.approx(27.43123126 + 10.45276705j, abs=1e-8)


def test_issue22_op4_truncated_full_data_line_is_refused(tmp_path):
    # before issue 22: accepted, Q(k=0.05)[7, 3] read as 2.743 + 10.45j (ten times too small)
    p = _mutated_ha145b(tmp_path, _HA145B_FULL_LINE, lambda s: s[:-1])
    with pytest.raises(ValueError, match=r"matrix 'QHHL': line 166 holds 79 characters; its 5 "
                                         r"value\(s\) of field width 16 need exactly 80"):
        load_ha145b(p)


def test_issue22_op4_truncated_last_data_line_is_refused(tmp_path):
    # the last line of a record holds the remainder (here 1 word of KHH's column 1, line 3)
    p = _mutated_ha145b(tmp_path, 3, lambda s: s[:-1])
    with pytest.raises(ValueError, match=r"matrix 'KHH': line 3 holds 15 characters"):
        read_op4(p)


def test_issue22_op4_extra_nan_token_on_column_record_is_refused(tmp_path):
    # before issue 22: the NaN after ICOL IROW NW was ignored and the file read as the original
    p = _mutated_ha145b(tmp_path, _HA145B_REC_LINE, lambda s: s + "     NaN")
    with pytest.raises(ValueError, match=r"matrix 'QHHL': line 163: unexpected text 'NaN' after "
                                         r"the column record"):
        load_ha145b(p)


def test_issue22_op4_extra_token_on_header_or_data_line_is_refused(tmp_path):
    p = _mutated_ha145b(tmp_path, 47, lambda s: s + " NaN")          # the QHHL header
    with pytest.raises(ValueError, match=r"header line 47: unsupported OP4 number format "
                                         r"'1P,5E16.9 NaN'"):
        read_op4(p)
    p = _mutated_ha145b(tmp_path, 3, lambda s: s + " NaN")           # after KHH's one word
    with pytest.raises(ValueError, match=r"matrix 'KHH': line 3 has unexpected text 'NaN' after "
                                         r"its 1 value\(s\)"):
        read_op4(p)


def test_op4_trailing_blanks_and_blank_fields(tmp_path):
    # blanks after a line's fields are allowed (a writer padding to 80 columns); a blank field
    # inside a line is not
    p = _mutated_ha145b(tmp_path, 3, lambda s: s.ljust(80))
    np.testing.assert_array_equal(read_op4(p)["KHH"].data, read_op4(ha145b_path())["KHH"].data)
    p = _mutated_ha145b(tmp_path, _HA145B_FULL_LINE, lambda s: s[:16] + " " * 16 + s[32:])
    with pytest.raises(ValueError, match=r"line 166: field 2 \(columns 17-32\) is blank"):
        read_op4(p)


def test_op4_duplicate_matrix_name_is_refused(tmp_path):
    text = ha145b_path().read_text().splitlines()
    khh = text[:text.index(next(s for s in text if s[32:40].strip() == "MHH"))]
    p = tmp_path / "dup.op4"
    p.write_text("\n".join(khh + khh) + "\n")
    with pytest.raises(ValueError, match=r"matrix 'KHH' at line 24 is already in the file"):
        read_op4(p)
