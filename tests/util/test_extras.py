"""Optional dependencies name the pip line that installs them (asekit/util/extras.py)."""

import sys
import tomllib
from pathlib import Path

import pytest

from asekit.util import extras

PYPROJECT = tomllib.loads((Path(__file__).resolve().parents[2] / "pyproject.toml").read_text())


def test_every_extra_named_exists_in_pyproject_and_provides_the_module():
    project = PYPROJECT["project"]
    assert project["name"] == extras.DISTRIBUTION
    optional = project["optional-dependencies"]
    for module, extra in extras.EXTRAS.items():
        assert extra in optional, (module, extra)
        top = module.split(".")[0]
        assert any(req.lower().startswith(top) for req in optional[extra]), (module, extra)


def test_a_missing_module_is_one_line_with_the_pip_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)        # import pandas -> ImportError
    with pytest.raises(extras.MissingExtra) as info:
        extras.require("pandas", "asekit sweep (the results table)")
    msg = str(info.value)
    assert msg == ("asekit sweep (the results table) needs pandas: "
                   "pip install 'asekit-aero[sweep]'")
    assert isinstance(info.value, ImportError) and "\n" not in msg


def test_an_installed_module_is_returned(monkeypatch):
    monkeypatch.setitem(extras.EXTRAS, "numpy", "fast")   # numpy is core; pretend it were an extra
    assert extras.require("numpy", "x").__name__ == "numpy"
