"""The thesis table (data/thesis.toml through asekit.reproduction.thesis) and the reproduce command's
plumbing (asekit.reproduction.driver): units and known values, difference formatting, chapter names."""

import math

import pytest

from asekit.reproduction.driver import CHAPTERS, difference
from asekit.reproduction.thesis import all_keys, thesis_value


def test_thesis_table_has_units_and_known_values():
    keys = all_keys()
    assert "servo.open_loop_poles" in keys
    for k in keys:
        assert thesis_value(k).unit
    assert thesis_value("servo.system3.gain_margin_db").value == math.inf
    assert thesis_value("aero.CLalpha_fin_per_rad").value is None
    with pytest.raises(KeyError):
        thesis_value("no.such.key")


def test_difference_formats():
    assert difference(100.0, 110.0).endswith("(+10.0 %)")
    assert difference([1.0, 2.0], [1.1, 2.0]) == "[+10.0, +0.0] %"
    assert difference(None, 3.0) == ""
    assert difference(math.inf, math.inf) == "same"


def test_chapter_names_are_unique():
    names = [n for n, _ in CHAPTERS]
    assert len(names) == len(set(names))
