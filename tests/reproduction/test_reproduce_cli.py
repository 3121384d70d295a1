"""The reproduce command as a newcomer meets it (issue 11): a 100-column table with a verdict
per row, output paths checked before any work, JSON to stdout with '-', and a non-zero exit when
a chapter's inputs failed (unless --keep-going)."""

import json

import pytest

from asekit.cli.main import main
from asekit.reproduction import driver as rp
from asekit.reproduction.driver import (
    ChapterResult,
    Quantity,
    comparison_kind,
    format_table,
    verdict,
)


# ---- verdicts --------------------------------------------------------------------------------
def test_verdict_kinds_from_thesis_sources():
    # data/thesis.toml: "Fig 53 (upper bound: ...)", "Section 3.2.1 (rule: at least 15)",
    # "Section 3.2.1 (rule: below 3)", "Fig 71 (range over the fin corners)", "Table 10"
    assert comparison_kind("servo.step14.settling_ms")[0] == "upper_bound"
    assert comparison_kind("aero.min_bpw")[0] == "lower_bound"
    assert comparison_kind("aero.max_box_aspect_ratio")[0] == "upper_bound"
    assert comparison_kind("ase.aem1.corner_overshoot_pct")[0] == "range"
    assert comparison_kind("flutter.pk.M075.h0.speed_ms") == ("value", rp.DEFAULT_RTOL)
    assert comparison_kind("servo.reversal.peak_rate_deg_s") == ("value", rp.APPROX_RTOL)
    assert comparison_kind("aero.boxes")[0] == "none"


def test_verdicts():
    assert verdict("servo.step14.settling_ms", 50.0, 30.0) == "requirement met"
    assert verdict("servo.step14.settling_ms", 50.0, 51.0) == "requirement missed"
    assert verdict("aero.min_bpw", 15.0, 16.6) == "requirement met"
    assert verdict("aero.min_bpw", 15.0, 14.0) == "requirement missed"
    assert verdict("ase.aem1.corner_overshoot_pct", [20.0, 40.0], [25.0, 33.0]) == "in range"
    assert verdict("ase.aem1.corner_overshoot_pct", [20.0, 40.0], [10.0, 16.0]) == \
        "outside range"
    assert verdict("flutter.pk.M075.h0.speed_ms", 251.12, 250.0) == "within tolerance"
    assert verdict("flutter.pk.M075.h0.freq_hz", 143.55, 120.0) == "differs"
    # outside tolerance with an `explained` text in data/thesis.toml
    assert verdict("flutter.pk.M075.h0.speed_ms", 251.12, 218.1) == "explained difference"
    assert verdict("flutter.pk.M075.h0.speed_ms", 251.12, None) == "not computed"
    assert verdict("aero.boxes", None, 140) == "not reported"
    assert verdict("servo.system3.gain_margin_db", float("inf"), float("inf")) == \
        "within tolerance"
    assert verdict("ase.aem2.linear_stable", False, True) == "differs"
    # bounds and ranges get no percent difference
    rows = rp.comparison_rows([Quantity("servo.step14.settling_ms", 30.0, "ms")])
    assert rows[0][4] == "" and rows[0][6] == "requirement met"


def test_table_fits_100_columns_and_wide_keeps_one_line_per_row():
    qs = [Quantity("flutter.first_instability.time_domain.M075.h0.speed_ms", 219.6, "m/s",
                   "a long note " * 20),
          Quantity("servo.system1.closed_loop_poles", [-214.38, -666.56, -9628.15], "rad/s",
                   "x"),
          Quantity("flutter.pk.M075.h0.speed_ms", 218.1, "m/s", "note"),
          Quantity("flutter.pk.M075.h0.freq_hz", 120.0, "Hz", "")]
    rows = rp.comparison_rows(qs)
    text = format_table(rows)
    assert max(len(line) for line in text.splitlines()) <= 100
    assert "verdict" in text.splitlines()[0] and "differs" in text
    assert text.count("long") == 20                          # folded, not cut
    # an explained difference carries its reason from data/thesis.toml under the row
    assert "explained difference" in text and "    why: the 6x7 single-node model" in text
    wide = format_table(rows, wide=True)
    assert len(wide.splitlines()) == 2 + len(rows)
    assert "why: the 6x7" in wide


