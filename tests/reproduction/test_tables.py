"""The notebooks' result tables (asekit.reproduction.tables, issue 30): units in the header,
numbers with the column's digits, never a numpy repr, HTML for JupyterLab."""

import numpy as np
import pytest

from asekit.reproduction.tables import Table, cell, significant


def test_numpy_values_print_as_numbers_not_reprs():
    t = Table(["mach", "speed"], [(np.float64(0.75), np.float64(251.123)), (np.int64(1), None)],
              units=["", "m/s"], formats=[".2f", ".1f"])
    text, page = str(t), t._repr_html_()
    assert "np." not in text and "np." not in page
    assert "0.75" in text and "251.1" in text and "-" in text.splitlines()[-1]
    assert t.header == ["mach", "speed (m/s)"]
    assert cell(np.array([1.0, 2.5]), ".1f") == "1.0, 2.5"
    assert cell(np.complex128(1 - 2j), ".1f") == "1.0-2.0j"


def test_text_columns_align_and_html_escapes():
    t = Table(["name", "value"], [("a < b", 1.0), ("long name", 12.345)], formats=["", ".2f"])
    lines = str(t).splitlines()
    assert len({len(line) for line in lines[1:]}) == 1          # every row as wide as the rule
    assert lines[2].endswith(" 1.00") and lines[3].endswith("12.35")
    assert "a &lt; b" in t._repr_html_()


def test_significant_digits():
    assert significant(157100.0) == "157,100"
    assert significant(4.61303) == "4.613"
    assert significant(float("inf")) == "inf"


def test_bad_shapes_are_refused():
    with pytest.raises(ValueError, match="row 0 has 1 values, expected 2"):
        Table(["a", "b"], [(1.0,)])
    with pytest.raises(ValueError, match="units must have one entry per column"):
        Table(["a", "b"], [], units=["m"])
