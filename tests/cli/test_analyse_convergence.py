"""``asekit analyse CASE --convergence`` and ``[convergence] enabled = true`` (issue 23): the
JSON flutter rows gain the extrapolated speed and frequency with their error bars, the table
prints them, and a study the case's meshes cannot carry is refused in one line (exit 2)
before any computation."""

from __future__ import annotations

import json

import pytest

from asekit.case import pipeline as P
from asekit.cli.main import main
from asekit.util.paths import CASES_DIR

AGARD = CASES_DIR / "agard445_6.toml"
KEYS = ("speed_extrapolated_ms", "speed_error_ms", "frequency_extrapolated_hz",
        "frequency_error_hz")

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


def test_analyse_convergence_writes_error_bars(tmp_path, capsys):
    out = tmp_path / "agard.json"
    assert main(["analyse", str(AGARD), "--convergence", "--quiet", "--json", str(out)]) == 0
    s = json.loads(out.read_text())
    (row,) = s["flutter"]
    assert all(isinstance(row[k], float) for k in KEYS)
    assert 0 < row["speed_error_ms"] < 0.05 * row["speed_extrapolated_ms"]
    conv = s["convergence"]
    assert conv["meshes"] == 3 and len(conv["rows"][0]["speeds_ms"]) == 3
    assert conv["rows"][0]["speeds_ms"][0] == row["speed_ms"]       # the case's own mesh
    text = capsys.readouterr().out
    assert f"{row['speed_extrapolated_ms']:.2f} +- {row['speed_error_ms']:.2f}" in text


def test_plain_analyse_has_no_convergence_fields(tmp_path):
    out = tmp_path / "agard.json"
    assert main(["analyse", str(AGARD), "--quiet", "--json", str(out)]) == 0
    s = json.loads(out.read_text())
    assert "convergence" not in s and not any(k in s["flutter"][0] for k in KEYS)


def test_case_key_enables_the_study(tmp_path):
    case = tmp_path / "agard.toml"
    case.write_text(AGARD.read_text() + "\n[convergence]\nenabled = true\nmeshes = 2\n")
    out = tmp_path / "agard.json"
    assert main(["analyse", str(case), "--quiet", "--json", str(out)]) == 0
    s = json.loads(out.read_text())
    assert s["convergence"]["meshes"] == 2 and s["flutter"][0]["speed_error_ms"] > 0


@pytest.mark.parametrize("table, fragment", [
    ("meshes = 3\nratio = 4.0", "convergence.meshes = 3 with convergence.ratio = 4: the coarsest "
                                "mesh would have panel[0].n_chord = 1"),
    ("meshes = 5", "convergence.meshes must be an integer in [2, 3], got 5")])
def test_bad_study_is_one_line_before_any_work(tmp_path, capsys, monkeypatch, table, fragment):
    def ran(*a, **k):
        pytest.fail("the pipeline ran")
    for name in ("modal_model", "gaf_database", "flutter"):
        monkeypatch.setattr(P, name, ran)
    case = tmp_path / "agard.toml"
    case.write_text(AGARD.read_text() + f"\n[convergence]\n{table}\n")
    assert main(["analyse", str(case), "--convergence", "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and fragment in err[0] and "Traceback" not in err[0], err
