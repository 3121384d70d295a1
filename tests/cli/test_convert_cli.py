"""``asekit convert`` input errors: one line on standard error, exit 2 (the deck's own
refusals are tested in tests/io/test_stick_case.py, with pyNastran)."""

import importlib.util

import pytest

from asekit.cli.main import main
from asekit.util.paths import DATA_DIR

PT145 = DATA_DIR / "benchmarks" / "pt145" / "pt145.bdf"


def test_missing_deck_is_one_line(tmp_path, capsys):
    assert main(["convert", str(tmp_path / "none.bdf"), str(tmp_path / "c.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "deck not found" in err[0]


@pytest.mark.skipif(importlib.util.find_spec("pyNastran") is not None,
                    reason="pyNastran installed: the conversion runs")
def test_without_pynastran_it_is_an_input_error(tmp_path, capsys):
    assert main(["convert", str(PT145), str(tmp_path / "c.toml"), "--units", "in-lbf-s"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "pyNastran" in err[0] and not (tmp_path / "c.toml").exists()
