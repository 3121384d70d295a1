"""``reproduce`` (issue 30): its table counts "not computed" (no asekit value in this run:
``--only``, ``--converged`` not given) apart from "not reported" (no thesis number), a "why"
line or note never cites a row that is empty in the run, and the command's messages follow
``-v`` / ``--quiet`` / ``--log-file`` with warnings as one line each over the progress bar.
The chapters are replaced by fakes (``driver.run_chapter``): these tests take a second."""

import json
import warnings

import pytest

from asekit.cli.main import main
from asekit.reproduction import driver as rp
from asekit.reproduction.driver import ChapterResult, Quantity, format_table
from asekit.reproduction.thesis import all_keys

#: data/thesis.toml: flutter.pk.M075.h2500.speed_ms is "explained" with a clause citing
#: flutter.converged.* ("..., and the uniform-mesh study gives 254 m/s (flutter.converged.*),
#: and of the thesis's stated inputs ...").
CITING = "flutter.pk.M075.h2500.speed_ms"
CONVERGED = ("flutter.converged.pk.M075.h0.speed_ms", "flutter.converged.pk.M075.h0.freq_hz")


def _fake(monkeypatch, converged=None, warn=False):
    """aero: one row with no thesis number (aero.boxes); flutter: an explained row (CITING,
    218 m/s against the thesis's 256.62) and the converged rows (None and computed=False unless
    ``converged`` gives their values)."""
    def run(name, figures=False):
        if warn:
            warnings.warn("p-k: the k-iteration did not converge at 17400 m/s",
                          RuntimeWarning, stacklevel=1)
        if name == "aero":
            return ChapterResult(name, (Quantity("aero.boxes", 140, "-", "fake"),))
        if name == "flutter":
            conv = [Quantity(k, None if converged is None else v, u, "how to compute it",
                             computed=converged is not None)
                    for k, v, u in zip(CONVERGED, converged or (None, None), ("m/s", "Hz"))]
            return ChapterResult(name, (Quantity(CITING, 218.0, "m/s", "flutter"), *conv))
        return ChapterResult(name, ())
    monkeypatch.setattr(rp, "run_chapter", run)


def test_not_computed_is_counted_apart_from_not_reported(monkeypatch, capsys, tmp_path):
    _fake(monkeypatch)
    j = tmp_path / "r.json"
    assert main(["reproduce", "--only", "aero", "flutter", "--quiet", "--json", str(j)]) == 0
    out = capsys.readouterr().out
    data = json.loads(j.read_text())
    q = data["quantities"]
    # the converged rows have no thesis number, but what they lack in this run is asekit's
    assert [q[k]["verdict"] for k in CONVERGED] == ["not computed"] * 2
    assert q["aero.boxes"]["verdict"] == "not reported"
    assert q[CITING]["verdict"] == "explained difference"
    counts = data["counts"]
    n_keys = len(all_keys())
    assert counts["not computed"] == 2 and counts["not reported"] == 1
    assert counts["not run"] == n_keys - 4            # every thesis row the run did not produce
    assert counts["chapters not run"] == ["servo", "structure", "ase", "supersonic",
                                          "freeplay", "design"]
    text = " ".join(out.split())
    assert "verdicts: 1 explained difference" in text
    assert (f"not computed in this run: {2 + n_keys - 4} rows (2 in the table, {n_keys - 4} of "
            "the chapters not run: servo, structure, ase, supersonic, freeplay, design); not "
            "reported (the thesis gives no number): 1 rows") in text


def test_why_line_never_cites_an_empty_row(monkeypatch, capsys):
    """Without the converged values the clause citing flutter.converged.* is left out (the
    rest of the explanation stays); with them, it is shown."""
    _fake(monkeypatch)
    assert main(["reproduce", "--only", "flutter", "--quiet"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "why: the 6x7 single-node model is not mesh-converged" in text
    assert "of the thesis's stated inputs only its mass level" in text    # the next clause
    assert "flutter.converged.*" not in text and "254 m/s" not in text
    _fake(monkeypatch, converged=(254.0, 139.0))
    assert main(["reproduce", "--only", "flutter", "--quiet"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert "the uniform-mesh study gives 254 m/s (flutter.converged.*)" in text


def test_format_table_alone_drops_citations_of_rows_it_lacks():
    """A chapter's own table (the notebooks' comparison_table) follows the same rule: a row
    the table does not hold is empty."""
    rows = rp.comparison_rows([Quantity(CITING, 218.0, "m/s", "")])
    assert "flutter.converged" not in format_table(rows)
    rows += rp.comparison_rows([Quantity(CONVERGED[0], 254.0, "m/s", "")])
    assert "(flutter.converged.*)" in " ".join(format_table(rows).split())


def test_verbose_quiet_and_log_file(monkeypatch, capsys, tmp_path):
    _fake(monkeypatch)
    assert main(["reproduce", "--only", "aero", "-v"]) == 0
    err = capsys.readouterr().err
    assert "info: chapter aero (Ch. 3.2 aerodynamics) ..." in err.splitlines()
    assert "chapter/s" in err or "chapter]" in err or "1/1" in err       # the progress bar
    assert main(["--quiet", "reproduce", "--only", "aero"]) == 0          # before the command
    err = capsys.readouterr().err
    assert err == "", err                                # no bar, no info line
    log = tmp_path / "logs" / "run.log"
    assert main(["reproduce", "--only", "aero", "--quiet", "--log-file", str(log)]) == 0
    assert capsys.readouterr().err == ""
    text = log.read_text()
    assert "DEBUG asekit.cli.main: asekit" in text
    assert "INFO asekit.reproduction.driver: chapter aero: 1 rows in" in text


def test_log_file_checked_before_any_chapter(monkeypatch, capsys, tmp_path):
    monkeypatch.setattr(rp, "run_chapter", lambda *a, **k: pytest.fail("ran a chapter"))
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["reproduce", "--only", "servo", "--log-file", str(blocker / "x.log")]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("error: --log-file") and "not a directory" in \
        err[0]


def test_warning_during_the_progress_bar_is_one_line_once(monkeypatch, capsys):
    """issue 30: a library warning was printed into the middle of the progress bar with its
    source line, on every chapter."""
    _fake(monkeypatch, warn=True)
    assert main(["reproduce", "--only", "aero", "flutter"]) == 0
    err = capsys.readouterr().err
    pieces = [p.strip() for line in err.split("\n") for p in line.split("\r")]
    assert pieces.count("warning: RuntimeWarning: p-k: the k-iteration did not converge at "
                        "17400 m/s") == 1, err
    assert sum("17400" in p for p in pieces) == 1
    assert "warnings.warn" not in err                    # no source line
