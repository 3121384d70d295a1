"""The flutter-method and RFA registries through the case layer (``[flutter]``): every method
finds the same flutter point on a case it was not tuned on, and unknown kinds fail at the door.

At the flutter point the roots are undamped (g = 0), where the p-k method and the state-space
eigenvalues of a rational function approximation solve the same flutter determinant; they may
differ only by the RFA's fit error (Roger / minimum state) and the p-k's k-interpolation
(Hassig 1971; Karpel 1982). AGARD 445.6 weakened wing 3 at M 0.499 (Yates 1987; the shipped
case data/cases/agard445_6.toml).
"""

import dataclasses

import pytest

from asekit import CASES_DIR, load_case, pipeline
from asekit.aeroelastic.methods import FLUTTER_METHODS
from asekit.case import CaseError, FlutterSpec, case_from_dict
from asekit.rfa.methods import RFA_FITS


@pytest.fixture(scope="module")
def agard():
    return load_case(CASES_DIR / "agard445_6.toml")


@pytest.fixture(scope="module")
def pk_flutter_point(agard):
    (r,) = pipeline.flutter(agard).results
    assert r.flutter is not None and not r.unstable_at_start
    return r.flutter


@pytest.mark.parametrize("rfa", sorted(RFA_FITS))
def test_root_locus_finds_the_pk_flutter_point(agard, pk_flutter_point, rfa):
    case = dataclasses.replace(agard, flutter=FlutterSpec("root_locus", rfa, 4))
    (r,) = pipeline.flutter(case).results
    assert r.flutter is not None
    # 1 %: the RFA's fit error (4 lag roots) and p-k's linear k-interpolation
    assert r.flutter.speed == pytest.approx(pk_flutter_point.speed, rel=0.01)
    assert r.flutter.frequency_hz == pytest.approx(pk_flutter_point.frequency_hz, rel=0.01)
    # the roots carried to the report are the state-space roots: the flutter root crosses 0
    j = r.flutter.mode
    assert (r.pk.p[0, j].real < 0) and (r.pk.p[-1, j].real > 0)


@pytest.mark.parametrize("name", ["nastran_pk", "k", "ke"])
def test_nastran_methods_find_the_pk_flutter_point(agard, pk_flutter_point, name):
    """MSC Nastran's PK, K and KE (asekit.aeroelastic.nastran) through the case layer: the
    same flutter point at g = 0 within 1 % (their crossings are read linearly from the V-g
    table of the case's velocities, or of the K method's k grid; asekit's p-k refines)."""
    case = dataclasses.replace(agard, flutter=FlutterSpec(name, "roger", 4))
    (r,) = pipeline.flutter(case).results
    assert r.flutter is not None and r.flutter.method == name
    assert r.flutter.speed == pytest.approx(pk_flutter_point.speed, rel=0.01)
    assert r.flutter.frequency_hz == pytest.approx(pk_flutter_point.frequency_hz, rel=0.01)


def test_default_is_pk_with_roger(agard):
    assert agard.flutter == FlutterSpec("pk", "roger", 4)
    assert set(FLUTTER_METHODS) >= {"pk", "root_locus"}


@pytest.mark.parametrize("table, key", [({"method": "kk"}, "flutter.method"),
                                        ({"rfa": "pade"}, "flutter.rfa"),
                                        ({"lags": 0}, "flutter.lags"),
                                        ({"mthod": "pk"}, "flutter.mthod")])
def test_unknown_kinds_fail_naming_the_key(table, key):
    import tomllib
    d = tomllib.loads((CASES_DIR / "agard445_6.toml").read_text())
    d["flutter"] = table
    with pytest.raises(CaseError, match=key.replace(".", r"\.")):
        case_from_dict(d)