def test_every_explanation_names_a_known_quantity_with_a_thesis_value():
    entries = rp._load(rp.Path(rp.THESIS_FILE))
    explained = {k: v for k, v in entries.items() if "explained" in v}
    assert explained
    from asekit.reproduction.thesis import all_keys
    known = set(all_keys())
    for key, entry in explained.items():
        assert key in known and entry.get("value") is not None, key
        assert isinstance(entry["explained"], str) and len(entry["explained"]) > 20, key


# ---- arguments -------------------------------------------------------------------------------
@pytest.mark.parametrize("extra, match", [
    (["--figures", ""], "--figures ''"),
    (["--figures", "   "], "--figures"),
    (["--json", ""], "--json"),
])
def test_bad_output_paths_refused_first(extra, match, capsys, monkeypatch):
    monkeypatch.setattr(rp, "run_chapter", lambda *a, **k: pytest.fail("ran a chapter"))
    with pytest.raises(SystemExit) as e:
        main(["reproduce", "--only", "servo", *extra])
    assert e.value.code == 2 and match in capsys.readouterr().err


def test_unwritable_paths_refused_before_any_chapter(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(rp, "run_chapter", lambda *a, **k: pytest.fail("ran a chapter"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for extra in (["--json", str(blocker / "out.json")], ["--figures", str(blocker / "figs")],
                  ["--figures", str(blocker)], ["--json", str(tmp_path)]):
        with pytest.raises(SystemExit) as e:
            main(["reproduce", "--only", "servo", *extra])
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert "not a directory" in err or "give a file path" in err, err


def _fake_chapters(monkeypatch, failing=None, raising=None):
    def run(name, figures=False):
        if name == raising:
            raise RuntimeError("boom: the cache is unreadable")
        q = (Quantity("aero.boxes", 140, "-", "fake"),)
        return ChapterResult(name, q, failures=("GAF cache unusable",) if name == failing
                             else ())
    monkeypatch.setattr(rp, "run_chapter", run)


def test_json_to_stdout_with_dash(monkeypatch, capsys):
    _fake_chapters(monkeypatch)
    assert main(["reproduce", "--only", "aero", "--json", "-", "--quiet"]) == 0
    out, err = capsys.readouterr()
    data = json.loads(out)                                   # stdout is pure JSON
    assert data["quantities"]["aero.boxes"]["note"] == "fake"
    assert data["quantities"]["aero.boxes"]["verdict"] == "not reported"
    assert "quantity" in err                                  # the table went to stderr


def test_failed_chapter_exits_nonzero_unless_keep_going(monkeypatch, capsys, tmp_path):
    _fake_chapters(monkeypatch, failing="aero")
    assert main(["reproduce", "--only", "aero", "servo", "--quiet"]) == 1
    out, err = capsys.readouterr()
    assert "FAILED chapter aero" in out and "GAF cache unusable" in err
    assert "not run: servo" in err
    j = tmp_path / "r.json"
    assert main(["reproduce", "--only", "aero", "servo", "--quiet", "--keep-going",
                 "--json", str(j)]) == 0
    data = json.loads(j.read_text())
    assert data["failures"] == {"aero": ["GAF cache unusable"]}
    assert set(data["seconds"]) == {"aero", "servo"}


def test_chapter_exception_is_a_reported_failure(monkeypatch, capsys):
    _fake_chapters(monkeypatch, raising="servo")
    assert main(["reproduce", "--only", "servo", "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "RuntimeError: boom" in err and "Traceback" not in err


def test_flutter_chapter_with_unusable_gaf_database_exits_nonzero(monkeypatch, capsys):
    """Issue reproducer: `reproduce --only flutter` with an unusable cache exited 0 with 20 of
    24 quantities null."""
    import asekit.reproduction.flutter as fl
    monkeypatch.setattr(fl, "load_fin_gafs",
                        lambda: (None, "fin GAF database unavailable: CacheError: checksum"))
    assert main(["reproduce", "--only", "flutter", "--quiet"]) == 1
    out, err = capsys.readouterr()
    assert "fin GAF database unavailable" in err
