"""``asekit trajectory CASE PROFILE [--json] [--plot]`` (issue 27): the table, the JSON rows
(their margins the case pipeline's at the case's own flight point), the plot, and input errors
as one line and exit 2 before any work."""

from __future__ import annotations

import json

import pytest

from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.cli.main import main
from asekit.util.paths import CASES_DIR

pytestmark = pytest.mark.usefixtures("session_gaf_cache")

KEYS = {"time_s", "mach", "altitude_m", "dynamic_pressure_Pa", "flutter_speed_ms",
        "flutter_margin_pct", "divergence_margin_pct", "hinge_moment_Nm",
        "tn4197_flutter_speed_ms", "transonic_gap"}


@pytest.fixture(scope="module")
def small_fin_file(tmp_path_factory):
    """The fin's case file at two Machs, sea level and a shorter sweep (a fast p-k)."""
    text = (CASES_DIR / "nalci2013_fin.toml").read_text()
    for old, new in (("machs = [0.4, 0.5, 0.6, 0.75]", "machs = [0.5, 0.6]"),
                     ("altitudes = [0.0, 2500.0, 5000.0]", "altitudes = [0.0]"),
                     ("velocities = { min = 100.0, max = 460.0, step = 2.0 }",
                      "velocities = { min = 150.0, max = 300.0, step = 2.0 }")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path_factory.mktemp("trajectory") / "small_fin.toml"
    path.write_text(text)
    return path


@pytest.fixture
def no_work(monkeypatch):
    def ran(*a, **k):
        pytest.fail("the pipeline ran")
    for name in ("modal_model", "gaf_database", "flutter", "box_mesh"):
        monkeypatch.setattr(P, name, ran)


def test_trajectory_command(small_fin_file, tmp_path, capsys):
    prof = tmp_path / "p.csv"
    prof.write_text("time_s,mach,altitude_m,alpha_deg\n0,0.6,0,2\n1,0.95,0,2\n")
    out, png = tmp_path / "o" / "t.json", tmp_path / "o" / "t.png"
    assert main(["trajectory", str(small_fin_file), str(prof), "--json", str(out),
                 "--plot", str(png), "--quiet"]) == 0
    table = capsys.readouterr().out.splitlines()
    assert table[0].startswith("trajectory of nalci2013_fin")
    assert table[2].split()[:2] == ["0.00", "0.600"] and table[3].endswith("G")
    doc = json.loads(out.read_text())
    rows = doc["trajectory"]
    assert len(rows) == 2 and KEYS <= set(rows[0])
    (m,) = P.flutter(load_case(small_fin_file)).margins      # sea level, M 0.6: the envelope
    assert rows[0]["flutter_margin_pct"] == pytest.approx(100 * m["margin"], rel=1e-12)
    assert rows[0]["hinge_moment_Nm"] > 0                     # Q_cc > 0: de-centering
    assert rows[1]["transonic_gap"] is True and rows[1]["flutter_speed_ms"] is None
    assert doc["units"]["dynamic_pressure_Pa"] == "Pa"
    assert doc["analysed_machs"] == [0.5, 0.6] and doc["extrapolated_times_s"] == []
    assert "clamped" in doc["tn4197"]["comparison"]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("text, words", [
    ("time_s,mach,altitude_m\n0,0.5,0\n1,0.5,99999\n", ["p.csv, row 3, column altitude_m"]),
    ("time_s,mach\n0,0.5\n", ["p.csv, row 1", "altitude_m"]),
])
def test_bad_profile_one_line_before_work(small_fin_file, tmp_path, capsys, no_work, text,
                                          words):
    prof = tmp_path / "p.csv"
    prof.write_text(text)
    assert main(["trajectory", str(small_fin_file), str(prof)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    for w in words:
        assert w in err


def test_missing_inputs_and_bad_outputs(small_fin_file, tmp_path, capsys, no_work):
    prof = tmp_path / "p.csv"
    prof.write_text("time_s,mach,altitude_m\n0,0.5,0\n")
    assert main(["trajectory", str(tmp_path / "none.toml"), str(prof)]) == 2
    assert "not found" in capsys.readouterr().err
    assert main(["trajectory", str(small_fin_file), str(tmp_path / "none.csv")]) == 2
    assert "no such profile file" in capsys.readouterr().err
    assert main(["trajectory", str(small_fin_file), str(prof), "--plot", str(tmp_path)]) == 2
    assert "--plot" in capsys.readouterr().err
