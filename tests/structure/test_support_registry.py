"""The support kinds registry (asekit.structure.supports.SUPPORTS): the schema reads a kind's
keys through it, the pipeline builds the kind's structure through it, an unknown kind fails
at the door naming ``support.kind`` and the known kinds, and a kind added to the registry is
usable from a case file without touching the schema or the pipeline."""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest

from asekit.case import CaseError, case_from_dict, load_case, pipeline
from asekit.case.variants import with_mesh, with_shaft
from asekit.structure import supports
from asekit.structure.assembly import clamped_edge
from asekit.structure.modes import fixed_modal_model
from asekit.util.paths import FIN_FILE
from asekit.util.validate import read_toml


def _fin_dict():
    return read_toml(FIN_FILE, CaseError)


def test_unknown_kind_names_the_key_and_the_known_kinds():
    d = _fin_dict()
    d["support"] = {"kind": "hinge"}
    with pytest.raises(CaseError) as err:
        case_from_dict(d)
    msg = str(err.value)
    assert msg.startswith("support.kind must be one of")
    assert all(repr(k) in msg for k in supports.SUPPORTS) and "'hinge'" in msg
    with pytest.raises(ValueError, match="support.kind must be one of"):
        supports.support_kind("hinge")


def test_kind_errors_name_their_key_path():
    d = _fin_dict()
    d["support"] = dict(d["support"], axis_point=[0.078, 0.05])
    with pytest.raises(CaseError, match=r"^support.axis_point \[0.078, 0.05\] must lie on the root"):
        case_from_dict(d)
    d["support"] = dict(_fin_dict()["support"], region=-1.0)
    with pytest.raises(CaseError, match=r"^support.region must be"):
        case_from_dict(d)
    d["support"] = dict(_fin_dict()["support"], spring=1.0)
    with pytest.raises(CaseError, match=r"^support.spring is not a known key"):
        case_from_dict(d)
    d["support"] = {"kind": "edges", "root": "free"}
    with pytest.raises(CaseError, match="all four edges free"):
        case_from_dict(_without_actuator(d))


def _without_actuator(d):
    return {k: v for k, v in d.items() if k != "actuator"}


def _parse_station(t, root):
    station = t.number("station", default=root.root_le[1], low=-1e3, high=1e3, unit="m")
    t.done()
    return {"station": station}


def _station_system(mesh, K, M, spec):
    return clamped_edge(mesh, K, M, y_edge=spec.option("station"))


def test_pipeline_builds_through_the_registry(monkeypatch):
    """A kind registered at run time (a clamp at a spanwise station, with its own key) is read
    from a case dict and analysed, with no change to the schema, SupportSpec or the pipeline."""
    kind = supports.SupportKind(
        "station_clamp_test", "test kind", _parse_station, _station_system,
        lambda mesh, K, M, spec, f, n, keep: fixed_modal_model(_station_system(mesh, K, M, spec),
                                                               M, f, n))
    monkeypatch.setitem(supports.SUPPORTS, kind.name, kind)
    d = _without_actuator(_fin_dict())
    d["support"] = {"kind": "station_clamp_test"}
    case = case_from_dict(d)
    assert case.support.options == (("station", 0.0),) and not case.modes.keep_rigid
    ref = dataclasses.replace(case, support=dataclasses.replace(case.support,
                                                                kind="clamped_root"))
    a, b = pipeline.modal_model(case), pipeline.modal_model(ref)
    assert a.n_rigid == 0 and np.array_equal(a.frequencies_hz, b.frequencies_hz)
    d["support"] = {"kind": "station_clamp_test", "station": 0.15}     # clamp the tip station
    tip = pipeline.modal_model(case_from_dict(d))
    assert tip.frequencies_hz[0] < a.frequencies_hz[0]   # the wide root free: a softer plate
    d["support"] = {"kind": "station_clamp_test", "radius": 1.0}
    with pytest.raises(CaseError, match=r"^support.radius is not a known key"):
        case_from_dict(d)


def test_memoised_model_is_read_only_and_warns_every_time():
    case = load_case(FIN_FILE)
    m = pipeline.modal_model(case)
    assert pipeline.modal_model(case) is m
    with pytest.raises(ValueError):
        m.K[0, 0] = 1.0
    coarse = with_mesh(with_shaft(case, radius=0.005), 6, 7)     # 1 node inside 5 mm
    for _ in range(2):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            pipeline.modal_model(coarse)
        assert any("not resolved" in str(w.message) for w in caught)
