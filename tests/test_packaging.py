"""The wheel must hold every package and the data files (pyproject lists packages explicitly
and maps data/ to asekit.data)."""

import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def test_every_subpackage_is_listed_in_pyproject():
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts)
             for p in (ROOT / "asekit").rglob("__init__.py")}
    assert found <= listed, f"add {sorted(found - listed)} to [tool.setuptools] packages"
    assert "asekit.data" in listed


def test_data_files_are_package_data():
    cfg = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    globs = cfg["package-data"]["asekit.data"]
    data = ROOT / "data"
    files = [p.relative_to(data) for p in data.rglob("*") if p.is_file()]
    missing = [str(f) for f in files
               if not any(f.match(g) for g in globs) and not f.name.startswith(".")]
    assert not missing, f"data files not shipped in the wheel: {missing}"
