"""The shipped elastic-aileron case data/cases/aileron_wing_elastic.toml (issue 25): the aileron
wing of aileron_wing.toml with ``kind = "elastic"`` (the aileron's plate released along its
hinge), everything else the same; ``asekit analyse`` runs it and its JSON holds the flutter
speeds with the surfaces locked and with the hinge free, next to the rigid case's.

Reference numbers: the locked-surface flutter rows of the two cases are those of one and the
same wing (a locked elastic aileron is the unsplit plate), so they agree to round-off; the
hinge-free flutter of the elastic aileron is computed (its own bending and torsion, and the
exact plate-strip inertia 0.456 g m^2 against the rigid kind's 0.475) and measured at 11.52 m/s
and 11.99 Hz at Mach 0 against the rigid kind's 12.75 m/s and 12.08 Hz (`asekit analyse
aileron_wing[_elastic] --json`): the test asserts the same flutter mechanism (frequency within
3 %) and a speed within 15 % of the rigid aileron's, not the measured values."""

import json
import tomllib

import pytest

from asekit.case import load_case
from asekit.util.paths import CASES_DIR

ELASTIC = CASES_DIR / "aileron_wing_elastic.toml"
RIGID = CASES_DIR / "aileron_wing.toml"


def test_the_elastic_case_is_the_rigid_one_with_the_elastic_kind():
    el, rg = tomllib.loads(ELASTIC.read_text()), tomllib.loads(RIGID.read_text())
    assert el["control_surface"][0].pop("kind") == "elastic"
    assert rg["control_surface"][0].pop("kind") == "rigid"
    for d in (el, rg):
        d.pop("case")
    assert el == rg
    case = load_case(ELASTIC)
    assert case.name == "aileron_wing_elastic"
    assert [c.kind for c in case.control_surfaces] == ["elastic"]
    assert case.control_surfaces[0].actuator is not None


@pytest.mark.slow
def test_analyse_runs_it_and_the_json_holds_the_rigid_and_elastic_flutter(tmp_path):
    from asekit.cli.main import main

    out = {}
    for name, path in (("elastic", ELASTIC), ("rigid", RIGID)):
        out[name] = tmp_path / f"{name}.json"
        assert main(["analyse", str(path), "--json", str(out[name]), "--quiet"]) == 0
    el, rg = (json.loads(out[k].read_text()) for k in ("elastic", "rigid"))
    assert [r["kind"] for r in el["control_surfaces"]] == ["elastic", "elastic"]
    for a, b in zip(el["flutter"], rg["flutter"]):            # surfaces locked: one wing
        assert a["speed_ms"] == pytest.approx(b["speed_ms"], rel=1e-6)
    for a, b in zip(el["control_surface_flutter"], rg["control_surface_flutter"]):
        assert a["mach"] == b["mach"]
        assert a["speed_ms"] is not None and b["speed_ms"] is not None
        assert a["frequency_hz"] == pytest.approx(b["frequency_hz"], rel=0.03)
        assert a["speed_ms"] == pytest.approx(b["speed_ms"], rel=0.15)
        assert a["speed_ms"] < el["flutter"][0]["speed_ms"]   # the free hinge flutters first
    assert [r["topology"] for r in el["control_surface_ase"]] == ["AEM1", "AEM2"]
    assert all(r["stable"] for r in el["control_surface_ase"])
