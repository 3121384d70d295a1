"""`asekit cases`: the shipped case files by name (asekit/cli/cases.py, asekit/util/paths.py)."""

import argparse
import json
import tomllib

import pytest

from asekit.cli import cases
from asekit.util.paths import CASES_DIR, shipped_case, shipped_cases


def _run(argv):
    p = argparse.ArgumentParser()
    cases.add_parser(p.add_subparsers())
    args = p.parse_args(["cases", *argv])
    return args.func(args)


def test_every_shipped_case_is_listed_with_its_reference(capsys):
    assert _run([]) == 0
    out = capsys.readouterr().out.splitlines()
    names = sorted(p.stem for p in CASES_DIR.glob("*.toml"))
    assert names and sorted(shipped_cases()) == names
    for name in names:
        ref = tomllib.loads((CASES_DIR / f"{name}.toml").read_text())["case"]["reference"]
        assert any(line.startswith(name + " ") and ref in line for line in out), name


def test_resolve_case_prefers_an_existing_path(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert cases.resolve_case("agard445_6") == CASES_DIR / "agard445_6.toml"
    (tmp_path / "agard445_6").write_text("")          # a local file of that name wins
    assert cases.resolve_case("agard445_6").resolve() == (tmp_path / "agard445_6").resolve()
    with pytest.raises(FileNotFoundError, match="asekit cases"):
        cases.resolve_case("no_such_case")
    assert shipped_case("../cases/agard445_6") is None     # names only, never paths


def test_copy_writes_an_editable_case_and_never_overwrites(tmp_path, capsys):
    dest = tmp_path / "new" / "agard445_6.toml"
    assert _run(["--copy", "agard445_6", str(tmp_path / "new")]) == 0
    assert dest.read_bytes() == (CASES_DIR / "agard445_6.toml").read_bytes()
    assert _run(["--copy", "agard445_6", str(tmp_path / "new")]) == 2
    assert "not overwritten" in capsys.readouterr().err
    assert _run(["--copy", "nope", str(tmp_path)]) == 2
    assert "choose from" in capsys.readouterr().err


def test_version_and_a_shipped_case_by_name_from_any_directory(tmp_path):
    """`asekit --version`; `asekit analyse agard445_6` run outside the checkout (issue 30: a
    wheel user got "not found"); an unknown name says where shipped cases live."""
    import subprocess
    import sys

    from asekit.util.version import __version__

    def run(*args):
        return subprocess.run([sys.executable, "-m", "asekit", *args], capture_output=True,
                              text=True, cwd=tmp_path, timeout=300)

    r = run("--version")
    assert r.returncode == 0 and r.stdout.strip() == f"asekit {__version__}"
    r = run("analyse", "no_such_case")
    assert r.returncode == 2
    assert r.stderr.strip().splitlines() == [
        f"error: case file no_such_case not found, and no shipped case of that name "
        f"(`asekit cases` lists them; they live in {CASES_DIR})"]
    r = run("analyse", "agard445_6", "--quiet", "--json", "out/o.json")
    assert r.returncode == 0, r.stderr
    summary = json.loads((tmp_path / "out" / "o.json").read_text())
    assert summary["case"] == "agard445_6_weakened_3"
