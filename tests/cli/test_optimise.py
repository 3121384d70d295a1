"""``asekit optimise`` (issue 28): refused input in one line before any work (exit 2); the
shipped fin problem end to end (slow): the written case re-analysed by the pipeline meets the
15 % flutter margin the baseline misses."""

from __future__ import annotations

import json
import tomllib

import numpy as np
import pytest

from asekit.case import load_case
from asekit.case import pipeline as P
from asekit.cli.main import main
from asekit.util.paths import CASES_DIR, DATA_DIR

FIN = CASES_DIR / "nalci2013_fin.toml"
DESIGN = DATA_DIR / "designs" / "fin_min_mass.toml"

pytestmark = pytest.mark.usefixtures("session_gaf_cache")


@pytest.fixture
def no_work(monkeypatch):
    def ran(*a, **k):
        pytest.fail("the pipeline ran")
    for name in ("modal_model", "gaf_database", "flutter", "box_mesh"):
        monkeypatch.setattr(P, name, ran)


def test_shipped_design_file_parses():
    from asekit.case.design import load_design
    p = load_design(DESIGN)
    assert [v.path for v in p.variables] == ["thickness.root", "thickness.tip"]
    assert p.flutter_margin == 0.15 and p.divergence_margin == 0.15


@pytest.mark.parametrize("text, fragment", [
    ("[design]\nobjective = 'drag'\n", "design.objective must be one of ['mass', 'flutter_speed']"),
    ("[design]\n[[design.variable]]\npath = 'thickness.tip'\nlower = 0.003\nupper = 0.006\n",
     "thickness.tip = 0.002 in the case lies outside its bounds"),
    ("[design\n", "design.toml"),
])
def test_bad_design_is_one_line_exit_2(tmp_path, capsys, no_work, text, fragment):
    d = tmp_path / "design.toml"
    d.write_text(text)
    assert main(["optimise", str(FIN), str(d)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("error:") and fragment in err[0], err


def test_missing_file_is_one_line_exit_2(tmp_path, capsys, no_work):
    assert main(["optimise", str(FIN), str(tmp_path / "none.toml")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "not found" in err[0], err


@pytest.mark.slow
def test_fin_minimum_mass_end_to_end(tmp_path, capsys):
    out, opt, rep = tmp_path / "out.json", tmp_path / "opt.toml", tmp_path / "rep"
    assert main(["optimise", str(FIN), str(DESIGN), "--json", str(out),
                 "--out-case", str(opt), "--report", str(rep)]) == 0
    assert {"index.html", "thickness.png", "vg.png", "history.png", "summary.json"} <= {
        p.name for p in rep.iterdir()}
    d = json.loads(out.read_text())["design"]
    # independent of the optimiser: the written file, loaded and analysed by the pipeline
    margins = [m["margin"] for m in P.flutter(load_case(opt)).margins]
    assert min(margins) >= 0.15
    assert d["optimised"]["flutter_margin_pct"] == pytest.approx(100 * min(margins), abs=1e-9)
    assert d["baseline"]["flutter_margin_pct"] < 15.0            # the fin misses it (4.3 %)
    assert d["gradient_check"]["max_rel_error"] <= 1e-5
    raw = tomllib.loads(opt.read_text())
    assert raw["thickness"]["tip"] == pytest.approx(d["optimised"]["values"]["thickness.tip"])
    assert d["optimised"]["mass_kg"] < d["baseline"]["mass_kg"]
    assert d["optimised"]["meets_constraints"] and not d["baseline"]["meets_constraints"]
    # divergence is a constraint of the shipped design (divergence_margin = 0.15): the
    # re-analysed divergence margin clears it, or the fin does not diverge in the sweep
    dm = d["optimised"]["divergence_margin_pct"]
    assert dm is None or dm >= 15.0 - 1e-9
    assert d["divergence_margin_required_pct"] == 15.0


FIELD = CASES_DIR / "nalci2013_fin_field.toml"
FIELD_DESIGN = DATA_DIR / "designs" / "fin_min_mass_field.toml"


def test_table_design_on_a_linear_case_is_one_line_exit_2(capsys, no_work):
    assert main(["optimise", str(FIN), str(FIELD_DESIGN)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "needs a thickness table in the case" in err[0], err


@pytest.mark.slow
def test_fin_thickness_field_end_to_end(tmp_path):
    # 50 table variables (issue 28's "Done when"); 110 s measured on the shared 2-core machine
    out, opt = tmp_path / "out.json", tmp_path / "opt.toml"
    assert main(["optimise", str(FIELD), str(FIELD_DESIGN), "--json", str(out),
                 "--out-case", str(opt)]) == 0
    d = json.loads(out.read_text())["design"]
    assert len(d["optimised"]["values"]) == 50
    written = load_case(opt)                     # the written table, analysed by the pipeline
    margins = [m["margin"] for m in P.flutter(written).margins]
    assert min(margins) >= 0.15
    assert d["optimised"]["mass_kg"] < d["baseline"]["mass_kg"]
    assert d["gradient_check"]["max_rel_error"] <= 1e-5
    v = np.array(written.thickness.values)       # the smoothness bound holds in the file
    step = 0.0005 * (1 + 1e-6)
    assert np.abs(np.diff(v, axis=0)).max() <= step and np.abs(np.diff(v, axis=1)).max() <= step
